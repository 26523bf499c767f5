//! The glTF's buffers and images, loaded one by one so that every failure names the element
//! and the file, and no URI reads outside the scene folder.
//!
//! A URI is either a `data:` URI or a relative path (percent-encoded, as glTF says) to a file
//! in the scene folder or below it. Absolute paths, `file:` URIs, other schemes and paths with
//! `..` are refused: a scene must not read files its author did not ship with it.

use std::path::{Component, Path, PathBuf};

use gltf::buffer::Data as BufferData;
use gltf::image::Data as ImageData;

use super::error::{element_name, SceneError};

/// Largest texture side, in texels (what every Vulkan device supports for 2D images).
pub const MAX_TEXTURE_SIDE: u32 = 16384;

/// Where a URI points.
enum Target {
    Embedded,
    File(PathBuf),
}

/// Checks a URI and resolves it against the scene folder `base`.
fn resolve(uri: &str, base: &Path) -> Result<Target, String> {
    if uri.starts_with("data:") {
        return Ok(Target::Embedded);
    }
    if uri.contains(':') {
        return Err(format!("URI {uri:?}: only data: URIs and relative paths inside the scene folder are read"));
    }
    let path = percent_decode(uri).ok_or_else(|| format!("URI {uri:?} has a malformed %-escape"))?;
    let path = Path::new(&path);
    if !path.components().all(|c| matches!(c, Component::Normal(_) | Component::CurDir)) {
        return Err(format!("URI {uri:?} points outside the scene folder; copy the file beside the glTF"));
    }
    Ok(Target::File(base.join(path)))
}

/// Percent-decodes `uri`; `None` for a malformed escape or bytes that are not UTF-8.
fn percent_decode(uri: &str) -> Option<String> {
    let bytes = uri.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = std::str::from_utf8(bytes.get(i + 1..i + 3)?).ok()?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    String::from_utf8(out).ok()
}

/// Loads every buffer, the GLB's binary chunk for the one without a URI.
pub fn load_buffers(
    file: &Path,
    document: &gltf::Document,
    base: &Path,
    mut blob: Option<Vec<u8>>,
) -> Result<Vec<BufferData>, SceneError> {
    let mut buffers = Vec::new();
    for buffer in document.buffers() {
        let element = element_name("buffers", buffer.index(), buffer.name());
        let err = |problem: String| SceneError::new(file, &element, problem);
        if let gltf::buffer::Source::Uri(uri) = buffer.source() {
            if let Target::File(path) = resolve(uri, base).map_err(err)? {
                if !path.is_file() {
                    return Err(err(format!("file {uri:?} not found beside the glTF")));
                }
            }
        }
        let data = BufferData::from_source_and_blob(buffer.source(), Some(base), &mut blob)
            .map_err(|e| err(format!("cannot load: {e}")))?;
        if data.len() < buffer.length() {
            return Err(err(format!("holds {} bytes but byteLength says {}", data.len(), buffer.length())));
        }
        buffers.push(data);
    }
    Ok(buffers)
}

/// Loads and decodes every image.
pub fn load_images(
    file: &Path,
    document: &gltf::Document,
    base: &Path,
    buffers: &[BufferData],
) -> Result<Vec<ImageData>, SceneError> {
    let mut images = Vec::new();
    for image in document.images() {
        let element = element_name("images", image.index(), image.name());
        let err = |problem: String| SceneError::new(file, &element, problem);
        let source = match image.source() {
            gltf::image::Source::Uri { uri, .. } => {
                if let Target::File(path) = resolve(uri, base).map_err(err)? {
                    if !path.is_file() {
                        return Err(err(format!("file {uri:?} not found beside the glTF")));
                    }
                }
                format!(" ({uri:?})")
            }
            gltf::image::Source::View { view, .. } => {
                let buffer_len = buffers[view.buffer().index()].len();
                if view.offset().checked_add(view.length()).is_none_or(|end| end > buffer_len) {
                    return Err(err(format!(
                        "bufferViews[{}] reaches past the end of buffers[{}] ({buffer_len} bytes)",
                        view.index(),
                        view.buffer().index()
                    )));
                }
                String::new()
            }
        };
        let data = ImageData::from_source(image.source(), Some(base), buffers)
            .map_err(|e| err(format!("cannot decode{source}: {e}")))?;
        if data.width == 0 || data.height == 0 || data.width.max(data.height) > MAX_TEXTURE_SIDE {
            return Err(err(format!(
                "is {}×{} texels{source}; textures must be between 1 and {MAX_TEXTURE_SIDE} texels a side",
                data.width, data.height
            )));
        }
        images.push(data);
    }
    Ok(images)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percent_escapes() {
        assert_eq!(percent_decode("a%20b.bin").as_deref(), Some("a b.bin"));
        assert_eq!(percent_decode("%E2%82%AC").as_deref(), Some("€"));
        assert_eq!(percent_decode("bad%FF"), None);
        assert_eq!(percent_decode("cut%2"), None);
        assert_eq!(percent_decode("%zz"), None);
    }

    #[test]
    fn uris_stay_in_the_scene_folder() {
        let base = Path::new("/scenes/a");
        assert!(
            matches!(resolve("textures/wood.png", base), Ok(Target::File(p)) if p == base.join("textures/wood.png"))
        );
        assert!(matches!(resolve("data:application/octet-stream;base64,AAAA", base), Ok(Target::Embedded)));
        for bad in ["../b/scene.bin", "/etc/passwd", "file:///etc/passwd", "https://x.org/a.bin", "a/%2E%2E/../x"] {
            assert!(resolve(bad, base).is_err(), "{bad}");
        }
    }
}
