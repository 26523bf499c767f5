//! `rrf bake --quality test --json` and `rrf render --cpu` from its model, as a user runs them.

mod common;

use common::{difference, rrf};

#[test]
fn bake_then_render_on_the_cpu() {
    let dir = std::env::temp_dir().join(format!("rrf-cli-bake-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let model = dir.join("model.safetensors");
    let model_arg = model.to_str().unwrap();
    let out = rrf(&["bake", "scenes/cornell-box", "--quality", "test", "--json", "-o", model_arg], &[]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let stdout = String::from_utf8(out.stdout).unwrap();
    assert_eq!(stdout.lines().count(), 1, "--json prints one line");
    let report: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    for key in ["samples", "paths", "sample_seconds", "train_seconds"] {
        assert!(report[key].as_f64().unwrap() > 0.0, "{key} in {report}");
    }
    let networks = report["networks"].as_array().unwrap();
    assert!(networks.len() >= 10, "{report}");
    for n in networks {
        assert!(["direct", "indirect"].contains(&n["component"].as_str().unwrap()));
        assert!(n["object"].is_string() && n["samples"].as_u64().unwrap() > 0);
        assert!(n["train_mse"].as_f64().unwrap().is_finite() && n["val_mse"].as_f64().unwrap().is_finite());
        assert!(n["val_noise"].as_f64().unwrap() >= 0.0, "{n}");
    }
    assert!(networks.iter().any(|n| n["region"].as_array().is_some_and(|r| !r.is_empty())), "a split: {report}");
    assert!(!dir.join("model.bake-cache").exists(), "sample shards are removed after a successful bake");

    let png = dir.join("frame.png");
    let light = "0.2,0.5,0.35";
    let out = rrf(
        &[
            "render",
            "scenes/cornell-box",
            "--cpu",
            "--model",
            model_arg,
            "--light",
            light,
            "--size",
            "64x64",
            "-o",
            png.to_str().unwrap(),
        ],
        &[],
    );
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let image = image::open(&png).unwrap().to_rgb8();
    assert_eq!(image.dimensions(), (64, 64));

    // The networks learned the light, not just its mean: the frame is close to the path
    // tracer's at the same light, where the networks the training starts from (each object's
    // mean target) are far from it and still pass the wall colours below.
    let reference = dir.join("reference.png");
    let out = rrf(
        &[
            "reference",
            "scenes/cornell-box",
            "--light",
            light,
            "--size",
            "64x64",
            "--spp",
            "64",
            "--footprint",
            "centre",
            "-o",
            reference.to_str().unwrap(),
        ],
        &[],
    );
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let (_, mean_levels) = difference(&image, &image::open(&reference).unwrap().to_rgb8(), 0);
    // 14 levels for this bake (most of it the reference's noise); 42 with training skipped.
    assert!(mean_levels < 25.0, "the bake's frame is {mean_levels:.1} levels from the path tracer's on average");
    // The walls are red on the left and green on the right.
    let left = image.get_pixel(5, 32);
    let right = image.get_pixel(58, 32);
    let dominant = |p: &image::Rgb<u8>, c: usize| (0..3).all(|o| o == c || f32::from(p[c]) > 1.5 * f32::from(p[o]));
    assert!(dominant(left, 0), "left wall {left:?}");
    assert!(dominant(right, 1), "right wall {right:?}");

    // A model from another scene is refused with a clear error.
    let out = rrf(&["render", "scenes/glossy-room", "--cpu", "--model", model_arg, "-o", png.to_str().unwrap()], &[]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("re-bake"));
}

/// `rrf bake --direct analytic` trains the indirect networks only; the model renders with
/// `--direct analytic` and refuses learned direct light with the reason. An area light
/// cannot be baked this way.
#[test]
fn a_bake_for_analytic_direct_light_trains_the_indirect_networks_only() {
    let dir = std::env::temp_dir().join(format!("rrf-cli-bake-analytic-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let model = dir.join("model.safetensors");
    let model_arg = model.to_str().unwrap();
    let bake = |scene: &str| {
        rrf(&["bake", scene, "--quality", "test", "--direct", "analytic", "--json", "-o", model_arg], &[])
    };
    let out = bake("scenes/many-objects");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let networks = report["networks"].as_array().unwrap();
    assert!(networks.len() >= 10 && networks.iter().all(|n| n["component"] == "indirect"), "{report}");

    let png = dir.join("frame.png");
    let render = |direct: &str| {
        let args = ["render", "scenes/many-objects", "--model", model_arg, "--direct", direct, "--size", "32x24"];
        rrf(&[&args[..], &["-o", png.to_str().unwrap()]].concat(), &[("RRF_VALIDATION", "required")])
    };
    let analytic = render("analytic");
    assert!(analytic.status.success(), "{}", String::from_utf8_lossy(&analytic.stderr));
    let learned = render("learned");
    let stderr = String::from_utf8_lossy(&learned.stderr);
    assert!(!learned.status.success() && stderr.contains("no direct networks"), "{stderr}");

    let area = bake("scenes/cornell-box");
    let stderr = String::from_utf8_lossy(&area.stderr);
    assert!(!area.status.success() && stderr.contains("moving area light"), "{stderr}");
    let _ = std::fs::remove_dir_all(dir);
}
