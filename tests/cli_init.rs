//! `rrf init`: a starter sidecar from the glTF alone, good enough to bake from at once.

mod common;

use std::path::{Path, PathBuf};

use common::rrf;
use rrf_baker::scene::{LightKind, Scene};

/// The Cornell box's glTF in a fresh folder, without its sidecar, under `name`.
fn bare_cornell(test: &str, name: &str, edit: impl FnOnce(&mut serde_json::Value)) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("rrf-init-{}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let mut gltf: serde_json::Value =
        serde_json::from_slice(&std::fs::read("scenes/cornell-box/scene.gltf").unwrap()).unwrap();
    edit(&mut gltf);
    std::fs::write(dir.join(name), serde_json::to_vec(&gltf).unwrap()).unwrap();
    std::fs::copy("scenes/cornell-box/scene.bin", dir.join("scene.bin")).unwrap();
    dir.join(name)
}

fn run(args: &[&str]) -> (bool, String) {
    let out = rrf(args, &[]);
    (out.status.success(), String::from_utf8_lossy(&out.stderr).into_owned())
}

#[test]
fn init_writes_a_sidecar_that_bakes() {
    let gltf = bare_cornell("cornell", "scene.gltf", |_| {});
    let dir = gltf.parent().unwrap().to_str().unwrap().to_string();
    let (ok, stderr) = run(&["init", &dir]);
    assert!(ok, "{stderr}");
    assert!(stderr.contains("\"CeilingLight\"") && stderr.contains("only emitter"), "it says what it chose: {stderr}");

    let scene = Scene::load(Path::new(&dir)).unwrap();
    let light = scene.moving_light.as_ref().expect("a moving light");
    assert!(matches!(light.kind, LightKind::Area(_)) && light.node_name == "CeilingLight");
    let start = scene.view("start").expect("a start view");
    assert!(scene.camera_box.unwrap().contains(start.eye));

    let (ok, stderr) = run(&["init", &dir]);
    assert!(!ok && stderr.contains("--force"), "an existing sidecar is kept: {stderr}");
    let (ok, stderr) = run(&["init", &dir, "--force"]);
    assert!(ok, "{stderr}");

    let model = Path::new(&dir).join("model.safetensors");
    let out = rrf(&["bake", &dir, "--quality", "test", "--json", "-o", model.to_str().unwrap()], &[]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(report["networks"].as_array().unwrap().len() >= 10, "{report}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_scene_without_lights_gets_one_from_the_sidecar() {
    // The ceiling light made dark, and the file under its own name.
    let gltf = bare_cornell("dark", "Dark.gltf", |g| {
        for m in g["materials"].as_array_mut().unwrap() {
            m.as_object_mut().unwrap().remove("emissiveFactor");
        }
    });
    let (ok, stderr) = run(&["init", gltf.to_str().unwrap()]);
    assert!(ok, "{stderr}");
    assert!(stderr.contains("SidecarLight") && stderr.contains("no light"), "{stderr}");
    assert!(gltf.with_extension("toml").is_file(), "the sidecar is Dark.toml");
    let scene = Scene::load(&gltf).unwrap();
    let light = scene.moving_light.as_ref().unwrap();
    assert!(matches!(light.kind, LightKind::Point(_)) && light.node_name == "SidecarLight");
    assert!(scene.point_lights.iter().any(|l| l.name == "SidecarLight" && l.intensity.min_element() > 0.0));

    // It lights the scene: a path-traced frame from the start view is not black.
    let png = gltf.with_file_name("start.png");
    let (ok, stderr) = run(&[
        "reference",
        gltf.to_str().unwrap(),
        "--view",
        "start",
        "--size",
        "32x32",
        "--spp",
        "4",
        "-o",
        png.to_str().unwrap(),
    ]);
    assert!(ok, "{stderr}");
    let image = image::open(&png).unwrap().to_rgb8();
    let mean =
        image.pixels().map(|p| p.0.iter().map(|&c| f64::from(c)).sum::<f64>()).sum::<f64>() / (32.0 * 32.0 * 3.0);
    assert!(mean > 20.0, "mean level {mean}");
    std::fs::remove_dir_all(gltf.parent().unwrap()).unwrap();
}
