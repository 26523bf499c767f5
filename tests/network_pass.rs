//! The GPU network pass against the CPU reference inference (`rrf render --cpu`), every
//! variant and every component, pixel by pixel, with the shipped models.

mod common;

use std::path::Path;

use common::{finish_clean, gpu};
use rrf::direct_mode::DirectMode;
use rrf::scene_frame::{FrameSettings, SceneFrame};
use rrf_baker::glam::{Vec2, Vec3};
use rrf_baker::model::Model;
use rrf_baker::network::Component;
use rrf_baker::predict::predict_image;
use rrf_baker::scene::{PlacedLight, Scene};
use rrf_baker::trace::{Camera, Geometry, Radiance, World};
use rrf_renderer::frame::{FrameOutput, Shown};
use rrf_renderer::passes::network::Variant;
use rrf_renderer::passes::tonemap::tonemap;
use rrf_renderer::vk;

/// One component of the CPU's radiance.
type Pick = fn(&Radiance) -> Vec3;

/// A light at `position` as bright as the glTF's.
fn at(position: Vec3) -> Vec<PlacedLight> {
    vec![PlacedLight { position, scale: Vec3::ONE }]
}

fn compare(scene_name: &str, view_name: &str, lights: &[PlacedLight], width: u32, height: u32) {
    compare_with(scene_name, view_name, lights, (width, height), DirectMode::Learned, &Variant::ALL, |_| {});
}

/// The GPU's `variants` against the CPU inference with direct light from `direct`: 99.9% of
/// the pixels of every component within [`TOLERANCE`], pixels near a shadow's edge left out
/// where direct light is analytic ([`shadow_edges`]). The scene is changed by `edit` first.
fn compare_with(
    scene_name: &str,
    view_name: &str,
    lights: &[PlacedLight],
    (width, height): (u32, u32),
    direct: DirectMode,
    variants: &[Variant],
    edit: fn(&mut Scene),
) {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(scene_name);
    let mut scene = Scene::load(&dir).unwrap();
    edit(&mut scene);
    let model = Model::load(&dir.join("model.safetensors"), Some(&scene)).unwrap();
    let view = scene.view(view_name).unwrap().clone();

    let ctx = gpu();
    let extent = vk::Extent2D { width, height };
    let rendered: Vec<_> = variants
        .iter()
        .map(|&variant| {
            // One frame serves every configuration: it starts at another size with the light
            // where the glTF puts it, then is resized and given the lights.
            let start = vk::Extent2D { width: width / 2 + 3, height: height / 2 + 1 };
            let mut frame =
                SceneFrame::new(&ctx, &scene, &model, variant, start, FrameOutput::Radiance, direct).unwrap();
            let mut settings = FrameSettings {
                view: view.clone(),
                lights: vec![scene.default_light()],
                exposure_scale: 1.0,
                shown: Shown::Gi,
            };
            frame.render(&ctx, &settings).unwrap();
            frame.gpu.resize(&ctx, extent).unwrap();
            settings.lights = lights.to_vec();
            let pixels = frame.render(&ctx, &settings).unwrap();
            frame.destroy(&ctx);
            (variant, pixels)
        })
        .collect();
    finish_clean(ctx);

    let geometry = Geometry::new(&scene);
    let world = World::with_lights(&scene, &geometry, lights);
    let camera = Camera::new(&view, width as f32 / height as f32);
    let cpu = predict_image(&world, &camera, &model, (width, height), direct.cpu(&scene));
    let pixels = (width * height) as usize;
    let edges = match direct {
        DirectMode::Analytic => shadow_edges(&world, &camera, (width, height)),
        _ => vec![false; pixels],
    };
    let near_edges = edges.iter().filter(|&&e| e).count();
    eprintln!("{scene_name}: {near_edges} of {pixels} pixels near a shadow's edge, not compared");
    assert!(near_edges * 3 <= pixels, "{near_edges} of {pixels} pixels near a shadow's edge: the mask hides too much");

    for (variant, pixels) in &rendered {
        let variant = variant.name();
        let components: [(&str, &Vec<f32>, Pick); 3] = [
            ("direct", &pixels.direct, |r| r.direct),
            ("indirect", &pixels.indirect, |r| r.indirect),
            ("gi", &pixels.gi, |r| r.gi()),
        ];
        for (name, gpu_pixels, pick) in components {
            check(&format!("{scene_name} {variant} {name}"), &cpu.pixels, gpu_pixels, pick, &edges);
        }
    }
}

