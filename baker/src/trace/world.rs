//! One light configuration of a scene: the geometry with the moving light in place, the
//! emitters to sample, and surface interactions at hits.

use glam::{Vec2, Vec3};
use obvhs::rt_triangle::RtTriangle;

use super::bsdf::Bsdf;
use super::geometry::{Geometry, Hit};
use super::sampling::uniform_triangle;
use crate::scene::{Cone, LightKind, Scene};

/// An emissive triangle where this configuration puts it, with the probability of choosing
/// it for next-event estimation.
#[derive(Clone, Copy, Debug)]
struct Emitter {
    corners: [Vec3; 3],
    normal: Vec3,
    emission: Vec3,
    double_sided: bool,
    area: f32,
    /// Probability of choosing this emitter, proportional to its power.
    probability: f32,
}

/// A point light at its position for this configuration.
#[derive(Clone, Copy, Debug)]
pub struct PointLightAt {
    pub position: Vec3,
    /// Radiant intensity, W/sr (on a spot light's axis).
    pub intensity: Vec3,
    pub cone: Option<Cone>,
}

pub struct World<'a> {
    pub scene: &'a Scene,
    pub geometry: &'a Geometry,
    /// How far the moving light is from where the glTF puts it.
    pub light_offset: Vec3,
    moved: Vec<(u32, RtTriangle)>,
    emitters: Vec<Emitter>,
    /// Cumulative emitter probabilities, for sampling by binary search.
    emitter_cdf: Vec<f32>,
    /// Emitter index by triangle id, for the MIS weight of a BSDF-sampled hit.
    emitter_of_triangle: Vec<u32>,
    pub point_lights: Vec<PointLightAt>,
}

/// Everything the integrator needs about the surface at a hit.
pub struct Interaction {
    pub position: Vec3,
    /// Geometric normal, facing the side the ray came from.
    pub geometric_normal: Vec3,
    /// Shading normal, on the same side as `geometric_normal`.
    pub shading_normal: Vec3,
    /// Whether the ray hit the front face (the side the winding faces).
    pub front_face: bool,
    pub bsdf: Bsdf,
    /// Emitted radiance towards the ray's origin.
    pub emission: Vec3,
    pub object: u32,
    pub uv: Vec2,
    pub roughness: f32,
}

/// A point sampled on an emitter for next-event estimation.
pub struct LightSample {
    pub direction: Vec3,
    pub distance: f32,
    /// Emitted radiance (area light) or intensity / distance² (point light) arriving.
    pub radiance: Vec3,
    /// Solid-angle density of the sample; `None` for point lights (a delta).
    pub pdf: Option<f32>,
}

const NO_EMITTER: u32 = u32::MAX;

impl<'a> World<'a> {
    /// The scene with its moving light at `light_position` (or where the glTF puts it).
    pub fn new(scene: &'a Scene, geometry: &'a Geometry, light_position: Option<Vec3>) -> Self {
        let moving = scene.moving_light.as_ref();
        let light_offset = match (moving, light_position) {
            (Some(light), Some(p)) => p - light.default_position,
            _ => Vec3::ZERO,
        };
        let mut point_lights: Vec<PointLightAt> = scene
            .point_lights
            .iter()
            .map(|l| PointLightAt { position: l.position, intensity: l.intensity, cone: l.cone })
            .collect();
        if let Some(LightKind::Point(i)) = moving.map(|l| l.kind) {
            point_lights[i].position += light_offset;
        }

        let mut emitters = Vec::new();
        let mut emitter_of_triangle = vec![NO_EMITTER; geometry.triangles.len()];
        let mut total = 0.0;
        for (id, info) in geometry.triangles.iter().enumerate() {
            let emission = scene.materials[info.material as usize].emission;
            if emission.max_element() <= 0.0 {
                continue;
            }
            let corners = geometry.corners(id as u32, light_offset);
            let [a, b, c] = corners;
            let cross = (b - a).cross(c - a);
            let area = 0.5 * cross.length();
            if area <= 0.0 {
                continue;
            }
            let power = luminance(emission) * area;
            emitter_of_triangle[id] = emitters.len() as u32;
            emitters.push(Emitter {
                corners,
                normal: cross.normalize(),
                emission,
                double_sided: scene.materials[info.material as usize].double_sided,
                area,
                probability: power,
            });
            total += power;
        }
        let mut cdf = Vec::with_capacity(emitters.len());
        let mut running = 0.0;
        for e in &mut emitters {
            e.probability /= total;
            running += e.probability;
            cdf.push(running);
        }
        World {
            scene,
            geometry,
            light_offset,
            moved: geometry.moved_triangles(light_offset),
            emitters,
            emitter_cdf: cdf,
            emitter_of_triangle,
            point_lights,
        }
    }

