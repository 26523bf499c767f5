//! glTF 2.0 (`.gltf` with external or embedded buffers, and `.glb`) to [`Scene`].
//!
//! Everything a malformed file could make the `gltf` crate panic on (accessor ranges, index
//! ranges) is checked first, so bad input is an error that names the element, never a panic.
//! Points and lines are skipped with a warning that counts them; triangle strips and fans
//! are turned into triangle lists.

use std::collections::{HashMap, HashSet};
use std::path::Path;

use glam::{Mat3, Mat4, Vec2, Vec3, Vec4};
use gltf::buffer::Data as BufferData;
use gltf::mesh::Mode;

use super::content_hash::content_hashes;
use super::error::{element_name, SceneError};
use super::external;
use super::sidecar::{Aabb, LightDomain, Sidecar};
use super::texture::{ColorSpace, Texture, TextureRef, UvTransform};
use super::{
    AlphaMode, Cone, LightKind, Material, MaterialRange, MovingLight, Object, PointLight, PointLightUnits, Scene, View,
    CANDELA_PER_WATT, MAX_COORDINATE, MAX_EMISSION,
};

/// Extensions a file may list in `extensionsRequired`.
const SUPPORTED_EXTENSIONS: &[&str] =
    &["KHR_lights_punctual", "KHR_materials_emissive_strength", "KHR_materials_specular", "KHR_texture_transform"];

/// Imports the glTF or GLB `bytes` of `file` with the sidecar at `sidecar_path`, if any;
/// external files resolve against `file`'s folder.
pub(super) fn import(
    file: &Path,
    bytes: &[u8],
    sidecar_path: Option<&Path>,
    name: String,
) -> Result<Scene, SceneError> {
    let (document, blob) = parse_document(file, bytes)?;
    let base = file.parent().unwrap_or(Path::new("."));
    let buffers = external::load_buffers(file, &document, base, blob)?;
    let images = external::load_images(file, &document, base, &buffers)?;
    let sidecar = match sidecar_path {
        Some(path) => Sidecar::read(path)?,
        None => Sidecar::default(),
    };

    let mut importer = Importer {
        file,
        buffers: &buffers,
        images: &images,
        warnings: Vec::new(),
        textures: Vec::new(),
        texture_ids: HashMap::new(),
    };
    let materials = importer.materials(&document)?;
    // glTF's default material, if a primitive uses it, follows the file's own.
    let default_material = document.materials().len();
    let Nodes { objects, mut point_lights, mut views } = importer.nodes(&document, &sidecar, default_material)?;
    let sidecar_file = sidecar_path.unwrap_or(file);
    views.extend(sidecar_views(&sidecar, sidecar_file)?);
    let moving_light = match &sidecar.light {
        None => None,
        Some(domain) => {
            let lights = Lights { file, sidecar_file, objects: &objects, materials: &materials };
            Some(lights.moving_light(domain, &mut point_lights)?)
        }
    };

    let mut scene = Scene {
        name,
        gltf_path: file.to_path_buf(),
        sidecar_path: sidecar_path.map(Path::to_path_buf),
        objects,
        materials,
        textures: importer.textures,
        point_lights,
        views,
        moving_light,
        camera_box: sidecar.camera.as_ref().map(|c| Aabb { min: c.min.into(), max: c.max.into() }),
        bake: sidecar.bake,
        eval: sidecar.eval,
        warnings: importer.warnings,
        content_hash: 0,
        light_transport_hash: 0,
    };
    let curved_mirrors = scene.curved_mirror_warnings();
    scene.warnings.extend(curved_mirrors);
    (scene.content_hash, scene.light_transport_hash) = content_hashes(&scene);
    Ok(scene)
}

/// The glTF document of `bytes` and its GLB binary chunk, checked: required extensions that
/// rrf supports, nothing the `gltf` crate would panic on, and the crate's own validation.
fn parse_document(file: &Path, bytes: &[u8]) -> Result<(gltf::Document, Option<Vec<u8>>), SceneError> {
    let err = |element: &str, problem: String| SceneError::new(file, element, problem);
    let gltf::Gltf { document, blob } = gltf::Gltf::from_slice_without_validation(bytes)
        .map_err(|e| err("", format!("not a valid glTF or GLB file: {e}")))?;
    for (i, ext) in document.extensions_required().enumerate() {
        if !SUPPORTED_EXTENSIONS.contains(&ext) {
            return Err(err(
                &format!("extensionsRequired[{i}]"),
                format!("extension {ext} is required but not supported (rrf supports {SUPPORTED_EXTENSIONS:?})"),
            ));
        }
    }
    let json = document.into_json();
    check_before_validation(&json).map_err(|(element, problem)| err(&element, problem))?;
    let document = gltf::Document::from_json(json).map_err(|e| match e {
        gltf::Error::Validation(errors) => {
            let (path, problem) = &errors[0];
            err(&path.to_string(), format!("{problem} ({} validation errors in all)", errors.len()))
        }
        e => err("", e.to_string()),
    })?;
    Ok((document, blob))
}