/// Texels per side of a shadow map's cube face.
const SHADOW_SIZE: f32 = rrf_renderer::passes::shadow::SHADOW_SIZE as f32;

/// Pixels where a cube shadow map cannot say whether the surface is lit: those whose point,
/// moved off its surface by a texel as the GPU moves it, is nearer to the light than the first
/// hit along some rays from the light within a texel and a half of it (the 2×2 texels the GPU
/// filters) but not along others, or where the moved point and the CPU's shadow ray to the
/// point itself disagree (an occluder within a texel of the surface: contact shadows). A
/// texel's angle is taken at a face's centre, where texels are widest (2/SHADOW_SIZE radians), and
/// the GPU's tolerance of half a texel is kept. Everywhere else the GPU's shadow must be the
/// CPU's.
fn shadow_edges(world: &World, camera: &Camera, (width, height): (u32, u32)) -> Vec<bool> {
    let size = Vec2::new(width as f32, height as f32);
    (0..width * height)
        .map(|i| {
            let film = (Vec2::new((i % width) as f32, (i / width) as f32) + 0.5) / size;
            let dir = camera.direction(film);
            let Some(hit) = world.intersect(camera.eye, dir) else { return false };
            let si = world.interaction(camera.eye, dir, hit);
            world.lights.iter().any(|light| {
                let texel = 2.0 * si.position.distance(light.position) / SHADOW_SIZE;
                let lit = |to: Vec3, d: Vec3| {
                    world.intersect(light.position, d).is_none_or(|h| to.length() <= h.t + 0.5 * texel)
                };
                let moved = si.position + si.geometric_normal * texel - light.position;
                let to_point = moved.normalize();
                let centre = lit(moved, to_point);
                let (u, v) = to_point.any_orthonormal_pair();
                let turn = 1.5 * 2.0 / SHADOW_SIZE;
                // The CPU's shadow ray: nothing between the light and the point itself.
                let unmoved = si.position - light.position;
                let ray_lit = world
                    .intersect(light.position, unmoved.normalize())
                    .is_none_or(|h| h.t >= unmoved.length() * (1.0 - 1e-3));
                ray_lit != centre
                    || (0..8).any(|k| {
                        let phi = k as f32 * std::f32::consts::TAU / 8.0;
                        lit(moved, (to_point + turn * (phi.cos() * u + phi.sin() * v)).normalize()) != centre
                    })
            })
        })
        .collect()
}

/// Relative error that 99.9% of the pixels stay within. The CPU inference takes the exact
/// shading normal; the GPU's comes from the G-buffer's 16-bit octahedral encoding, which moves
/// it by up to 3e-5 and the networks' output by up to a few 1e-3 where they are steep. A step
/// of the 8-bit display is 4e-3 or more. (The rest are silhouette pixels, where the raster and
/// the ray cast see different objects.)
const TOLERANCE: f32 = 5e-3;

/// Radiance added to the reference in the relative error's denominator: near black, the two
/// may differ by [`TOLERANCE`] times this, 5e-5, a sixth of the darkest 8-bit sRGB step (the
/// networks' output near zero moves by 1e-5 with the normal's encoding).
const NEAR_BLACK: f32 = 1e-2;

