//! Scene import: the shipped scenes load, every container form gives the same scene, and
//! each kind of bad input is an error that names the file and the element.

use std::path::{Path, PathBuf};

use rrf_baker::bake::{BakeSettings, Quality};
use rrf_baker::glam::Vec3;
use rrf_baker::scene::{AlphaMode, LightKind, Scene, SceneError, UvTransform};
use serde_json::{json, Value};

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).parent().unwrap().to_path_buf()
}

/// A fresh, empty folder for one test.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("rrf-scene-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A mesh over `positions` with `indices`, as a glTF with an external buffer.
fn tiny_gltf(positions: &[[f32; 3]], indices: &[u32]) -> (Value, Vec<u8>) {
    let mut bin: Vec<u8> = positions.iter().flatten().flat_map(|v| v.to_le_bytes()).collect();
    let index_offset = bin.len();
    bin.extend(indices.iter().flat_map(|i| i.to_le_bytes()));
    // glTF requires bounds on POSITION; they need not be tight for these tests.
    let (min, max) = ([-1e3f32; 3], [1e3f32; 3]);
    let gltf = json!({
        "asset": { "version": "2.0" },
        "scene": 0,
        "scenes": [{ "nodes": [0] }],
        "nodes": [{ "name": "Tri", "mesh": 0 }],
        "meshes": [{ "primitives": [{ "attributes": { "POSITION": 0 }, "indices": 1 }] }],
        "accessors": [
            { "bufferView": 0, "componentType": 5126, "count": positions.len(), "type": "VEC3", "min": min, "max": max },
            { "bufferView": 1, "componentType": 5125, "count": indices.len(), "type": "SCALAR" },
        ],
        "bufferViews": [
            { "buffer": 0, "byteOffset": 0, "byteLength": index_offset },
            { "buffer": 0, "byteOffset": index_offset, "byteLength": bin.len() - index_offset },
        ],
        "buffers": [{ "uri": "scene.bin", "byteLength": bin.len() }],
    });
    (gltf, bin)
}

const TRIANGLE: [[f32; 3]; 3] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];

fn write_scene(dir: &Path, gltf: &Value, bin: &[u8]) -> PathBuf {
    std::fs::write(dir.join("scene.gltf"), serde_json::to_string(gltf).unwrap()).unwrap();
    std::fs::write(dir.join("scene.bin"), bin).unwrap();
    dir.to_path_buf()
}

fn load_err(path: &Path) -> String {
    let err: SceneError = Scene::load(path).expect_err("bad input must be refused");
    err.to_string()
}

#[test]
fn shipped_scenes_load() {
    for (name, min_objects, min_triangles) in
        [("cornell-box", 8, 30), ("glossy-room", 10, 1000), ("many-objects", 24, 50_000), ("gallery", 11, 250_000)]
    {
        let scene = Scene::load(&repo().join("scenes").join(name)).unwrap_or_else(|e| panic!("{e}"));
        assert!(scene.objects.len() >= min_objects, "{name}: {} objects", scene.objects.len());
        assert!(scene.triangle_count() >= min_triangles, "{name}: {} triangles", scene.triangle_count());
        assert!(scene.warnings.is_empty(), "{name}: {:?}", scene.warnings);
        assert_eq!(scene.views[0].name, "default", "{name}: the glTF camera is the default view");
        let light = scene.moving_light.as_ref().expect("every shipped scene has a moving light");
        assert!(light.bounds.contains(light.default_position));
        assert!(scene.camera_box.is_some());
    }
    let many = Scene::load(&repo().join("scenes/many-objects")).unwrap();
    assert!(many.materials.iter().filter(|m| m.base_color_texture.is_some()).count() >= 3);
    assert!(matches!(many.moving_light.unwrap().kind, LightKind::Point(_)));
}

#[test]
fn cornell_box_matches_the_published_data() {
    let scene = Scene::load(&repo().join("scenes/cornell-box")).unwrap();
    let red = scene.object_by_name("RedWall").unwrap();
    let material = &scene.materials[red.parts[0].material as usize];
    assert_eq!(material.base_color.to_array(), [0.63, 0.065, 0.05]);
    let light = scene.object_by_name("CeilingLight").unwrap();
    let emission = scene.materials[light.parts[0].material as usize].emission;
    assert!((emission - Vec3::new(17.0, 12.0, 4.0)).abs().max_element() < 1e-5, "{emission}");
    // The light faces down, the floor up, the red wall (x = 0.55) towards -x.
    assert!(light.normals.iter().all(|n| n.y < -0.99));
    assert!(scene.object_by_name("Floor").unwrap().normals.iter().all(|n| n.y > 0.99));
    assert!(red.normals.iter().all(|n| n.x < -0.99));
    let b = scene.bounds();
    assert!((b.max.y - 0.5488).abs() < 1e-4 && (b.max.z - 0.5592).abs() < 1e-4);
    let view = &scene.views[0];
    assert!((view.eye - Vec3::new(0.278, 0.273, -0.8)).length() < 1e-5);
    assert!((view.target - view.eye).normalize().z > 0.999);
}

/// Winding agrees with the normals: counter-clockwise seen from the front.
fn winding_agrees(scene: &Scene) -> bool {
    scene.objects.iter().all(|o| {
        o.triangles.iter().all(|t| {
            let [a, b, c] = t.map(|i| o.positions[i as usize]);
            let n = o.normals[t[0] as usize] + o.normals[t[1] as usize] + o.normals[t[2] as usize];
            (b - a).cross(c - a).dot(n) > 0.0
        })
    })
}

#[test]
fn shipped_scenes_wind_counter_clockwise() {
    for name in ["cornell-box", "glossy-room", "many-objects"] {
        assert!(winding_agrees(&Scene::load(&repo().join("scenes").join(name)).unwrap()), "{name}");
    }
}