/// What the walk of a scene's node tree finds.
struct Nodes {
    objects: Vec<Object>,
    point_lights: Vec<PointLight>,
    /// The default view: the first perspective camera, or one that frames the whole scene.
    views: Vec<View>,
}

/// The views the sidecar names.
fn sidecar_views(sidecar: &Sidecar, sidecar_file: &Path) -> Result<Vec<View>, SceneError> {
    let mut views = Vec::new();
    for (view_name, spec) in &sidecar.views {
        if view_name == "default" {
            return Err(SceneError::new(sidecar_file, "views.default", "the name is taken by the glTF camera"));
        }
        views.push(View {
            name: view_name.clone(),
            eye: spec.eye.into(),
            target: spec.target.into(),
            up: Vec3::Y,
            fov_y: spec.fov_y,
        });
    }
    Ok(views)
}

/// What the sidecar's moving light is checked against.
struct Lights<'a> {
    file: &'a Path,
    sidecar_file: &'a Path,
    objects: &'a [Object],
    materials: &'a [Material],
}

impl Lights<'_> {
    /// The sidecar's moving light: a point light or an emissive object of the glTF that emits
    /// and lies inside the box, or a new point light (`intensity`) added to `point_lights`.
    fn moving_light(
        &self,
        domain: &LightDomain,
        point_lights: &mut Vec<PointLight>,
    ) -> Result<MovingLight, SceneError> {
        let error = |element: &str, problem: String| SceneError::new(self.sidecar_file, element, problem);
        let bounds = Aabb { min: domain.min.into(), max: domain.max.into() };
        let emissive = |o: &&Object| o.parts.iter().any(|p| self.materials[p.material as usize].is_emissive());
        if let Some(intensity) = domain.intensity {
            let taken = point_lights.iter().any(|l| l.name == domain.node)
                || self.objects.iter().any(|o| o.name == domain.node);
            if taken {
                return Err(error(
                    "light.intensity",
                    format!(
                        "adds a new light, but {:?} names a node of the glTF; remove `intensity` to move that one",
                        domain.node
                    ),
                ));
            }
            point_lights.push(PointLight {
                name: domain.node.clone(),
                node: None,
                position: (bounds.min + bounds.max) * 0.5,
                intensity: Vec3::from(intensity),
                cone: None,
            });
        }
        let dark = |what: &str| Err(error("light.node", format!("node {:?} {what}", domain.node)));
        let (kind, default_position) = if let Some(i) = point_lights.iter().position(|l| l.name == domain.node) {
            if point_lights[i].intensity.max_element() <= 0.0 {
                return dark("emits nothing: its point light has zero intensity");
            }
            (LightKind::Point(i), point_lights[i].position)
        } else if let Some(o) = self.objects.iter().find(|o| o.name == domain.node) {
            if !emissive(&o) {
                return dark("is not a light: it has no emissive material and no point light");
            }
            if emitting_area(o, self.materials) <= 0.0 {
                return dark("is an emitter with no area: its emissive triangles are degenerate");
            }
            (LightKind::Area(o.id), o.origin)
        } else {
            let points = point_lights.iter().map(|l| l.name.as_str());
            let lights: Vec<&str> =
                points.chain(self.objects.iter().filter(emissive).map(|o| o.name.as_str())).collect();
            return Err(error(
                "light.node",
                format!("no light node named {:?} in {} (lights: {lights:?})", domain.node, self.file.display()),
            ));
        };
        if !bounds.contains(default_position) {
            return Err(error(
                "light",
                format!("the glTF puts {:?} at {default_position}, outside the box", domain.node),
            ));
        }
        Ok(MovingLight { node_name: domain.node.clone(), kind, default_position, bounds })
    }
}

/// What the `gltf` crate (1.4) panics on instead of reporting, found by fuzzing: a POSITION
/// index past the accessors (read by its validation before it is checked), and an image
/// without a source, or from a buffer view without a MIME type (unwrapped by its reader).
fn check_before_validation(root: &gltf::json::Root) -> Result<(), (String, String)> {
    for (i, image) in root.images.iter().enumerate() {
        let problem = match (&image.uri, &image.buffer_view, &image.mime_type) {
            (None, None, _) => "has neither a uri nor a bufferView",
            (Some(_), Some(_), _) => "has both a uri and a bufferView",
            (None, Some(_), None) => "comes from a bufferView but has no mimeType",
            _ => continue,
        };
        return Err((format!("images[{i}]"), problem.into()));
    }
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let position = primitive.attributes.get(&gltf::json::validation::Checked::Valid(gltf::Semantic::Positions));
            if let Some(index) = position.filter(|i| i.value() >= root.accessors.len()) {
                return Err((
                    format!("meshes[{m}].primitives[{p}].attributes.POSITION"),
                    format!("accessors[{}] does not exist ({} accessors)", index.value(), root.accessors.len()),
                ));
            }
        }
    }
    Ok(())
}

