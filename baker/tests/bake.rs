//! Baking: resumption gives the same model, the model file round-trips, and every kind of bad
//! model file is refused with a clear error.

use std::collections::HashSet;
use std::path::{Path, PathBuf};

use rrf_baker::bake::{bake, BakeProgress, BakeSettings, Quality};
use rrf_baker::model::Model;
use rrf_baker::network::Component;
use rrf_baker::scene::Scene;

struct Quiet;

impl BakeProgress for Quiet {
    fn sampled(&self, _: u64, _: u64) {}
    fn trained(&self, _: u64, _: u64) {}
}

fn scene(name: &str) -> Scene {
    Scene::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes").join(name)).unwrap()
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("rrf-bake-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn test_bake(scene: &Scene, cache: &Path) -> (Model, rrf_baker::bake::BakeReport) {
    let settings = BakeSettings::new(Quality::Test, 3, scene);
    bake(scene, &settings, cache, &Quiet).unwrap()
}

#[test]
fn interrupted_bake_resumes_to_the_same_model() {
    let scene = scene("cornell-box");
    let full_cache = scratch("full");
    let (full, report) = test_bake(&scene, &full_cache);
    assert_eq!(report.resumed_shards, 0);
    assert!(report.shards >= 4, "the test preset should make several shards");
    assert!(!full.networks.is_empty());

    // An interrupted bake: half the shards finished, one half-written shard left behind.
    let partial_cache = scratch("partial");
    let shards = cache_files(&full_cache, "shard-");
    let keep = shards.len() / 2;
    for shard in &shards[..keep] {
        std::fs::copy(shard, partial_cache.join(shard.file_name().unwrap())).unwrap();
    }
    let torn = std::fs::read(&shards[keep]).unwrap();
    std::fs::write(partial_cache.join(shards[keep].file_name().unwrap()), &torn[..torn.len() / 3]).unwrap();

    let (resumed, report) = test_bake(&scene, &partial_cache);
    assert_eq!(report.resumed_shards, keep, "finished shards are reused, the torn one is not");
    assert!(
        resumed.to_bytes().unwrap() == full.to_bytes().unwrap(),
        "a resumed bake must give a model file byte-identical to the uninterrupted one"
    );

    // A shard whose bytes were damaged on disk is recomputed, not trusted.
    let damaged_cache = scratch("damaged");
    for file in sample_files(&full_cache) {
        let mut bytes = std::fs::read(&file).unwrap();
        if file.ends_with("shard-00001.bin") {
            let middle = bytes.len() / 2;
            bytes[middle] ^= 0x10;
        }
        std::fs::write(damaged_cache.join(file.file_name().unwrap()), bytes).unwrap();
    }
    let (repaired, report) = test_bake(&scene, &damaged_cache);
    assert_eq!((report.resumed_shards, report.corrupt_files), (report.shards - 1, 1));
    assert!(repaired.to_bytes().unwrap() == full.to_bytes().unwrap());

    // Killed during training: the networks already trained are kept, the rest trained again.
    let checkpoints = cache_files(&full_cache, "network-");
    let jobs: HashSet<_> = full.networks.iter().map(|n| (n.object.clone(), n.component)).collect();
    assert_eq!(checkpoints.len(), jobs.len(), "one checkpoint per object and component");
    assert!(full.networks.len() > jobs.len(), "the test bake splits some object with its kd-tree");
    let training_cache = scratch("training");
    let kept = &checkpoints[..checkpoints.len() / 2];
    for file in sample_files(&full_cache).iter().chain(kept) {
        std::fs::copy(file, training_cache.join(file.file_name().unwrap())).unwrap();
    }
    // network-OBJECT-COMPONENT.bin holds every leaf of that object's component.
    let leaves_kept: usize = kept
        .iter()
        .map(|file| {
            let name = file.file_stem().unwrap().to_str().unwrap();
            let (id, component) = name["network-".len()..].split_once('-').unwrap();
            let object = &scene.objects[id.parse::<usize>().unwrap()].name;
            full.networks.iter().filter(|n| &n.object == object && n.component.name() == component).count()
        })
        .sum();
    let (resumed, report) = test_bake(&scene, &training_cache);
    assert_eq!((report.resumed_shards, report.resumed_networks), (report.shards, leaves_kept));
    assert!(resumed.to_bytes().unwrap() == full.to_bytes().unwrap());
    assert_eq!(report.non_finite_dropped, 0, "no shard was traced again");
    let (_, report) = test_bake(&scene, &scratch("fresh"));
    assert_eq!(report.non_finite_dropped, 0, "the Cornell box's paths are all finite");

    // Different settings never reuse shards made with others.
    let other = BakeSettings::new(Quality::Test, 4, &scene);
    let (_, report) = bake(&scene, &other, &partial_cache, &Quiet).unwrap();
    assert_eq!(report.resumed_shards, 0);
}

/// The sample shards of both sampling passes (rays over the sphere, rays aimed at objects).
fn sample_files(cache: &Path) -> Vec<PathBuf> {
    [cache_files(cache, "shard-"), cache_files(cache, "aimed-")].concat()
}

/// The cache files whose names start with `prefix`, sorted.
fn cache_files(cache: &Path, prefix: &str) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(cache)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.file_name().unwrap().to_string_lossy().starts_with(prefix))
        .collect();
    files.sort();
    files
}

