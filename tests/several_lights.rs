//! Several lights end to end: a frame lit by two coloured copies of the Cornell box's ceiling
//! light, from the shipped networks on the GPU, against the path-traced two-light reference;
//! and frames lit by `MAX_LIGHTS` lights against the sums of their one-light frames.
//!
//! Per pixel, the two-light frame's direct and indirect light are the sums of the one-light
//! frames' (a second light 5% too bright fails, tried). Its error must also stay within that
//! of the one-light frames of the same two lights. Light is
//! linear in the emission, so per pixel |pA + pB − (rA + rB)| ≤ |pA − rA| + |pB − rB|: the
//! two-light frame's mean absolute error is at most the sum of the one-light frames', up to
//! the references' noise, if summing the networks per light (and drawing each light's own
//! geometry) adds no error of its own.

mod common;

use std::path::Path;

use common::{finish_clean, gpu};
use rrf::direct_mode::DirectMode;
use rrf::eval::metrics::{compare, Metrics};
use rrf::lights::MAX_LIGHTS;
use rrf::scene_frame::{rgb, FrameSettings, SceneFrame};
use rrf_baker::glam::Vec3;
use rrf_baker::model::Model;
use rrf_baker::scene::{PlacedLight, Scene};
use rrf_baker::trace::{render, Camera, Footprint, Geometry, RenderSettings, TraceSettings, World};
use rrf_renderer::frame::{FrameOutput, Shown};
use rrf_renderer::passes::network::Variant;
use rrf_renderer::vk;

const SIZE: u32 = 64;

#[test]
fn two_lights_match_the_path_traced_two_light_reference() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-box");
    let scene = Scene::load(&dir).unwrap();
    let model = Model::load(&dir.join("model.safetensors"), Some(&scene)).unwrap();
    let view = scene.views[0].clone();
    let warm = PlacedLight { position: Vec3::new(0.2, 0.5, 0.2), scale: Vec3::new(1.0, 0.7, 0.4) };
    let cool = PlacedLight { position: Vec3::new(0.38, 0.46, 0.4), scale: Vec3::new(0.4, 0.6, 1.0) };
    let cases = [vec![warm], vec![cool], vec![warm, cool]];

    let ctx = gpu();
    let extent = vk::Extent2D { width: SIZE, height: SIZE };
    let frame =
        SceneFrame::new(&ctx, &scene, &model, Variant::Tiled, extent, FrameOutput::Radiance, DirectMode::Learned)
            .unwrap();
    let frames: Vec<[Vec<Vec3>; 3]> = cases
        .iter()
        .map(|lights| {
            let settings =
                FrameSettings { view: view.clone(), lights: lights.clone(), exposure_scale: 1.0, shown: Shown::Gi };
            let pixels = frame.render(&ctx, &settings).unwrap();
            [rgb(&pixels.gi), rgb(&pixels.direct), rgb(&pixels.indirect)]
        })
        .collect();
    frame.destroy(&ctx);
    finish_clean(ctx);
    sums_of_one_light_frames(&frames[..2], &frames[2]);
    let predicted: Vec<&Vec<Vec3>> = frames.iter().map(|f| &f[0]).collect();

    let geometry = Geometry::new(&scene);
    let camera = Camera::new(&view, 1.0);
    let settings = RenderSettings {
        width: SIZE,
        height: SIZE,
        spp: 256,
        trace: TraceSettings { max_depth: 8, rr_depth: Some(5) },
        seed: 7,
        footprint: Footprint::Area,
    };
    let errors: Vec<(f64, Metrics)> = cases
        .iter()
        .zip(&predicted)
        .map(|(lights, predicted)| {
            let world = World::with_lights(&scene, &geometry, lights);
            let reference = render(&world, &camera, &settings, &|_| {}).component(|r| r.gi());
            let absolute = predicted.iter().zip(&reference).map(|(p, r)| f64::from((*p - *r).abs().element_sum()));
            (absolute.sum::<f64>() / (3 * reference.len()) as f64, compare(predicted, &reference, SIZE, SIZE).metrics)
        })
        .collect();
    for (name, (mae, m)) in ["warm", "cool", "both"].iter().zip(&errors) {
        eprintln!(
            "{name}: mean absolute error {mae:.5}, relMSE {:.4}, FLIP {:.4}, PSNR {:.2} dB",
            m.relmse, m.flip, m.psnr
        );
    }
    let (warm_error, cool_error, both) = (errors[0].0, errors[1].0, &errors[2]);
    // 10% for the references' noise (three independent 256 spp renders).
    assert!(
        both.0 <= 1.1 * (warm_error + cool_error),
        "two lights: mean absolute error {} over the one-light frames' {warm_error} + {cool_error}",
        both.0
    );
    // The picture's error stays near one light's (FLIP is not additive: a loose bound).
    let worst_flip = errors[..2].iter().map(|e| e.1.flip).fold(0.0, f64::max);
    assert!(both.1.flip <= 1.5 * worst_flip, "two lights: FLIP {} vs one light's {worst_flip}", both.1.flip);
}