/// The default view from a perspective camera's world transform; the camera looks down its
/// local -z with +y up.
fn camera_view(world: &Mat4, yfov: f32) -> Result<View, String> {
    if !(yfov > 0.0 && yfov < std::f32::consts::PI) {
        return Err(format!("camera field of view {yfov} rad must lie between 0 and π"));
    }
    let eye = world.transform_point3(Vec3::ZERO);
    let forward = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
    let up = world.transform_vector3(Vec3::Y).normalize_or_zero();
    if forward == Vec3::ZERO || up == Vec3::ZERO || forward.cross(up).length() < 1e-3 {
        return Err("the camera's transform leaves it no viewing direction (a zero or degenerate scale)".into());
    }
    Ok(View { name: "default".into(), eye, target: eye + forward, up, fov_y: yfov.to_degrees() })
}

/// The default view of a glTF without a camera: from the +z side, far enough back that the
/// bounding sphere of `bounds` fits in a 45° field of view.
fn framing_view(bounds: &Aabb) -> View {
    const FOV_Y: f32 = 45.0;
    let centre = (bounds.min + bounds.max) * 0.5;
    let radius = ((bounds.max - bounds.min).length() * 0.5).max(1e-3);
    let distance = radius / (FOV_Y.to_radians() * 0.5).sin();
    View { name: "default".into(), eye: centre + Vec3::Z * distance, target: centre, up: Vec3::Y, fov_y: FOV_Y }
}

/// A spot light's cone from its angles and its node's -z; `None` for a point light.
fn spot_cone(light: &gltf::khr_lights_punctual::Light, world: &Mat4) -> Result<Option<Cone>, String> {
    let gltf::khr_lights_punctual::Kind::Spot { inner_cone_angle, outer_cone_angle } = light.kind() else {
        return Ok(None);
    };
    if !(0.0 <= inner_cone_angle
        && inner_cone_angle < outer_cone_angle
        && outer_cone_angle <= std::f32::consts::FRAC_PI_2)
    {
        return Err(format!(
            "spot cone angles {inner_cone_angle} and {outer_cone_angle} rad must satisfy 0 ≤ inner < outer ≤ π/2"
        ));
    }
    let direction = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
    if direction == Vec3::ZERO {
        return Err("the spot light's transform leaves it no direction (a zero scale)".into());
    }
    Ok(Some(Cone { direction, cos_inner: inner_cone_angle.cos(), cos_outer: outer_cone_angle.cos() }))
}

/// Total area of an object's emissive triangles.
fn emitting_area(object: &Object, materials: &[Material]) -> f32 {
    object
        .parts
        .iter()
        .filter(|p| materials[p.material as usize].is_emissive())
        .map(|p| object.area(p.triangles.clone()))
        .sum()
}

struct Importer<'a> {
    file: &'a Path,
    buffers: &'a [BufferData],
    images: &'a [gltf::image::Data],
    warnings: Vec<String>,
    textures: Vec<Texture>,
    texture_ids: HashMap<(usize, ColorSpace), u32>,
}