#[test]
fn bakes_too_large_to_hold_are_refused_before_any_work() {
    let mut scene = scene("cornell-box");
    scene.bake.test = Some(rrf_baker::scene::BakeOverrides {
        configurations: Some(65_536),
        rays_per_configuration: Some(1_000_000),
        ..Default::default()
    });
    let settings = BakeSettings::new(Quality::Test, 1, &scene);
    let cache = scratch("too-large").join("cache");
    let message = bake(&scene, &settings, &cache, &Quiet).unwrap_err().to_string();
    assert!(message.contains("GiB of samples") && message.contains("[bake]"), "{message}");
    assert!(!cache.exists(), "nothing was written");
}

/// A model made by hand, written, and read back field by field as the safetensors format and
/// the README describe the file (not through the model's own decoder): the length of the
/// header, one tensor per layer named `OBJECT/COMPONENT/CUTS/LAYER` with its shape and bytes,
/// and the `rrf` metadata with each network's record and the FNV-1a 64 checksum of the
/// tensor data.
#[test]
fn a_hand_made_model_is_written_as_the_format_says() {
    use rrf_baker::model::{Metadata, NetworkInfo, Untrained, FORMAT_VERSION, INPUT_NAMES};
    use rrf_baker::network::PARAMETERS;
    use rrf_baker::partition::{Region, Split};
    use serde_json::{json, Value};

    let leaf = |below: bool| NetworkInfo {
        object: "Box".into(),
        component: Component::Indirect,
        region: Region(vec![Split { axis: 0, at: 0.5, below }]),
        input_min: vec![-1.0; 13],
        input_max: vec![1.0; 13],
        target_transform: "scale".into(),
        output_scale: 2.0,
        samples: 10,
        train_mse: 0.25,
        val_mse: 0.5,
        val_noise: 0.125,
        iterations: 7,
    };
    let infos = [leaf(true), leaf(false)];
    let params: [Vec<f32>; 2] = [0, 1].map(|k| (0..PARAMETERS).map(|i| (1000 * k + i) as f32 * 0.5).collect());
    let model = Model {
        metadata: Metadata {
            format_version: FORMAT_VERSION,
            scene: "hand-made".into(),
            scene_hash: "0123456789abcdef".into(),
            inputs: INPUT_NAMES.iter().map(|s| s.to_string()).collect(),
            layers: vec![20, 10, 3],
            activation: "tanh".into(),
            networks: infos.to_vec(),
            untrained: vec![Untrained { object: "Lamp".into(), samples: 3, reason: "too few samples".into() }],
            borrowed: vec![],
            bake: json!({ "seed": 9 }),
            blend_band: 0.1,
            checksum: String::new(),
        },
        networks: infos.iter().zip(&params).map(|(info, p)| info.network(p.clone(), 0.1).unwrap()).collect(),
    };
    let bytes = model.to_bytes().unwrap();

    let header_len = u64::from_le_bytes(bytes[..8].try_into().unwrap()) as usize;
    let header: Value = serde_json::from_slice(&bytes[8..8 + header_len]).unwrap();
    let data = &bytes[8 + header_len..];
    let layers = [("w1", vec![20, 13], 0), ("b1", vec![20], 260), ("w2", vec![10, 20], 280)];
    let layers = layers.into_iter().chain([("b2", vec![10], 480), ("w3", vec![3, 10], 490), ("b3", vec![3], 520)]);
    for (layer, shape, offset) in layers {
        for (cut, p) in ["x<0.5", "x>=0.5"].iter().zip(&params) {
            let name = format!("Box/indirect/{cut}/{layer}");
            let tensor = &header[&name];
            assert_eq!(tensor["dtype"], "F32", "{name}");
            assert_eq!(tensor["shape"], json!(shape), "{name}");
            let at: Vec<usize> = serde_json::from_value(tensor["data_offsets"].clone()).unwrap();
            let count: usize = shape.iter().product();
            let expected: Vec<u8> = p[offset..offset + count].iter().flat_map(|v| v.to_le_bytes()).collect();
            assert_eq!(&data[at[0]..at[1]], expected.as_slice(), "{name}");
        }
    }
    let mut fnv = 0xcbf2_9ce4_8422_2325u64;
    for byte in params.iter().flatten().flat_map(|v| v.to_le_bytes()) {
        fnv = (fnv ^ u64::from(byte)).wrapping_mul(0x0000_0100_0000_01b3);
    }
    let rrf: Value = serde_json::from_str(header["__metadata__"]["rrf"].as_str().unwrap()).unwrap();
    assert_eq!(rrf["checksum"], format!("{fnv:016x}"));
    assert_eq!(rrf["format_version"], FORMAT_VERSION);
    assert_eq!(
        (&rrf["scene"], &rrf["scene_hash"], &rrf["blend_band"]),
        (&json!("hand-made"), &json!("0123456789abcdef"), &json!(0.1))
    );
    assert_eq!(
        (&rrf["layers"], &rrf["activation"], &rrf["bake"]),
        (&json!([20, 10, 3]), &json!("tanh"), &json!({ "seed": 9 }))
    );
    assert_eq!(rrf["untrained"], json!([{ "object": "Lamp", "samples": 3, "reason": "too few samples" }]));
    assert!(rrf.get("borrowed").is_none(), "no borrowed samples, no field");
    let low = &rrf["networks"][0];
    assert_eq!((&low["object"], &low["component"]), (&json!("Box"), &json!("indirect")));
    assert_eq!(low["region"], json!([{ "axis": 0, "at": 0.5, "below": true }]));
    assert_eq!((&low["output_scale"], &low["samples"], &low["iterations"]), (&json!(2.0), &json!(10), &json!(7)));
    assert_eq!((&low["train_mse"], &low["val_mse"], &low["val_noise"]), (&json!(0.25), &json!(0.5), &json!(0.125)));
    assert_eq!(low["input_min"], json!(vec![-1.0; 13]));

    let read = Model::from_bytes(&bytes).unwrap();
    assert_eq!(read.metadata, Metadata { checksum: format!("{fnv:016x}"), ..model.metadata.clone() });
    assert_eq!(read.networks, model.networks);
}

