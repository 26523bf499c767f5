//! Scenes: a glTF 2.0 file plus a TOML sidecar, imported into plain data.
//!
//! **Radiometric convention.** All colours are linear RGB. Emission (`emissiveFactor ×
//! KHR_materials_emissive_strength`) is *radiance*, in W·sr⁻¹·m⁻² per channel. A
//! `KHR_lights_punctual` point light's intensity is in candela, as glTF says; rrf takes
//! `color × intensity / 683` as its *radiant intensity* in W·sr⁻¹ per channel (683 lm/W, the
//! luminous efficacy at 555 nm, for every channel). A sidecar's `[units] point_lights = "W/sr"`
//! reads the number as W·sr⁻¹ directly. Lengths are metres.
//!
//! An **object** is a glTF node with a mesh. Objects are numbered in depth-first order of the
//! scene's nodes, and named by their node: per-object networks are keyed by that name, so
//! names must be unique.

mod content_hash;
mod error;
mod external;
mod gltf_import;
mod mirror;
mod sidecar;
mod texture;

use std::ops::Range;
use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3, Vec4};

pub use error::SceneError;
pub use mirror::Mirror;
pub use sidecar::{Aabb, BakeOverrides, BakePresets, EvalDefaults, PointLightUnits, Sidecar, Units, ViewSpec};

/// Candela per W/sr: the luminous efficacy of 555 nm light, which rrf applies to every channel
/// of a glTF point light's intensity.
pub const CANDELA_PER_WATT: f32 = 683.0;
pub use texture::{ColorSpace, Texture, TextureRef, UvTransform};

/// Largest distance from the origin, per axis, of anything in a scene (vertices, boxes,
/// views), in metres: a thousand kilometres. Beyond it, areas and BVH costs overflow f32.
pub const MAX_COORDINATE: f32 = 1.0e6;

/// Largest emissive strength (`KHR_materials_emissive_strength`) and point-light intensity
/// (W/sr) a scene may give: far above the sun's disc, far below where sums of radiance
/// overflow f32.
pub const MAX_EMISSION: f32 = 1e9;

/// File names looked for in a scene folder.
pub const GLTF_NAMES: [&str; 2] = ["scene.gltf", "scene.glb"];

#[derive(Clone, Debug)]
pub struct Scene {
    /// The scene folder's name, or the glTF file's stem.
    pub name: String,
    pub gltf_path: PathBuf,
    pub sidecar_path: Option<PathBuf>,
    pub objects: Vec<Object>,
    pub materials: Vec<Material>,
    pub textures: Vec<Texture>,
    pub point_lights: Vec<PointLight>,
    /// The default view first (the glTF camera, or one that frames the whole scene when the
    /// glTF has none), then the sidecar's views: never empty.
    pub views: Vec<View>,
    /// The moving light and its box; `None` without a sidecar `[light]`.
    pub moving_light: Option<MovingLight>,
    /// Where the camera may be during the walkthrough; `None` without a sidecar `[camera]`.
    pub camera_box: Option<Aabb>,
    pub bake: BakePresets,
    /// The sidecar's defaults for `rrf eval`.
    pub eval: EvalDefaults,
    /// Things that were skipped or approximated while importing, for the user to see.
    pub warnings: Vec<String>,
    /// FNV-1a 64 over what shapes the training samples (not the views): a model file records
    /// it so that a model cannot be used with another scene. See `content_hash.rs`.
    pub content_hash: u64,
    /// The content hash without the bake presets: what a path-traced image of a view and a
    /// light position depends on (eval's reference cache key). See `content_hash.rs`.
    pub light_transport_hash: u64,
}

#[derive(Clone, Debug)]
pub struct Object {
    pub id: u32,
    pub name: String,
    /// Index of the glTF node.
    pub node: usize,
    /// The node's world translation: where a moving area light "is".
    pub origin: Vec3,
    /// World-space vertices.
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub uvs: Vec<Vec2>,
    /// World-space tangents (xyz) and the bitangent's sign (w, bitangent = w · normal ×
    /// tangent): glTF's TANGENT, or derived from the UVs when a primitive has none.
    pub tangents: Vec<Vec4>,
    /// Counter-clockwise seen from the front.
    pub triangles: Vec<[u32; 3]>,
    /// Runs of triangles that share a material, one per glTF primitive.
    pub parts: Vec<MaterialRange>,
}

