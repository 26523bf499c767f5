//! One light configuration of a scene: the geometry with the moving light in place (a copy of
//! it per light), the emitters to sample, and surface interactions at hits.

use glam::{Vec2, Vec3, Vec4};

use super::bsdf::Bsdf;
use super::geometry::{corner_values, Geometry, Hit, MovedTriangle};
use super::sampling::uniform_triangle;
use crate::scene::{Cone, LightKind, PlacedLight, Scene, TextureRef};

/// An emissive triangle where this configuration puts it, with the probability of choosing
/// it for next-event estimation.
#[derive(Clone, Copy, Debug)]
struct Emitter {
    corners: [Vec3; 3],
    uvs: [Vec2; 3],
    normal: Vec3,
    /// The material's emission, before `texture`.
    emission: Vec3,
    /// The emissive texture, looked up at each sampled point.
    texture: Option<TextureRef>,
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
    /// The configuration's lights: copies of the moving light, at least one.
    pub lights: Vec<PlacedLight>,
    /// How far each copy of the moving light is from where the glTF puts it.
    offsets: Vec<Vec3>,
    moved: Vec<MovedTriangle>,
    emitters: Vec<Emitter>,
    /// Cumulative emitter probabilities, for sampling by binary search.
    emitter_cdf: Vec<f32>,
    /// The emitter index of each of the geometry's emissive triangles (`Geometry::emissive`),
    /// for the MIS weight of a BSDF-sampled hit; a moving triangle's copies follow its first
    /// one.
    emitter_of_emissive: Vec<u32>,
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
        let default = scene.default_light();
        let position = light_position.unwrap_or(default.position);
        World::with_lights(scene, geometry, &[PlacedLight { position, ..default }])
    }

    /// The scene with a copy of its moving light for each of `lights` (at least one), in its
    /// place and scaled by its `scale`; the scene's other lights stay as they are.
    pub fn with_lights(scene: &'a Scene, geometry: &'a Geometry, lights: &[PlacedLight]) -> Self {
        assert!(!lights.is_empty(), "a configuration has at least one light");
        let moving = scene.moving_light.as_ref();
        let offsets: Vec<Vec3> =
            lights.iter().map(|l| moving.map_or(Vec3::ZERO, |m| l.position - m.default_position)).collect();
        let mut point_lights: Vec<PointLightAt> = scene
            .point_lights
            .iter()
            .map(|l| PointLightAt { position: l.position, intensity: l.intensity, cone: l.cone })
            .collect();
        if let Some(LightKind::Point(i)) = moving.map(|l| l.kind) {
            let trained = point_lights[i];
            let copies: Vec<PointLightAt> = (0..lights.len())
                .map(|k| PointLightAt {
                    position: trained.position + offsets[k],
                    intensity: trained.intensity * lights[k].scale,
                    ..trained
                })
                .collect();
            point_lights[i] = copies[0];
            point_lights.extend_from_slice(&copies[1..]);
        }

        let mut emitters = Vec::new();
        let mut emitter_of_emissive = vec![NO_EMITTER; geometry.emissive.len()];
        for (k, &id) in geometry.emissive.iter().enumerate() {
            let info = &geometry.triangles[id as usize];
            let material = &scene.materials[info.material as usize];
            let uvs = corner_values(&geometry.uvs, info.vertices);
            let texture = material.emissive_texture;
            // The same for every copy: a copy moves the triangle, not its UVs.
            let share = texture.map_or(1.0, |t| textured_share(scene, t, uvs));
            let copies = if info.moving { lights.len() } else { 1 };
            for copy in 0..copies {
                let corners = geometry.corners(id, offsets[copy]);
                let [a, b, c] = corners;
                let cross = (b - a).cross(c - a);
                let area = 0.5 * cross.length();
                if area <= 0.0 {
                    break;
                }
                let emission = material.emission * if info.moving { lights[copy].scale } else { Vec3::ONE };
                if copy == 0 {
                    emitter_of_emissive[k] = emitters.len() as u32;
                }
                emitters.push(Emitter {
                    corners,
                    uvs,
                    normal: cross.normalize(),
                    emission,
                    texture,
                    double_sided: material.double_sided,
                    area,
                    probability: luminance(emission) * area * share,
                });
            }
        }
        let total: f32 = emitters.iter().map(|e| e.probability).sum();
        if total <= 0.0 {
            // Every copy of the only area light is black: nothing to sample.
            emitters.clear();
            emitter_of_emissive.fill(NO_EMITTER);
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
            lights: lights.to_vec(),
            moved: geometry.moved_triangles(&offsets),
            offsets,
            emitters,
            emitter_cdf: cdf,
            emitter_of_emissive,
            point_lights,
        }
    }

    pub fn intersect(&self, origin: Vec3, dir: Vec3) -> Option<Hit> {
        let covers = |hit: Hit| self.covers(hit, origin + dir * hit.t);
        self.geometry.intersect(origin, dir, f32::INFINITY, &self.moved, &covers)
    }

    pub fn occluded(&self, origin: Vec3, dir: Vec3, distance: f32) -> bool {
        let covers = |hit: Hit| self.covers(hit, origin + dir * hit.t);
        self.geometry.occluded(origin, dir, distance, &self.moved, &covers)
    }

    /// The corners of the triangle of `hit`, moved with its copy of the light if it moves.
    fn corners(&self, hit: Hit) -> [Vec3; 3] {
        self.geometry.corners(hit.triangle, self.offsets[hit.copy as usize])
    }

    /// The alpha test of the triangle of `hit` at `point`, a point on it.
    fn covers(&self, hit: Hit, point: Vec3) -> bool {
        let info = &self.geometry.triangles[hit.triangle as usize];
        let b = barycentrics(self.corners(hit), point);
        let uv = interpolate(corner_values(&self.geometry.uvs, info.vertices), b);
        self.scene.materials[info.material as usize].covers(&self.scene.textures, uv)
    }

    pub fn has_area_lights(&self) -> bool {
        !self.emitters.is_empty()
    }

    /// The surface at `hit` seen along `dir`.
    pub fn interaction(&self, origin: Vec3, dir: Vec3, hit: Hit) -> Interaction {
        let g = self.geometry;
        let info = g.triangles[hit.triangle as usize];
        let [p0, p1, p2] = self.corners(hit);
        let b = barycentrics([p0, p1, p2], origin + dir * hit.t);
        let position = interpolate([p0, p1, p2], b);
        let uv = interpolate(corner_values(&g.uvs, info.vertices), b);
        let material = &self.scene.materials[info.material as usize];
        let shading = material.shading(&self.scene.textures, uv);
        let mut ng = (p1 - p0).cross(p2 - p0).normalize_or(Vec3::Z);
        let interpolated = interpolate(corner_values(&g.normals, info.vertices), b).normalize_or(ng);
        let mut ns = match shading.tangent_normal {
            Some(m) => {
                let tangent = interpolate(corner_values(&g.tangents, info.vertices), b);
                normal_mapped(interpolated, tangent, m)
            }
            None => interpolated,
        };
        let front_face = ng.dot(dir) < 0.0;
        if !front_face {
            ng = -ng;
        }
        if ns.dot(ng) < 0.0 {
            ns = -ns;
        }
        let emits = front_face || material.double_sided;
        let scale = if info.moving { self.lights[hit.copy as usize].scale } else { Vec3::ONE };
        Interaction {
            position,
            geometric_normal: ng,
            shading_normal: ns,
            front_face,
            bsdf: Bsdf::new(shading.base_color, shading.metallic, shading.roughness, material.specular),
            emission: if emits { shading.emission * scale } else { Vec3::ZERO },
            object: info.object,
            uv,
            roughness: shading.roughness,
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
        let weights = Vec3::new(1.0 - bary.x - bary.y, bary.x, bary.y);
        let point = interpolate([a, b, c], weights);
        let to_light = point - from;
        let distance2 = to_light.length_squared();
        let distance = distance2.sqrt();
        let direction = to_light / distance;
        let cos_light = -e.normal.dot(direction);
        if cos_light <= 0.0 && !e.double_sided {
            return None;
        }
        let pdf = e.probability / e.area * distance2 / cos_light.abs();
        let texture =
            e.texture.map_or(Vec3::ONE, |t| t.sample(&self.scene.textures, interpolate(e.uvs, weights)).truncate());
        Some(LightSample { direction, distance, radiance: e.emission * texture, pdf: Some(pdf) })
    }

    /// Solid-angle density with which [`World::sample_area_light`] would have produced the
    /// point of `hit`, met along direction `dir`.
    pub fn area_light_pdf(&self, hit: Hit, dir: Vec3) -> f32 {
        let Ok(k) = self.geometry.emissive.binary_search(&hit.triangle) else {
            return 0.0;
        };
        let index = self.emitter_of_emissive[k];
        if index == NO_EMITTER {
            return 0.0;
        }
        let e = &self.emitters[(index + hit.copy) as usize];
        let t = hit.t;
        let cos_light = e.normal.dot(dir).abs();
        if cos_light <= 0.0 {
            return 0.0;
        }
        e.probability / e.area * t * t / cos_light
    }
}

