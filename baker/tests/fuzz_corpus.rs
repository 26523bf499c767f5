//! Replays the fuzz targets' seed corpus and every input the fuzzers found a crash with
//! (`baker/fuzz/corpus/TARGET/`, `baker/fuzz/regressions/TARGET/`) through the same code the
//! targets run. The seeds are valid inputs and must load; the regressions must simply return.

use std::path::{Path, PathBuf};

use rrf_baker::fuzzing;
use rrf_baker::model::Model;
use rrf_baker::scene::{Scene, Sidecar};

fn inputs(kind: &str, target: &str) -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz").join(kind).join(target);
    let mut files: Vec<PathBuf> = match std::fs::read_dir(&dir) {
        Ok(entries) => entries.map(|e| e.unwrap().path()).collect(),
        Err(_) => Vec::new(),
    };
    files.sort();
    files
}

fn replay(target: &str, run: fn(&[u8])) -> usize {
    let files: Vec<PathBuf> = inputs("corpus", target).into_iter().chain(inputs("regressions", target)).collect();
    for file in &files {
        let bytes = std::fs::read(file).unwrap();
        // A panic here names the input through the test's output.
        eprintln!("{target}: {}", file.display());
        run(&bytes);
    }
    files.len()
}

#[test]
fn model_inputs() {
    for seed in inputs("corpus", "model") {
        Model::from_bytes(&std::fs::read(&seed).unwrap()).unwrap_or_else(|e| panic!("{}: {e}", seed.display()));
    }
    assert!(replay("model", fuzzing::model) > 0);
}

#[test]
fn sidecar_inputs() {
    for seed in inputs("corpus", "sidecar") {
        let text = std::fs::read_to_string(&seed).unwrap();
        Sidecar::parse(&seed, &text).unwrap_or_else(|e| panic!("{e}"));
    }
    assert!(replay("sidecar", fuzzing::sidecar) > 0);
}

#[test]
fn gltf_inputs() {
    for seed in inputs("corpus", "gltf") {
        let scene = Scene::from_gltf_bytes(&seed, &std::fs::read(&seed).unwrap()).unwrap_or_else(|e| panic!("{e}"));
        assert!(scene.triangle_count() > 0 && !scene.views.is_empty(), "{}", seed.display());
    }
    assert!(replay("gltf", fuzzing::gltf) > 0);
}
