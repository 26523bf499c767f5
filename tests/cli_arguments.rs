//! Arguments on the command line: negative coordinates are values, not flags; `--camera`
//! works on a scene whose glTF has no camera; `--direct analytic` refuses what it cannot do.

mod common;

use common::rrf;

#[test]
fn negative_coordinates_are_values() {
    let out = std::env::temp_dir().join(format!("rrf-negative-{}.png", std::process::id()));
    let run = rrf(
        &[
            "reference",
            "scenes/cornell-box",
            "--light",
            "-0.1,0.5,-0.2",
            "--camera",
            "-0.5,0.3,-0.8:0.28,0.27,0.28",
            "--size",
            "8x8",
            "--spp",
            "1",
            "-o",
            out.to_str().unwrap(),
        ],
        &[],
    );
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    assert!(stderr.contains("outside the light's box"), "the light is outside its box: {stderr}");
    std::fs::remove_file(out).unwrap();
}

#[test]
fn a_free_camera_needs_no_camera_in_the_gltf() {
    let dir = std::env::temp_dir().join(format!("rrf-no-camera-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut gltf: serde_json::Value =
        serde_json::from_slice(&std::fs::read("scenes/cornell-box/scene.gltf").unwrap()).unwrap();
    gltf.as_object_mut().unwrap().remove("cameras");
    for node in gltf["nodes"].as_array_mut().unwrap() {
        node.as_object_mut().unwrap().remove("camera");
    }
    std::fs::write(dir.join("scene.gltf"), serde_json::to_vec(&gltf).unwrap()).unwrap();
    std::fs::copy("scenes/cornell-box/scene.bin", dir.join("scene.bin")).unwrap();
    let out = dir.join("frame.png");
    for camera in [None, Some("0.28,0.27,-0.8:0.28,0.27,0")] {
        let mut args = vec!["reference", dir.to_str().unwrap(), "--size", "8x8", "--spp", "1", "-o"];
        args.push(out.to_str().unwrap());
        if let Some(camera) = camera {
            args.extend(["--camera", camera]);
        }
        let run = rrf(&args, &[]);
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert!(run.status.success(), "--camera {camera:?}: {stderr}");
        assert!(stderr.contains("no camera"), "the import says what it chose: {stderr}");
    }
    std::fs::remove_dir_all(dir).unwrap();
}

/// `--direct analytic` says why it cannot run: an area light, or the storage variant.
#[test]
fn analytic_direct_light_refuses_what_it_cannot_do() {
    let out = std::env::temp_dir().join(format!("rrf-analytic-{}.png", std::process::id()));
    let out = out.to_str().unwrap();
    let area = rrf(&["render", "scenes/cornell-box", "--direct", "analytic", "--size", "8x8", "-o", out], &[]);
    let stderr = String::from_utf8_lossy(&area.stderr);
    assert!(!area.status.success() && stderr.contains("moving area light"), "{stderr}");
    let storage = rrf(
        &["render", "scenes/many-objects", "--direct", "analytic", "--variant", "storage", "--size", "8x8", "-o", out],
        &[],
    );
    let stderr = String::from_utf8_lossy(&storage.stderr);
    assert!(!storage.status.success() && stderr.contains("specialized network variant"), "{stderr}");
    assert!(!std::path::Path::new(out).exists());
}
