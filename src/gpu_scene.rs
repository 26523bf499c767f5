//! What the renderer gets from a scene: flat G-buffer vertices and per-frame constants. The
//! camera matches the path tracer's ([`rrf_baker::trace::Camera`]) pixel for pixel.

use rrf_baker::glam::{Mat4, Vec3, Vec4};
use rrf_baker::scene::{self, AlphaMode, ColorSpace, LightKind, Mirror, PlacedLight, Scene, View};
use rrf_renderer::lights::{NetworkLight, PointLightShape, Spot};
use rrf_renderer::passes::gbuffer::{GBufferConstants, LightCopy};
use rrf_renderer::passes::mesh::{GBufferVertex, SurfaceMaterial, TextureRef};
use rrf_renderer::passes::mirror::Reflected;
use rrf_renderer::vk;

/// The object id of the moving light's own geometry (an area light), if it has any.
pub fn moving_light_object(scene: &Scene) -> Option<u32> {
    match scene.moving_light.as_ref().map(|l| l.kind) {
        Some(LightKind::Area(id)) => Some(id),
        _ => None,
    }
}

/// Where the G-buffer draws the moving light's geometry for each of `lights`, given where the
/// glTF puts the light (`default`), and how its emission is scaled there.
pub fn light_copies(default: Vec3, lights: &[PlacedLight]) -> Vec<LightCopy> {
    lights.iter().map(|l| LightCopy { offset: (l.position - default).to_array(), scale: l.scale.to_array() }).collect()
}

/// The point light whose direct light the network pass computes in analytic mode: the
/// scene's moving light, which must be a point or spot light and the scene's only light.
pub fn analytic_light(scene: &Scene) -> anyhow::Result<PointLightShape> {
    let Some(LightKind::Point(i)) = scene.moving_light.as_ref().map(|l| l.kind) else {
        anyhow::bail!(
            "--direct analytic needs a moving point or spot light; scene {} has {}",
            scene.name,
            if scene.moving_light.is_some() { "a moving area light (use --direct learned)" } else { "no moving light" }
        );
    };
    let others = scene.static_lights();
    if !others.is_empty() {
        anyhow::bail!(
            "--direct analytic computes the moving light's direct light only, and scene {} is also lit by {}",
            scene.name,
            others.join(", ")
        );
    }
    let light = &scene.point_lights[i];
    Ok(PointLightShape {
        intensity: light.intensity.to_array(),
        spot: light.cone.map(|c| Spot { axis: c.direction.to_array(), cos_inner: c.cos_inner, cos_outer: c.cos_outer }),
    })
}

/// `lights` as the network pass reads them.
pub fn network_lights(lights: &[PlacedLight]) -> Vec<NetworkLight> {
    lights
        .iter()
        .map(|l| NetworkLight { position: l.position.extend(1.0).to_array(), scale: l.scale.extend(0.0).to_array() })
        .collect()
}

/// The scene's vertices where the glTF puts them, and its triangles as indices into them; the
/// moving light's geometry follows each light through a [`LightCopy`]. A
/// vertex is shared by the triangles of one object part (one material).
pub fn gbuffer_mesh(scene: &Scene) -> (Vec<GBufferVertex>, Vec<u32>) {
    let mut vertices = Vec::new();
    let mut indices = Vec::with_capacity(scene.triangle_count() * 3);
    for object in &scene.objects {
        // Where each of the object's vertices went in this part, or u32::MAX.
        let mut placed = vec![u32::MAX; object.positions.len()];
        for part in &object.parts {
            placed.fill(u32::MAX);
            for t in part.triangles.clone() {
                for &v in &object.triangles[t as usize] {
                    let slot = &mut placed[v as usize];
                    if *slot == u32::MAX {
                        *slot = vertices.len() as u32;
                        vertices.push(GBufferVertex {
                            position: object.positions[v as usize].to_array(),
                            normal: object.normals[v as usize].to_array(),
                            uv: object.uvs[v as usize].to_array(),
                            tangent: object.tangents[v as usize].to_array(),
                            object: object.id,
                            material: part.material,
                        });
                    }
                    indices.push(*slot);
                }
            }
        }
    }
    (vertices, indices)
}

/// Each material's emitted radiance (rgb, before its emissive texture) and specular factor,
/// as the network pass reads them.
pub fn network_materials(scene: &Scene) -> Vec<[f32; 4]> {
    scene.materials.iter().map(|m| m.emission.extend(m.specular).to_array()).collect()
}

