//! `rrf eval` end to end on a `--quality test` model: held-out configurations, cached
//! references, finite metrics, figures and the index, and a real margin over trivial
//! predictions (black, and the reference's mean colour) that a model of zero weights misses.
//! Small sizes and few samples: the shipped models' quality is in BENCHMARKS.md.

mod common;

use std::path::Path;

use common::rrf;
use rrf::eval::configs::held_out;
use rrf_baker::bake::samples::latin_hypercube;
use rrf_baker::model::Model;
use rrf_baker::scene::Scene;
use rrf_baker::trace::Geometry;

#[test]
fn eval_reports_metrics_figures_and_caches_references() {
    let dir = std::env::temp_dir().join(format!("rrf-cli-eval-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let model = dir.join("model.safetensors");
    let out = rrf(&["bake", "scenes/cornell-box", "--quality", "test", "-o", model.to_str().unwrap()], &[]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));

    let cache = dir.join("cache");
    let eval = |model: &Path, report_dir: &Path, extra: &[&str]| {
        let mut args = vec![
            "eval",
            "scenes/cornell-box",
            "--model",
            model.to_str().unwrap(),
            "--configs",
            "1",
            "--spp",
            "8",
            "--size",
            "48x32",
            "--cache",
            cache.to_str().unwrap(),
            "-o",
            report_dir.to_str().unwrap(),
        ];
        args.extend(extra);
        let out = rrf(&args, &[("RRF_VALIDATION", "required")]);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let text = std::fs::read_to_string(report_dir.join("metrics.json")).unwrap();
        serde_json::from_str::<serde_json::Value>(&text).unwrap()
    };

    let report_dir = dir.join("eval");
    let first = eval(&model, &report_dir, &[]);
    assert_eq!(first["scene"], "cornell-box");
    let configs = first["configs"].as_array().unwrap();
    // One per named view (default, corner, front) and one from the hypercube.
    assert_eq!(configs.len(), 4, "{first}");
    let html = std::fs::read_to_string(report_dir.join("index.html")).unwrap();
    for c in configs {
        assert_eq!(c["reference_cached"], false);
        assert_eq!(c["camera"]["eye"].as_array().unwrap().len(), 3);
        assert_eq!(c["light"].as_array().unwrap().len(), 3);
        let figure = c["figure"].as_str().unwrap();
        assert!(html.contains(figure), "index.html shows {figure}");
        let png = image::open(report_dir.join(figure)).unwrap();
        assert!(png.width() > 5 * 48 && png.height() > 32, "five panels and the labels");
        finite(&c["metrics"]);
        assert!(beats_trivial_predictions(c), "{c}");
        // Two 8-spp references differ, but far less than a black image does.
        let floor = c["floor"]["flip"].as_f64().unwrap();
        assert!(floor > 0.0 && floor < c["baselines"]["black"]["flip"].as_f64().unwrap(), "{c}");
    }
    finite(&first["mean"]);

    let second = eval(&model, &report_dir, &[]);
    for c in second["configs"].as_array().unwrap() {
        assert_eq!(c["reference_cached"], true, "the second eval reads the cached references");
    }
    assert_eq!(first["mean"], second["mean"], "the same references and predictions give the same numbers");

    // --floor-below raises the references' spp until two of them agree that well.
    let floor_at_8 = first["configs"][0]["floor"]["flip"].as_f64().unwrap();
    let limit = format!("{:.4}", 0.7 * floor_at_8);
    let raised = eval(&model, &dir.join("eval-floor"), &["--floor-below", &limit]);
    let c = &raised["configs"][0];
    assert!(c["spp"].as_u64().unwrap() > 8, "{c}");
    assert!(c["floor"]["flip"].as_f64().unwrap() < floor_at_8, "{c}");

    // The margin has teeth: a model with every weight zero (black but for the emitters) misses it.
    let mut zero = Model::load(&model, None).unwrap();
    zero.networks.iter_mut().for_each(|n| n.params.fill(0.0));
    let zero_path = dir.join("zero.safetensors");
    zero.save(&zero_path).unwrap();
    let report = eval(&zero_path, &dir.join("eval-zero"), &[]);
    let configs = report["configs"].as_array().unwrap();
    assert!(!configs.iter().any(beats_trivial_predictions), "a zero model must fail: {report}");

    // The seam figure has teeth: the same leaves with hard cuts step across them by more than
    // their blend does, and by more than the reference (at a size with pixels enough along
    // the cuts).
    let mut hard = Model::load(&model, None).unwrap();
    assert!(hard.metadata.blend_band > 0.0, "test bakes blend");
    hard.metadata.blend_band = 0.0;
    let hard_path = dir.join("hard.safetensors");
    hard.save(&hard_path).unwrap();
    let worst_seam = |model: &Path, name: &str| {
        let report_dir = dir.join(name);
        #[rustfmt::skip]
        let args = [
            "eval", "scenes/cornell-box", "--model", model.to_str().unwrap(), "--configs", "0", "--spp", "8",
            "--size", "160x120", "--cache", cache.to_str().unwrap(), "-o", report_dir.to_str().unwrap(),
        ];
        let out = rrf(&args, &[("RRF_VALIDATION", "required")]);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let report: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(report_dir.join("metrics.json")).unwrap()).unwrap();
        let excess = |s: &serde_json::Value| {
            s["predicted_step"].as_f64().unwrap().abs() - s["reference_step"].as_f64().unwrap().abs()
        };
        let configs = report["configs"].as_array().unwrap().iter();
        configs.filter(|c| !c["worst_seam"].is_null()).map(|c| excess(&c["worst_seam"])).fold(f64::MIN, f64::max)
    };
    let (blended, hard) = (worst_seam(&model, "seams-blended"), worst_seam(&hard_path, "seams-hard"));
    assert!(blended > f64::MIN, "a cut is in view");
    assert!(hard > blended + 1.0 && hard > 2.0, "hard cuts step by {hard} levels, blended ones by {blended}");

    // Without --spp, the references take the sidecar's [eval] spp.
    let copy = dir.join("cornell-copy");
    std::fs::create_dir_all(&copy).unwrap();
    for file in ["scene.gltf", "scene.bin"] {
        std::fs::copy(Path::new("scenes/cornell-box").join(file), copy.join(file)).unwrap();
    }
    let sidecar = std::fs::read_to_string("scenes/cornell-box/scene.toml").unwrap();
    let sidecar = sidecar.split("[eval]").next().unwrap().to_string() + "[eval]\nspp = 6\n";
    std::fs::write(copy.join("scene.toml"), sidecar).unwrap();
    let report_dir = dir.join("eval-sidecar");
    #[rustfmt::skip]
    let args = [
        "eval", copy.to_str().unwrap(), "--model", model.to_str().unwrap(), "--configs", "0", "--size", "48x32",
        "--cache", cache.to_str().unwrap(), "-o", report_dir.to_str().unwrap(),
    ];
    let out = rrf(&args, &[("RRF_VALIDATION", "required")]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(report_dir.join("metrics.json")).unwrap()).unwrap();
    assert_eq!(report["spp"], 6, "{report}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Every component's metrics finite and in range.
fn finite(metrics: &serde_json::Value) {
    for component in ["gi", "direct", "indirect"] {
        let m = &metrics[component];
        let value = |key: &str| m[key].as_f64().unwrap();
        let (relmse, psnr) = (value("relmse"), value("psnr"));
        assert!(relmse.is_finite() && relmse >= 0.0, "{component}: {m}");
        assert!(psnr.is_finite() && psnr > 0.0 && psnr <= 100.0, "{component}: {m}");
        assert!((0.0..=1.0).contains(&value("flip")) && (0.0..=1.0).contains(&value("hdr_flip")), "{component}: {m}");
    }
}

/// The global image's FLIP at most 0.6 of the better trivial prediction's, and its PSNR 5 dB
/// above a black image's. (relMSE does not tell a model from black on a dark 8-spp Cornell
/// box: most pixels are darker than its 0.1 guard.)
fn beats_trivial_predictions(config: &serde_json::Value) -> bool {
    let (gi, baselines) = (&config["metrics"]["gi"], &config["baselines"]);
    let value = |v: &serde_json::Value, key: &str| v[key].as_f64().unwrap();
    let trivial_flip = value(&baselines["black"], "flip").min(value(&baselines["mean_colour"], "flip"));
    value(gi, "flip") <= 0.6 * trivial_flip && value(gi, "psnr") >= value(&baselines["black"], "psnr") + 5.0
}

#[test]
fn held_out_cameras_look_into_the_scene_and_differ_from_training() {
    let scene = Scene::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/glossy-room")).unwrap();
    let geometry = Geometry::new(&scene);
    let configs = held_out(&scene, &geometry, 16, 0).unwrap();
    assert_eq!(configs.len(), scene.views.len() + 16);
    let bounds = scene.bounds();
    let diagonal = (bounds.max - bounds.min).length();
    let light_box = &scene.moving_light.as_ref().unwrap().bounds;
    let camera_box = scene.camera_box.as_ref().unwrap();
    let training = latin_hypercube(16, light_box, camera_box, 0);
    for c in &configs[scene.views.len()..] {
        assert!(camera_box.contains(c.view.eye) && light_box.contains(c.light), "{c:?}");
        let dir = (c.view.target - c.view.eye).normalize();
        let depth = geometry.intersect(c.view.eye, dir, f32::INFINITY, &[], &|_| true).map_or(f32::INFINITY, |h| h.t);
        assert!(depth >= 0.2 * diagonal, "{}: looks at a surface {depth} m away", c.name);
        assert!(training.iter().all(|t| t.light != c.light && t.viewpoint != c.view.eye));
    }
}
