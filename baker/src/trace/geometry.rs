//! The scene's triangles in one eight-wide BVH ([`Bvh8`]), built once per scene.
//!
//! The moving area light, if there is one, stays out of the BVH: it is a handful of
//! triangles tested directly, so moving it never rebuilds the BVH.

use glam::{Vec2, Vec3, Vec3A, Vec4};
use obvhs::ray::Ray;
use obvhs::rt_triangle::RtTriangle;
use obvhs::triangle::Triangle;

use super::bvh8::Bvh8;

use crate::scene::{AlphaMode, LightKind, Mirror, Scene};

/// A triangle's vertices (indices into the global vertex arrays), object and material.
#[derive(Clone, Copy, Debug)]
pub struct TriangleInfo {
    pub vertices: [u32; 3],
    pub object: u32,
    pub material: u32,
    /// Part of the moving area light (outside the BVH, moved with the light).
    pub moving: bool,
    /// Its material is alpha-masked: a hit counts only where the mask covers it.
    pub masked: bool,
}

pub struct Geometry {
    /// Every triangle but the moving light's.
    bvh: Bvh8,
    /// The BVH's primitive index to triangle id.
    bvh_ids: Vec<u32>,
    /// The BVH's primitive index to whether the triangle is alpha-masked.
    bvh_masked: Vec<bool>,
    /// Every triangle of the scene, by id.
    pub triangles: Vec<TriangleInfo>,
    /// World-space vertices of all objects (the moving light at its default position).
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub uvs: Vec<Vec2>,
    pub tangents: Vec<Vec4>,
    /// Triangle ids of the moving area light, not in the BVH.
    pub moving: Vec<u32>,
    /// Ids of the triangles whose material emits, in order: a light configuration's emitters
    /// are found among these, not among every triangle.
    pub emissive: Vec<u32>,
    /// Per object id, its plane if it is a planar mirror ([`Scene::mirrors`]).
    pub mirrors: Vec<Option<Mirror>>,
}

/// The alpha test: whether the masked triangle of `hit` is there, at `hit.t` along the ray
/// being traced.
pub type Covers<'a> = &'a dyn Fn(Hit) -> bool;

/// The closest intersection along a ray.
#[derive(Clone, Copy, Debug)]
pub struct Hit {
    pub t: f32,
    pub triangle: u32,
    /// Which copy of the moving light a moving triangle belongs to (see [`MovedTriangle`]);
    /// 0 for every other triangle.
    pub copy: u32,
}

/// A triangle of the moving area light where one copy of the light puts it. A configuration
/// with several lights holds one copy of the light's triangles per light.
#[derive(Clone, Copy)]
pub struct MovedTriangle {
    pub triangle: u32,
    pub copy: u32,
    pub placed: RtTriangle,
}

impl Geometry {
    pub fn new(scene: &Scene) -> Self {
        let moving_object = match scene.moving_light.as_ref().map(|l| l.kind) {
            Some(LightKind::Area(id)) => Some(id),
            _ => None,
        };
        let mut g = Geometry {
            bvh: Bvh8::new(&[]),
            bvh_ids: Vec::new(),
            bvh_masked: Vec::new(),
            triangles: Vec::with_capacity(scene.triangle_count()),
            positions: Vec::new(),
            normals: Vec::new(),
            uvs: Vec::new(),
            tangents: Vec::new(),
            moving: Vec::new(),
            emissive: Vec::new(),
            mirrors: scene.mirror_by_object(),
        };
        for object in &scene.objects {
            let base = g.positions.len() as u32;
            g.positions.extend(&object.positions);
            g.normals.extend(&object.normals);
            g.uvs.extend(&object.uvs);
            g.tangents.extend(&object.tangents);
            for part in &object.parts {
                for t in part.triangles.clone() {
                    let id = g.triangles.len() as u32;
                    let moving = Some(object.id) == moving_object;
                    if moving {
                        g.moving.push(id);
                    }
                    if scene.materials[part.material as usize].is_emissive() {
                        g.emissive.push(id);
                    }
                    g.triangles.push(TriangleInfo {
                        vertices: object.triangles[t as usize].map(|i| base + i),
                        object: object.id,
                        material: part.material,
                        moving,
                        masked: scene.materials[part.material as usize].alpha_mode != AlphaMode::Opaque,
                    });
                }
            }
        }
        g.bvh_ids = (0..g.triangles.len() as u32).filter(|id| !g.moving.contains(id)).collect();
        g.bvh_masked = g.bvh_ids.iter().map(|&id| g.triangles[id as usize].masked).collect();
        let tris: Vec<Triangle> = g
            .bvh_ids
            .iter()
            .map(|&id| {
                let [a, b, c] = g.corners(id, Vec3::ZERO);
                Triangle { v0: a.into(), v1: b.into(), v2: c.into() }
            })
            .collect();
        g.bvh = Bvh8::new(&tris);
        g
    }

