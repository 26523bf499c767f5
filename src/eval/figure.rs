//! One figure per configuration: predicted direct | predicted indirect | predicted global |
//! reference | FLIP error map of the global image with a colour bar, each panel labelled,
//! metrics underneath.

use font8x8::legacy::BASIC_LEGACY;
use image::{Rgb, RgbImage};

const MARGIN: u32 = 8;
const GAP: u32 = 8;
const BAR: u32 = 12;
const BACKGROUND: Rgb<u8> = Rgb([24, 24, 24]);
const TEXT: Rgb<u8> = Rgb([235, 235, 235]);

/// A panel: tonemapped RGB8 rows, and its label.
pub struct Panel<'a> {
    pub label: &'a str,
    pub rgb: &'a [u8],
}

/// Lays out `panels` (each `width × height`) in a row, then the FLIP `error` map in magma
/// with a colour bar from 0 to 1, and `footer` lines of text underneath.
pub fn compose(panels: &[Panel], error: &[f32], width: u32, height: u32, footer: &[String]) -> RgbImage {
    let big = width >= 192;
    let line = if big { 20 } else { 12 };
    let columns = panels.len() as u32 + 1;
    let bar_labels = 3 * 8 * if big { 2 } else { 1 };
    let total_width = 2 * MARGIN + columns * width + (columns - 1) * GAP + GAP + BAR + 4 + bar_labels;
    let top = MARGIN + line;
    let total_height = top + height + 6 + footer.len() as u32 * line + MARGIN;
    let mut image = RgbImage::from_pixel(total_width, total_height, BACKGROUND);

    let magma = nv_flip::magma_lut();
    let heat = nv_flip::FlipImageFloat::with_data(width, height, error).apply_color_lut(&magma).to_vec();
    let error_panel = Panel { label: "FLIP (global)", rgb: &heat };
    for (i, panel) in panels.iter().chain([&error_panel]).enumerate() {
        let x0 = MARGIN + i as u32 * (width + GAP);
        label(&mut image, x0, MARGIN, panel.label, width, big);
        blit(&mut image, x0, top, width, height, panel.rgb);
    }

    // Colour bar: 1 at the top, 0 at the bottom.
    let bar_x = MARGIN + columns * (width + GAP);
    let values: Vec<f32> = (0..height).map(|y| 1.0 - y as f32 / (height - 1).max(1) as f32).collect();
    let bar = nv_flip::FlipImageFloat::with_data(1, height, &values).apply_color_lut(&magma).to_vec();
    for y in 0..height {
        let c = &bar[3 * y as usize..3 * y as usize + 3];
        for x in 0..BAR {
            image.put_pixel(bar_x + x, top + y, Rgb([c[0], c[1], c[2]]));
        }
    }
    let scale = if big { 2 } else { 1 };
    let text_x = bar_x + BAR + 4;
    text(&mut image, text_x, top, "1.0", scale);
    text(&mut image, text_x, top + height / 2 - 4 * scale, "0.5", scale);
    text(&mut image, text_x, top + height - 8 * scale, "0.0", scale);

    for (i, line_text) in footer.iter().enumerate() {
        text(&mut image, MARGIN, top + height + 6 + i as u32 * line, line_text, scale);
    }
    image
}

fn blit(image: &mut RgbImage, x0: u32, y0: u32, width: u32, height: u32, rgb: &[u8]) {
    for y in 0..height {
        for x in 0..width {
            let i = 3 * (y * width + x) as usize;
            image.put_pixel(x0 + x, y0 + y, Rgb([rgb[i], rgb[i + 1], rgb[i + 2]]));
        }
    }
}

/// A label over a panel: twice the font size where it fits.
fn label(image: &mut RgbImage, x: u32, y: u32, s: &str, width: u32, big: bool) {
    let scale = if big && s.len() as u32 * 16 <= width { 2 } else { 1 };
    text(image, x, y + if scale == 1 && big { 4 } else { 0 }, s, scale);
}

/// ASCII text in the 8×8 public-domain font, `scale` pixels per font pixel.
pub fn text(image: &mut RgbImage, x: u32, y: u32, s: &str, scale: u32) {
    for (i, ch) in s.chars().enumerate() {
        let Some(glyph) = BASIC_LEGACY.get(ch as usize) else { continue };
        for (row, bits) in glyph.iter().enumerate() {
            for col in 0..8 {
                if bits & (1 << col) == 0 {
                    continue;
                }
                for dy in 0..scale {
                    for dx in 0..scale {
                        let px = x + (i as u32 * 8 + col) * scale + dx;
                        let py = y + row as u32 * scale + dy;
                        if px < image.width() && py < image.height() {
                            image.put_pixel(px, py, TEXT);
                        }
                    }
                }
            }
        }
    }
}
