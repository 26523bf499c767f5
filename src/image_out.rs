//! Writing images: linear HDR as OpenEXR, display-referred as 8-bit sRGB PNG through the
//! same tonemap the GPU uses.

use std::path::Path;

use anyhow::{bail, Context, Result};
use rrf_baker::atomic_file::write_atomically;
use rrf_baker::glam::Vec3;
use rrf_renderer::passes::tonemap::tonemap;

/// What an image output path holds, by its extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageKind {
    Exr,
    Png,
}

/// Checks an output path before any work starts: a `.exr` or `.png` name in a folder that
/// exists.
pub fn check_output(path: &Path) -> Result<ImageKind> {
    let kind = match path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() {
        Some("exr") => ImageKind::Exr,
        Some("png") => ImageKind::Png,
        _ => bail!("{}: the output must end in .exr (linear HDR) or .png (tonemapped)", path.display()),
    };
    let folder = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    if !folder.is_dir() {
        bail!("{}: the folder {} does not exist", path.display(), folder.display());
    }
    Ok(kind)
}

/// Writes `pixels` (rows top to bottom, linear RGB) to `path`: EXR for `.exr`, tonemapped
/// PNG for `.png`, with `exposure` in stops for the PNG. The image goes to a temporary file
/// beside `path` that is then renamed, so a failed or interrupted write never leaves a
/// half-written image where a good one was.
pub fn write_image(path: &Path, width: u32, height: u32, pixels: &[Vec3], exposure: f32) -> Result<()> {
    let kind = check_output(path)?;
    write_atomically(path, |tmp| write_kind(kind, tmp, width, height, pixels, exposure))
}

fn write_kind(kind: ImageKind, path: &Path, width: u32, height: u32, pixels: &[Vec3], exposure: f32) -> Result<()> {
    match kind {
        ImageKind::Exr => {
            use exr::prelude::{Encoding, Image, LineOrder, SpecificChannels, Vec2, WritableImage};
            let channels = SpecificChannels::rgb(|Vec2(x, y): Vec2<usize>| {
                let p = pixels[y * width as usize + x];
                (p.x, p.y, p.z)
            });
            // Chunks in a fixed order: compressed in parallel with no order asked for, they
            // land as they finish, and the same pixels could make different bytes.
            let encoding = Encoding { line_order: LineOrder::Increasing, ..Encoding::FAST_LOSSLESS };
            Image::from_encoded_channels((width as usize, height as usize), encoding, channels)
                .write()
                .to_file(path)
                .with_context(|| format!("cannot write {}", path.display()))?;
        }
        ImageKind::Png => {
            image::RgbImage::from_raw(width, height, tonemap_rgb8(pixels, exposure))
                .context("image size does not match its pixels")?
                .save(path)
                .with_context(|| format!("cannot write {}", path.display()))?;
        }
    }
    Ok(())
}

/// Linear radiance to display sRGB, 8 bits per channel, RGB rows: what a PNG of the pixels
/// shows (exposure in stops, ACES, sRGB; the tonemap pass's CPU twin).
pub fn tonemap_rgb8(pixels: &[Vec3], exposure: f32) -> Vec<u8> {
    let scale = exposure.exp2();
    pixels.iter().flat_map(|p| tonemap(p.to_array(), scale).map(|c| (c * 255.0 + 0.5) as u8)).collect()
}