/// Barycentric coordinates (of the corners in order) of `p`, a point in the triangle's plane,
/// clamped into the triangle.
fn barycentrics([p0, p1, p2]: [Vec3; 3], p: Vec3) -> Vec3 {
    let (e1, e2, ep) = (p1 - p0, p2 - p0, p - p0);
    let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let (dp1, dp2) = (ep.dot(e1), ep.dot(e2));
    let denom = d11 * d22 - d12 * d12;
    let (b1, b2) = if denom > 0.0 {
        (((d22 * dp1 - d12 * dp2) / denom).clamp(0.0, 1.0), ((d11 * dp2 - d12 * dp1) / denom).clamp(0.0, 1.0))
    } else {
        (0.0, 0.0)
    };
    Vec3::new((1.0 - b1 - b2).max(0.0), b1, b2)
}

fn interpolate<T>(values: [T; 3], b: Vec3) -> T
where
    T: std::ops::Mul<f32, Output = T> + std::ops::Add<Output = T> + Copy,
{
    values[0] * b.x + values[1] * b.y + values[2] * b.z
}

/// The shading normal that normal map value `m` (tangent space, scaled) gives on a surface of
/// interpolated `normal` and `tangent` (xyz, and the bitangent's sign in w), as glTF says.
/// The GPU's twin is in `gbuffer.frag`.
pub fn normal_mapped(normal: Vec3, tangent: Vec4, m: Vec3) -> Vec3 {
    let t =
        (tangent.truncate() - normal * normal.dot(tangent.truncate())).normalize_or(normal.any_orthonormal_vector());
    let b = normal.cross(t) * if tangent.w < 0.0 { -1.0 } else { 1.0 };
    (t * m.x + b * m.y + normal * m.z).normalize_or(normal)
}

/// The mean luminance of emissive texture `t` over a triangle of corner UVs `uvs`, from 16
/// fixed points: the triangle is picked for light sampling in proportion to its area times
/// this. Its floor of 1/64 keeps every emitting triangle samplable where the 16 points missed
/// its bright texels (a zero probability would bias the estimate).
fn textured_share(scene: &Scene, t: TextureRef, uvs: [Vec2; 3]) -> f32 {
    let mut sum = 0.0;
    for i in 0..16 {
        let u = Vec2::new((i % 4) as f32 + 0.5, (i / 4) as f32 + 0.5) / 4.0;
        let b = uniform_triangle(u);
        let uv = interpolate(uvs, Vec3::new(1.0 - b.x - b.y, b.x, b.y));
        sum += luminance(t.sample(&scene.textures, uv).truncate());
    }
    (sum / 16.0).max(1.0 / 64.0)
}

pub fn luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.2126, 0.7152, 0.0722))
}
