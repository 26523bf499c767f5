//! Held-out evaluation configurations: a Latin hypercube over the light box and the camera
//! box, on a random stream that baking never draws from, plus the sidecar's named views with
//! held-out light positions.

use anyhow::{bail, Result};
use rrf_baker::bake::samples::latin_hypercube;
use rrf_baker::glam::Vec3;
use rrf_baker::scene::{Scene, View};
use rrf_baker::trace::sampling::{mix64, Rng};
use rrf_baker::trace::Geometry;

/// Mixed into the seed: bakes draw their configurations with `latin_hypercube(.., seed)`
/// directly, so eval's hypercube differs from every bake's, whatever the two seeds.
const EVAL_TAG: u64 = 0x6576_616c_2d72_7266;
/// A random camera is redrawn while the surface its centre ray hits is nearer than this
/// fraction of the scene's diagonal, so that it looks into the scene, not at a wall.
const MIN_DEPTH: f32 = 0.2;
const TRIES: u32 = 64;

#[derive(Clone, Debug)]
pub struct EvalConfig {
    /// `view-NAME` for the sidecar's named views, `random-N` for the hypercube's.
    pub name: String,
    pub view: View,
    pub light: Vec3,
}

/// `random` hypercube configurations after one per named view, all with held-out lights.
pub fn held_out(scene: &Scene, geometry: &Geometry, random: usize, seed: u64) -> Result<Vec<EvalConfig>> {
    let (Some(light), Some(camera_box)) = (&scene.moving_light, &scene.camera_box) else {
        bail!(
            "{}: eval needs the sidecar's light box and camera box (moving_light, camera_box)",
            scene.sidecar_path.as_ref().unwrap_or(&scene.gltf_path).display()
        );
    };
    let first_view = &scene.views[0];
    let named = scene.views.len();
    let stream = mix64(seed ^ EVAL_TAG);
    let lhs = latin_hypercube(named + random, &light.bounds, camera_box, stream);
    let mut configs: Vec<EvalConfig> = scene
        .views
        .iter()
        .zip(&lhs)
        .map(|(view, c)| EvalConfig { name: format!("view-{}", view.name), view: view.clone(), light: c.light })
        .collect();

    let bounds = scene.bounds();
    let (centre, extent) = ((bounds.min + bounds.max) * 0.5, bounds.max - bounds.min);
    let diagonal = extent.length();
    let mut rng = Rng::new(stream, 0x7461_7267);
    for (i, c) in lhs[named..].iter().enumerate() {
        let eye = c.viewpoint;
        // A target in the middle half of the scene's bounds, where its objects are.
        let mut target = centre;
        for _ in 0..TRIES {
            let jitter = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) - 0.5;
            let candidate = centre + jitter * extent * 0.5;
            let dir = (candidate - eye).normalize_or_zero();
            // Alpha masks count as solid here: a view target need not see through foliage.
            let solid = |_| true;
            let deep = dir != Vec3::ZERO
                && geometry
                    .intersect(eye, dir, f32::INFINITY, &[], &solid)
                    .is_none_or(|hit| hit.t >= MIN_DEPTH * diagonal);
            if deep {
                target = candidate;
                break;
            }
        }
        let view = View { name: format!("random-{i}"), eye, target, ..first_view.clone() };
        configs.push(EvalConfig { name: view.name.clone(), view, light: c.light });
    }
    Ok(configs)
}