#[test]
fn glb_and_embedded_buffers_give_the_same_scene() {
    let src = repo().join("scenes/cornell-box");
    let gltf: Value = serde_json::from_slice(&std::fs::read(src.join("scene.gltf")).unwrap()).unwrap();
    let bin = std::fs::read(src.join("scene.bin")).unwrap();
    let reference = Scene::load(&src).unwrap();

    // Embedded: the buffer as a base64 data URI.
    let dir = scratch("embedded");
    let mut embedded = gltf.clone();
    embedded["buffers"][0]["uri"] = json!(format!("data:application/octet-stream;base64,{}", base64(&bin)));
    std::fs::write(dir.join("scene.gltf"), serde_json::to_string(&embedded).unwrap()).unwrap();
    let a = Scene::load(&dir).unwrap();

    // GLB: JSON chunk and BIN chunk in one container.
    let dir = scratch("glb");
    let mut glb_json = gltf.clone();
    glb_json["buffers"][0].as_object_mut().unwrap().remove("uri");
    let mut json_bytes = serde_json::to_vec(&glb_json).unwrap();
    while !json_bytes.len().is_multiple_of(4) {
        json_bytes.push(b' ');
    }
    let mut bin_bytes = bin.clone();
    while !bin_bytes.len().is_multiple_of(4) {
        bin_bytes.push(0);
    }
    let total = 12 + 8 + json_bytes.len() + 8 + bin_bytes.len();
    let mut glb = Vec::new();
    glb.extend(b"glTF");
    glb.extend(2u32.to_le_bytes());
    glb.extend((total as u32).to_le_bytes());
    glb.extend((json_bytes.len() as u32).to_le_bytes());
    glb.extend(b"JSON");
    glb.extend(&json_bytes);
    glb.extend((bin_bytes.len() as u32).to_le_bytes());
    glb.extend(b"BIN\0");
    glb.extend(&bin_bytes);
    std::fs::write(dir.join("scene.glb"), &glb).unwrap();
    let b = Scene::load(&dir).unwrap();

    for scene in [&a, &b] {
        assert_eq!(scene.objects.len(), reference.objects.len());
        for (x, y) in scene.objects.iter().zip(&reference.objects) {
            assert_eq!((&x.name, &x.positions, &x.triangles), (&y.name, &y.positions, &y.triangles));
        }
    }
}

