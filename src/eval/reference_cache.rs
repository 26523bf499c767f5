//! Path-traced references by component, cached on disk under a key of the scene's light
//! transport (its content without the bake settings), the configuration and the render
//! settings, so that a second eval only renders what changed, and a re-bake with other
//! settings renders nothing.
//!
//! A file holds a header (magic, width, height) and per pixel nine little-endian f32s:
//! emitted, direct and indirect RGB.

use std::path::{Path, PathBuf};

use anyhow::{Context as _, Result};
use rrf_baker::glam::Vec3;
use rrf_baker::hash::Fnv64;
use rrf_baker::scene::Scene;
use rrf_baker::trace::render::{render, Footprint, RadianceImage, RenderSettings};
use rrf_baker::trace::{Camera, Geometry, Radiance, World};

use super::configs::EvalConfig;

const MAGIC: &[u8; 8] = b"RRFREF01";

/// Where a scene's cached references live by default: `.cache/references/` in its folder.
pub fn default_cache_dir(scene: &Scene) -> PathBuf {
    scene.gltf_path.parent().unwrap_or(Path::new(".")).join(".cache").join("references")
}

/// The cache key: everything the reference image depends on.
fn key(scene: &Scene, config: &EvalConfig, s: &RenderSettings) -> u64 {
    let mut h = Fnv64::default();
    h.write(MAGIC);
    h.write(&scene.light_transport_hash.to_le_bytes());
    let v = &config.view;
    for x in [v.eye, v.target, v.up, config.light].iter().flat_map(|p| p.to_array()).chain([v.fov_y]) {
        h.write(&x.to_le_bytes());
    }
    for x in [s.width, s.height, s.spp, s.trace.max_depth, s.trace.rr_depth.unwrap_or(0)] {
        h.write(&x.to_le_bytes());
    }
    h.write(&s.seed.to_le_bytes());
    // Area-footprint keys stay what they were before the footprint existed, so that the
    // references cached then are still found.
    if s.footprint == Footprint::Centre {
        h.write(b"centre");
    }
    h.0
}

/// The reference for `config`: from the cache in `dir`, or path-traced (reporting finished pixels to
/// `progress`) and then cached. Returns the image and whether it came from the cache.
pub fn reference(
    scene: &Scene,
    geometry: &Geometry,
    config: &EvalConfig,
    settings: &RenderSettings,
    dir: &Path,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<(RadianceImage, bool)> {
    let path = dir.join(format!("{:016x}.bin", key(scene, config, settings)));
    if let Ok(bytes) = std::fs::read(&path) {
        match decode(&bytes, settings.width, settings.height) {
            Some(image) => return Ok((image, true)),
            None => eprintln!("warning: {}: not a valid cached reference; rendering it again", path.display()),
        }
    }
    let world = World::new(scene, geometry, Some(config.light));
    let camera = Camera::new(&config.view, settings.width as f32 / settings.height as f32);
    let image = render(&world, &camera, settings, progress);
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    // Write, then rename: an interrupted eval never leaves a truncated file under the key.
    let partial = path.with_extension("partial");
    std::fs::write(&partial, encode(&image))
        .and_then(|()| std::fs::rename(&partial, &path))
        .with_context(|| format!("cannot write {}", path.display()))?;
    Ok((image, false))
}

fn encode(image: &RadianceImage) -> Vec<u8> {
    let mut out = Vec::with_capacity(16 + image.pixels.len() * 36);
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&image.width.to_le_bytes());
    out.extend_from_slice(&image.height.to_le_bytes());
    for r in &image.pixels {
        for c in [r.emitted, r.direct, r.indirect] {
            for x in c.to_array() {
                out.extend_from_slice(&x.to_le_bytes());
            }
        }
    }
    out
}

fn decode(bytes: &[u8], width: u32, height: u32) -> Option<RadianceImage> {
    let (header, body) = bytes.split_at_checked(16)?;
    if &header[..8] != MAGIC || header[8..12] != width.to_le_bytes() || header[12..16] != height.to_le_bytes() {
        return None;
    }
    if body.len() != width as usize * height as usize * 36 {
        return None;
    }
    let floats: Vec<f32> = body.chunks_exact(4).map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]])).collect();
    let pixels = floats
        .chunks_exact(9)
        .map(|p| Radiance {
            emitted: Vec3::new(p[0], p[1], p[2]),
            direct: Vec3::new(p[3], p[4], p[5]),
            indirect: Vec3::new(p[6], p[7], p[8]),
        })
        .collect();
    Some(RadianceImage { width, height, pixels })
}