impl Object {
    /// The bounding box of the object's vertices: the root of its kd-trees.
    pub fn bounds(&self) -> Aabb {
        let min = self.positions.iter().copied().fold(Vec3::splat(f32::INFINITY), Vec3::min);
        let max = self.positions.iter().copied().fold(Vec3::splat(f32::NEG_INFINITY), Vec3::max);
        Aabb { min, max }
    }

    /// The total area of the triangles in `triangles` (a part's range, say), in m².
    pub fn area(&self, triangles: Range<u32>) -> f32 {
        self.triangles[triangles.start as usize..triangles.end as usize]
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| self.positions[i as usize]);
                0.5 * (b - a).cross(c - a).length()
            })
            .sum()
    }
}

/// A run of an object's triangles that share a material (a glTF primitive).
#[derive(Clone, Debug)]
pub struct MaterialRange {
    pub material: u32,
    pub triangles: Range<u32>,
}

#[derive(Clone, Debug)]
pub struct Material {
    pub name: String,
    /// Linear RGB base colour factor.
    pub base_color: Vec3,
    /// The base colour factor's alpha: coverage, for [`AlphaMode::Mask`].
    pub alpha: f32,
    pub base_color_texture: Option<TextureRef>,
    pub metallic: f32,
    pub roughness: f32,
    /// Roughness in G, metalness in B, as glTF says; multiplies the factors.
    pub metallic_roughness_texture: Option<TextureRef>,
    /// Tangent-space normals and glTF's `scale` of their x and y.
    pub normal_texture: Option<(TextureRef, f32)>,
    /// Emitted radiance (linear RGB), before the emissive texture.
    pub emission: Vec3,
    /// Multiplies `emission` where the surface is.
    pub emissive_texture: Option<TextureRef>,
    /// `KHR_materials_specular` factor (1 without the extension): scales the dielectric
    /// specular lobe; 0 leaves pure Lambert diffuse.
    pub specular: f32,
    pub double_sided: bool,
    pub alpha_mode: AlphaMode,
}

/// glTF's `alphaMode`, as rrf draws it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AlphaMode {
    /// Every surface point is solid (also `BLEND`, with an import warning).
    Opaque,
    /// Points whose alpha is below the cutoff are not there: rays pass, pixels are discarded.
    Mask { cutoff: f32 },
}

/// A material's values at one surface point: factors times textures.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shading {
    pub base_color: Vec3,
    pub alpha: f32,
    pub metallic: f32,
    pub roughness: f32,
    /// Emitted radiance, on the side(s) the material emits from.
    pub emission: Vec3,
    /// The normal map's tangent-space normal, scaled, not normalized; `None` without one.
    pub tangent_normal: Option<Vec3>,
}

impl Material {
    /// Whether the material emits anywhere: its surfaces are area lights.
    pub fn is_emissive(&self) -> bool {
        self.emission.max_element() > 0.0
    }

    /// Whether the material is a plain light: emissive and untextured emission. Such surfaces
    /// show their emission and learn nothing; a textured emitter (a lamp's decal, a screen)
    /// also reflects, so it gets networks like any surface.
    pub fn is_plain_emitter(&self) -> bool {
        self.is_emissive() && self.emissive_texture.is_none()
    }

    /// Whether every point of the material is pure Lambert diffuse (`KHR_materials_specular`
    /// factor 0, metallic factor 0: a metallic texture only scales the factor), so that the light
    /// it reflects is the same in every direction: every `Bsdf` made from it is then Lambert too
    /// (`Bsdf::is_lambert`, the same test on one shading point's values).
    pub fn is_lambert(&self) -> bool {
        self.specular == 0.0 && self.metallic == 0.0
    }

    /// Its base colour, metallic-roughness, normal and emissive textures, in that order (the
    /// G-buffer's).
    pub fn textures(&self) -> [Option<TextureRef>; 4] {
        [
            self.base_color_texture,
            self.metallic_roughness_texture,
            self.normal_texture.map(|n| n.0),
            self.emissive_texture,
        ]
    }

