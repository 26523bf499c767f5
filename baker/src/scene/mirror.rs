//! Planar mirrors. A mirror reflects an image of the room, which no 20-10 network over
//! position and view can hold; but the radiance it reflects is the radiance leaving the point
//! its reflected ray hits, towards the mirror, which that point's networks already predict.
//! So a mirror object gets no networks: the renderer draws the scene again seen in its plane
//! and weights what it sees by the mirror's Fresnel term ([`crate::trace::bsdf::schlick`]; `predict.rs`
//! on the CPU).
//!
//! A mirror is an object whose every material is a perfect metal mirror ([`Material::is_mirror`])
//! and whose triangles lie in one plane. A mirror material on a curved object is learned by
//! networks like any glossy surface, with an import warning.

use glam::Vec3;

use super::{Material, Object, Scene};

/// A planar mirror: an object and its plane, `normal · p = offset` (the normal is the
/// geometry's front side; a double-sided mirror reflects on both).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mirror {
    pub object: u32,
    pub normal: Vec3,
    pub offset: f32,
}

impl Material {
    /// Metallic 1, roughness 0 and nothing that varies them or bends the normal: glTF's
    /// perfect mirror. An emissive material is a light, not a mirror.
    pub fn is_mirror(&self) -> bool {
        self.metallic == 1.0
            && self.roughness == 0.0
            && self.metallic_roughness_texture.is_none()
            && self.normal_texture.is_none()
            && !self.is_emissive()
    }
}

impl Mirror {
    /// The plane's normal on the side of `point` (the viewer), or `None` when `point` lies in
    /// the plane.
    pub fn normal_towards(&self, point: Vec3) -> Option<Vec3> {
        let distance = self.normal.dot(point) - self.offset;
        (distance != 0.0).then(|| self.normal * distance.signum())
    }
}

impl Scene {
    /// Whether every material of `object` is a perfect mirror.
    fn mirror_materials(&self, object: &Object) -> bool {
        !object.parts.is_empty() && object.parts.iter().all(|p| self.materials[p.material as usize].is_mirror())
    }

    /// The scene's planar mirrors, in object order.
    pub fn mirrors(&self) -> Vec<Mirror> {
        self.objects
            .iter()
            .filter(|o| self.mirror_materials(o))
            .filter_map(|o| plane_of(o).map(|(normal, offset)| Mirror { object: o.id, normal, offset }))
            .collect()
    }

    /// Whether object `id` is a planar mirror.
    pub fn is_mirror(&self, id: u32) -> bool {
        let object = &self.objects[id as usize];
        self.mirror_materials(object) && plane_of(object).is_some()
    }

    /// Per object id, its mirror if it is one.
    pub fn mirror_by_object(&self) -> Vec<Option<Mirror>> {
        let mut by_object = vec![None; self.objects.len()];
        for m in self.mirrors() {
            by_object[m.object as usize] = Some(m);
        }
        by_object
    }

    /// Warnings for objects with mirror materials that are not planar mirrors.
    pub(super) fn curved_mirror_warnings(&self) -> Vec<String> {
        self.objects
            .iter()
            .filter(|o| self.mirror_materials(o) && plane_of(o).is_none())
            .map(|o| {
                format!(
                    "object {:?}: its material is a perfect mirror (metallic 1, roughness 0), but its triangles do not \
                     lie in one plane; rrf reflects in planar mirrors only, so networks learn it like a glossy surface",
                    o.name
                )
            })
            .collect()
    }
}

/// The plane of `object`'s triangles (unit normal towards their front, offset), if they all
/// lie in one: every vertex within a millionth of the object's size of the plane through its
/// largest triangle.
fn plane_of(object: &Object) -> Option<(Vec3, f32)> {
    let corners = |t: &[u32; 3]| t.map(|i| object.positions[i as usize]);
    let cross = |t: &[u32; 3]| {
        let [a, b, c] = corners(t);
        (b - a).cross(c - a)
    };
    let largest =
        object.triangles.iter().max_by(|x, y| cross(x).length_squared().total_cmp(&cross(y).length_squared()))?;
    let normal = cross(largest).try_normalize()?;
    let offset = normal.dot(corners(largest)[0]);
    let bounds = object.bounds();
    let tolerance =
        1e-6 * (1.0 + (bounds.max - bounds.min).length() + bounds.max.abs().max(bounds.min.abs()).max_element());
    let used = object.triangles.iter().flatten().map(|&i| object.positions[i as usize]);
    used.map(|p| (normal.dot(p) - offset).abs()).all(|d| d <= tolerance).then_some((normal, offset))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::MaterialRange;
    use glam::{Vec2, Vec4};

    fn quad(positions: [Vec3; 4]) -> Object {
        Object {
            id: 0,
            name: "quad".into(),
            node: 0,
            origin: Vec3::ZERO,
            positions: positions.to_vec(),
            normals: vec![Vec3::Z; 4],
            uvs: vec![Vec2::ZERO; 4],
            tangents: vec![Vec4::X; 4],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            parts: vec![MaterialRange { material: 0, triangles: 0..2 }],
        }
    }

    #[test]
    fn a_flat_quad_has_its_plane_and_a_bent_one_none() {
        let flat = quad([
            Vec3::new(0.0, 0.0, 2.0),
            Vec3::new(1.0, 0.0, 2.0),
            Vec3::new(1.0, 1.0, 2.0),
            Vec3::new(0.0, 1.0, 2.0),
        ]);
        let (normal, offset) = plane_of(&flat).unwrap();
        assert!((normal - Vec3::Z).length() < 1e-6 && (offset - 2.0).abs() < 1e-6, "{normal} {offset}");
        let bent = quad([
            Vec3::new(0.0, 0.0, 2.0),
            Vec3::new(1.0, 0.0, 2.0),
            Vec3::new(1.0, 1.0, 2.0),
            Vec3::new(0.0, 1.0, 2.01),
        ]);
        assert_eq!(plane_of(&bent), None);
    }

    #[test]
    fn the_normal_faces_the_viewer_on_either_side() {
        let m = Mirror { object: 0, normal: Vec3::Z, offset: 2.0 };
        assert_eq!(m.normal_towards(Vec3::new(5.0, 1.0, 3.0)), Some(Vec3::Z));
        assert_eq!(m.normal_towards(Vec3::new(5.0, 1.0, 1.0)), Some(-Vec3::Z));
        assert_eq!(m.normal_towards(Vec3::new(5.0, 1.0, 2.0)), None);
    }
}