#[test]
fn model_round_trips_and_refuses_bad_files() {
    let scene = scene("cornell-box");
    let dir = scratch("model");
    let (model, _) = test_bake(&scene, &dir.join("cache"));
    let path = dir.join("model.safetensors");
    model.save(&path).unwrap();
    let loaded = Model::load(&path, Some(&scene)).unwrap();
    // The checksum is computed as the model is written.
    assert_eq!(loaded.metadata.checksum.len(), 16);
    let metadata = rrf_baker::model::Metadata { checksum: loaded.metadata.checksum.clone(), ..model.metadata.clone() };
    assert_eq!(loaded.metadata, metadata);
    assert_eq!(loaded.networks, model.networks);
    let floor = loaded.networks("Floor", Component::Direct);
    assert!(!floor.is_empty(), "the floor has a direct network");
    assert!(floor.iter().all(|n| n.params.len() == 523));
    assert!(!loaded.has("CeilingLight", Component::Direct), "emitters get no network");

    let bytes = std::fs::read(&path).unwrap();
    let write = |name: &str, content: &[u8]| {
        let p = dir.join(name);
        std::fs::write(&p, content).unwrap();
        p
    };
    let error = |p: &Path, scene: Option<&Scene>| Model::load(p, scene).unwrap_err().to_string();

    let message = error(&write("truncated.safetensors", &bytes[..bytes.len() - 100]), None);
    assert!(message.contains("truncated.safetensors") && message.contains("truncated or corrupted"), "{message}");

    let mut flipped = bytes.clone();
    let last = flipped.len() - 7;
    flipped[last] ^= 0x40;
    let message = error(&write("flipped.safetensors", &flipped), None);
    assert!(message.contains("checksum"), "{message}");

    let needle = format!("format_version\\\":{}", rrf_baker::model::FORMAT_VERSION).into_bytes();
    let at = bytes.windows(needle.len()).position(|w| w == needle).expect("the metadata holds the version");
    let mut versioned = bytes.clone();
    versioned[at + needle.len() - 1] = b'7';
    let message = error(&write("version.safetensors", &versioned), None);
    assert!(message.contains("version 7") && message.contains("re-bake"), "{message}");

    let message = error(&path, Some(&crate::scene("glossy-room")));
    assert!(message.contains("cornell-box") && message.contains("re-bake"), "{message}");

    let message = error(&dir.join("missing.safetensors"), None);
    assert!(message.contains("rrf bake"), "{message}");

    let message = error(&write("not-a-model.safetensors", b"hello"), None);
    assert!(message.contains("not a valid model file"), "{message}");
}