    /// Whether the surface point at `uv` is there at all (alpha mask).
    pub fn covers(&self, textures: &[Texture], uv: Vec2) -> bool {
        match self.alpha_mode {
            AlphaMode::Opaque => true,
            AlphaMode::Mask { cutoff } => {
                let texture = self.base_color_texture.map_or(1.0, |t| t.sample(textures, uv).w);
                self.alpha * texture >= cutoff
            }
        }
    }

    /// The material at `uv`; the GPU's twin is `material_at` in `gbuffer.frag`.
    pub fn shading(&self, textures: &[Texture], uv: Vec2) -> Shading {
        let base = self.base_color_texture.map_or(Vec4::ONE, |t| t.sample(textures, uv));
        let mr = self.metallic_roughness_texture.map_or(Vec4::ONE, |t| t.sample(textures, uv));
        let emissive = self.emissive_texture.map_or(Vec3::ONE, |t| t.sample(textures, uv).truncate());
        let tangent_normal = self.normal_texture.map(|(t, scale)| {
            let n = t.sample(textures, uv).truncate() * 2.0 - Vec3::ONE;
            Vec3::new(n.x * scale, n.y * scale, n.z)
        });
        Shading {
            base_color: self.base_color * base.truncate(),
            alpha: self.alpha * base.w,
            metallic: self.metallic * mr.z,
            roughness: self.roughness * mr.y,
            emission: self.emission * emissive,
            tangent_normal,
        }
    }
}

#[derive(Clone, Debug)]
pub struct PointLight {
    pub name: String,
    /// The glTF node; `None` for the light a sidecar adds.
    pub node: Option<usize>,
    pub position: Vec3,
    /// Radiant intensity (linear RGB, W/sr); on a spot light's axis.
    pub intensity: Vec3,
    /// For a spot light (`KHR_lights_punctual` type `spot`), its cone; `None` shines everywhere.
    pub cone: Option<Cone>,
}

/// A spot light's cone, with glTF's falloff: full intensity within the inner angle, none
/// outside the outer one, and in between the square of a linear ramp in the cosine.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cone {
    /// Where the spot points (unit, world space): the node's -z.
    pub direction: Vec3,
    pub cos_inner: f32,
    pub cos_outer: f32,
}