    /// The triangle's corners, the moving light's moved by `offset`.
    pub fn corners(&self, id: u32, offset: Vec3) -> [Vec3; 3] {
        let info = &self.triangles[id as usize];
        let shift = if info.moving { offset } else { Vec3::ZERO };
        let [a, b, c] = corner_values(&self.positions, info.vertices);
        [a + shift, b + shift, c + shift]
    }

    /// The moving light's triangles, one copy per light, each light `offsets[copy]` from the
    /// light's default position.
    pub fn moved_triangles(&self, offsets: &[Vec3]) -> Vec<MovedTriangle> {
        (0..offsets.len() as u32)
            .flat_map(|copy| {
                self.moving.iter().map(move |&triangle| {
                    let [a, b, c] = self.corners(triangle, offsets[copy as usize]);
                    MovedTriangle { triangle, copy, placed: RtTriangle::new(a.into(), b.into(), c.into()) }
                })
            })
            .collect()
    }

    /// `hit.t` if the ray meets the triangle there (it is finite) and, for a masked triangle,
    /// `covers(hit)` says the surface is there; else infinity.
    fn test(&self, hit: Hit, covers: Covers) -> f32 {
        if hit.t < f32::INFINITY && self.triangles[hit.triangle as usize].masked && !covers(hit) {
            f32::INFINITY
        } else {
            hit.t
        }
    }

    /// Whether the BVH's hit of its primitive `i` at `t` counts: the alpha test of a masked
    /// triangle.
    #[inline(always)]
    fn accept_static(&self, i: u32, t: f32, covers: Covers) -> bool {
        !self.bvh_masked[i as usize] || covers(Hit { t, triangle: self.bvh_ids[i as usize], copy: 0 })
    }

    /// Closest hit in `[0, tmax]` against the BVH and the moved light triangles; a masked
    /// triangle is hit only where `covers` says so (see [`Covers`]).
    pub fn intersect(
        &self,
        origin: Vec3,
        dir: Vec3,
        tmax: f32,
        moved: &[MovedTriangle],
        covers: Covers,
    ) -> Option<Hit> {
        let mut ray = Ray::new(Vec3A::from(origin), Vec3A::from(dir), 0.0, tmax);
        let mut best = self.bvh.closest(&ray, |i, t| self.accept_static(i, t, covers)).map(|(i, t)| Hit {
            t,
            triangle: self.bvh_ids[i as usize],
            copy: 0,
        });
        for m in moved {
            ray.tmax = best.map_or(tmax, |h| h.t);
            let candidate = Hit { t: m.placed.intersect(&ray), triangle: m.triangle, copy: m.copy };
            if self.test(candidate, covers) < ray.tmax {
                best = Some(candidate);
            }
        }
        best
    }

    /// Whether anything lies between `origin` and `origin + dir · tmax`.
    pub fn occluded(&self, origin: Vec3, dir: Vec3, tmax: f32, moved: &[MovedTriangle], covers: Covers) -> bool {
        let ray = Ray::new(Vec3A::from(origin), Vec3A::from(dir), 0.0, tmax);
        if self.bvh.any(&ray, |i, t| self.accept_static(i, t, covers)) {
            return true;
        }
        moved.iter().any(|m| {
            let hit = Hit { t: m.placed.intersect(&ray), triangle: m.triangle, copy: m.copy };
            self.test(hit, covers) < tmax
        })
    }
}

/// A vertex attribute at a triangle's three `vertices`. (Indexing by hand: `[u32; 3]::map`
/// was not inlined in the path tracer's hot loop, and cost 2.5% of its time.)
pub(super) fn corner_values<T: Copy>(values: &[T], [a, b, c]: [u32; 3]) -> [T; 3] {
    [values[a as usize], values[b as usize], values[c as usize]]
}