#[test]
fn model_with_non_finite_values_under_a_valid_checksum_is_refused() {
    let scene = scene("cornell-box");
    let (model, _) = test_bake(&scene, &scratch("non-finite"));
    let mut nan_weight = model.clone();
    nan_weight.networks[0].params[7] = f32::NAN;
    let message = Model::from_bytes(&nan_weight.to_bytes().unwrap()).unwrap_err();
    assert!(message.contains("parameter 7 is not finite"), "{message}");

    let mut gap = model.clone();
    let leaf = gap.networks.iter().position(|n| !n.region.is_whole()).expect("the test bake splits an object");
    gap.networks.remove(leaf);
    gap.metadata.networks.remove(leaf);
    let message = Model::from_bytes(&gap.to_bytes().unwrap()).unwrap_err();
    assert!(message.contains("not the leaves of one kd-tree"), "{message}");

    let mut inverted_range = model.clone();
    inverted_range.metadata.networks[0].input_min[3] = 2.0;
    let message = Model::from_bytes(&inverted_range.to_bytes().unwrap()).unwrap_err();
    assert!(message.contains("input ranges"), "{message}");
}

/// The models shipped beside the scenes load against them: a scene changed without a re-bake
/// fails here (its content hash no longer matches). Every object but lights, mirrors and
/// objects the bake names as untrained has networks.
#[test]
fn shipped_models_load() {
    for name in ["cornell-box", "glossy-room", "many-objects"] {
        let scene = scene(name);
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes").join(name).join("model.safetensors");
        let model = Model::load(&path, Some(&scene)).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(model.metadata.bake["quality"], "final", "{name} ships a final model");
        for object in &scene.objects {
            let emissive = object.parts.iter().all(|p| scene.materials[p.material as usize].is_emissive());
            let untrained = model.metadata.untrained.iter().any(|u| u.object == object.name);
            let has = model.has(&object.name, Component::Direct);
            let learns = !emissive && !untrained && !scene.is_mirror(object.id);
            assert_eq!(has, learns, "{name}: {}", object.name);
        }
    }
}