/// 99.9% of the pixels within [`TOLERANCE`], leaving out those `exempt` (near a shadow's edge).
fn check(what: &str, cpu: &[Radiance], gpu: &[f32], pick: Pick, exempt: &[bool]) {
    let (mut within, mut compared) = (0, 0);
    let mut worst = 0.0f32;
    for (i, r) in cpu.iter().enumerate().filter(|&(i, _)| !exempt[i]) {
        let c = pick(r);
        let g = Vec3::new(gpu[4 * i], gpu[4 * i + 1], gpu[4 * i + 2]);
        // Relative error per pixel, with an absolute floor far below what a display shows.
        let error = ((g - c).abs() / (c.abs() + Vec3::splat(NEAR_BLACK))).max_element();
        worst = worst.max(error);
        within += usize::from(error <= TOLERANCE);
        compared += 1;
    }
    eprintln!("{what}: {within}/{compared} pixels within {TOLERANCE:e} relative, worst {worst:.2e}");
    assert!(within * 1000 >= compared * 999, "{what}: only {within} of {compared} pixels within {TOLERANCE:e}");
}

#[test]
fn gpu_matches_cpu_inference_cornell_box() {
    compare("cornell-box", "default", &at(Vec3::new(0.2, 0.5, 0.35)), 96, 96);
}

/// Three coloured copies of the ceiling light, one dimmed: the networks summed per light on
/// the GPU against the CPU inference's sum, and each copy's own geometry drawn where it is
/// with its scaled emission (the default view sees the ceiling).
#[test]
fn gpu_matches_cpu_inference_with_three_lights() {
    let lights = [
        PlacedLight { position: Vec3::new(0.2, 0.5, 0.35), scale: Vec3::new(1.0, 0.4, 0.2) },
        PlacedLight { position: Vec3::new(0.38, 0.45, 0.2), scale: Vec3::new(0.2, 0.5, 1.0) },
        PlacedLight { position: Vec3::new(0.3, 0.54, 0.4), scale: Vec3::splat(0.25) },
    ];
    compare("cornell-box", "default", &lights, 96, 96);
}

#[test]
fn gpu_matches_cpu_inference_many_objects() {
    compare("many-objects", "table", &at(Vec3::new(0.8, 2.2, -0.5)), 120, 80);
}

/// Analytic direct light, two coloured copies of the lamp: the BRDF on the GPU with cube
/// shadow maps against the path tracer's next-event estimate with shadow rays. Lit and shadowed
/// pixels agree (tests/brdf.rs holds the BRDFs together) to 99.9%; they may differ only where
/// a shadow map texel (256² per cube face, 2×2 filtered) straddles a shadow's edge, and those
/// pixels are left out.
#[test]
fn analytic_direct_matches_the_cpu_many_objects() {
    let lights = [
        PlacedLight { position: Vec3::new(0.8, 2.2, -0.5), scale: Vec3::ONE },
        PlacedLight { position: Vec3::new(-1.2, 2.5, 0.6), scale: Vec3::new(0.3, 0.5, 1.0) },
    ];
    let variants = [Variant::Tiled, Variant::PerObject];
    compare_with("many-objects", "table", &lights, (120, 80), DirectMode::Analytic, &variants, |_| {});
}

/// Analytic direct light needs only the indirect networks: a model without its direct
/// networks renders the same frame.
#[test]
fn analytic_direct_needs_no_direct_networks() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/many-objects");
    let scene = Scene::load(&dir).unwrap();
    let model = Model::load(&dir.join("model.safetensors"), Some(&scene)).unwrap();
    let mut indirect_only = model.clone();
    indirect_only.networks.retain(|n| n.component == Component::Indirect);
    assert!(!indirect_only.networks.is_empty() && indirect_only.networks.len() < model.networks.len());
    let ctx = gpu();
    let extent = vk::Extent2D { width: 64, height: 48 };
    let settings = FrameSettings {
        view: scene.view("table").unwrap().clone(),
        lights: vec![scene.default_light()],
        exposure_scale: 1.0,
        shown: Shown::Gi,
    };
    let render = |model: &Model| {
        let frame =
            SceneFrame::new(&ctx, &scene, model, Variant::Tiled, extent, FrameOutput::Radiance, DirectMode::Analytic)
                .unwrap();
        let pixels = frame.render(&ctx, &settings).unwrap();
        frame.destroy(&ctx);
        pixels.gi
    };
    let (full, stripped) = (render(&model), render(&indirect_only));
    finish_clean(ctx);
    assert!(full.iter().any(|&v| v > 0.0));
    assert!(full == stripped, "the direct networks changed an analytic frame");
}

