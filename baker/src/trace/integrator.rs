//! Path tracing with next-event estimation and multiple importance sampling, keeping the
//! light that reaches a surface point apart by how it got there.
//!
//! For the first surface point x seen along a ray, with paths counted in segments from the
//! viewer (Mitsuba's `max_depth` convention):
//! - **emitted**: x's own emission (1 segment);
//! - **direct**: light that left a light source and reached x with no other bounce (2
//!   segments: next-event estimation at x, and BSDF-sampled rays from x that hit an emitter);
//! - **indirect**: everything else (3 segments or more).
//!
//! The three are disjoint sets of path contributions of one estimator, so they sum to the
//! full radiance of the same paths.

use std::sync::atomic::{AtomicU64, Ordering};

use glam::Vec3;

use super::bsdf::SeenFrom;
use super::sampling::{Frame, Rng};
use super::stratified::VertexSamples;
use super::world::{Interaction, World};

#[derive(Clone, Copy, Debug)]
pub struct TraceSettings {
    /// Longest path in segments from the viewer: 1 shows emitters only, 2 adds direct light.
    pub max_depth: u32,
    /// Russian roulette from this many segments on; `None` turns it off (exact expectations
    /// for tests).
    pub rr_depth: Option<u32>,
}

impl Default for TraceSettings {
    fn default() -> Self {
        TraceSettings { max_depth: 8, rr_depth: Some(5) }
    }
}

/// Radiance leaving a surface point, by component.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Radiance {
    pub emitted: Vec3,
    pub direct: Vec3,
    pub indirect: Vec3,
}

/// Contributions dropped because they were not finite (a degenerate BSDF sample or light
/// sample), counted over the whole process: a bake reports how many its paths dropped.
static NON_FINITE_DROPPED: AtomicU64 = AtomicU64::new(0);

/// How many path contributions this process has dropped as non-finite so far.
pub fn non_finite_dropped() -> u64 {
    NON_FINITE_DROPPED.load(Ordering::Relaxed)
}

impl Radiance {
    pub fn gi(&self) -> Vec3 {
        self.emitted + self.direct + self.indirect
    }

    fn add(&mut self, segments: u32, value: Vec3) {
        if !value.is_finite() {
            NON_FINITE_DROPPED.fetch_add(1, Ordering::Relaxed);
            return;
        }
        match segments {
            0 | 1 => self.emitted += value,
            2 => self.direct += value,
            _ => self.indirect += value,
        }
    }

    pub fn scaled(self, s: f32) -> Self {
        Radiance { emitted: self.emitted * s, direct: self.direct * s, indirect: self.indirect * s }
    }
}

impl std::ops::AddAssign for Radiance {
    fn add_assign(&mut self, o: Self) {
        self.emitted += o.emitted;
        self.direct += o.direct;
        self.indirect += o.indirect;
    }
}

/// Power heuristic (β = 2) weight of a strategy with density `a` against one with `b`.
fn power_heuristic(a: f32, b: f32) -> f32 {
    let (a2, b2) = (a * a, b * b);
    if a2 + b2 > 0.0 {
        a2 / (a2 + b2)
    } else {
        0.0
    }
}

/// A ray origin just off the surface on the side that `dir` leaves towards.
pub fn offset_origin(si: &Interaction, dir: Vec3) -> Vec3 {
    let eps = 1e-4 * (1.0 + si.position.abs().max_element());
    let side = if dir.dot(si.geometric_normal) >= 0.0 { 1.0 } else { -1.0 };
    si.position + si.geometric_normal * (eps * side)
}

/// The light of the world's point lights that leaves `si` towards the direction `bsdf` is
/// seen from (`si`'s BSDF, in `frame`, the shading frame) after one bounce: next-event
/// estimation of every point light, which has no noise (a delta), with a shadow ray each. The
/// analytic direct light of `predict::predict_image` is this at the primary hit.
pub fn point_lights_at(world: &World, si: &Interaction, frame: &Frame, bsdf: &SeenFrom) -> Vec3 {
    let mut sum = Vec3::ZERO;
    for light in &world.point_lights {
        let to_light = light.position - si.position;
        let distance2 = to_light.length_squared();
        let distance = distance2.sqrt();
        let direction = to_light / distance;
        let spot = light.cone.map_or(1.0, |cone| cone.attenuation(-direction));
        if direction.dot(si.geometric_normal) <= 0.0 || spot == 0.0 {
            continue;
        }
        let wi = frame.to_local(direction);
        let f = bsdf.eval(wi);
        if f == Vec3::ZERO {
            continue;
        }
        let origin = offset_origin(si, direction);
        if !world.occluded(origin, direction, distance * (1.0 - 1e-4)) {
            sum += f * light.intensity * (spot * wi.z / distance2);
        }
    }
    sum
}