#[test]
fn a_bake_that_would_train_nothing_fails_and_says_why() {
    // The camera box behind the Cornell box's back wall: every ray meets the back of a
    // one-sided wall.
    let mut scene = scene("cornell-box");
    scene.camera_box = Some(rrf_baker::scene::Aabb {
        min: rrf_baker::glam::Vec3::new(0.2, 0.2, 0.7),
        max: rrf_baker::glam::Vec3::new(0.3, 0.3, 0.8),
    });
    let settings = BakeSettings::new(Quality::Test, 1, &scene);
    let message = bake(&scene, &settings, &scratch("behind-wall"), &Quiet).unwrap_err().to_string();
    assert!(message.contains("no network") && message.contains("camera box"), "{message}");
}

#[test]
fn a_bake_without_boxes_says_which_file_to_write_and_what() {
    let mut scene = scene("cornell-box");
    scene.moving_light = None;
    let settings = BakeSettings::new(Quality::Test, 1, &scene);
    let message = bake(&scene, &settings, &scratch("no-boxes"), &Quiet).unwrap_err().to_string();
    assert!(message.contains("cornell-box/scene.toml") && message.contains("[light]\nnode = "), "{message}");
}

#[test]
fn every_object_seen_from_the_camera_box_gets_networks() {
    // At the test preset, rays over the sphere leave most of the dining room's small objects
    // with too few samples; rays aimed at them make up the difference.
    let scene = scene("many-objects");
    let (model, report) = test_bake(&scene, &scratch("aimed"));
    assert!(report.aimed_objects.iter().any(|o| o == "Vase7"), "{:?}", report.aimed_objects);
    assert!(model.metadata.untrained.is_empty(), "{:?}", model.metadata.untrained);
    for object in &scene.objects {
        let emitter = object.parts.iter().all(|p| scene.materials[p.material as usize].is_emissive());
        assert_eq!(model.has(&object.name, Component::Direct), !emitter, "{}", object.name);
    }
}

#[test]
fn aimed_rays_sample_only_their_object_where_it_is_seen() {
    use rrf_baker::bake::samples::{latin_hypercube, sample_configuration, Aim, SurfacePoints};
    use rrf_baker::trace::{Geometry, TraceSettings};
    let scene = scene("cornell-box");
    let geometry = Geometry::new(&scene);
    let light = scene.moving_light.as_ref().unwrap();
    let config = latin_hypercube(1, &light.bounds, scene.camera_box.as_ref().unwrap(), 7)[0];
    let block = scene.object_by_name("ShortBlock").unwrap();
    let target = SurfacePoints::new(&scene, block.id);
    let samples =
        sample_configuration(&scene, &geometry, &config, Aim::At(&target), 400, 2, &TraceSettings::default(), 3);
    // Nothing stands between the camera box and the block: rays aimed at its far side meet
    // its near side first, which is the block too.
    assert_eq!(samples.len(), 400);
    let (min, max) =
        block.positions.iter().fold((block.positions[0], block.positions[0]), |(lo, hi), &p| (lo.min(p), hi.max(p)));
    for s in &samples {
        assert_eq!(s.object, block.id);
        let p = rrf_baker::glam::Vec3::new(s.inputs[0], s.inputs[1], s.inputs[2]);
        assert!(p.cmpge(min - 1e-4).all() && p.cmple(max + 1e-4).all(), "{p} is not on the block");
        let (to_viewer, normal) = (&s.inputs[3..6], &s.inputs[9..12]);
        assert!(to_viewer.iter().zip(normal).map(|(a, b)| a * b).sum::<f32>() > 0.0, "a face seen from behind");
    }
    assert_eq!(
        samples,
        sample_configuration(&scene, &geometry, &config, Aim::At(&target), 400, 2, &TraceSettings::default(), 3)
    );
}