impl Importer<'_> {
    /// The file's materials, then glTF's default material if a primitive has none.
    fn materials(&mut self, document: &gltf::Document) -> Result<Vec<Material>, SceneError> {
        let mut materials: Vec<Material> =
            document.materials().map(|m| self.material(&m, document.as_json())).collect::<Result<_, _>>()?;
        let uses_default = document.meshes().flat_map(|m| m.primitives()).any(|p| p.material().index().is_none());
        // glTF's default material, for primitives without one: white, fully metallic, fully rough.
        if uses_default {
            materials.push(Material {
                name: "default".into(),
                base_color: Vec3::ONE,
                alpha: 1.0,
                base_color_texture: None,
                metallic: 1.0,
                roughness: 1.0,
                metallic_roughness_texture: None,
                normal_texture: None,
                emission: Vec3::ZERO,
                emissive_texture: None,
                specular: 1.0,
                double_sided: false,
                alpha_mode: AlphaMode::Opaque,
            });
        }
        Ok(materials)
    }

    /// Walks the default scene's node tree: an object per mesh node (primitives without a
    /// material get `default_material`), a point light per point or spot light, the first
    /// perspective camera as the default view.
    fn nodes(
        &mut self,
        document: &gltf::Document,
        sidecar: &Sidecar,
        default_material: usize,
    ) -> Result<Nodes, SceneError> {
        let err = |element: &str, problem: String| SceneError::new(self.file, element, problem);
        let gltf_scene = document
            .default_scene()
            .or_else(|| document.scenes().next())
            .ok_or_else(|| err("scenes", "the file has no scene".into()))?;
        let mut found = Nodes { objects: Vec::new(), point_lights: Vec::new(), views: Vec::new() };
        let mut visited = HashSet::new();
        let mut skipped_primitives = 0;
        let mut stack: Vec<(gltf::Node, Mat4)> =
            gltf_scene.nodes().map(|n| (n, Mat4::IDENTITY)).collect::<Vec<_>>().into_iter().rev().collect();
        while let Some((node, parent)) = stack.pop() {
            let element = element_name("nodes", node.index(), node.name());
            if !visited.insert(node.index()) {
                return Err(err(&element, "is reachable twice; the node hierarchy must be a tree".into()));
            }
            let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
            if !world.is_finite() {
                return Err(err(&element, "has a non-finite transform".into()));
            }
            let node_name = node.name().map(str::to_owned).unwrap_or_else(|| format!("node{}", node.index()));

            if let Some(mesh) = node.mesh() {
                if let Some(other) = found.objects.iter().find(|o| o.name == node_name) {
                    return Err(err(
                        &element,
                        format!(
                            "object name {node_name:?} is also used by nodes[{}]; networks are keyed by name",
                            other.node
                        ),
                    ));
                }
                let id = found.objects.len() as u32;
                let object = self.object(
                    id,
                    node_name.clone(),
                    node.index(),
                    &mesh,
                    world,
                    default_material as u32,
                    &mut skipped_primitives,
                )?;
                found.objects.push(object);
            }
            if let Some(light) = node.light() {
                let light =
                    self.point_light(&element, (&node_name, node.index()), &light, world, sidecar.units.point_lights)?;
                found.point_lights.extend(light);
            }
            if let Some(camera) = node.camera() {
                match camera.projection() {
                    gltf::camera::Projection::Perspective(p) if found.views.is_empty() => {
                        found.views.push(camera_view(&world, p.yfov()).map_err(|problem| err(&element, problem))?);
                    }
                    gltf::camera::Projection::Perspective(_) => {
                        self.warnings.push(format!("{element}: only the first camera is used"))
                    }
                    gltf::camera::Projection::Orthographic(_) => {
                        self.warnings.push(format!("{element}: orthographic cameras are not supported; skipped"))
                    }
                }
            }
            stack.extend(node.children().map(|c| (c, world)).collect::<Vec<_>>().into_iter().rev());
        }
        if found.objects.iter().all(|o| o.triangles.is_empty()) {
            return Err(err(
                "",
                "has no triangles to render (only meshes of TRIANGLES, TRIANGLE_STRIP or TRIANGLE_FAN are drawn)"
                    .into(),
            ));
        }
        if found.views.is_empty() {
            let bounds = found.objects.iter().flat_map(|o| &o.positions).fold(
                Aabb { min: Vec3::INFINITY, max: Vec3::NEG_INFINITY },
                |b, &p| Aabb { min: b.min.min(p), max: b.max.max(p) },
            );
            found.views.push(framing_view(&bounds));
            self.warnings.push("the glTF has no camera: the default view looks at the whole scene along -z".into());
        }
        if skipped_primitives > 0 {
            self.warnings
                .push(format!("skipped {skipped_primitives} primitives that are not triangles (points or lines)"));
        }
        Ok(found)
    }

    /// The point or spot light of node `node` called `name` (`element`) at `world`, its
    /// intensity read in `units`; a directional light is skipped with a warning.
    fn point_light(
        &mut self,
        element: &str,
        (name, node): (&str, usize),
        light: &gltf::khr_lights_punctual::Light,
        world: Mat4,
        units: PointLightUnits,
    ) -> Result<Option<PointLight>, SceneError> {
        let err = |problem: String| SceneError::new(self.file, element, problem);
        if let gltf::khr_lights_punctual::Kind::Directional = light.kind() {
            self.warnings.push(format!(
                "{element}: directional light skipped: rrf's networks learn a light that moves inside a box, \
                 and a directional light has no position (use a distant point light or an emissive quad)"
            ));
            return Ok(None);
        }
        let watts = match units {
            PointLightUnits::Candela => light.intensity() / CANDELA_PER_WATT,
            PointLightUnits::WattsPerSteradian => light.intensity(),
        };
        let intensity = Vec3::from(light.color()) * watts;
        if !(intensity.min_element() >= 0.0 && intensity.max_element() <= MAX_EMISSION) {
            return Err(err(format!(
                "point light colour × intensity {intensity} must lie between 0 and {MAX_EMISSION:e}"
            )));
        }
        Ok(Some(PointLight {
            name: name.to_owned(),
            node: Some(node),
            position: world.transform_point3(Vec3::ZERO),
            intensity,
            cone: spot_cone(light, &world).map_err(err)?,
        }))
    }

    /// The material, with every factor checked against the range glTF gives it: values
    /// outside would make negative or non-finite radiance.
    fn material(&mut self, m: &gltf::Material, json: &gltf::json::Root) -> Result<Material, SceneError> {
        let index = m.index().unwrap_or(0);
        let name = m.name().map(str::to_owned).unwrap_or_else(|| format!("materials[{index}]"));
        let element = element_name("materials", index, m.name());
        let pbr = m.pbr_metallic_roughness();
        let [r, g, b, alpha] = pbr.base_color_factor();
        // Each factor's values, and the largest glTF allows (the least is 0).
        let factors: [(&str, Vec<f32>, f32); 6] = [
            ("baseColorFactor", vec![r, g, b, alpha], 1.0),
            ("metallicFactor", vec![pbr.metallic_factor()], 1.0),
            ("roughnessFactor", vec![pbr.roughness_factor()], 1.0),
            ("emissiveFactor", m.emissive_factor().to_vec(), 1.0),
            ("emissiveStrength", m.emissive_strength().into_iter().collect(), MAX_EMISSION),
            ("specularFactor", m.specular().map(|s| s.specular_factor()).into_iter().collect(), 1.0),
        ];
        if let Some((key, values, max)) = factors.iter().find(|(_, v, max)| !v.iter().all(|x| (0.0..=*max).contains(x)))
        {
            let shown = match values[..] {
                [value] => value.to_string(),
                _ => format!("{values:?}"),
            };
            let max = if *max == 1.0 { "1".to_string() } else { format!("{max:e}") };
            return Err(SceneError::new(self.file, element, format!("{key} {shown} must be between 0 and {max}")));
        }
        let mut texture = |info: gltf::texture::Info, space| {
            let transform = info
                .texture_transform()
                .map(|t| (UvTransform::new(t.offset(), t.rotation(), t.scale()), t.tex_coord()));
            self.texture(&name, info.texture(), info.tex_coord(), transform, space)
        };
        let base_color_texture = pbr.base_color_texture().map(|t| texture(t, ColorSpace::Srgb));
        let metallic_roughness_texture = pbr.metallic_roughness_texture().map(|t| texture(t, ColorSpace::Linear));
        let emissive_texture = m.emissive_texture().map(|t| texture(t, ColorSpace::Srgb));
        // gltf 1.4 gives no texture transform for normal textures: it is read from the JSON.
        let normal_texture = match m.normal_texture() {
            Some(t) => {
                let transform = normal_texture_transform(json, index).map_err(|e| {
                    SceneError::new(self.file, &element, format!("normalTexture KHR_texture_transform: {e}"))
                })?;
                Some((self.texture(&name, t.texture(), t.tex_coord(), transform, ColorSpace::Linear), t.scale()))
            }
            None => None,
        };
        let alpha_mode = match m.alpha_mode() {
            gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
            gltf::material::AlphaMode::Mask => AlphaMode::Mask { cutoff: m.alpha_cutoff().unwrap_or(0.5) },
            gltf::material::AlphaMode::Blend => {
                self.warnings.push(format!(
                    "{element}: alphaMode BLEND is drawn opaque (rrf has no transparency; MASK cuts out)"
                ));
                AlphaMode::Opaque
            }
        };
        let material = Material {
            base_color: Vec3::new(r, g, b),
            alpha,
            base_color_texture,
            metallic: pbr.metallic_factor(),
            roughness: pbr.roughness_factor(),
            metallic_roughness_texture,
            normal_texture,
            emission: Vec3::from(m.emissive_factor()) * m.emissive_strength().unwrap_or(1.0),
            emissive_texture,
            specular: m.specular().map_or(1.0, |s| s.specular_factor()),
            double_sided: m.double_sided(),
            alpha_mode,
            name,
        };
        // Offsets, scales and rotations beyond this would only make UVs that f32 cannot tell
        // apart, or non-finite ones.
        const MAX_TRANSFORM: f32 = 1e6;
        let unusable = |t: &TextureRef| {
            let t = t.transform;
            !t.matrix.iter().chain(&t.offset.to_array()).all(|v| v.is_finite() && v.abs() <= MAX_TRANSFORM)
        };
        if material.textures().iter().flatten().any(unusable) {
            return Err(SceneError::new(
                self.file,
                &element,
                format!("a KHR_texture_transform value is not finite or beyond ±{MAX_TRANSFORM:e}"),
            ));
        }
        if let Some(scale) = m.normal_texture().map(|t| t.scale()).filter(|s| !s.is_finite()) {
            return Err(SceneError::new(self.file, &element, format!("normalTexture scale {scale} is not finite")));
        }
        Ok(material)
    }

    /// The texture of `texture` in colour space `space` (decoded once per image and space),
    /// used through UV set `tex_coord` and its `KHR_texture_transform`, if any: the transform
    /// and its texCoord override.
    fn texture(
        &mut self,
        material: &str,
        texture: gltf::Texture,
        tex_coord: u32,
        transform: Option<(UvTransform, Option<u32>)>,
        space: ColorSpace,
    ) -> TextureRef {
        let tex_coord = transform.and_then(|t| t.1).unwrap_or(tex_coord);
        if tex_coord != 0 {
            self.warnings.push(format!("material {material:?}: texture uses TEXCOORD_{tex_coord}; UV0 is used"));
        }
        let transform = transform.map_or(UvTransform::IDENTITY, |t| t.0);
        TextureRef { texture: self.decoded(texture.source().index(), space), transform }
    }

    /// The index of image `image` decoded for colour space `space`.
    fn decoded(&mut self, image: usize, space: ColorSpace) -> u32 {
        if let Some(&id) = self.texture_ids.get(&(image, space)) {
            return id;
        }
        let data = &self.images[image];
        let texels = to_rgba8(data).unwrap_or_else(|| {
            self.warnings.push(format!("images[{image}]: pixel format {:?} unsupported; white used", data.format));
            vec![[255; 4]; (data.width * data.height) as usize]
        });
        let id = self.textures.len() as u32;
        self.textures.push(Texture {
            name: format!("images[{image}]"),
            width: data.width,
            height: data.height,
            texels,
            color_space: space,
        });
        self.texture_ids.insert((image, space), id);
        id
    }

    /// The object of mesh node `node` at `world`: its triangle primitives in world space, one
    /// material range each (`default_material` where a primitive has none); other primitives
    /// are counted in `skipped`.
    #[allow(clippy::too_many_arguments)]
    fn object(
        &mut self,
        id: u32,
        name: String,
        node: usize,
        mesh: &gltf::Mesh,
        world: Mat4,
        default_material: u32,
        skipped: &mut usize,
    ) -> Result<Object, SceneError> {
        let mut object = Object {
            id,
            name,
            node,
            origin: world.transform_point3(Vec3::ZERO),
            positions: vec![],
            normals: vec![],
            uvs: vec![],
            tangents: vec![],
            triangles: vec![],
            parts: vec![],
        };
        for prim in mesh.primitives() {
            let element = format!("{} primitives[{}]", element_name("meshes", mesh.index(), mesh.name()), prim.index());
            if !matches!(prim.mode(), Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan) {
                *skipped += 1;
                continue;
            }
            self.check_primitive(&prim, &element)?;
            let primitive = self.read_primitive(&prim, &element, world)?;
            let first = object.triangles.len() as u32;
            append(&mut object, primitive, world);
            let material = prim.material().index().map_or(default_material, |i| i as u32);
            object.parts.push(MaterialRange { material, triangles: first..object.triangles.len() as u32 });
        }
        Ok(object)
    }

    /// Checks the accessors a triangle primitive is read from: their types and bounds, and
    /// that every vertex attribute has as many elements as POSITION.
    fn check_primitive(&self, prim: &gltf::Primitive, element: &str) -> Result<(), SceneError> {
        let position_count = prim.get(&gltf::Semantic::Positions).map(|a| a.count());
        for (semantic, accessor) in prim.attributes() {
            let role = match semantic {
                gltf::Semantic::Positions => Role::Position,
                gltf::Semantic::Normals => Role::Normal,
                gltf::Semantic::TexCoords(0) => Role::TexCoord,
                gltf::Semantic::Tangents => Role::Tangent,
                _ => continue,
            };
            self.check_accessor(&accessor, role)?;
            if position_count.is_some_and(|n| n != accessor.count()) {
                return Err(SceneError::new(
                    self.file,
                    element,
                    format!(
                        "{} (accessors[{}]) has {} elements but POSITION has {}",
                        role.name(),
                        accessor.index(),
                        accessor.count(),
                        position_count.unwrap_or(0)
                    ),
                ));
            }
        }
        if let Some(indices) = prim.indices() {
            self.check_accessor(&indices, Role::Indices)?;
        }
        Ok(())
    }

    /// A checked triangle primitive's vertices in world space (at `world`) and its triangles,
    /// wound counter-clockwise.
    fn read_primitive(&self, prim: &gltf::Primitive, element: &str, world: Mat4) -> Result<Primitive, SceneError> {
        let error = |problem: String| SceneError::new(self.file, element, problem);
        let flip = world.determinant() < 0.0;
        let reader = prim.reader(|b| self.buffers.get(b.index()).map(|d| &d.0[..]));
        let local: Vec<Vec3> =
            reader.read_positions().ok_or_else(|| error("has no POSITION attribute".into()))?.map(Vec3::from).collect();
        if let Some(i) = local.iter().position(|p| !p.is_finite()) {
            return Err(error(format!("POSITION of vertex {i} is not finite")));
        }
        let n = local.len() as u32;
        let indices: Vec<u32> = match reader.read_indices() {
            Some(i) => i.into_u32().collect(),
            None => (0..n).collect(),
        };
        if let Some(bad) = indices.iter().find(|&&i| i >= n) {
            let accessor = prim.indices().map_or(0, |a| a.index());
            return Err(error(format!("index {bad} is out of range for {n} vertices (accessors[{accessor}])")));
        }
        let mut triangles = triangle_list(prim.mode(), &indices);
        if flip {
            triangles.iter_mut().for_each(|t| t.swap(1, 2));
        }
        let normals: Option<Vec<Vec3>> = reader.read_normals().map(|n| n.map(Vec3::from).collect());
        // glTF tangents only go with glTF normals; flat-shaded primitives derive theirs.
        let tangents: Option<Vec<Vec4>> = reader.read_tangents().filter(|_| normals.is_some()).map(|t| {
            let to_world = Mat3::from_mat4(world);
            let handedness = if flip { -1.0 } else { 1.0 };
            t.map(|[x, y, z, w]| {
                (to_world * Vec3::new(x, y, z))
                    .normalize_or(Vec3::X)
                    .extend(if w < 0.0 { -1.0 } else { 1.0 } * handedness)
            })
            .collect()
        });
        let uvs: Vec<Vec2> = match reader.read_tex_coords(0) {
            Some(t) => t.into_f32().map(Vec2::from).collect(),
            None => vec![Vec2::ZERO; local.len()],
        };
        let positions: Vec<Vec3> = local.iter().map(|&p| world.transform_point3(p)).collect();
        if let Some(i) = positions.iter().position(|p| !p.is_finite() || p.abs().max_element() > MAX_COORDINATE) {
            return Err(error(format!(
                "vertex {i} lies at {} in the world, more than {MAX_COORDINATE:e} m from the origin on an axis \
                 (check the node's scale and the file's units)",
                positions[i]
            )));
        }
        Ok(Primitive { positions, normals, tangents, uvs, triangles })
    }

    /// Checks that an accessor has a type glTF allows for its role, that its elements lie
    /// inside its buffer view and the view inside its buffer, so that reading it cannot go out
    /// of bounds.
    fn check_accessor(&self, accessor: &gltf::Accessor, role: Role) -> Result<(), SceneError> {
        use gltf::accessor::{DataType as T, Dimensions as D};
        let element = format!("accessors[{}]", accessor.index());
        let fail = |problem: String| Err(SceneError::new(self.file, &element, problem));
        let (kind, dimensions, normalized) = (accessor.data_type(), accessor.dimensions(), accessor.normalized());
        let allowed = match role {
            Role::Position | Role::Normal => dimensions == D::Vec3 && kind == T::F32,
            Role::TexCoord => {
                dimensions == D::Vec2 && (kind == T::F32 || (matches!(kind, T::U8 | T::U16) && normalized))
            }
            Role::Tangent => dimensions == D::Vec4 && kind == T::F32,
            Role::Indices => dimensions == D::Scalar && matches!(kind, T::U8 | T::U16 | T::U32) && !normalized,
        };
        if !allowed {
            return fail(format!(
                "{dimensions:?} of {kind:?}{} is not a type glTF allows for {}",
                if normalized { " (normalized)" } else { "" },
                role.name()
            ));
        }
        if accessor.sparse().is_some() {
            return fail("sparse accessors are not supported".into());
        }
        let Some(view) = accessor.view() else {
            return fail("has no bufferView".into());
        };
        let buffer_len = self.buffers[view.buffer().index()].len();
        let view_end = view.offset().checked_add(view.length());
        if view_end.is_none_or(|end| end > buffer_len) {
            return fail(format!(
                "bufferViews[{}] reaches past the end of buffers[{}] ({buffer_len} bytes)",
                view.index(),
                view.buffer().index()
            ));
        }
        let element_size = accessor.size();
        let stride = view.stride().unwrap_or(element_size);
        if stride < element_size {
            return fail(format!(
                "bufferViews[{}] has a byteStride of {stride}, less than the {element_size} bytes of one element",
                view.index()
            ));
        }
        if accessor.count() > 0 {
            let end = (accessor.count() - 1)
                .checked_mul(stride)
                .and_then(|n| n.checked_add(accessor.offset()))
                .and_then(|n| n.checked_add(element_size));
            if end.is_none_or(|end| end > view.length()) {
                return fail(format!(
                    "{} elements reach past the end of bufferViews[{}] ({} bytes)",
                    accessor.count(),
                    view.index(),
                    view.length()
                ));
            }
        }
        Ok(())
    }
}