/// Radiance along a camera ray: emitted, direct and indirect at its first hit.
pub fn trace_ray(world: &World, origin: Vec3, dir: Vec3, settings: &TraceSettings, rng: &mut Rng) -> Radiance {
    match world.intersect(origin, dir) {
        Some(hit) => {
            let si = world.interaction(origin, dir, hit);
            radiance_leaving(world, &FirstVertex::new(world, &si, -dir, settings), None, settings, rng)
        }
        None => Radiance::default(),
    }
}

/// A path vertex's shading frame and its BSDF seen from the direction the path leaves it in.
#[derive(Clone, Copy)]
struct Vertex {
    frame: Frame,
    bsdf: SeenFrom,
}

impl Vertex {
    fn new(si: &Interaction, wo: Vec3) -> Self {
        let frame = Frame::new(si.shading_normal);
        Vertex { frame, bsdf: si.bsdf.seen_from(frame.to_local(wo)) }
    }
}

/// The first surface point of paths that leave it towards `wo` (unit, pointing away from the
/// surface), with what all of them share: its [`Vertex`] and the light its point lights send
/// towards `wo`, which has no noise. A bake's sample traces hundreds of paths from one point;
/// each would otherwise trace the same shadow rays to the point lights.
pub struct FirstVertex<'a> {
    si: &'a Interaction,
    vertex: Vertex,
    point_lights: Vec3,
}

impl<'a> FirstVertex<'a> {
    pub fn new(world: &World, si: &'a Interaction, wo: Vec3, settings: &TraceSettings) -> Self {
        let vertex = Vertex::new(si, wo);
        // No shadow rays where no path reaches a second segment.
        let point_lights = match settings.max_depth > 1 {
            true => point_lights_at(world, si, &vertex.frame, &vertex.bsdf),
            false => Vec3::ZERO,
        };
        FirstVertex { si, vertex, point_lights }
    }
}

/// One path-traced estimate of the radiance leaving `first` towards its `wo`. The path's
/// decisions at `first` take `first_samples` where given (a stratified set's,
/// [`super::stratified`]), and every other one numbers from `rng`.
pub fn radiance_leaving(
    world: &World,
    first: &FirstVertex,
    first_samples: Option<&VertexSamples>,
    settings: &TraceSettings,
    rng: &mut Rng,
) -> Radiance {
    let mut out = Radiance::default();
    if settings.max_depth >= 1 {
        out.emitted = first.si.emission;
    }
    let mut beta = Vec3::ONE;
    let mut segments = 1;
    // The vertex the path has reached, and the direction it leaves it in; `None` at `first`.
    let mut current: Option<(Interaction, Vec3)> = None;
    while segments < settings.max_depth {
        let (si, Vertex { frame, bsdf }) = match &current {
            None => (first.si, first.vertex),
            Some((si, wo)) => (si, Vertex::new(si, *wo)),
        };
        let given = if current.is_none() { first_samples } else { None };
        if bsdf.wo().z <= 0.0 {
            break;
        }

        // Next-event estimation: a path one segment longer.
        if world.has_area_lights() {
            let (pick, u) = given.map_or_else(|| (rng.next_f32(), rng.next_vec2()), |v| (v.light_pick, v.light));
            if let Some(light) = world.sample_area_light(si.position, pick, u) {
                let wi = frame.to_local(light.direction);
                let (f, bsdf_pdf) = bsdf.eval_pdf(wi);
                if f != Vec3::ZERO && light.direction.dot(si.geometric_normal) > 0.0 {
                    let origin = offset_origin(si, light.direction);
                    if !world.occluded(origin, light.direction, light.distance * (1.0 - 1e-3)) {
                        let pdf = light.pdf.unwrap_or(1.0);
                        let weight = power_heuristic(pdf, bsdf_pdf);
                        out.add(segments + 1, beta * f * light.radiance * (wi.z * weight / pdf));
                    }
                }
            }
        }
        let point_lights = match current {
            None => first.point_lights,
            Some(_) => point_lights_at(world, si, &frame, &bsdf),
        };
        out.add(segments + 1, beta * point_lights);

        // Continue the path by sampling the BSDF.
        let (lobe, u) = given.map_or_else(|| (rng.next_f32(), rng.next_vec2()), |v| (v.lobe, v.direction));
        let Some(sample) = bsdf.sample(lobe, u) else {
            break;
        };
        let wi = frame.to_world(sample.wi);
        if wi.dot(si.geometric_normal) <= 0.0 {
            break;
        }
        beta *= sample.weight;
        let origin = offset_origin(si, wi);
        let Some(hit) = world.intersect(origin, wi) else {
            break;
        };
        let next = world.interaction(origin, wi, hit);
        segments += 1;
        if next.emission != Vec3::ZERO {
            let light_pdf = world.area_light_pdf(hit, wi);
            out.add(segments, beta * next.emission * power_heuristic(sample.pdf, light_pdf));
        }
        if let Some(rr_depth) = settings.rr_depth {
            if segments >= rr_depth {
                let survive = beta.max_element().min(0.95);
                if rng.next_f32() >= survive {
                    break;
                }
                beta /= survive;
            }
        }
        current = Some((next, -wi));
    }
    out
}