/// With the kd-tree's depth at 0 the bake is the paper's plain form: one network per object
/// and component, over the whole object; with depth 1 some objects split, in two leaves each.
#[test]
fn split_depth_bounds_the_kd_tree() {
    let scene = scene("cornell-box");
    let dir = scratch("split-depth");
    let mut settings = BakeSettings::new(Quality::Test, 1, &scene);
    for depth in [0, 1] {
        settings.split_depth = depth;
        let (model, _) = bake(&scene, &settings, &dir, &Quiet).unwrap();
        let jobs: HashSet<_> = model.networks.iter().map(|n| (n.object.clone(), n.component)).collect();
        for (object, component) in &jobs {
            let leaves = model.networks(object, *component);
            assert!(leaves.len() <= 1 << depth, "{object} {component:?}: {} leaves at depth {depth}", leaves.len());
            assert!(leaves.iter().all(|n| n.region.0.len() == leaves.len().ilog2() as usize));
        }
        assert_eq!(model.networks.len() > jobs.len(), depth > 0, "depth {depth}");
    }
}

/// A pure Lambert surface reflects the same light towards every viewer, so its networks get
/// the direction to the viewer as the constant 0 (an empty input range); one with a specular
/// lobe sees it.
#[test]
fn lambert_networks_do_not_see_the_viewpoint() {
    let mut scene = scene("cornell-box");
    let tall = scene.object_by_name("TallBlock").unwrap().id as usize;
    let mut glossy = scene.materials[scene.objects[tall].parts[0].material as usize].clone();
    glossy.specular = 1.0;
    scene.materials.push(glossy);
    let glossy = scene.materials.len() as u32 - 1;
    scene.objects[tall].parts.iter_mut().for_each(|p| p.material = glossy);
    let mut settings = BakeSettings::new(Quality::Test, 1, &scene);
    settings.split_depth = 0;
    let (model, _) = bake(&scene, &settings, &scratch("lambert"), &Quiet).unwrap();

    use rrf_baker::network::{Network, INPUTS, VIEW_INPUT};
    let view = VIEW_INPUT..VIEW_INPUT + 3;
    let towards = |n: &Network, to_viewer: [f32; 3]| {
        let mut raw = [0.3f32; INPUTS];
        raw[view.clone()].copy_from_slice(&to_viewer);
        n.evaluate(&raw)
    };
    let (a, b) = ([0.0, 0.0, -1.0], [0.6, 0.64, -0.48]);
    for n in &model.networks {
        let (lo, hi) = (&n.input_min[view.clone()], &n.input_max[view.clone()]);
        if n.object == "TallBlock" {
            assert_eq!((lo, hi), (&[-1.0; 3][..], &[1.0; 3][..]), "{} {:?}", n.object, n.component);
            assert_ne!(towards(n, a), towards(n, b), "{} {:?}", n.object, n.component);
        } else {
            assert_eq!((lo, hi), (&[0.0; 3][..], &[0.0; 3][..]), "{} {:?}", n.object, n.component);
            assert_eq!(towards(n, a), towards(n, b), "{} {:?}", n.object, n.component);
        }
    }
    assert!(model.networks.iter().any(|n| n.object == "TallBlock"));
}