fn base64(bytes: &[u8]) -> String {
    const ALPHABET: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for chunk in bytes.chunks(3) {
        let n = chunk.iter().enumerate().fold(0u32, |n, (i, &b)| n | (u32::from(b) << (16 - 8 * i)));
        for i in 0..4 {
            if i <= chunk.len() {
                out.push(ALPHABET[((n >> (18 - 6 * i)) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

#[test]
fn node_hierarchy_is_applied_and_mirroring_flips_the_winding() {
    let dir = scratch("hierarchy");
    let (mut gltf, bin) = tiny_gltf(&TRIANGLE, &[0, 1, 2]);
    // Parent: a matrix that translates by (10, 0, 0); child: TRS mirroring x.
    gltf["scenes"][0]["nodes"] = json!([1]);
    gltf["nodes"] = json!([
        { "name": "Tri", "mesh": 0, "translation": [0.0, 2.0, 0.0], "scale": [-1.0, 1.0, 1.0] },
        { "name": "Parent", "children": [0],
          "matrix": [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 10.0, 0.0, 0.0, 1.0] },
    ]);
    let scene = Scene::load(&write_scene(&dir, &gltf, &bin)).unwrap();
    let tri = scene.object_by_name("Tri").unwrap();
    let mut corners = tri.positions.clone();
    corners.sort_by(|a, b| a.to_array().partial_cmp(&b.to_array()).unwrap());
    assert_eq!(corners, vec![Vec3::new(9.0, 2.0, 0.0), Vec3::new(10.0, 2.0, 0.0), Vec3::new(10.0, 3.0, 0.0)]);
    // The mirror image of a +z-facing triangle still faces +z. Its vertices in file order
    // would wind clockwise; the import flips the order to keep it counter-clockwise.
    let [a, b, c] = tri.triangles[0].map(|i| tri.positions[i as usize]);
    assert!((b - a).cross(c - a).z > 0.0);
    // No normals in the file: flat normals that agree with the winding.
    assert!(winding_agrees(&scene));
    assert!(tri.normals.iter().all(|n| (n.length() - 1.0).abs() < 1e-6));
}

#[test]
fn missing_file() {
    let message = load_err(Path::new("/nonexistent/scene-folder"));
    assert!(message.contains("/nonexistent/scene-folder") && message.contains("no such file"), "{message}");
}

#[test]
fn folder_without_a_scene() {
    let dir = scratch("empty-folder");
    let message = load_err(&dir);
    assert!(message.contains("scene.gltf") && message.contains("scene.glb"), "{message}");
}

#[test]
fn broken_json() {
    let dir = scratch("broken-json");
    std::fs::write(dir.join("scene.gltf"), "{ \"asset\": { \"version\": \"2.0\" ").unwrap();
    let message = load_err(&dir);
    assert!(message.contains("scene.gltf") && message.contains("not a valid glTF"), "{message}");
}

#[test]
fn broken_glb_container() {
    let dir = scratch("broken-glb");
    let mut glb = b"glTF".to_vec();
    glb.extend(2u32.to_le_bytes());
    glb.extend(4000u32.to_le_bytes()); // claims far more than there is
    glb.extend([0u8; 12]);
    std::fs::write(dir.join("scene.glb"), glb).unwrap();
    let message = load_err(&dir);
    assert!(message.contains("scene.glb") && message.contains("not a valid glTF or GLB"), "{message}");
}

#[test]
fn missing_buffer_file() {
    let dir = scratch("missing-buffer");
    let (gltf, _) = tiny_gltf(&TRIANGLE, &[0, 1, 2]);
    std::fs::write(dir.join("scene.gltf"), serde_json::to_string(&gltf).unwrap()).unwrap();
    let message = load_err(&dir);
    assert!(message.contains("buffers[0]") && message.contains("scene.bin"), "{message}");
}

#[test]
fn short_buffer() {
    let dir = scratch("short-buffer");
    let (gltf, bin) = tiny_gltf(&TRIANGLE, &[0, 1, 2]);
    let message = load_err(&write_scene(&dir, &gltf, &bin[..20]));
    assert!(message.contains("buffer"), "{message}");
}

#[test]
fn accessor_past_its_buffer_view() {
    let dir = scratch("accessor-range");
    let (mut gltf, bin) = tiny_gltf(&TRIANGLE, &[0, 1, 2]);
    gltf["accessors"][0]["count"] = json!(30);
    let message = load_err(&write_scene(&dir, &gltf, &bin));
    assert!(message.contains("accessors[0]") && message.contains("bufferViews[0]"), "{message}");
}

#[test]
fn index_out_of_range() {
    let dir = scratch("index-range");
    let (gltf, bin) = tiny_gltf(&TRIANGLE, &[0, 1, 7]);
    let message = load_err(&write_scene(&dir, &gltf, &bin));
    assert!(message.contains("meshes[0] primitives[0]") && message.contains("index 7 is out of range"), "{message}");
}

#[test]
fn non_finite_positions() {
    let dir = scratch("nan");
    let (gltf, bin) = tiny_gltf(&[[0.0, 0.0, 0.0], [f32::NAN, 0.0, 0.0], [0.0, f32::INFINITY, 0.0]], &[0, 1, 2]);
    let message = load_err(&write_scene(&dir, &gltf, &bin));
    assert!(message.contains("meshes[0] primitives[0]") && message.contains("vertex 1 is not finite"), "{message}");
}

#[test]
fn unsupported_required_extension_is_named() {
    let dir = scratch("extension");
    let (mut gltf, bin) = tiny_gltf(&TRIANGLE, &[0, 1, 2]);
    gltf["extensionsUsed"] = json!(["KHR_draco_mesh_compression"]);
    gltf["extensionsRequired"] = json!(["KHR_draco_mesh_compression"]);
    let message = load_err(&write_scene(&dir, &gltf, &bin));
    assert!(message.contains("extensionsRequired[0]") && message.contains("KHR_draco_mesh_compression"), "{message}");
}

#[test]
fn non_triangle_primitives_are_skipped_and_counted() {
    let dir = scratch("lines");
    let (mut gltf, bin) = tiny_gltf(&TRIANGLE, &[0, 1, 2]);
    let triangles = gltf["meshes"][0]["primitives"][0].clone();
    let mut lines = triangles.clone();
    lines["mode"] = json!(1);
    let mut points = triangles.clone();
    points["mode"] = json!(0);
    gltf["meshes"][0]["primitives"] = json!([triangles, lines, points]);
    let scene = Scene::load(&write_scene(&dir, &gltf, &bin)).unwrap();
    assert_eq!(scene.triangle_count(), 1);
    assert!(scene.warnings.iter().any(|w| w.contains("skipped 2 primitives")), "{:?}", scene.warnings);
}

#[test]
fn duplicate_object_names_are_refused() {
    let dir = scratch("duplicate-names");
    let (mut gltf, bin) = tiny_gltf(&TRIANGLE, &[0, 1, 2]);
    gltf["scenes"][0]["nodes"] = json!([0, 1]);
    gltf["nodes"] = json!([{ "name": "Tri", "mesh": 0 }, { "name": "Tri", "mesh": 0 }]);
    let message = load_err(&write_scene(&dir, &gltf, &bin));
    assert!(message.contains("nodes[1] \"Tri\"") && message.contains("nodes[0]"), "{message}");
}

/// The Cornell box with its sidecar replaced by `sidecar`.
fn cornell_with_sidecar(test: &str, sidecar: &str) -> PathBuf {
    let dir = scratch(test);
    for file in ["scene.gltf", "scene.bin"] {
        std::fs::copy(repo().join("scenes/cornell-box").join(file), dir.join(file)).unwrap();
    }
    std::fs::write(dir.join("scene.toml"), sidecar).unwrap();
    dir
}

#[test]
fn sidecar_naming_a_missing_light() {
    let dir = cornell_with_sidecar("no-light", "[light]\nnode = \"Sun\"\nmin = [0, 0, 0]\nmax = [1, 1, 1]\n");
    let message = load_err(&dir);
    assert!(
        message.contains("scene.toml") && message.contains("light.node") && message.contains("\"Sun\""),
        "{message}"
    );
    assert!(message.contains("CeilingLight"), "the error lists the lights there are: {message}");
}

#[test]
fn sidecar_naming_a_node_that_is_not_a_light() {
    let dir = cornell_with_sidecar("not-a-light", "[light]\nnode = \"TallBlock\"\nmin = [0, 0, 0]\nmax = [1, 1, 1]\n");
    let message = load_err(&dir);
    assert!(message.contains("light.node") && message.contains("is not a light"), "{message}");
}

#[test]
fn sidecar_box_with_min_above_max() {
    let dir = cornell_with_sidecar("inverted-box", "[camera]\nmin = [0, 0.5, 0]\nmax = [1, 0.2, 1]\n");
    let message = load_err(&dir);
    assert!(
        message.contains("scene.toml") && message.contains("camera") && message.contains("min > max on axis y"),
        "{message}"
    );
}

#[test]
fn sidecar_unknown_key() {
    let dir = cornell_with_sidecar("unknown-key", "[camera]\nmin = [0, 0, 0]\nmax = [1, 1, 1]\nfov = 3\n");
    let message = load_err(&dir);
    assert!(
        message.contains("scene.toml") && message.contains("line 4") && message.contains("unknown field `fov`"),
        "{message}"
    );
}

#[test]
fn sidecar_view_with_bad_field_of_view() {
    let dir = cornell_with_sidecar("bad-view", "[views.top]\neye = [0, 1, 0]\ntarget = [0, 0, 0]\nfov_y = 190\n");
    let message = load_err(&dir);
    assert!(message.contains("views.top.fov_y"), "{message}");
}

#[test]
fn default_light_outside_its_box() {
    let dir = cornell_with_sidecar(
        "light-outside",
        "[light]\nnode = \"CeilingLight\"\nmin = [0, 0, 0]\nmax = [0.1, 0.1, 0.1]\n",
    );
    let message = load_err(&dir);
    assert!(message.contains("outside the box"), "{message}");
}

// Hostile input: each of these panicked, or was accepted and gave black or non-finite pixels,
// before the importer checked it.

/// `tiny_gltf` with one more accessor (and its own buffer view) appended to the buffer.
fn with_accessor(gltf: &mut Value, bin: &mut Vec<u8>, data: &[u8], accessor: Value) -> usize {
    let offset = bin.len();
    bin.extend(data);
    let views = gltf["bufferViews"].as_array_mut().unwrap();
    views.push(json!({ "buffer": 0, "byteOffset": offset, "byteLength": data.len() }));
    let view = views.len() - 1;
    let mut accessor = accessor;
    accessor["bufferView"] = json!(view);
    gltf["accessors"].as_array_mut().unwrap().push(accessor);
    gltf["buffers"][0]["byteLength"] = json!(bin.len());
    gltf["accessors"].as_array().unwrap().len() - 1
}

fn f32_bytes(values: &[f32]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

#[test]
fn normals_shorter_than_positions() {
    let dir = scratch("short-normals");
    let (mut gltf, mut bin) = tiny_gltf(&TRIANGLE, &[0, 1, 2]);
    let normals = f32_bytes(&[0.0, 0.0, 1.0, 0.0, 0.0, 1.0]);
    let a = with_accessor(&mut gltf, &mut bin, &normals, json!({ "componentType": 5126, "count": 2, "type": "VEC3" }));
    gltf["meshes"][0]["primitives"][0]["attributes"]["NORMAL"] = json!(a);
    let message = load_err(&write_scene(&dir, &gltf, &bin));
    assert!(message.contains("NORMAL") && message.contains("2") && message.contains("POSITION"), "{message}");
}

#[test]
fn texture_coordinates_shorter_than_positions() {
    let dir = scratch("short-uvs");
    let (mut gltf, mut bin) = tiny_gltf(&TRIANGLE, &[0, 1, 2]);
    let a = with_accessor(
        &mut gltf,
        &mut bin,
        &f32_bytes(&[0.0; 2]),
        json!({ "componentType": 5126, "count": 1, "type": "VEC2" }),
    );
    gltf["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"] = json!(a);
    let message = load_err(&write_scene(&dir, &gltf, &bin));
    assert!(message.contains("TEXCOORD_0") && message.contains("POSITION"), "{message}");
}

#[test]
fn float_indices_are_refused() {
    let dir = scratch("float-indices");
    let (mut gltf, bin) = tiny_gltf(&TRIANGLE, &[0, 1, 2]);
    gltf["accessors"][1]["componentType"] = json!(5126);
    let message = load_err(&write_scene(&dir, &gltf, &bin));
    assert!(message.contains("accessors[1]") && message.contains("indices"), "{message}");
}

#[test]
fn signed_texture_coordinates_are_refused() {
    let dir = scratch("signed-uvs");
    let (mut gltf, mut bin) = tiny_gltf(&TRIANGLE, &[0, 1, 2]);
    let a =
        with_accessor(&mut gltf, &mut bin, &[0u8; 12], json!({ "componentType": 5122, "count": 3, "type": "VEC2" }));
    gltf["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"] = json!(a);
    let message = load_err(&write_scene(&dir, &gltf, &bin));
    assert!(message.contains(&format!("accessors[{a}]")) && message.contains("TEXCOORD_0"), "{message}");
}

#[test]
fn stride_smaller_than_the_element() {
    let dir = scratch("small-stride");
    let (mut gltf, bin) = tiny_gltf(&TRIANGLE, &[0, 1, 2]);
    gltf["bufferViews"][0]["byteStride"] = json!(4);
    let message = load_err(&write_scene(&dir, &gltf, &bin));
    assert!(message.contains("accessors[0]") && message.contains("stride"), "{message}");
}

#[test]
fn huge_node_scale() {
    let dir = scratch("huge-scale");
    let (mut gltf, bin) = tiny_gltf(&TRIANGLE, &[0, 1, 2]);
    gltf["nodes"][0]["scale"] = json!([1e20, 1e20, 1e20]);
    let message = load_err(&write_scene(&dir, &gltf, &bin));
    assert!(message.contains("meshes[0] primitives[0]") && message.contains("from the origin"), "{message}");
}

#[test]
fn scene_without_triangles() {
    let dir = scratch("no-triangles");
    let (mut gltf, bin) = tiny_gltf(&TRIANGLE, &[0, 1, 2]);
    gltf["meshes"][0]["primitives"][0]["mode"] = json!(0);
    let message = load_err(&write_scene(&dir, &gltf, &bin));
    assert!(message.contains("scene.gltf") && message.contains("no triangles"), "{message}");
}

fn with_camera(gltf: &mut Value, camera: Value, node: Value) {
    gltf["cameras"] = json!([camera]);
    gltf["nodes"].as_array_mut().unwrap().push(node);
    let index = gltf["nodes"].as_array().unwrap().len() - 1;
    gltf["scenes"][0]["nodes"].as_array_mut().unwrap().push(json!(index));
}

#[test]
fn camera_without_a_field_of_view() {
    for (test, yfov) in [("zero-fov", 0.0), ("negative-fov", -0.5), ("wide-fov", 3.5)] {
        let dir = scratch(test);
        let (mut gltf, bin) = tiny_gltf(&TRIANGLE, &[0, 1, 2]);
        with_camera(
            &mut gltf,
            json!({ "type": "perspective", "perspective": { "yfov": yfov, "znear": 0.01 } }),
            json!({ "name": "Cam", "camera": 0 }),
        );
        let message = load_err(&write_scene(&dir, &gltf, &bin));
        assert!(message.contains("nodes[1] \"Cam\"") && message.contains("field of view"), "{test}: {message}");
    }
}

#[test]
fn camera_with_zero_scale() {
    let dir = scratch("zero-scale-camera");
    let (mut gltf, bin) = tiny_gltf(&TRIANGLE, &[0, 1, 2]);
    with_camera(
        &mut gltf,
        json!({ "type": "perspective", "perspective": { "yfov": 0.7, "znear": 0.01 } }),
        json!({ "name": "Cam", "camera": 0, "scale": [0.0, 0.0, 0.0] }),
    );
    let message = load_err(&write_scene(&dir, &gltf, &bin));
    assert!(message.contains("nodes[1] \"Cam\"") && message.contains("direction"), "{message}");
}

fn with_material(gltf: &mut Value, material: Value) {
    gltf["materials"] = json!([material]);
    gltf["meshes"][0]["primitives"][0]["material"] = json!(0);
}

#[test]
fn material_values_out_of_range() {
    let cases = [
        (
            "negative-base",
            json!({ "name": "M", "pbrMetallicRoughness": { "baseColorFactor": [-1.0, 0.5, 0.5, 1.0] } }),
            "baseColorFactor",
        ),
        (
            "huge-emission",
            json!({ "name": "M", "emissiveFactor": [1.0, 1.0, 1.0],
            "extensions": { "KHR_materials_emissive_strength": { "emissiveStrength": 1e10 } } }),
            "emissi",
        ),
        ("negative-emission", json!({ "name": "M", "emissiveFactor": [1.0, -1.0, 1.0] }), "emissiveFactor"),
    ];
    for (test, material, key) in cases {
        let dir = scratch(test);
        let (mut gltf, bin) = tiny_gltf(&TRIANGLE, &[0, 1, 2]);
        with_material(&mut gltf, material);
        if test == "huge-emission" {
            gltf["extensionsUsed"] = json!(["KHR_materials_emissive_strength"]);
        }
        let message = load_err(&write_scene(&dir, &gltf, &bin));
        assert!(message.contains("materials[0] \"M\"") && message.contains(key), "{test}: {message}");
    }
}

#[test]
fn buffer_outside_the_scene_folder() {
    for (test, uri) in
        [("parent-uri", "../secret.bin"), ("absolute-uri", "/etc/passwd"), ("file-uri", "file:///etc/passwd")]
    {
        let dir = scratch(test);
        let (mut gltf, bin) = tiny_gltf(&TRIANGLE, &[0, 1, 2]);
        std::fs::write(dir.parent().unwrap().join("secret.bin"), &bin).unwrap();
        gltf["buffers"][0]["uri"] = json!(uri);
        let message = load_err(&write_scene(&dir, &gltf, &bin));
        assert!(message.contains("buffers[0]") && message.contains("scene folder"), "{test}: {message}");
    }
}

#[test]
fn malformed_percent_encoding() {
    let dir = scratch("percent");
    let (mut gltf, bin) = tiny_gltf(&TRIANGLE, &[0, 1, 2]);
    gltf["buffers"][0]["uri"] = json!("scene%FF.bin");
    let message = load_err(&write_scene(&dir, &gltf, &bin));
    assert!(message.contains("buffers[0]") && message.contains("%FF"), "{message}");
}

fn with_texture(gltf: &mut Value, image: Value) {
    gltf["images"] = json!([image]);
    gltf["textures"] = json!([{ "source": 0 }]);
    with_material(gltf, json!({ "name": "M", "pbrMetallicRoughness": { "baseColorTexture": { "index": 0 } } }));
}

#[test]
fn missing_texture_is_named() {
    let dir = scratch("missing-texture");
    let (mut gltf, bin) = tiny_gltf(&TRIANGLE, &[0, 1, 2]);
    with_texture(&mut gltf, json!({ "name": "Bricks", "uri": "bricks.png" }));
    let message = load_err(&write_scene(&dir, &gltf, &bin));
    assert!(message.contains("images[0] \"Bricks\"") && message.contains("bricks.png"), "{message}");
}

#[test]
fn undecodable_texture_is_named() {
    let dir = scratch("broken-texture");
    let (mut gltf, bin) = tiny_gltf(&TRIANGLE, &[0, 1, 2]);
    std::fs::write(dir.join("bricks.png"), b"\x89PNG\r\n\x1a\nnot really").unwrap();
    with_texture(&mut gltf, json!({ "uri": "bricks.png" }));
    let message = load_err(&write_scene(&dir, &gltf, &bin));
    assert!(message.contains("images[0]") && message.contains("bricks.png"), "{message}");
}

#[test]
fn texture_view_past_its_buffer() {
    let dir = scratch("texture-view");
    let (mut gltf, bin) = tiny_gltf(&TRIANGLE, &[0, 1, 2]);
    gltf["bufferViews"].as_array_mut().unwrap().push(json!({ "buffer": 0, "byteOffset": 8, "byteLength": 4000 }));
    with_texture(&mut gltf, json!({ "bufferView": 2, "mimeType": "image/png" }));
    let message = load_err(&write_scene(&dir, &gltf, &bin));
    assert!(message.contains("images[0]") && message.contains("bufferViews[2]"), "{message}");
}

#[test]
fn light_with_no_area() {
    let dir = scratch("flat-light");
    // Three collinear vertices: a triangle of zero area.
    let (mut gltf, bin) = tiny_gltf(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]], &[0, 1, 2]);
    with_material(&mut gltf, json!({ "name": "Glow", "emissiveFactor": [1.0, 1.0, 1.0] }));
    std::fs::write(dir.join("scene.toml"), "[light]\nnode = \"Tri\"\nmin = [-1, -1, -1]\nmax = [1, 1, 1]\n").unwrap();
    let message = load_err(&write_scene(&dir, &gltf, &bin));
    assert!(message.contains("light.node") && message.contains("no area"), "{message}");
}

/// `lights` added to a `tiny_gltf` as `KHR_lights_punctual`, light i on a node of its own named
/// `nodes[i].0` (with the extra node properties `nodes[i].1`), in the scene beside the triangle.
fn with_lights(gltf: &mut Value, lights: Value, nodes: &[(&str, Value)]) {
    gltf["extensionsUsed"] = json!(["KHR_lights_punctual"]);
    gltf["extensions"] = json!({ "KHR_lights_punctual": { "lights": lights } });
    for (light, (name, extra)) in nodes.iter().enumerate() {
        let mut node = json!({ "name": name, "extensions": { "KHR_lights_punctual": { "light": light } } });
        node.as_object_mut().unwrap().extend(extra.as_object().unwrap().clone());
        gltf["nodes"].as_array_mut().unwrap().push(node);
    }
    gltf["scenes"][0]["nodes"] = json!((0..=nodes.len()).collect::<Vec<_>>());
}

#[test]
fn point_light_that_emits_nothing() {
    let dir = scratch("dark-light");
    let (mut gltf, bin) = tiny_gltf(&TRIANGLE, &[0, 1, 2]);
    with_lights(&mut gltf, json!([{ "type": "point", "intensity": 0.0 }]), &[("Bulb", json!({}))]);
    std::fs::write(dir.join("scene.toml"), "[light]\nnode = \"Bulb\"\nmin = [-1, -1, -1]\nmax = [1, 1, 1]\n").unwrap();
    let message = load_err(&write_scene(&dir, &gltf, &bin));
    assert!(message.contains("light.node") && message.contains("emits nothing"), "{message}");
}

#[test]
fn sidecar_bake_overrides_out_of_range() {
    for (test, value) in [("zero-configs", "0"), ("huge-configs", "4000000000")] {
        let dir = cornell_with_sidecar(test, &format!("[bake.final]\nconfigurations = {value}\n"));
        let message = load_err(&dir);
        assert!(message.contains("scene.toml") && message.contains("bake.final.configurations"), "{test}: {message}");
    }
    let dir = cornell_with_sidecar("zero-paths", "[bake.test]\npaths_per_sample = 0\n");
    let message = load_err(&dir);
    assert!(message.contains("bake.test.paths_per_sample"), "{message}");
}

#[test]
fn sidecar_tree_overrides() {
    let text = "[bake.final]\nsplit_depth = 3\nmax_samples_per_network = 20000\n";
    let scene = Scene::load(&cornell_with_sidecar("tree-overrides", text)).unwrap();
    let settings = BakeSettings::new(Quality::Final, 1, &scene);
    assert_eq!((settings.split_depth, settings.max_samples_per_network), (3, 20_000));
    let without = Scene::load(&cornell_with_sidecar("no-tree-overrides", "")).unwrap();
    let deeper = Scene::load(&cornell_with_sidecar("deeper", "[bake.final]\nsplit_depth = 4\n")).unwrap();
    let hashes = [scene.content_hash, without.content_hash, deeper.content_hash];
    assert!(hashes[0] != hashes[1] && hashes[0] != hashes[2] && hashes[1] != hashes[2], "{hashes:x?}");
    // Bake settings do not change what a path-traced image shows: eval's references stay cached.
    assert_eq!(scene.light_transport_hash, without.light_transport_hash);
    let message = load_err(&cornell_with_sidecar("too-deep", "[bake.final]\nsplit_depth = 9\n"));
    assert!(message.contains("bake.final.split_depth") && message.contains("0 to 8"), "{message}");
}

#[test]
fn sidecar_eval_spp() {
    let dir = cornell_with_sidecar("eval-spp", "[eval]\nspp = 2048\n");
    let scene = Scene::load(&dir).unwrap();
    assert_eq!(scene.eval.spp, Some(2048));
    let without = Scene::load(&cornell_with_sidecar("no-eval", "")).unwrap();
    assert_eq!(without.eval.spp, None);
    assert_eq!(scene.content_hash, without.content_hash, "eval defaults do not call for a re-bake");
    let message = load_err(&cornell_with_sidecar("zero-spp", "[eval]\nspp = 0\n"));
    assert!(message.contains("scene.toml") && message.contains("eval.spp"), "{message}");
}

#[test]
fn sidecar_box_far_from_the_origin() {
    let dir = cornell_with_sidecar("huge-box", "[camera]\nmin = [-1e38, 0, 0]\nmax = [1e38, 1, 1]\n");
    let message = load_err(&dir);
    assert!(
        message.contains("scene.toml") && message.contains("camera") && message.contains("from the origin"),
        "{message}"
    );
}

#[test]
fn point_light_too_bright_to_sum() {
    let dir = scratch("bright-light");
    let (mut gltf, bin) = tiny_gltf(&TRIANGLE, &[0, 1, 2]);
    with_lights(&mut gltf, json!([{ "type": "point", "intensity": 1e38 }]), &[("Sun", json!({}))]);
    let message = load_err(&write_scene(&dir, &gltf, &bin));
    assert!(message.contains("nodes[1] \"Sun\"") && message.contains("intensity"), "{message}");
}

#[test]
fn a_scene_without_a_camera_gets_a_view_of_everything() {
    let dir = scratch("no-camera");
    let (gltf, bin) = tiny_gltf(&TRIANGLE, &[0, 1, 2]);
    let scene = Scene::load(&write_scene(&dir, &gltf, &bin)).unwrap();
    let view = &scene.views[0];
    assert_eq!(view.name, "default");
    assert!(scene.warnings.iter().any(|w| w.contains("no camera")), "{:?}", scene.warnings);
    // The triangle lies in front of the eye, inside the field of view.
    let forward = (view.target - view.eye).normalize();
    for p in TRIANGLE.map(Vec3::from) {
        let angle = forward.angle_between(p - view.eye).to_degrees();
        assert!(angle < view.fov_y / 2.0, "{p} is {angle}° off the view axis");
    }
}

#[test]
fn the_scene_hash_covers_what_shapes_the_samples_and_not_the_views() {
    let sidecar = std::fs::read_to_string(repo().join("scenes/cornell-box/scene.toml")).unwrap();
    let hash = |test: &str, sidecar: &str| Scene::load(&cornell_with_sidecar(test, sidecar)).unwrap().content_hash;
    let original = hash("hash-original", &sidecar);
    let with_view = format!("{sidecar}\n[views.extra]\neye = [0.1, 0.2, -0.5]\ntarget = [0.3, 0.3, 0.3]\nfov_y = 50\n");
    assert_eq!(hash("hash-view", &with_view), original, "a new view needs no re-bake");
    let wider_camera = sidecar.replace("max = [0.50, 0.50, 0.05]", "max = [0.51, 0.50, 0.05]");
    assert_ne!(wider_camera, sidecar, "the test must change the sidecar");
    assert_ne!(hash("hash-camera", &wider_camera), original, "the camera box shapes the samples");
    let more_configurations = format!("{sidecar}\n[bake.test]\nconfigurations = 17\n");
    assert_ne!(hash("hash-bake", &more_configurations), original);
}

#[test]
fn a_sidecar_under_another_name_is_named_not_silently_ignored() {
    let dir = cornell_with_sidecar(
        "other-name",
        &std::fs::read_to_string(repo().join("scenes/cornell-box/scene.toml")).unwrap(),
    );
    std::fs::rename(dir.join("scene.gltf"), dir.join("MyScene.gltf")).unwrap();
    let scene = Scene::load(&dir.join("MyScene.gltf")).unwrap();
    assert!(scene.moving_light.is_none());
    assert!(
        scene.warnings.iter().any(|w| w.contains("scene.toml is not read") && w.contains("MyScene.toml")),
        "{:?}",
        scene.warnings
    );
    assert_eq!(scene.sidecar_file(), dir.join("MyScene.toml"));
    assert_eq!(scene.model_file(), dir.join("MyScene.safetensors"), "two glTFs in a folder keep their models apart");
    assert_eq!(
        Scene::load(&repo().join("scenes/cornell-box")).unwrap().model_file(),
        repo().join("scenes/cornell-box/model.safetensors")
    );
    std::fs::rename(dir.join("scene.toml"), dir.join("MyScene.toml")).unwrap();
    let scene = Scene::load(&dir.join("MyScene.gltf")).unwrap();
    assert!(scene.moving_light.is_some() && scene.warnings.is_empty(), "{:?}", scene.warnings);
}

#[test]
fn a_sidecar_light_may_not_take_a_name_of_the_gltf() {
    let dir = cornell_with_sidecar(
        "added-light",
        "[light]\nnode = \"TallBlock\"\nmin = [0.1, 0.3, 0.1]\nmax = [0.4, 0.5, 0.4]\nintensity = [1, 1, 1]\n",
    );
    let message = load_err(&dir);
    assert!(message.contains("light.intensity") && message.contains("TallBlock"), "{message}");
}

#[test]
fn point_light_intensity_is_candela_unless_the_sidecar_says_otherwise() {
    let make = |test: &str, sidecar: Option<&str>| {
        let dir = scratch(test);
        let (mut gltf, bin) = tiny_gltf(&TRIANGLE, &[0, 1, 2]);
        let light = json!([{ "type": "point", "intensity": 1366.0, "color": [1.0, 0.5, 0.25] }]);
        with_lights(&mut gltf, light, &[("Bulb", json!({}))]);
        if let Some(text) = sidecar {
            std::fs::write(dir.join("scene.toml"), text).unwrap();
        }
        Scene::load(&write_scene(&dir, &gltf, &bin)).unwrap().point_lights[0].intensity
    };
    // 1366 cd = 2 W/sr at 683 lm/W.
    assert_eq!(make("candela", None), Vec3::new(2.0, 1.0, 0.5));
    assert_eq!(make("watts", Some("[units]\npoint_lights = \"W/sr\"\n")), Vec3::new(1366.0, 683.0, 341.5));
    let dir = cornell_with_sidecar("bad-units", "[units]\npoint_lights = \"lumen\"\n");
    let message = load_err(&dir);
    assert!(message.contains("scene.toml") && message.contains("lumen"), "{message}");
}

#[test]
fn spot_lights_keep_their_cone_and_directional_lights_say_why_they_are_skipped() {
    let dir = scratch("spot");
    let (mut gltf, bin) = tiny_gltf(&TRIANGLE, &[0, 1, 2]);
    let lights = json!([
        { "type": "spot", "intensity": 683.0, "spot": { "innerConeAngle": 0.2, "outerConeAngle": 0.5 } },
        { "type": "directional", "intensity": 3.0 },
    ]);
    // Rotated 90° about x: the node's -z points down (-y).
    let (sin, cos) = (std::f32::consts::FRAC_PI_4.sin(), std::f32::consts::FRAC_PI_4.cos());
    let spot = json!({ "rotation": [-sin, 0.0, 0.0, cos], "translation": [0.0, 2.0, 0.0] });
    with_lights(&mut gltf, lights, &[("Spot", spot), ("Sun", json!({}))]);
    let scene = Scene::load(&write_scene(&dir, &gltf, &bin)).unwrap();
    let spot = &scene.point_lights[0];
    let cone = spot.cone.expect("a spot light has a cone");
    assert!((cone.direction - Vec3::NEG_Y).length() < 1e-5, "{}", cone.direction);
    assert!((cone.cos_inner - 0.2f32.cos()).abs() < 1e-6 && (cone.cos_outer - 0.5f32.cos()).abs() < 1e-6);
    assert_eq!(spot.intensity, Vec3::ONE);
    assert_eq!(scene.point_lights.len(), 1);
    assert!(scene.warnings.iter().any(|w| w.contains("\"Sun\"") && w.contains("no position")), "{:?}", scene.warnings);
}

/// The gallery carries every material feature as the generator wrote it.
#[test]
fn gallery_materials_as_written() {
    let scene = Scene::load(&repo().join("scenes/gallery")).unwrap();
    let material = |name: &str| scene.materials.iter().find(|m| m.name == name).unwrap();
    let tiles = material("tiles").base_color_texture.expect("tiles are textured");
    assert_eq!(tiles.transform, UvTransform::new([0.1, 0.2], 0.3, [3.0, 3.0]));
    let brick = material("brick");
    assert!(brick.metallic_roughness_texture.is_some());
    assert_eq!(brick.normal_texture.map(|n| n.1), Some(1.0));
    let leaf = material("leaf");
    assert_eq!(leaf.alpha_mode, AlphaMode::Mask { cutoff: 0.5 });
    assert!(leaf.double_sided);
    let screen = material("screen");
    assert!(screen.emissive_texture.is_some() && screen.double_sided);
    assert!(screen.is_emissive() && !screen.is_plain_emitter(), "a textured emitter also learns");
    let light = scene.moving_light.as_ref().unwrap();
    let LightKind::Point(i) = light.kind else { panic!("the spot is the moving light") };
    assert!(scene.point_lights[i].cone.is_some());
    // Tangents, derived from the UVs: one per vertex, unit, orthogonal to the normal.
    for object in &scene.objects {
        assert_eq!(object.tangents.len(), object.positions.len(), "{}", object.name);
        for (t, n) in object.tangents.iter().zip(&object.normals) {
            assert!((t.truncate().length() - 1.0).abs() < 1e-4 && t.truncate().dot(*n).abs() < 1e-3);
            assert!(t.w == 1.0 || t.w == -1.0);
        }
    }
}

/// One textured triangle whose material is `material` (a glTF material object), with UVs.
fn textured_triangle(test: &str, material: Value, extra_attributes: Option<(&str, Vec<f32>, &str)>) -> PathBuf {
    let dir = scratch(test);
    let (mut gltf, mut bin) = tiny_gltf(&TRIANGLE, &[0, 1, 2]);
    let mut attribute = |name: &str, values: Vec<f32>, kind: &str, gltf: &mut Value| {
        let offset = bin.len();
        bin.extend(values.iter().flat_map(|v| v.to_le_bytes()));
        gltf["bufferViews"]
            .as_array_mut()
            .unwrap()
            .push(json!({ "buffer": 0, "byteOffset": offset, "byteLength": bin.len() - offset }));
        let view = gltf["bufferViews"].as_array().unwrap().len() - 1;
        gltf["accessors"]
            .as_array_mut()
            .unwrap()
            .push(json!({ "bufferView": view, "componentType": 5126, "count": 3, "type": kind }));
        gltf["meshes"][0]["primitives"][0]["attributes"][name] = json!(gltf["accessors"].as_array().unwrap().len() - 1);
    };
    attribute("TEXCOORD_0", vec![0.0, 0.0, 1.0, 0.0, 0.0, 1.0], "VEC2", &mut gltf);
    attribute("NORMAL", vec![0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0], "VEC3", &mut gltf);
    if let Some((name, values, kind)) = extra_attributes {
        attribute(name, values, kind, &mut gltf);
    }
    gltf["buffers"][0]["byteLength"] = json!(bin.len());
    // A 1×1 PNG as a data URI.
    let mut png = Vec::new();
    image::RgbaImage::from_pixel(1, 1, image::Rgba([128, 128, 255, 255]))
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .unwrap();
    gltf["images"] = json!([{ "uri": format!("data:image/png;base64,{}", base64(&png)) }]);
    gltf["textures"] = json!([{ "source": 0 }]);
    gltf["materials"] = json!([material]);
    gltf["meshes"][0]["primitives"][0]["material"] = json!(0);
    write_scene(&dir, &gltf, &bin)
}

#[test]
fn blend_is_drawn_opaque_with_a_warning() {
    let path = textured_triangle("blend", json!({ "alphaMode": "BLEND" }), None);
    let scene = Scene::load(&path).unwrap();
    assert_eq!(scene.materials[0].alpha_mode, AlphaMode::Opaque);
    assert!(scene.warnings.iter().any(|w| w.contains("BLEND")), "{:?}", scene.warnings);
}

#[test]
fn normal_texture_transform_is_read() {
    let material = json!({
        "normalTexture": {
            "index": 0, "scale": 0.5,
            "extensions": { "KHR_texture_transform": { "offset": [0.25, 0.5], "rotation": 1.0, "scale": [2.0, 4.0] } }
        },
    });
    let scene = Scene::load(&textured_triangle("normal-transform", material, None)).unwrap();
    let (texture, scale) = scene.materials[0].normal_texture.unwrap();
    assert_eq!(scale, 0.5);
    assert_eq!(texture.transform, UvTransform::new([0.25, 0.5], 1.0, [2.0, 4.0]));
}

#[test]
fn tangents_are_derived_from_uvs_or_read() {
    // u along +x and v along +y on a triangle facing +z: tangent +x, bitangent +y (w = 1).
    let scene = Scene::load(&textured_triangle("derived-tangents", json!({}), None)).unwrap();
    assert_eq!(scene.objects[0].tangents, vec![rrf_baker::glam::Vec4::new(1.0, 0.0, 0.0, 1.0); 3]);
    let material = json!({ "normalTexture": { "index": 0 } });
    let tangents = vec![0.0, 1.0, 0.0, -1.0, 0.0, 1.0, 0.0, -1.0, 0.0, 1.0, 0.0, -1.0];
    let scene = Scene::load(&textured_triangle("tangents", material, Some(("TANGENT", tangents, "VEC4")))).unwrap();
    // Read as written (the node has no transform).
    assert_eq!(scene.objects[0].tangents, vec![rrf_baker::glam::Vec4::new(0.0, 1.0, 0.0, -1.0); 3]);
}

#[test]
fn unusable_texture_transforms_are_refused() {
    let material = json!({
        "pbrMetallicRoughness": {
            "baseColorTexture": { "index": 0, "extensions": { "KHR_texture_transform": { "scale": [1e30, 1.0] } } }
        },
    });
    let err = load_err(&textured_triangle("huge-transform", material, None));
    assert!(err.contains("materials[0]") && err.contains("KHR_texture_transform"), "{err}");
    let material = json!({ "pbrMetallicRoughness": { "baseColorFactor": [1.0, 1.0, 1.0, 2.0] } });
    let err = load_err(&textured_triangle("alpha-factor", material, None));
    assert!(err.contains("baseColorFactor"), "{err}");
}
