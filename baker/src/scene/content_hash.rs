//! The scene's content hash, which a model records so that it is used only with the scene it
//! was baked from. It covers what shapes the training samples: the objects (names and
//! geometry), materials and their textures, the point lights, the moving light and its box,
//! the camera box and the bake presets. It leaves out the views and the eval defaults, so
//! adding a named view, moving the glTF camera or raising the references' spp does not call
//! for a re-bake; nor does anything glTF carries that rrf does not read.
//!
//! The same hash before the bake presets is the scene's light-transport hash: what a
//! path-traced image of a given view and light position depends on, so that eval's cached
//! references outlive a change of bake settings.

use glam::Vec3;

use super::{AlphaMode, LightKind, Scene, UvTransform};
use crate::hash::Fnv64;

struct Writer(Fnv64);

impl Writer {
    fn bytes(&mut self, b: &[u8]) {
        self.u64(b.len() as u64);
        self.0.write(b);
    }

    fn u64(&mut self, v: u64) {
        self.0.write(&v.to_le_bytes());
    }

    fn f32s(&mut self, values: impl IntoIterator<Item = f32>) {
        for v in values {
            self.0.write(&v.to_le_bytes());
        }
    }

    fn vec3s<'a>(&mut self, values: impl IntoIterator<Item = &'a Vec3>) {
        self.f32s(values.into_iter().flat_map(|v| v.to_array()));
    }
}

