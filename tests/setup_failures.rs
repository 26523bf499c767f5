//! Every error path of GPU set-up is clean: a frame whose set-up fails at any step, or whose
//! resize fails at any step, leaves no GPU object alive and no validation message, and a failed
//! resize leaves the frame usable at its old size: it renders the pixels it rendered before,
//! and once resized, those of a frame made at the new size.

mod common;

use std::path::Path;

use common::{finish_clean, gpu};
use rrf::direct_mode::DirectMode;
use rrf::scene_frame::{FrameSettings, SceneFrame};
use rrf_baker::model::Model;
use rrf_baker::scene::Scene;
use rrf_renderer::frame::{FrameOutput, Shown};
use rrf_renderer::passes::network::Variant;
use rrf_renderer::vk;

fn cornell_box() -> (Scene, Model) {
    shipped("cornell-box")
}

fn shipped(name: &str) -> (Scene, Model) {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name);
    let scene = Scene::load(&dir).unwrap();
    let model = Model::load(&dir.join("model.safetensors"), Some(&scene)).unwrap();
    (scene, model)
}

const EXTENT: vk::Extent2D = vk::Extent2D { width: 48, height: 32 };

#[test]
fn a_frame_that_fails_at_any_set_up_step_leaves_nothing_behind() {
    let (cornell, cornell_model) = cornell_box();
    // many-objects' point light allows analytic direct light: the shadow pass's set-up too.
    let (many, many_model) = shipped("many-objects");
    let cases = [
        (&cornell, &cornell_model, Variant::Tiled, DirectMode::Learned),
        (&cornell, &cornell_model, Variant::Storage, DirectMode::Learned),
        (&many, &many_model, Variant::Tiled, DirectMode::Analytic),
    ];
    for (scene, model, variant, direct) in cases {
        let mut step = 0;
        loop {
            let ctx = gpu();
            ctx.fail_at_step(Some(ctx.steps_taken() + step));
            match SceneFrame::new(&ctx, scene, model, variant, EXTENT, FrameOutput::Radiance, direct) {
                Ok(frame) => {
                    frame.destroy(&ctx);
                    finish_clean(ctx);
                    break;
                }
                Err(e) => {
                    let message = format!("{e:#}");
                    assert!(message.contains("device memory allocation has failed"), "step {step}: {message}");
                    finish_clean(ctx);
                    step += 1;
                }
            }
        }
        eprintln!("{} ({:?}): set-up failed cleanly at each of its {step} steps", variant.name(), direct);
        assert!(step >= 15, "{}: only {step} steps were tried", variant.name());
    }
}

#[test]
fn a_failed_resize_leaves_the_frame_usable_and_nothing_behind() {
    let (scene, model) = cornell_box();
    let ctx = gpu();
    let mut frame =
        SceneFrame::new(&ctx, &scene, &model, Variant::Tiled, EXTENT, FrameOutput::Radiance, DirectMode::Learned)
            .unwrap();
    let settings = FrameSettings {
        view: scene.views[0].clone(),
        lights: vec![scene.default_light()],
        exposure_scale: 1.0,
        shown: Shown::Gi,
    };
    let before = frame.render(&ctx, &settings).unwrap();
    let bigger = vk::Extent2D { width: 64, height: 40 };
    let mut step = 0;
    loop {
        ctx.fail_at_step(Some(ctx.steps_taken() + step));
        let resized = frame.gpu.resize(&ctx, bigger);
        ctx.fail_at_step(None);
        match resized {
            Ok(()) => break,
            Err(e) => {
                assert!(format!("{e:#}").contains("device memory allocation has failed"));
                assert_eq!(frame.gpu.extent(), EXTENT, "a failed resize keeps the old size");
                let pixels = frame.render(&ctx, &settings).unwrap();
                assert!(pixels.gi == before.gi, "step {step}: the frame after a failed resize is not the frame before");
                step += 1;
            }
        }
    }
    assert!(step >= 5, "only {step} resize steps were tried");
    assert_eq!(frame.gpu.extent(), bigger);
    let resized = frame.render(&ctx, &settings).unwrap();
    frame.destroy(&ctx);
    let fresh =
        SceneFrame::new(&ctx, &scene, &model, Variant::Tiled, bigger, FrameOutput::Radiance, DirectMode::Learned)
            .unwrap();
    let expected = fresh.render(&ctx, &settings).unwrap();
    fresh.destroy(&ctx);
    assert!(resized.gi == expected.gi, "the resized frame is not a frame made at its size");
    finish_clean(ctx);
}
