//! What the renderer gets from a scene: flat G-buffer vertices and camera constants. The
//! camera matches the path tracer's ([`rrf_baker::trace::Camera`]) pixel for pixel.

use rrf_baker::glam::{Mat4, Vec3, Vec4};
use rrf_baker::scene::{LightKind, Scene, View};
use rrf_renderer::gbuffer::{CameraConstants, GBufferVertex};

/// Every triangle of the scene, vertex by vertex, with the moving area light moved by
/// `light_offset`.
pub fn gbuffer_vertices(scene: &Scene, light_offset: Vec3) -> Vec<GBufferVertex> {
    let moving = match scene.moving_light.as_ref().map(|l| l.kind) {
        Some(LightKind::Area(id)) => Some(id),
        _ => None,
    };
    let mut out = Vec::with_capacity(scene.triangle_count() * 3);
    for object in &scene.objects {
        let shift = if Some(object.id) == moving { light_offset } else { Vec3::ZERO };
        for part in &object.parts {
            let m = &scene.materials[part.material as usize];
            for t in part.triangles.clone() {
                for &v in &object.triangles[t as usize] {
                    out.push(GBufferVertex {
                        position: (object.positions[v as usize] + shift).to_array(),
                        normal: object.normals[v as usize].to_array(),
                        emission_roughness: m.emission.extend(m.roughness).to_array(),
                        object: object.id,
                    });
                }
            }
        }
    }
    out
}

/// View-projection into Vulkan clip space (y down, depth 0 at `NEAR` to 1 at `FAR`).
pub fn camera_constants(view: &View, aspect: f32) -> CameraConstants {
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
    CameraConstants {
        view_projection: (projection * world_to_view).to_cols_array_2d(),
        eye: view.eye.extend(1.0).to_array(),
    }
}