/// The scene's (content hash, light-transport hash).
pub(super) fn content_hashes(scene: &Scene) -> (u64, u64) {
    let mut w = Writer(Fnv64::default());
    w.u64(scene.objects.len() as u64);
    for o in &scene.objects {
        w.bytes(o.name.as_bytes());
        w.vec3s(&o.positions);
        w.vec3s(&o.normals);
        w.f32s(o.uvs.iter().flat_map(|v| v.to_array()));
        w.u64(o.triangles.len() as u64);
        o.triangles.iter().flatten().for_each(|&i| w.u64(u64::from(i)));
        for part in &o.parts {
            for v in [part.material, part.triangles.start, part.triangles.end] {
                w.u64(u64::from(v));
            }
        }
        // Tangents shape samples only through normal maps (and came with them).
        if o.parts.iter().any(|p| scene.materials[p.material as usize].normal_texture.is_some()) {
            w.f32s(o.tangents.iter().flat_map(|t| t.to_array()));
        }
    }
    w.u64(scene.materials.len() as u64);
    for m in &scene.materials {
        w.vec3s([&m.base_color, &m.emission]);
        w.f32s([m.metallic, m.roughness, m.specular, f32::from(u8::from(m.double_sided))]);
        for texture in [m.base_color_texture, m.metallic_roughness_texture] {
            w.u64(texture.map_or(u64::MAX, |t| u64::from(t.texture)));
        }
        // Texture transforms, normal maps, emissive textures and alpha masks came later: they
        // are written only where a material uses them, so that older scenes keep their hash
        // and their models.
        let textures = m.textures();
        let transformed = textures.iter().flatten().any(|t| t.transform != UvTransform::IDENTITY);
        let cutoff = match m.alpha_mode {
            AlphaMode::Opaque => None,
            AlphaMode::Mask { cutoff } => Some(cutoff),
        };
        if transformed || m.normal_texture.is_some() || m.emissive_texture.is_some() || cutoff.is_some() {
            w.bytes(b"material features");
            for texture in textures {
                w.u64(texture.map_or(u64::MAX, |t| u64::from(t.texture)));
                let t = texture.map_or(UvTransform::IDENTITY, |t| t.transform);
                w.f32s(t.matrix.into_iter().chain(t.offset.to_array()));
            }
            w.f32s([m.normal_texture.map_or(0.0, |n| n.1), m.alpha, cutoff.unwrap_or(-1.0)]);
        }
    }
    w.u64(scene.textures.len() as u64);
    for t in &scene.textures {
        w.u64(u64::from(t.width));
        w.u64(u64::from(t.height));
        w.bytes(format!("{:?}", t.color_space).as_bytes());
        w.bytes(t.texels.as_flattened());
    }
    w.u64(scene.point_lights.len() as u64);
    for l in &scene.point_lights {
        w.bytes(l.name.as_bytes());
        w.vec3s([&l.position, &l.intensity]);
        w.u64(u64::from(l.cone.is_some()));
        if let Some(cone) = l.cone {
            w.vec3s([&cone.direction]);
            w.f32s([cone.cos_inner, cone.cos_outer]);
        }
    }
    w.u64(u64::from(scene.moving_light.is_some()));
    if let Some(light) = &scene.moving_light {
        w.bytes(light.node_name.as_bytes());
        let (kind, index) = match light.kind {
            LightKind::Point(i) => (0, i as u64),
            LightKind::Area(id) => (1, u64::from(id)),
        };
        w.u64(kind);
        w.u64(index);
        w.vec3s([&light.default_position, &light.bounds.min, &light.bounds.max]);
    }
    w.u64(u64::from(scene.camera_box.is_some()));
    if let Some(camera) = &scene.camera_box {
        w.vec3s([&camera.min, &camera.max]);
    }
    let light_transport = w.0 .0;
    for preset in [&scene.bake.test, &scene.bake.preview, &scene.bake.final_] {
        let values = preset.as_ref().map_or([None; 7], |p| p.values());
        // The settings added later (split_depth on) are hashed only when set, so that a
        // sidecar without them keeps its hash, and its shipped model stays current.
        let (first, later) = values.split_at(5);
        first.iter().for_each(|v| w.u64(v.map_or(u64::MAX, u64::from)));
        for (i, v) in later.iter().enumerate() {
            if let Some(v) = v {
                w.u64(i as u64);
                w.u64(u64::from(*v));
            }
        }
    }
    (w.0 .0, light_transport)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::BakeOverrides;

    /// Whether a change moves the light-transport hash as well as the content hash.
    #[derive(Clone, Copy, Debug, PartialEq)]
    enum Moves {
        Both,
        ContentOnly,
    }

    /// A change to a scene, and which hashes it moves.
    type Change = (&'static str, Moves, fn(&mut Scene));

    /// Each change to what shapes a path-traced image or eval's held-out configurations
    /// changes both hashes; a change to a bake preset (what shapes only the samples) changes
    /// the content hash alone. The gallery has textures, a normal map, alpha masks, a textured
    /// emitter and a spot light.
    #[test]
    fn every_input_of_the_light_transport_moves_the_hashes() {
        let scene = Scene::load(&std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/gallery")).unwrap();
        let before = content_hashes(&scene);
        assert_eq!(before, (scene.content_hash, scene.light_transport_hash));
        let changes: [Change; 14] = [
            ("a vertex", Moves::Both, |s| s.objects[0].positions[0].x += 1e-3),
            ("a normal", Moves::Both, |s| s.objects[0].normals[0].y = -s.objects[0].normals[0].y),
            ("a texture coordinate", Moves::Both, |s| s.objects[0].uvs[0].x += 0.5),
            ("a base colour", Moves::Both, |s| s.materials[0].base_color.x *= 0.5),
            ("a roughness", Moves::Both, |s| s.materials[0].roughness *= 0.5),
            ("an emission", Moves::Both, |s| s.materials[0].emission.y += 1.0),
            ("a texel", Moves::Both, |s| s.textures[0].texels[0][0] ^= 1),
            ("an alpha cutoff", Moves::Both, |s| {
                let m = s.materials.iter_mut().find(|m| matches!(m.alpha_mode, AlphaMode::Mask { .. })).unwrap();
                m.alpha_mode = AlphaMode::Mask { cutoff: 0.25 };
            }),
            ("a point light's intensity", Moves::Both, |s| s.point_lights[0].intensity.x *= 2.0),
            ("a spot light's cone", Moves::Both, |s| s.point_lights[0].cone.as_mut().unwrap().cos_outer *= 0.9),
            ("the light's box", Moves::Both, |s| s.moving_light.as_mut().unwrap().bounds.max.y += 0.1),
            ("the light's default position", Moves::Both, |s| {
                s.moving_light.as_mut().unwrap().default_position.x += 0.1
            }),
            // Eval's held-out viewpoints are drawn from it.
            ("the camera box", Moves::Both, |s| s.camera_box.as_mut().unwrap().min.z -= 0.1),
            ("a bake preset", Moves::ContentOnly, |s| {
                s.bake.final_ = Some(BakeOverrides { split_depth: Some(1), ..Default::default() })
            }),
        ];
        for (what, moves, change) in changes {
            let mut changed = scene.clone();
            change(&mut changed);
            let after = content_hashes(&changed);
            assert_ne!(before.0, after.0, "{what}: content hash");
            assert_eq!(before.1 != after.1, moves == Moves::Both, "{what}: light-transport hash");
        }
    }
}