impl Cone {
    /// The share of the intensity sent along `to` (unit, from the light).
    pub fn attenuation(&self, to: Vec3) -> f32 {
        let scale = 1.0 / (self.cos_inner - self.cos_outer).max(1e-3);
        let t = ((self.direction.dot(to) - self.cos_outer) * scale).clamp(0.0, 1.0);
        t * t
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct View {
    pub name: String,
    pub eye: Vec3,
    pub target: Vec3,
    pub up: Vec3,
    /// Vertical field of view, degrees.
    pub fov_y: f32,
}

/// The light the networks learn to follow.
#[derive(Clone, Debug)]
pub struct MovingLight {
    pub node_name: String,
    pub kind: LightKind,
    /// Where the glTF puts the light: the node's world translation.
    pub default_position: Vec3,
    /// The box the position may take.
    pub bounds: Aabb,
}

/// One light of a configuration: a copy of the moving light at `position`, emitting the
/// glTF's emission times `scale` (per channel: colour × intensity).
///
/// Light transport is linear in the emission, so one trained model serves any number of
/// copies: a renderer evaluates the networks once per copy, at its position, scales each by
/// the copy's `scale` and sums them (the RRF paper's several lights). The path tracer places
/// every copy in the scene instead.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlacedLight {
    pub position: Vec3,
    pub scale: Vec3,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LightKind {
    /// Index into [`Scene::point_lights`].
    Point(usize),
    /// Id of the emissive object; moving the light translates it.
    Area(u32),
}

impl Scene {
    /// Loads a scene folder (holding `scene.gltf` or `scene.glb`) or a glTF file. The sidecar
    /// is always the glTF's path with the extension `.toml` ([`Scene::sidecar_file`]).
    pub fn load(path: &Path) -> Result<Self, SceneError> {
        let (gltf_path, name) = locate(path)?;
        let bytes =
            std::fs::read(&gltf_path).map_err(|e| SceneError::new(&gltf_path, "", format!("cannot read: {e}")))?;
        let sidecar = gltf_path.with_extension("toml");
        let mut scene = gltf_import::import(&gltf_path, &bytes, sidecar.is_file().then_some(&sidecar), name)?;
        let beside = gltf_path.with_file_name("scene.toml");
        if !sidecar.is_file() && beside.is_file() {
            scene.warnings.push(format!(
                "{} is not read: the sidecar of {} is {}",
                beside.display(),
                gltf_path.display(),
                sidecar.display()
            ));
        }
        Ok(scene)
    }

    /// Where this scene's sidecar is, or would be: the glTF's path with the extension `.toml`.
    pub fn sidecar_file(&self) -> PathBuf {
        self.gltf_path.with_extension("toml")
    }

    /// Where this scene's model goes by default: `model.safetensors` beside a `scene.gltf` or
    /// `scene.glb` (a scene folder), else the glTF's path with the extension `.safetensors`,
    /// so that two glTF files in one folder keep their models apart.
    pub fn model_file(&self) -> PathBuf {
        match self.gltf_path.file_stem().and_then(|s| s.to_str()) {
            Some("scene") => self.gltf_path.with_file_name("model.safetensors"),
            _ => self.gltf_path.with_extension("safetensors"),
        }
    }

    /// Imports glTF or GLB `bytes` as if read from `file`, without a sidecar: external buffers
    /// and images resolve against `file`'s folder.
    pub fn from_gltf_bytes(file: &Path, bytes: &[u8]) -> Result<Self, SceneError> {
        let name = file.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
        gltf_import::import(file, bytes, None, name)
    }

    pub fn triangle_count(&self) -> usize {
        self.objects.iter().map(|o| o.triangles.len()).sum()
    }

    pub fn object_by_name(&self, name: &str) -> Option<&Object> {
        self.objects.iter().find(|o| o.name == name)
    }

    pub fn view(&self, name: &str) -> Option<&View> {
        self.views.iter().find(|v| v.name == name)
    }

    /// Emissive objects: every object with an emissive material is an area light.
    pub fn area_lights(&self) -> impl Iterator<Item = &Object> {
        self.objects.iter().filter(|o| o.parts.iter().any(|p| self.materials[p.material as usize].is_emissive()))
    }

    /// The moving light where the glTF puts it, as bright as the glTF makes it: the light the
    /// networks were trained with. Without a moving light, a light at the origin (the
    /// networks' light inputs are then constant).
    pub fn default_light(&self) -> PlacedLight {
        let position = self.moving_light.as_ref().map_or(Vec3::ZERO, |l| l.default_position);
        PlacedLight { position, scale: Vec3::ONE }
    }

    /// The lights besides the moving one, by name: the networks learned their light together
    /// with the moving light's, so it cannot be scaled or copied with the moving light.
    pub fn static_lights(&self) -> Vec<String> {
        let moving = self.moving_light.as_ref().map(|l| l.kind);
        let points = self.point_lights.iter().enumerate().filter(|&(i, _)| moving != Some(LightKind::Point(i)));
        let areas = self.area_lights().filter(|o| moving != Some(LightKind::Area(o.id)));
        points.map(|(_, l)| l.name.clone()).chain(areas.map(|o| o.name.clone())).collect()
    }

    /// The bounding box of all geometry.
    pub fn bounds(&self) -> Aabb {
        let mut b = Aabb { min: Vec3::splat(f32::INFINITY), max: Vec3::splat(f32::NEG_INFINITY) };
        for p in self.objects.iter().flat_map(|o| &o.positions) {
            b.min = b.min.min(*p);
            b.max = b.max.max(*p);
        }
        b
    }
}

/// The glTF file of `path` and the scene's name.
fn locate(path: &Path) -> Result<(PathBuf, String), SceneError> {
    if path.is_dir() {
        let gltf = GLTF_NAMES.iter().map(|n| path.join(n)).find(|p| p.is_file()).ok_or_else(|| {
            SceneError::new(path, "", format!("no scene here: expected {} or {}", GLTF_NAMES[0], GLTF_NAMES[1]))
        })?;
        let name = path.canonicalize().ok().and_then(|p| p.file_name().map(|n| n.to_string_lossy().into_owned()));
        Ok((gltf, name.unwrap_or_else(|| "scene".into())))
    } else if path.is_file() {
        let name = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
        Ok((path.to_path_buf(), name))
    } else {
        Err(SceneError::new(path, "", "no such file or folder"))
    }
}
