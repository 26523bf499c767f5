//! `rrf info SCENE`: the summary a user sees, and the errors for bad paths.

mod common;

use common::rrf;

#[test]
fn many_objects_summary_as_json() {
    let out = rrf(&["info", "scenes/many-objects", "--json"], &[]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let stdout = String::from_utf8(out.stdout).unwrap();
    assert_eq!(stdout.lines().count(), 1, "--json prints one line");
    let info: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    assert!(info["objects"].as_u64().unwrap() >= 24, "{info}");
    assert!(info["triangles"].as_u64().unwrap() >= 50_000, "{info}");
    assert_eq!(info["lights"].as_u64(), Some(1));
    assert_eq!(info["moving_light"]["node"], "Lamp");
}

#[test]
fn cornell_box_summary_as_text() {
    let out = rrf(&["info", "scenes/cornell-box"], &[]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = String::from_utf8(out.stdout).unwrap();
    for expected in [
        "8 objects, 36 triangles",
        "TallBlock",
        "CeilingLight",
        "radiance [17.0, 12.0, 4.0]",
        "front",
        "sidecar    scenes/cornell-box/scene.toml\n",
        "model      scenes/cornell-box/model.safetensors\n",
    ] {
        assert!(text.contains(expected), "missing {expected:?} in\n{text}");
    }
}

#[test]
fn info_says_which_files_are_missing_and_what_makes_them() {
    let dir = std::env::temp_dir().join(format!("rrf-info-files-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for file in ["scene.gltf", "scene.bin"] {
        std::fs::copy(format!("scenes/cornell-box/{file}"), dir.join(file)).unwrap();
    }
    std::fs::rename(dir.join("scene.gltf"), dir.join("Box.gltf")).unwrap();
    let out = rrf(&["info", dir.join("Box.gltf").to_str().unwrap()], &[]);
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.contains("Box.toml (not there: `rrf init` writes a starter)"), "{text}");
    assert!(text.contains("Box.safetensors (not baked yet: `rrf bake`)"), "{text}");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn missing_scene_is_a_clear_error() {
    let out = rrf(&["info", "scenes/no-such-scene"], &[]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.starts_with("error: scenes/no-such-scene: no such file or folder"), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
}

#[test]
fn gallery_materials_say_what_was_read() {
    let out = rrf(&["info", "scenes/gallery", "--json"], &[]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let info: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let features = |name: &str| -> Vec<String> {
        let materials = info["material_list"].as_array().unwrap();
        let m = materials.iter().find(|m| m["name"] == name).unwrap_or_else(|| panic!("no {name} in {info}"));
        serde_json::from_value(m["features"].clone()).unwrap()
    };
    assert_eq!(features("tiles"), ["base colour texture (transformed)"]);
    assert_eq!(features("brick"), ["metallic-roughness texture", "normal texture"]);
    assert_eq!(features("leaf"), ["base colour texture", "alpha mask (cutoff 0.5)", "double-sided"]);
    assert_eq!(features("screen"), ["emissive texture", "double-sided", "emits [3.0, 3.0, 3.0]"]);
    assert!(features("plaster").is_empty());
}

#[test]
fn the_glossy_rooms_panel_is_its_only_mirror() {
    let out = rrf(&["info", "scenes/glossy-room", "--json"], &[]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let mirrors: Vec<&str> = v["object_list"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|o| o["mirror"] == true)
        .map(|o| o["name"].as_str().unwrap())
        .collect();
    assert_eq!(mirrors, ["MirrorPanel"]);
    let text = rrf(&["info", "scenes/glossy-room"], &[]);
    assert!(String::from_utf8_lossy(&text.stdout).contains("MirrorPanel"));
    assert!(String::from_utf8_lossy(&text.stdout).contains("(planar mirror: reflects, has no networks)"));
}
