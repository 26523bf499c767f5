//! The G-buffer raster pass against the path tracer's primary hits, pixel by pixel.

mod common;

use std::path::Path;

use common::{finish_clean, gpu};
use rrf::gpu_scene::{gbuffer_constants, gbuffer_mesh, surface_materials};
use rrf::shaders;
use rrf_baker::glam::{Vec2, Vec3};
use rrf_baker::scene::Scene;
use rrf_baker::trace::{Camera, Geometry, World};
use rrf_renderer::passes::gbuffer::{GBufferPass, GBufferTargets, GBufferTexel};
use rrf_renderer::passes::mesh::GBufferMesh;
use rrf_renderer::vk;

fn compare(scene_name: &str, view_name: &str, width: u32, height: u32) {
    let scene = Scene::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(scene_name)).unwrap();
    let view = scene.view(view_name).unwrap().clone();
    let aspect = width as f32 / height as f32;

    let ctx = gpu();
    let extent = vk::Extent2D { width, height };
    let targets = GBufferTargets::new(&ctx, extent, false).unwrap();
    let (vertices, indices) = gbuffer_mesh(&scene);
    let (materials, texture_texels) = surface_materials(&scene);
    let mesh = GBufferMesh::new(&ctx, &vertices, &indices, &materials, &texture_texels).unwrap();
    let pass = GBufferPass::new(&ctx, shaders::GBUFFER_VERT, shaders::GBUFFER_FRAG, &mesh).unwrap();
    ctx.submit_once(|cmd| {
        pass.record(&ctx, cmd, &targets, &mesh, (&gbuffer_constants(&view, aspect, None), None), &[])
    })
    .unwrap();
    let surface = ctx.read_image(&targets.surface, vk::ImageLayout::GENERAL).unwrap();
    let id = ctx.read_image(&targets.id, vk::ImageLayout::GENERAL).unwrap();
    let shading = ctx.read_image(&targets.shading, vk::ImageLayout::GENERAL).unwrap();
    let words = |s: &[f32]| [s[0], s[1], s[2], s[3]].map(f32::to_bits);
    let texels: Vec<GBufferTexel> = surface
        .chunks_exact(4)
        .zip(&id)
        .zip(shading.chunks_exact(4))
        .map(|((s, i), m)| GBufferTexel::decode(words(s), i.to_bits(), words(m)))
        .collect();
    pass.destroy(&ctx);
    mesh.destroy(&ctx);
    targets.destroy(&ctx);
    finish_clean(ctx);

    let geometry = Geometry::new(&scene);
    let world = World::new(&scene, &geometry, None);
    let camera = Camera::new(&view, aspect);
    let id_at = |x: i64, y: i64| -> Option<u32> {
        if x < 0 || y < 0 || x >= width as i64 || y >= height as i64 {
            return None;
        }
        let film = (Vec2::new(x as f32, y as f32) + 0.5) / Vec2::new(width as f32, height as f32);
        let dir = camera.direction(film);
        world.intersect(camera.eye, dir).map(|h| geometry.triangles[h.triangle as usize].object + 1)
    };
    let (mut same_id, mut interior, mut checked) = (0usize, 0usize, 0usize);
    let mut worst_position = 0.0f32;
    let mut worst_normal = 0.0f32;
    // Base colour, roughness, metallic, emission.
    let mut worst_material = [0.0f32; 4];
    let mut material_off = 0usize;
    for y in 0..height as i64 {
        for x in 0..width as i64 {
            let texel = texels[y as usize * width as usize + x as usize];
            let gpu_id = texel.object;
            let cpu_id = id_at(x, y).unwrap_or(0);
            same_id += usize::from(gpu_id == cpu_id);
            // Away from silhouettes: the same object all around.
            let neighbours = [(-1, 0), (1, 0), (0, -1), (0, 1)]
                .iter()
                .all(|(dx, dy)| id_at(x + dx, y + dy).is_none_or(|n| n == cpu_id));
            if cpu_id == 0 || !neighbours || gpu_id != cpu_id {
                continue;
            }
            interior += 1;
            let film = (Vec2::new(x as f32, y as f32) + 0.5) / Vec2::new(width as f32, height as f32);
            let dir = camera.direction(film);
            let hit = world.intersect(camera.eye, dir).unwrap();
            let si = world.interaction(camera.eye, dir, hit);
            let p = Vec3::from(texel.position);
            let n = Vec3::from(texel.normal);
            let scale = (si.position - camera.eye).length();
            worst_position = worst_position.max((p - si.position).length() / scale);
            worst_normal = worst_normal.max((n - si.shading_normal).length());
            // The material's textured values (emission from the faces that emit).
            let material = &scene.materials[texel.material as usize];
            let e = material.emission * Vec3::from(texel.emissive_texture);
            let errors = [
                (Vec3::from(texel.base_color) - si.bsdf.base_color).abs().max_element(),
                (texel.roughness - si.roughness).abs(),
                (texel.metallic - si.bsdf.metallic).abs(),
                (e - si.emission).abs().max_element() / material.emission.max_element().max(1.0),
            ];
            for (worst, error) in worst_material.iter_mut().zip(errors) {
                *worst = worst.max(error);
            }
            // Texels are filtered from UVs interpolated two ways (perspective-correct by the
            // rasterizer, barycentric at the hit here): close, not equal, across texel edges.
            material_off += usize::from(errors.iter().any(|&e| e > 0.01));
            checked += 1;
        }
    }
    let pixels = (width * height) as usize;
    eprintln!(
        "{scene_name}/{view_name}: object id equal on {same_id}/{pixels}; {checked} interior pixels, worst position error \
         {worst_position:.2e} of the distance, worst normal error {worst_normal:.2e}; worst base colour, roughness, \
         metallic, emission errors {worst_material:?}, {material_off} pixels off by more than 0.01"
    );
    assert!(same_id as f64 >= 0.999 * pixels as f64, "object id equal on only {same_id} of {pixels} pixels");
    assert!(interior > pixels / 2);
    assert!(worst_position < 1e-4, "position error {worst_position}");
    assert!(worst_normal < 1e-3, "normal error {worst_normal}");
    assert!(material_off * 200 <= checked, "{material_off} of {checked} pixels' material values are off");
    // Values agree up to the G-buffer's half floats and 16-bit unorms, and textured ones up to
    // the filtering of slightly different UVs.
    assert!(worst_material.iter().all(|&e| e < 1e-3), "material values off: {worst_material:?}");
}

#[test]
fn gbuffer_matches_primary_hits_cornell_box() {
    compare("cornell-box", "default", 96, 96);
}

#[test]
fn gbuffer_matches_primary_hits_many_objects() {
    compare("many-objects", "table", 120, 80);
}

/// Textures with a transform, a normal map and roughness texture, alpha-masked leaves and a
/// textured emitter seen from both sides.
#[test]
fn gbuffer_matches_primary_hits_gallery() {
    compare("gallery", "default", 120, 90);
    compare("gallery", "plant", 120, 90);
    compare("gallery", "screen-back", 120, 90);
}