/// One triangle primitive, read and placed in the world (normals in the mesh's frame).
struct Primitive {
    positions: Vec<Vec3>,
    normals: Option<Vec<Vec3>>,
    tangents: Option<Vec<Vec4>>,
    uvs: Vec<Vec2>,
    triangles: Vec<[u32; 3]>,
}

/// Adds `primitive` (of a node at `world`) to `object`: its normals to world space, or flat
/// normals where it has none (glTF's rule), and tangents derived where it has none.
fn append(object: &mut Object, primitive: Primitive, world: Mat4) {
    let Primitive { positions, normals, tangents, uvs, triangles } = primitive;
    let base = object.positions.len() as u32;
    let first = object.triangles.len();
    let has_tangents = tangents.is_some();
    match normals {
        Some(normals) => {
            let normal_matrix = Mat3::from_mat4(world).inverse().transpose();
            object.positions.extend(&positions);
            object.normals.extend(normals.iter().map(|&n| (normal_matrix * n).normalize_or(Vec3::Y)));
            object.uvs.extend(&uvs);
            object.tangents.extend(tangents.into_iter().flatten());
            object.triangles.extend(triangles.iter().map(|t| t.map(|i| base + i)));
        }
        // Each triangle gets its own vertices.
        None => {
            for t in &triangles {
                let [a, b, c] = t.map(|i| positions[i as usize]);
                let face = (b - a).cross(c - a).normalize_or(Vec3::Y);
                let v = object.positions.len() as u32;
                object.positions.extend([a, b, c]);
                object.normals.extend([face; 3]);
                object.uvs.extend(t.map(|i| uvs[i as usize]));
                object.triangles.push([v, v + 1, v + 2]);
            }
        }
    }
    if !has_tangents {
        derive_tangents(object, base as usize, first);
    }
}

