//! Writes a plain glTF 2.0 scene (`scene.gltf`, `scene.bin`, PNG textures) that Blender opens.

use std::path::Path;

use glam::{Mat3, Quat, Vec3, Vec4};
use serde_json::{json, Value};

use super::shapes::Mesh;

#[derive(Clone)]
pub struct MaterialDesc {
    pub name: &'static str,
    /// Linear RGB.
    pub base_color: [f32; 3],
    pub metallic: f32,
    pub roughness: f32,
    /// Emitted radiance, linear RGB (written as a factor with its maximum at 1, times
    /// `KHR_materials_emissive_strength`).
    pub emission: [f32; 3],
    /// A PNG written beside the glTF, used as the base colour texture.
    pub texture: Option<(&'static str, image::RgbaImage)>,
    /// `KHR_texture_transform` of the base colour texture: offset, rotation, scale.
    pub texture_transform: Option<([f32; 2], f32, [f32; 2])>,
    /// Metallic-roughness, normal (with its scale) and emissive textures.
    pub metallic_roughness_texture: Option<(&'static str, image::RgbaImage)>,
    pub normal_texture: Option<(&'static str, image::RgbaImage, f32)>,
    pub emissive_texture: Option<(&'static str, image::RgbaImage)>,
    /// `alphaMode` MASK with this `alphaCutoff`.
    pub alpha_cutoff: Option<f32>,
    pub double_sided: bool,
    /// `KHR_materials_specular` factor; `Some(0.0)` makes a pure Lambert surface.
    pub specular: Option<f32>,
}

impl MaterialDesc {
    pub fn diffuse(name: &'static str, base_color: [f32; 3]) -> Self {
        Self {
            name,
            base_color,
            metallic: 0.0,
            roughness: 1.0,
            emission: [0.0; 3],
            texture: None,
            texture_transform: None,
            metallic_roughness_texture: None,
            normal_texture: None,
            emissive_texture: None,
            alpha_cutoff: None,
            double_sided: false,
            specular: None,
        }
    }

    /// Pure Lambert: no specular lobe at all.
    pub fn lambert(name: &'static str, base_color: [f32; 3]) -> Self {
        Self { specular: Some(0.0), ..Self::diffuse(name, base_color) }
    }

    pub fn glossy(name: &'static str, base_color: [f32; 3], metallic: f32, roughness: f32) -> Self {
        Self { metallic, roughness, ..Self::diffuse(name, base_color) }
    }

    pub fn emissive(name: &'static str, radiance: [f32; 3]) -> Self {
        Self { emission: radiance, ..Self::diffuse(name, [0.0; 3]) }
    }

    pub fn textured(name: &'static str, file: &'static str, image: image::RgbaImage) -> Self {
        Self { texture: Some((file, image)), ..Self::diffuse(name, [1.0; 3]) }
    }
}

#[derive(Default)]
pub struct GltfBuilder {
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
    meshes: Vec<Value>,
    nodes: Vec<Value>,
    materials: Vec<Value>,
    images: Vec<Value>,
    textures: Vec<Value>,
    cameras: Vec<Value>,
    lights: Vec<Value>,
    pngs: Vec<(&'static str, image::RgbaImage)>,
    /// Per material: whether it has a normal map, so that its meshes need tangents.
    normal_mapped: Vec<bool>,
    pub triangles: usize,
}

impl GltfBuilder {
    pub fn material(&mut self, m: MaterialDesc) -> usize {
        let mut pbr = json!({
            "baseColorFactor": [m.base_color[0], m.base_color[1], m.base_color[2], 1.0],
            "metallicFactor": m.metallic,
            "roughnessFactor": m.roughness,
        });
        if let Some((file, image)) = m.texture {
            pbr["baseColorTexture"] = json!({ "index": self.texture(file, image) });
            if let Some((offset, rotation, scale)) = m.texture_transform {
                pbr["baseColorTexture"]["extensions"] = json!({
                    "KHR_texture_transform": { "offset": offset, "rotation": rotation, "scale": scale }
                });
            }
        }
        if let Some((file, image)) = m.metallic_roughness_texture {
            pbr["metallicRoughnessTexture"] = json!({ "index": self.texture(file, image) });
        }
        let mut material = json!({ "name": m.name, "pbrMetallicRoughness": pbr });
        self.normal_mapped.push(m.normal_texture.is_some());
        if let Some((file, image, scale)) = m.normal_texture {
            material["normalTexture"] = json!({ "index": self.texture(file, image), "scale": scale });
        }
        if let Some((file, image)) = m.emissive_texture {
            material["emissiveTexture"] = json!({ "index": self.texture(file, image) });
        }
        if let Some(cutoff) = m.alpha_cutoff {
            material["alphaMode"] = json!("MASK");
            material["alphaCutoff"] = json!(cutoff);
        }
        if m.double_sided {
            material["doubleSided"] = json!(true);
        }
        let mut extensions = serde_json::Map::new();
        let strength = m.emission.iter().copied().fold(0.0f32, f32::max);
        if strength > 0.0 {
            material["emissiveFactor"] = json!(m.emission.map(|c| c / strength));
            if strength != 1.0 {
                extensions.insert("KHR_materials_emissive_strength".into(), json!({ "emissiveStrength": strength }));
            }
        }
        if let Some(specular) = m.specular {
            extensions.insert("KHR_materials_specular".into(), json!({ "specularFactor": specular }));
        }
        if !extensions.is_empty() {
            material["extensions"] = Value::Object(extensions);
        }
        self.materials.push(material);
        self.materials.len() - 1
    }

    /// A texture of its own for the PNG `image`, written as `file`.
    fn texture(&mut self, file: &'static str, image: image::RgbaImage) -> usize {
        self.images.push(json!({ "uri": file }));
        self.textures.push(json!({ "source": self.images.len() - 1, "sampler": 0 }));
        self.pngs.push((file, image));
        self.textures.len() - 1
    }

    /// Adds `mesh` as a node of its own, named `name`, at `translation`.
    pub fn object(&mut self, name: &str, mesh: &Mesh, material: usize, translation: Vec3) -> usize {
        assert_eq!(mesh.positions.len(), mesh.normals.len());
        self.triangles += mesh.triangle_count();
        let (lo, hi) = mesh
            .positions
            .iter()
            .fold((Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)), |(lo, hi), p| (lo.min(*p), hi.max(*p)));
        let n = mesh.positions.len();
        let positions = self.accessor(bytes_of(&mesh.positions), n, "VEC3", 5126, Some((lo, hi)), 34962);
        let normals = self.accessor(bytes_of(&mesh.normals), n, "VEC3", 5126, None, 34962);
        let uvs = self.accessor(bytes_of(&mesh.uvs), n, "VEC2", 5126, None, 34962);
        let mut attributes = json!({ "POSITION": positions, "NORMAL": normals, "TEXCOORD_0": uvs });
        if self.normal_mapped[material] {
            attributes["TANGENT"] = json!(self.accessor(bytes_of(&tangents(mesh)), n, "VEC4", 5126, None, 34962));
        }
        let index_bytes: Vec<u8> = mesh.indices.iter().flat_map(|i| i.to_le_bytes()).collect();
        let indices = self.accessor(index_bytes, mesh.indices.len(), "SCALAR", 5125, None, 34963);
        self.meshes.push(json!({
            "name": name,
            "primitives": [{ "attributes": attributes, "indices": indices, "material": material }],
        }));
        self.node(json!({ "name": name, "mesh": self.meshes.len() - 1, "translation": translation.to_array() }))
    }

    /// A KHR_lights_punctual point light; `intensity` is radiant intensity, W/sr per channel,
    /// written in candela as glTF says (683 cd per W/sr, as rrf reads it back).
    pub fn point_light(&mut self, name: &str, position: Vec3, intensity: [f32; 3]) -> usize {
        let strength = intensity.iter().copied().fold(0.0f32, f32::max);
        self.lights.push(json!({
            "name": name,
            "type": "point",
            "color": intensity.map(|c| c / strength),
            "intensity": strength * 683.0,
        }));
        self.node(json!({
            "name": name,
            "translation": position.to_array(),
            "extensions": { "KHR_lights_punctual": { "light": self.lights.len() - 1 } },
        }))
    }

    /// A KHR_lights_punctual spot light at `position` shining along `direction`, its cone
    /// between `inner` and `outer` (radians); `intensity` as for [`GltfBuilder::point_light`].
    pub fn spot_light(
        &mut self,
        name: &str,
        position: Vec3,
        direction: Vec3,
        intensity: [f32; 3],
        inner: f32,
        outer: f32,
    ) -> usize {
        let strength = intensity.iter().copied().fold(0.0f32, f32::max);
        self.lights.push(json!({
            "name": name,
            "type": "spot",
            "color": intensity.map(|c| c / strength),
            "intensity": strength * 683.0,
            "spot": { "innerConeAngle": inner, "outerConeAngle": outer },
        }));
        // glTF lights shine down the node's -z.
        let rotation = Quat::from_rotation_arc(Vec3::NEG_Z, direction.normalize());
        self.node(json!({
            "name": name,
            "translation": position.to_array(),
            "rotation": rotation.to_array(),
            "extensions": { "KHR_lights_punctual": { "light": self.lights.len() - 1 } },
        }))
    }

    /// A perspective camera at `eye` looking at `target` (glTF cameras look down -Z).
    pub fn camera(&mut self, name: &str, eye: Vec3, target: Vec3, fov_y_degrees: f32) -> usize {
        let forward = (target - eye).normalize();
        let right = forward.cross(Vec3::Y).normalize();
        let rotation = Quat::from_mat3(&Mat3::from_cols(right, right.cross(forward), -forward)).normalize();
        self.cameras.push(json!({
            "name": name,
            "type": "perspective",
            "perspective": { "yfov": fov_y_degrees.to_radians(), "znear": 0.01 },
        }));
        self.node(json!({
            "name": name,
            "camera": self.cameras.len() - 1,
            "translation": eye.to_array(),
            "rotation": rotation.to_array(),
        }))
    }

    fn node(&mut self, node: Value) -> usize {
        self.nodes.push(node);
        self.nodes.len() - 1
    }

    fn accessor(
        &mut self,
        bytes: Vec<u8>,
        count: usize,
        kind: &str,
        component: u32,
        bounds: Option<(Vec3, Vec3)>,
        target: u32,
    ) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        self.views.push(json!({
            "buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len(), "target": target,
        }));
        self.bin.extend(bytes);
        let mut accessor =
            json!({ "bufferView": self.views.len() - 1, "componentType": component, "count": count, "type": kind });
        if let Some((lo, hi)) = bounds {
            accessor["min"] = json!(lo.to_array());
            accessor["max"] = json!(hi.to_array());
        }
        self.accessors.push(accessor);
        self.accessors.len() - 1
    }

    pub fn write(self, dir: &Path) -> Result<(), String> {
        std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        let mut used = vec![];
        if !self.lights.is_empty() {
            used.push("KHR_lights_punctual");
        }
        for ext in ["KHR_materials_emissive_strength", "KHR_materials_specular"] {
            if self.materials.iter().any(|m| m.get("extensions").and_then(|e| e.get(ext)).is_some()) {
                used.push(ext);
            }
        }
        let transform = |m: &Value| m["pbrMetallicRoughness"]["baseColorTexture"]["extensions"].is_object();
        if self.materials.iter().any(transform) {
            used.push("KHR_texture_transform");
        }
        let mut root = json!({
            "asset": { "version": "2.0", "generator": "rrf xtask scenes" },
            "scene": 0,
            "scenes": [{ "nodes": (0..self.nodes.len()).collect::<Vec<_>>() }],
            "nodes": self.nodes,
            "meshes": self.meshes,
            "materials": self.materials,
            "accessors": self.accessors,
            "bufferViews": self.views,
            "buffers": [{ "uri": "scene.bin", "byteLength": self.bin.len() }],
        });
        if !used.is_empty() {
            root["extensionsUsed"] = json!(used);
        }
        if !self.cameras.is_empty() {
            root["cameras"] = json!(self.cameras);
        }
        if !self.lights.is_empty() {
            root["extensions"] = json!({ "KHR_lights_punctual": { "lights": self.lights } });
        }
        if !self.images.is_empty() {
            root["images"] = json!(self.images);
            root["textures"] = json!(self.textures);
            // Linear filtering with mipmaps, repeat wrapping.
            root["samplers"] = json!([{ "magFilter": 9729, "minFilter": 9987, "wrapS": 10497, "wrapT": 10497 }]);
        }
        let text = serde_json::to_string_pretty(&root).map_err(|e| e.to_string())?;
        let write = |name: &str, bytes: &[u8]| {
            std::fs::write(dir.join(name), bytes).map_err(|e| format!("{}: {e}", dir.join(name).display()))
        };
        write("scene.gltf", text.as_bytes())?;
        write("scene.bin", &self.bin)?;
        for (file, image) in &self.pngs {
            image.save(dir.join(file)).map_err(|e| format!("{}: {e}", dir.join(file).display()))?;
        }
        Ok(())
    }
}

/// Per-vertex tangents for a normal map, as exporters write them: each triangle's direction of
/// increasing u, summed at its corners and made orthogonal to the normal; w is the handedness
/// of the direction of increasing v.
fn tangents(mesh: &Mesh) -> Vec<Vec4> {
    let mut sums = vec![(Vec3::ZERO, Vec3::ZERO); mesh.positions.len()];
    for t in mesh.indices.chunks_exact(3) {
        let [a, b, c] = [t[0], t[1], t[2]].map(|i| i as usize);
        let (e1, e2) = (mesh.positions[b] - mesh.positions[a], mesh.positions[c] - mesh.positions[a]);
        let (d1, d2) = (mesh.uvs[b] - mesh.uvs[a], mesh.uvs[c] - mesh.uvs[a]);
        let det = d1.x * d2.y - d2.x * d1.y;
        if det.abs() > 1e-12 {
            for v in [a, b, c] {
                sums[v].0 += (e1 * d2.y - e2 * d1.y) / det;
                sums[v].1 += (e2 * d1.x - e1 * d2.x) / det;
            }
        }
    }
    sums.iter()
        .zip(&mesh.normals)
        .map(|(&(t, b), &n)| {
            let t = (t - n * n.dot(t)).try_normalize().unwrap_or_else(|| n.any_orthonormal_vector());
            t.extend(if n.cross(t).dot(b) < 0.0 { -1.0 } else { 1.0 })
        })
        .collect()
}

fn bytes_of<T: Copy + Into<[f32; N]>, const N: usize>(values: &[T]) -> Vec<u8> {
    values.iter().flat_map(|&v| v.into()).flat_map(f32::to_le_bytes).collect()
}