/// The networks' light is linear in the lights: per pixel, the direct and indirect light of
/// the frame lit by all the lights (`all`: gi, direct, indirect) are the sums of those of the
/// frames lit by one light each (`singles`), up to float rounding, except where a light's own
/// geometry shows in some frame (it hides what is behind it). A light summed with the wrong
/// scale or position fails here, however small its share of the mean error.
fn sums_of_one_light_frames(singles: &[[Vec<Vec3>; 3]], all: &[Vec<Vec3>; 3]) {
    let emits = |f: &[Vec<Vec3>; 3], i: usize| (f[0][i] - f[1][i] - f[2][i]).max_element() > 1e-4;
    let mut compared = 0;
    for i in 0..all[0].len() {
        if singles.iter().chain([all]).any(|f| emits(f, i)) {
            continue;
        }
        compared += 1;
        for (c, name) in [(1, "direct"), (2, "indirect")] {
            let sum: Vec3 = singles.iter().map(|f| f[c][i]).sum();
            let error = ((all[c][i] - sum).abs() / (sum.abs() + Vec3::splat(1e-3))).max_element();
            assert!(
                error < 1e-3,
                "pixel {i}: {name} {} with {} lights, {sum} summed from one light each",
                all[c][i],
                singles.len()
            );
        }
    }
    assert!(compared > 9 * all[0].len() / 10, "only {compared} pixels show no light's geometry");
}

/// A frame lit by `MAX_LIGHTS` lights, each its own colour and place in the light's box, is
/// the sum of the frames lit by each alone: with the learned direct light on the Cornell box
/// (16 copies of the ceiling light's geometry), and with analytic direct light on
/// many-objects (16 point lights, so 16 cube shadow maps, the atlas full).
#[test]
fn max_lights_add_up() {
    for (name, direct) in [("cornell-box", DirectMode::Learned), ("many-objects", DirectMode::Analytic)] {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name);
        let scene = Scene::load(&dir).unwrap();
        let model = Model::load(&dir.join("model.safetensors"), Some(&scene)).unwrap();
        let bounds = scene.moving_light.as_ref().unwrap().bounds;
        // Spread over the box by the golden-ratio sequence per axis; colours cycle.
        let lights: Vec<PlacedLight> = (0..MAX_LIGHTS)
            .map(|i| {
                let t = |a: f32| (0.5 + i as f32 * a).fract();
                let position =
                    bounds.min + (bounds.max - bounds.min) * Vec3::new(t(0.618_034), t(0.754_878), t(0.569_840));
                let scale = [Vec3::new(1.0, 0.5, 0.3), Vec3::new(0.3, 1.0, 0.5), Vec3::new(0.5, 0.3, 1.0)][i % 3] / 4.0;
                PlacedLight { position, scale }
            })
            .collect();
        let ctx = gpu();
        let extent = vk::Extent2D { width: SIZE, height: SIZE };
        let frame =
            SceneFrame::new(&ctx, &scene, &model, Variant::Tiled, extent, FrameOutput::Radiance, direct).unwrap();
        let render = |lights: &[PlacedLight]| {
            let settings = FrameSettings {
                view: scene.views[0].clone(),
                lights: lights.to_vec(),
                exposure_scale: 1.0,
                shown: Shown::Gi,
            };
            let pixels = frame.render(&ctx, &settings).unwrap();
            [rgb(&pixels.gi), rgb(&pixels.direct), rgb(&pixels.indirect)]
        };
        let singles: Vec<[Vec<Vec3>; 3]> = lights.iter().map(|l| render(std::slice::from_ref(l))).collect();
        let all = render(&lights);
        frame.destroy(&ctx);
        finish_clean(ctx);
        assert!(all[1].iter().map(|p| p.element_sum()).sum::<f32>() > 0.0, "{name}: no direct light");
        sums_of_one_light_frames(&singles, &all);
    }
}