/// The materials as the G-buffer pass reads them, and every texture's texels after one another
/// (RGBA8 in a word, r in the low byte). Textures of more than [`TextureRef::MAX_SIDE`] texels
/// a side cannot be told to the GPU; the importer allows no more than 16384.
pub fn surface_materials(scene: &Scene) -> (Vec<SurfaceMaterial>, Vec<u32>) {
    let mut first_texel = Vec::with_capacity(scene.textures.len());
    let mut texels = Vec::new();
    for t in &scene.textures {
        first_texel.push(texels.len() as u32);
        texels.extend(t.texels.iter().map(|&rgba| u32::from_le_bytes(rgba)));
    }
    let texture = |r: Option<scene::TextureRef>| match r {
        None => TextureRef::default(),
        Some(r) => {
            let t = &scene.textures[r.texture as usize];
            let srgb = if t.color_space == ColorSpace::Srgb { TextureRef::SRGB } else { 0 };
            TextureRef {
                matrix: r.transform.matrix,
                offset: r.transform.offset.to_array(),
                first_texel: first_texel[r.texture as usize],
                shape: t.width.min(TextureRef::MAX_SIDE)
                    | t.height.min(TextureRef::MAX_SIDE) << 15
                    | srgb
                    | TextureRef::PRESENT,
            }
        }
    };
    let materials = scene
        .materials
        .iter()
        .map(|m| SurfaceMaterial {
            base_color: m.base_color.extend(m.alpha).to_array(),
            factors: [
                m.metallic,
                m.roughness,
                m.normal_texture.map_or(1.0, |n| n.1),
                match m.alpha_mode {
                    AlphaMode::Opaque => -1.0,
                    AlphaMode::Mask { cutoff } => cutoff,
                },
            ],
            textures: m.textures().map(texture),
            emits_back: u32::from(m.double_sided),
            pad: [0; 3],
        })
        .collect();
    (materials, texels)
}

/// The G-buffer pass's constants: the view-projection into Vulkan clip space (y down, depth
/// 0 at `NEAR` to 1 at `FAR`), and object `light_object` (the moving light's), which the pass
/// draws once per light copy.
pub fn gbuffer_constants(view: &View, aspect: f32, light_object: Option<u32>) -> GBufferConstants {
    let (world_to_view, projection) = camera_matrices(view, aspect);
    GBufferConstants {
        view_projection: (projection * world_to_view).to_cols_array_2d(),
        eye: view.eye.extend(1.0).to_array(),
        light_offset: [0.0; 4],
        light_scale: [1.0; 4],
        light_object: light_object.map_or(0, |id| id + 1),
        pad: [0; 3],
    }
}

/// The view's world-to-view matrix (right-handed, looking down -z) and its projection.
fn camera_matrices(view: &View, aspect: f32) -> (Mat4, Mat4) {
    const NEAR: f32 = 0.01;
    const FAR: f32 = 1000.0;
    let forward = (view.target - view.eye).normalize();
    let right = forward.cross(view.up).normalize_or(Vec3::X);
    let up = right.cross(forward);
    let world_to_view = Mat4::from_cols(
        Vec4::new(right.x, up.x, -forward.x, 0.0),
        Vec4::new(right.y, up.y, -forward.y, 0.0),
        Vec4::new(right.z, up.z, -forward.z, 0.0),
        Vec4::new(-right.dot(view.eye), -up.dot(view.eye), forward.dot(view.eye), 1.0),
    );
    let t = (view.fov_y.to_radians() * 0.5).tan();
    let (a, b) = (FAR / (NEAR - FAR), NEAR * FAR / (NEAR - FAR));
    let projection = Mat4::from_cols(
        Vec4::new(1.0 / (t * aspect), 0.0, 0.0, 0.0),
        Vec4::new(0.0, -1.0 / t, 0.0, 0.0),
        Vec4::new(0.0, 0.0, a, -1.0),
        Vec4::new(0.0, 0.0, b, 0.0),
    );
    (world_to_view, projection)
}

/// `mirror` as a frame from `view` sees it: the scene reflected in its plane and seen from
/// `view`, clipped to what lies in front of the mirror (Lengyel's oblique near plane, so that
/// nothing behind the mirror shows in it). `None` when the camera is in the mirror's plane.
/// `area` is the part of the frame that the mirror may cover.
pub fn reflected(
    view: &View,
    aspect: f32,
    light_object: Option<u32>,
    mirror: &Mirror,
    area: vk::Rect2D,
) -> Option<Reflected> {
    let normal = mirror.normal_towards(view.eye)?;
    // The plane on the camera's side: n·p = d.
    let d = mirror.offset * normal.dot(mirror.normal);
    let reflection = Mat4::from_cols(
        (Vec3::X - 2.0 * normal.x * normal).extend(0.0),
        (Vec3::Y - 2.0 * normal.y * normal).extend(0.0),
        (Vec3::Z - 2.0 * normal.z * normal).extend(0.0),
        (2.0 * d * normal).extend(1.0),
    );
    let (world_to_view, mut projection) = camera_matrices(view, aspect);
    let seen_to_view = world_to_view * reflection;
    // Geometry closer to the mirror's plane than this is the mirror itself, or behind it.
    let gap = 1e-4 * (1.0 + d.abs());
    let plane = seen_to_view.inverse().transpose() * normal.extend(-d - gap);
    let clip_plane = projection.inverse().transpose() * plane;
    let corner = projection.inverse() * Vec4::new(clip_plane.x.signum(), clip_plane.y.signum(), 1.0, 1.0);
    let scale = projection.row(3).dot(corner) / plane.dot(corner);
    for column in 0..4 {
        projection.col_mut(column)[2] = scale * plane[column];
    }
    let eye = reflection.transform_point3(view.eye);
    Some(Reflected {
        object: mirror.object,
        normal: normal.to_array(),
        gbuffer: GBufferConstants {
            view_projection: (projection * seen_to_view).to_cols_array_2d(),
            eye: eye.extend(1.0).to_array(),
            ..gbuffer_constants(view, aspect, light_object)
        },
        area,
    })
}