/// Tangents for the vertices from `first_vertex` on, from the UV gradients of the triangles
/// from `first_triangle` on (Lengyel's method: per-triangle tangents summed at each vertex,
/// then made orthogonal to its normal). Where UVs do not vary, any tangent will do.
fn derive_tangents(object: &mut Object, first_vertex: usize, first_triangle: usize) {
    let count = object.positions.len() - first_vertex;
    let (mut t_sum, mut b_sum) = (vec![Vec3::ZERO; count], vec![Vec3::ZERO; count]);
    for triangle in &object.triangles[first_triangle..] {
        let [a, b, c] = triangle.map(|i| i as usize);
        let (e1, e2) = (object.positions[b] - object.positions[a], object.positions[c] - object.positions[a]);
        let (d1, d2) = (object.uvs[b] - object.uvs[a], object.uvs[c] - object.uvs[a]);
        let det = d1.x * d2.y - d2.x * d1.y;
        if det.abs() < 1e-12 {
            continue;
        }
        let t = (e1 * d2.y - e2 * d1.y) / det;
        let bt = (e2 * d1.x - e1 * d2.x) / det;
        for v in [a, b, c] {
            t_sum[v - first_vertex] += t;
            b_sum[v - first_vertex] += bt;
        }
    }
    for (i, (t, b)) in t_sum.into_iter().zip(b_sum).enumerate() {
        let n = object.normals[first_vertex + i];
        let tangent = (t - n * n.dot(t)).try_normalize().unwrap_or_else(|| n.any_orthonormal_vector());
        let w = if n.cross(tangent).dot(b) < 0.0 { -1.0 } else { 1.0 };
        object.tangents.push(tangent.extend(w));
    }
}