/// The glossy room's mirror: what it reflects, drawn by the G-buffer pass again in its plane,
/// merged into the frame's G-buffer and shaded by the one network pass from the mirrored
/// camera, weighted by its Fresnel term, against the CPU's reflected rays through the same
/// networks. Two lights, so that the reflection sums them.
#[test]
fn gpu_matches_cpu_inference_in_a_mirror() {
    let lights = [
        PlacedLight { position: Vec3::new(0.0, 2.6, 0.0), scale: Vec3::ONE },
        PlacedLight { position: Vec3::new(0.5, 2.6, -1.0), scale: Vec3::new(0.3, 0.6, 1.0) },
    ];
    let one_mirror = |scene: &mut Scene| assert_eq!(scene.mirrors().len(), 1);
    compare_with("glossy-room", "mirror", &lights, (96, 64), DirectMode::Learned, &Variant::ALL, one_mirror);
}

/// Textured surfaces, whose networks' output the G-buffer's reflectance multiplies, a normal
/// map, alpha-masked leaves and a textured emitter.
#[test]
fn gpu_matches_cpu_inference_gallery() {
    compare("gallery", "plant", &at(Vec3::new(-1.0, 2.5, -0.5)), 120, 90);
}

/// The display frame (the walkthrough's: the network pass tonemaps and writes the display
/// image itself) against the radiance frame tonemapped on the CPU, every component, with two
/// lights.
#[test]
fn display_frame_matches_the_tonemapped_radiance() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/glossy-room");
    let scene = Scene::load(&dir).unwrap();
    // The display pass draws models whose leaves meet at hard cuts (blended ones go through
    // the radiance images): the shipped model with its blend band set to 0.
    let mut model = Model::load(&dir.join("model.safetensors"), Some(&scene)).unwrap();
    model.metadata.blend_band = 0.0;
    let model = Model::from_bytes(&model.to_bytes().unwrap()).unwrap();
    let extent = vk::Extent2D { width: 96, height: 64 };
    let ctx = gpu();
    let radiance =
        SceneFrame::new(&ctx, &scene, &model, Variant::Tiled, extent, FrameOutput::Radiance, DirectMode::Learned)
            .unwrap();
    for variant in [Variant::Tiled, Variant::PerObject] {
        let display =
            SceneFrame::new(&ctx, &scene, &model, variant, extent, FrameOutput::Display, DirectMode::Learned).unwrap();
        for shown in [Shown::Gi, Shown::Direct, Shown::Indirect] {
            let settings = FrameSettings {
                view: scene.views[0].clone(),
                lights: vec![
                    scene.default_light(),
                    PlacedLight { position: Vec3::new(0.5, 2.6, -1.0), scale: Vec3::new(0.3, 0.6, 1.0) },
                ],
                exposure_scale: 1.5,
                shown,
            };
            let hdr = radiance.render(&ctx, &settings).unwrap();
            let hdr = match shown {
                Shown::Gi => hdr.gi,
                Shown::Direct => hdr.direct,
                Shown::Indirect => hdr.indirect,
            };
            let shown_ldr = display.render_display(&ctx, &settings).unwrap();
            let mut off = 0;
            for (h, d) in hdr.chunks_exact(4).zip(shown_ldr.chunks_exact(4)) {
                let expected = tonemap([h[0], h[1], h[2]], settings.exposure_scale);
                let worst = (0..3).map(|c| (expected[c] - d[c]).abs()).fold(0.0, f32::max);
                off += usize::from(worst > 1.5 / 255.0);
            }
            let n = (extent.width * extent.height) as usize;
            assert!(
                off * 1000 <= n,
                "{} {shown:?}: {off} of {n} pixels differ by more than 1.5 levels",
                variant.name()
            );
        }
        display.destroy(&ctx);
    }
    radiance.destroy(&ctx);
    finish_clean(ctx);
}
