//! Seams: how much the prediction steps where the kd-tree cuts an object, against how much
//! the reference steps across the same pixels.
//!
//! FLIP averages a seam away over the image; an eye does not. For every cut of every object's
//! direct and indirect tree, the pixel pairs that straddle it (neighbours in a row or a column
//! whose surface points lie on the same face, inside the cut's node, on the two sides of the
//! plane) give the mean signed step across the cut, in display levels (0-255) of luminance,
//! of the prediction and of the reference. A continuous prediction steps like the reference,
//! by the light's own gradient over one pixel; a seam adds the leaves' disagreement to every
//! pair.

use rrf_baker::glam::{Vec2, Vec3};
use rrf_baker::model::Model;
use rrf_baker::network::Component;
use rrf_baker::partition::Region;
use rrf_baker::scene::Scene;
use rrf_baker::trace::{Camera, Geometry, World};
use serde::Serialize;

use super::configs::EvalConfig;

/// One kd-tree cut seen in a configuration.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Seam {
    pub object: String,
    pub component: Component,
    /// The cut: `x`, `y` or `z` and where, as in the model's tensor names (`y<0.165`).
    pub cut: String,
    /// Pixel pairs across it.
    pub pairs: usize,
    /// Mean signed step of the prediction's luminance from the cut's low side to its high
    /// side, in display levels.
    pub predicted_step: f64,
    /// The same for the reference, and its standard error (the reference's noise).
    pub reference_step: f64,
    pub reference_noise: f64,
}

impl Seam {
    /// By how much the prediction's step exceeds the reference's, in levels.
    pub fn excess(&self) -> f64 {
        self.predicted_step.abs() - self.reference_step.abs()
    }
}

/// Pairs across a cut fewer than this are too few to tell a step from noise; not reported.
const MIN_PAIRS: usize = 8;

/// The primary hit through each pixel centre: object id and position; `None` for the
/// background. The rays of the centre-footprint references and the renderer's G-buffer.
pub fn pixel_hits(scene: &Scene, geometry: &Geometry, config: &EvalConfig, (w, h): (u32, u32)) -> Vec<Option<Hit>> {
    let world = World::new(scene, geometry, Some(config.light));
    let camera = Camera::new(&config.view, w as f32 / h as f32);
    let size = Vec2::new(w as f32, h as f32);
    (0..w * h)
        .map(|i| {
            let film = (Vec2::new((i % w) as f32, (i / w) as f32) + 0.5) / size;
            let dir = camera.direction(film);
            let hit = world.intersect(camera.eye, dir)?;
            let si = world.interaction(camera.eye, dir, hit);
            Some(Hit { object: si.object, position: si.position, normal: si.geometric_normal })
        })
        .collect()
}

/// A pixel's surface point.
#[derive(Clone, Copy, Debug)]
pub struct Hit {
    pub object: u32,
    pub position: Vec3,
    pub normal: Vec3,
}

/// Every cut of the trees of `components` with enough pixel pairs in a configuration, given
/// its pixel `hits` and the predicted and reference images in display RGB8 (`width` ×
/// `height`), and a mask of the pixels of every pair (to draw the cuts).
pub fn seams(
    scene: &Scene,
    model: &Model,
    components: &[Component],
    hits: &[Option<Hit>],
    predicted: &[u8],
    reference: &[u8],
    (w, h): (u32, u32),
) -> (Vec<Seam>, Vec<bool>) {
    let luminance = |rgb: &[u8], i: usize| {
        0.2126 * f64::from(rgb[3 * i]) + 0.7152 * f64::from(rgb[3 * i + 1]) + 0.0722 * f64::from(rgb[3 * i + 2])
    };
    let mut mask = vec![false; hits.len()];
    let mut out = Vec::new();
    for object in &scene.objects {
        let bounds = object.bounds();
        let extent = (bounds.max - bounds.min).max_element();
        for &component in components {
            for (node, axis, at) in
                cuts(&model.networks(&object.name, component).iter().map(|n| &n.region).collect::<Vec<_>>())
            {
                let (mut predicted_steps, mut reference_steps) = (Vec::new(), Vec::new());
                for y in 0..h {
                    for x in 0..w {
                        let i = (y * w + x) as usize;
                        let neighbours = [(x + 1 < w).then_some(i + 1), (y + 1 < h).then_some(i + w as usize)];
                        for j in neighbours.into_iter().flatten() {
                            let (Some(a), Some(b)) = (hits[i], hits[j]) else { continue };
                            let same_face = a.object == object.id
                                && b.object == object.id
                                && a.normal.dot(b.normal) > 0.99
                                && a.position.distance(b.position) < 0.05 * extent;
                            if !same_face || !node.contains(a.position) || !node.contains(b.position) {
                                continue;
                            }
                            let (low, high) = match (a.position[axis] < at, b.position[axis] < at) {
                                (true, false) => (i, j),
                                (false, true) => (j, i),
                                _ => continue,
                            };
                            predicted_steps.push(luminance(predicted, high) - luminance(predicted, low));
                            reference_steps.push(luminance(reference, high) - luminance(reference, low));
                            mask[i] = true;
                            mask[j] = true;
                        }
                    }
                }
                if predicted_steps.len() < MIN_PAIRS {
                    continue;
                }
                let (reference_step, reference_noise) = mean_and_error(&reference_steps);
                out.push(Seam {
                    object: object.name.clone(),
                    component,
                    cut: format!("{}={at}", ["x", "y", "z"][axis]),
                    pairs: predicted_steps.len(),
                    predicted_step: mean_and_error(&predicted_steps).0,
                    reference_step,
                    reference_noise,
                });
            }
        }
    }
    (out, mask)
}

/// The cuts of the kd-tree whose leaves are `leaves`: each inner node's region, and its
/// split's axis and position.
fn cuts(leaves: &[&Region]) -> Vec<(Region, usize, f32)> {
    let mut out: Vec<(Region, usize, f32)> = Vec::new();
    for leaf in leaves {
        for depth in 0..leaf.0.len() {
            let node = Region(leaf.0[..depth].to_vec());
            let split = leaf.0[depth];
            if !out.iter().any(|(n, _, _)| *n == node) {
                out.push((node, split.axis as usize, split.at));
            }
        }
    }
    out
}

/// The mean of `values` and its standard error.
fn mean_and_error(values: &[f64]) -> (f64, f64) {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let variance = values.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / (n - 1.0).max(1.0);
    (mean, (variance / n).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mean_and_error_of_a_small_sample() {
        let (mean, error) = mean_and_error(&[1.0, 2.0, 3.0, 6.0]);
        assert_eq!(mean, 3.0);
        // Sample variance (4 + 1 + 0 + 9) / 3 = 14/3; its standard error sqrt(14/3 / 4).
        assert!((error - (14.0f64 / 12.0).sqrt()).abs() < 1e-12);
    }

    #[test]
    fn cuts_are_the_inner_nodes_of_the_tree() {
        let root = Region::default();
        let (low, high) = (root.child(0, 0.5, true), root.child(0, 0.5, false));
        let (a, b) = (high.child(2, 0.25, true), high.child(2, 0.25, false));
        let cuts = cuts(&[&low, &a, &b]);
        assert_eq!(cuts, vec![(root, 0, 0.5), (high, 2, 0.25)]);
    }
}