    pub fn intersect(&self, origin: Vec3, dir: Vec3) -> Option<Hit> {
        self.geometry.intersect(origin, dir, f32::INFINITY, &self.moved)
    }

    pub fn occluded(&self, origin: Vec3, dir: Vec3, distance: f32) -> bool {
        self.geometry.occluded(origin, dir, distance, &self.moved)
    }

    pub fn has_area_lights(&self) -> bool {
        !self.emitters.is_empty()
    }

    /// The surface at `hit` seen along `dir`.
    pub fn interaction(&self, origin: Vec3, dir: Vec3, hit: Hit) -> Interaction {
        let g = self.geometry;
        let info = g.triangles[hit.triangle as usize];
        let [p0, p1, p2] = g.corners(hit.triangle, self.light_offset);
        let p = origin + dir * hit.t;
        // Barycentric coordinates of p.
        let (e1, e2, ep) = (p1 - p0, p2 - p0, p - p0);
        let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
        let (dp1, dp2) = (ep.dot(e1), ep.dot(e2));
        let denom = d11 * d22 - d12 * d12;
        let (b1, b2) = if denom > 0.0 {
            (((d22 * dp1 - d12 * dp2) / denom).clamp(0.0, 1.0), ((d11 * dp2 - d12 * dp1) / denom).clamp(0.0, 1.0))
        } else {
            (0.0, 0.0)
        };
        let b0 = (1.0 - b1 - b2).max(0.0);
        let [i0, i1, i2] = info.vertices.map(|v| v as usize);
        let position = p0 * b0 + p1 * b1 + p2 * b2;
        let uv = g.uvs[i0] * b0 + g.uvs[i1] * b1 + g.uvs[i2] * b2;
        let mut ng = e1.cross(e2).normalize_or(Vec3::Z);
        let mut ns = (g.normals[i0] * b0 + g.normals[i1] * b1 + g.normals[i2] * b2).normalize_or(ng);
        let front_face = ng.dot(dir) < 0.0;
        if !front_face {
            ng = -ng;
        }
        if ns.dot(ng) < 0.0 {
            ns = -ns;
        }

        let material = &self.scene.materials[info.material as usize];
        let mut base = material.base_color;
        if let Some(t) = material.base_color_texture {
            base *= self.scene.textures[t as usize].sample(uv).truncate();
        }
        let (mut metallic, mut roughness) = (material.metallic, material.roughness);
        if let Some(t) = material.metallic_roughness_texture {
            let mr = self.scene.textures[t as usize].sample(uv);
            roughness *= mr.y;
            metallic *= mr.z;
        }
        let emits = front_face || material.double_sided;
        Interaction {
            position,
            geometric_normal: ng,
            shading_normal: ns,
            front_face,
            bsdf: Bsdf::new(base, metallic, roughness, material.specular),
            emission: if emits { material.emission } else { Vec3::ZERO },
            object: info.object,
            uv,
            roughness,
        }
    }

    /// Samples a point on an emissive triangle, chosen in proportion to power, as seen from
    /// `from`; `None` when the scene has no area lights or the point faces away.
    pub fn sample_area_light(&self, from: Vec3, u_pick: f32, u: Vec2) -> Option<LightSample> {
        if self.emitters.is_empty() {
            return None;
        }
        let index = self.emitter_cdf.partition_point(|&c| c <= u_pick).min(self.emitters.len() - 1);
        let e = &self.emitters[index];
        let [a, b, c] = e.corners;
        let bary = uniform_triangle(u);
        let point = a * (1.0 - bary.x - bary.y) + b * bary.x + c * bary.y;
        let to_light = point - from;
        let distance2 = to_light.length_squared();
        let distance = distance2.sqrt();
        let direction = to_light / distance;
        let cos_light = -e.normal.dot(direction);
        if cos_light <= 0.0 && !e.double_sided {
            return None;
        }
        let pdf = e.probability / e.area * distance2 / cos_light.abs();
        Some(LightSample { direction, distance, radiance: e.emission, pdf: Some(pdf) })
    }

    /// Solid-angle density with which [`World::sample_area_light`] would have produced the
    /// point at distance `t` along direction `dir` on emissive triangle `triangle`.
    pub fn area_light_pdf(&self, triangle: u32, dir: Vec3, t: f32) -> f32 {
        let index = self.emitter_of_triangle[triangle as usize];
        if index == NO_EMITTER {
            return 0.0;
        }
        let e = &self.emitters[index as usize];
        let cos_light = e.normal.dot(dir).abs();
        if cos_light <= 0.0 {
            return 0.0;
        }
        e.probability / e.area * t * t / cos_light
    }
}

pub fn luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.2126, 0.7152, 0.0722))
}
