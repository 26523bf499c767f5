//! What each fuzz target (`baker/fuzz/`) does with its input, shared with the test that
//! replays the seed corpus and every crash found so far (`baker/tests/fuzz_corpus.rs`).
//! Each function must return, whatever the bytes: a panic or an abort is the bug.

use std::path::Path;

use glam::Vec3;

use crate::model::Model;
use crate::scene::{Scene, Sidecar};
use crate::trace::{render, Camera, Footprint, Geometry, RenderSettings, TraceSettings, World};

/// The model loader.
pub fn model(data: &[u8]) {
    let _ = Model::from_bytes(data);
}

/// The sidecar parser and its checks.
pub fn sidecar(data: &[u8]) {
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = Sidecar::parse(Path::new("scene.toml"), text);
    }
}

/// glTF or GLB import with embedded buffers and images, then what every command does next
/// with a scene: the BVH, light sampling, and a tiny path-traced image from its camera.
pub fn gltf(data: &[u8]) {
    let Ok(scene) = Scene::from_gltf_bytes(Path::new("fuzz-input/scene.gltf"), data) else { return };
    let geometry = Geometry::new(&scene);
    let light = scene.point_lights.first().map(|l| l.position + Vec3::splat(0.01));
    let world = World::new(&scene, &geometry, light);
    if let Some(view) = scene.views.first() {
        let settings = RenderSettings {
            width: 4,
            height: 4,
            spp: 1,
            trace: TraceSettings { max_depth: 3, rr_depth: None },
            seed: 0,
            footprint: Footprint::Area,
        };
        render(&world, &Camera::new(view, 1.0), &settings, &|_| {});
    }
}
