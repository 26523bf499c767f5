//! Many noisy samples or few clean ones? At an equal budget of paths, trains the Cornell box
//! floor's direct and indirect networks on N samples of K paths each, for several (N, K), and
//! measures each network against a clean held-out set (512 paths per sample) that no network
//! trains on. A least-squares fit converges to the mean, so noise in the targets costs less
//! than the lack of samples does, up to a point.
//!
//! `cargo bench -p rrf-baker --bench sampling_tradeoff`

use std::path::Path;

use rrf_baker::bake::lm::{self, initial_parameters, Dataset, LmSettings};
use rrf_baker::bake::samples::{latin_hypercube, sample_configuration, Aim, Sample};
use rrf_baker::bake::{network_data, BakeSettings, Quality};
use rrf_baker::network::{normalize, Component};
use rrf_baker::scene::Scene;
use rrf_baker::trace::{Geometry, TraceSettings};

fn floor_samples(scene: &Scene, geometry: &Geometry, count: usize, paths: u32, seed: u64) -> Vec<Sample> {
    let light = scene.moving_light.as_ref().unwrap();
    let floor = scene.object_by_name("Floor").unwrap().id;
    let trace = TraceSettings { max_depth: 8, rr_depth: Some(5) };
    let mut out = Vec::new();
    let configs = latin_hypercube(256, &light.bounds, &scene.camera_box.unwrap(), seed);
    for (i, c) in configs.iter().cycle().enumerate() {
        out.extend(
            sample_configuration(scene, geometry, c, Aim::Sphere, 400, paths, &trace, seed * 1_000_003 + i as u64)
                .into_iter()
                .filter(|s| s.object == floor),
        );
        if out.len() >= count {
            break;
        }
    }
    out.truncate(count);
    out
}

fn main() {
    let scene = Scene::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/cornell-box")).expect("scene");
    let geometry = Geometry::new(&scene);
    let floor = scene.object_by_name("Floor").unwrap().id;
    let clean = floor_samples(&scene, &geometry, 1500, 512, 99);
    const BUDGET: usize = 96_000;
    println!("Floor networks, {BUDGET} paths per training set; MSE against 1500 held-out samples of 512 paths");
    println!("{:>8} {:>6}  {:>12} {:>12}", "samples", "paths", "direct MSE", "indirect MSE");
    for k in [2u32, 4, 8, 16, 32, 64] {
        let n = BUDGET / k as usize;
        let samples = floor_samples(&scene, &geometry, n, k, 1);
        let refs: Vec<&Sample> = samples.iter().collect();
        let mut settings = BakeSettings::new(Quality::Final, 1, &scene);
        settings.max_samples_per_network = usize::MAX;
        let mut errors = Vec::new();
        for component in Component::ALL {
            let data = network_data(&scene, &settings, floor, component, &refs);
            let result = lm::train(
                &data.train,
                &data.validation,
                initial_parameters(3, [0.0; 3]),
                &LmSettings { max_iterations: 40, patience: 10 },
            );
            let test = Dataset {
                inputs: clean
                    .iter()
                    .map(|s| std::array::from_fn(|i| normalize(s.inputs[i], data.input_min[i], data.input_max[i])))
                    .collect(),
                targets: clean.iter().map(|s| s.target(component).map(|v| v / data.output_scale)).collect(),
                gains: Vec::new(),
            };
            errors.push(test.mse(&result.params) * f64::from(data.output_scale).powi(2));
        }
        println!("{n:>8} {k:>6}  {:>12.3e} {:>12.3e}", errors[0], errors[1]);
    }
}