/// Where the kd-tree cuts an object, its two leaves disagree (each learned its own half), but
/// the blend of the two is continuous: across the cut, over a millionth of the object,
/// the prediction steps by a tiny share of the leaves' disagreement (the blend band's
/// slope allows 3e-5), where a hard cut would step by all of it. The points lie where the cut
/// plane crosses the object's vertices' edges (on the blocks' side faces), lit from the
/// middle of the light's box.
#[test]
fn blended_leaves_do_not_step_across_their_cut() {
    use rrf_baker::glam::Vec3;
    use rrf_baker::network::{evaluate_blended, raw_inputs};
    let scene = scene("cornell-box");
    let settings = BakeSettings::new(Quality::Test, 1, &scene);
    assert!(settings.blend_band > 0.0);
    let (model, _) = bake(&scene, &settings, &scratch("blend"), &Quiet).unwrap();
    let light = scene.moving_light.as_ref().unwrap().bounds;
    let light = (light.min + light.max) * 0.5;
    let (mut cuts, mut worst) = (0, 0.0f32);
    for object in &scene.objects {
        for component in Component::ALL {
            let leaves = model.networks(&object.name, component);
            if leaves.len() != 2 {
                continue;
            }
            let cut = leaves[0].region.0[0];
            let axis = cut.axis as usize;
            let delta = 1e-6 * (leaves[0].input_max[axis] - leaves[0].input_min[axis]);
            for (v, n) in object.positions.iter().zip(&object.normals) {
                let at = |offset: f32| {
                    let mut p = *v;
                    p[axis] = cut.at + offset;
                    raw_inputs(p, Vec3::new(0.0, 0.0, -1.0), light, *n, 0.5)
                };
                let disagreement = (leaves[0].evaluate(&at(0.0)) - leaves[1].evaluate(&at(0.0))).abs().max_element();
                if disagreement < 0.02 * leaves[0].output_scale {
                    continue;
                }
                let step = evaluate_blended(&leaves, &at(delta)) - evaluate_blended(&leaves, &at(-delta));
                worst = worst.max(step.abs().max_element() / disagreement);
                cuts += 1;
            }
        }
    }
    assert!(cuts > 0, "no leaves disagree at their cut: nothing to blend");
    assert!(worst < 0.005, "across a cut the blend steps by {worst} of the leaves' disagreement");
}

/// An object that no ray from the camera box reaches (here the Cornell box's short block,
/// moved behind the back wall) still gets networks, from the samples nearest to it on its
/// neighbours, and the model says so; its front, facing the room as the back wall does, is not
/// black.
#[test]
fn an_object_short_of_samples_borrows_its_neighbours() {
    let mut scene = scene("cornell-box");
    let short = scene.object_by_name("ShortBlock").unwrap().id as usize;
    scene.objects[short].positions.iter_mut().for_each(|p| p.z += 1.0);
    let settings = BakeSettings::new(Quality::Test, 1, &scene);
    let (model, _) = bake(&scene, &settings, &scratch("borrowed"), &Quiet).unwrap();
    assert!(model.metadata.untrained.is_empty(), "{:?}", model.metadata.untrained);
    let [note] = &model.metadata.borrowed[..] else { panic!("{:?}", model.metadata.borrowed) };
    assert_eq!((note.object.as_str(), note.samples), ("ShortBlock", 0));
    assert!(note.reason.contains("BackWall"), "the back wall is nearest: {}", note.reason);
    let light = scene.moving_light.as_ref().unwrap().bounds;
    let light = (light.min + light.max) * 0.5;
    let object = &scene.objects[short];
    for (p, n) in object.positions.iter().zip(&object.normals) {
        let raw = rrf_baker::network::raw_inputs(*p, rrf_baker::glam::Vec3::Z, light, *n, 0.5);
        let mut gi = rrf_baker::glam::Vec3::ZERO;
        for component in Component::ALL {
            let leaves = model.networks("ShortBlock", component);
            assert!(!leaves.is_empty(), "{component:?}");
            let radiance = rrf_baker::network::evaluate_blended(&leaves, &raw);
            assert!(radiance.is_finite(), "{component:?} at {p}: {radiance}");
            gi += radiance;
        }
        if n.z < -0.9 {
            assert!(gi.min_element() > 0.0, "the front at {p}: {gi}");
        }
    }
    let round_trip = Model::from_bytes(&model.to_bytes().unwrap()).unwrap();
    assert_eq!(round_trip.metadata.borrowed, model.metadata.borrowed);
}
