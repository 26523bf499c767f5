//! Writing images: linear HDR as OpenEXR, display-referred as 8-bit sRGB PNG through the
//! same tonemap the GPU uses.

use std::path::Path;

use anyhow::{bail, Context, Result};
use rrf_baker::glam::Vec3;
use rrf_renderer::tonemap::tonemap;

/// Writes `pixels` (rows top to bottom, linear RGB) to `path`: EXR for `.exr`, tonemapped
/// PNG for `.png`, with `exposure` in stops for the PNG.
pub fn write_image(path: &Path, width: u32, height: u32, pixels: &[Vec3], exposure: f32) -> Result<()> {
    match path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() {
        Some("exr") => {
            exr::prelude::write_rgb_file(path, width as usize, height as usize, |x, y| {
                let p = pixels[y * width as usize + x];
                (p.x, p.y, p.z)
            })
            .with_context(|| format!("cannot write {}", path.display()))?;
        }
        Some("png") => {
            image::RgbImage::from_raw(width, height, tonemap_rgb8(pixels, exposure))
                .context("image size does not match its pixels")?
                .save(path)
                .with_context(|| format!("cannot write {}", path.display()))?;
        }
        _ => bail!("{}: the output must end in .exr (linear HDR) or .png (tonemapped)", path.display()),
    }
    Ok(())
}

/// Linear radiance to display sRGB, 8 bits per channel, RGB rows: what a PNG of the pixels
/// shows (exposure in stops, ACES, sRGB; the tonemap pass's CPU twin).
pub fn tonemap_rgb8(pixels: &[Vec3], exposure: f32) -> Vec<u8> {
    let scale = exposure.exp2();
    pixels.iter().flat_map(|p| tonemap(p.to_array(), scale).map(|c| (c * 255.0 + 0.5) as u8)).collect()
}