/// The `KHR_texture_transform` of material `index`'s normal texture, if it has one, and its
/// texCoord override.
fn normal_texture_transform(
    json: &gltf::json::Root,
    index: usize,
) -> Result<Option<(UvTransform, Option<u32>)>, serde_json::Error> {
    let extension = json
        .materials
        .get(index)
        .and_then(|m| m.normal_texture.as_ref())
        .and_then(|t| t.extensions.as_ref())
        .and_then(|e| e.others.get("KHR_texture_transform"));
    let Some(value) = extension else { return Ok(None) };
    let t: gltf::json::extensions::texture::TextureTransform = serde_json::from_value(value.clone())?;
    Ok(Some((UvTransform::new(t.offset.0, t.rotation.0, t.scale.0), t.tex_coord)))
}

/// What an accessor is read as.
#[derive(Clone, Copy)]
enum Role {
    Position,
    Normal,
    TexCoord,
    Tangent,
    Indices,
}

impl Role {
    fn name(self) -> &'static str {
        match self {
            Role::Position => "POSITION",
            Role::Normal => "NORMAL",
            Role::TexCoord => "TEXCOORD_0",
            Role::Tangent => "TANGENT",
            Role::Indices => "indices",
        }
    }
}

/// Triangle list from indices in any of the three triangle modes; counter-clockwise kept.
fn triangle_list(mode: Mode, indices: &[u32]) -> Vec<[u32; 3]> {
    match mode {
        Mode::TriangleStrip => (2..indices.len())
            .map(|i| {
                if i % 2 == 0 {
                    [indices[i - 2], indices[i - 1], indices[i]]
                } else {
                    [indices[i - 1], indices[i - 2], indices[i]]
                }
            })
            .collect(),
        Mode::TriangleFan => (2..indices.len()).map(|i| [indices[0], indices[i - 1], indices[i]]).collect(),
        _ => indices.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
    }
}

fn to_rgba8(data: &gltf::image::Data) -> Option<Vec<[u8; 4]>> {
    use gltf::image::Format;
    let p = &data.pixels;
    let texels = match data.format {
        Format::R8 => p.iter().map(|&v| [v, v, v, 255]).collect(),
        Format::R8G8 => p.chunks_exact(2).map(|c| [c[0], c[1], 0, 255]).collect(),
        Format::R8G8B8 => p.chunks_exact(3).map(|c| [c[0], c[1], c[2], 255]).collect(),
        Format::R8G8B8A8 => p.chunks_exact(4).map(|c| [c[0], c[1], c[2], c[3]]).collect(),
        // 16-bit channels are little-endian; keep the high byte.
        Format::R16G16B16 => p.chunks_exact(6).map(|c| [c[1], c[3], c[5], 255]).collect(),
        Format::R16G16B16A16 => p.chunks_exact(8).map(|c| [c[1], c[3], c[5], c[7]]).collect(),
        _ => return None,
    };
    Some(texels)
}
