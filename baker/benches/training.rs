//! Levenberg–Marquardt against Adam on one object's real training samples: the Cornell box
//! floor's direct light (shadows of both blocks), sampled with the preview preset and cut
//! to the final preset's 12,000 samples. Prints the validation error against time for both:
//! Adam on one thread, LM on rayon's pool as in a bake (`RAYON_NUM_THREADS=1` for one).
//!
//! Adam: mini-batches of 1024, β = (0.9, 0.999); the learning rate is picked from a sweep of
//! short runs, then run for 60 s. LM runs a fixed 300 iterations, as Adam runs a fixed time,
//! and each is judged by its best validation error so far. The question: how much sooner does
//! LM reach Adam's one-minute validation error? LM is then run again with a bake's stopping
//! rule, to show where that would stop it.
//!
//! `cargo bench -p rrf-baker --bench training [-- --adam-seconds S]`

use std::path::Path;
use std::time::Instant;

use rrf_baker::bake::lm::{self, initial_parameters, Dataset, LmSettings};
use rrf_baker::bake::samples::{latin_hypercube, sample_configuration, Aim};
use rrf_baker::bake::{self, network_data, BakeSettings, Quality};
use rrf_baker::network::{
    hidden_layers, Component, B1, B2, B3, HIDDEN1, HIDDEN2, INPUTS, OUTPUTS, PARAMETERS, W1, W2, W3,
};
use rrf_baker::scene::Scene;
use rrf_baker::trace::sampling::Rng;
use rrf_baker::trace::Geometry;

/// Adds ∂/∂p of Σ_c (y_c − t_c)² for one sample to `grad`; returns the squared error.
fn add_gradient(p: &[f32], x: &[f32; INPUTS], t: &[f32; OUTPUTS], grad: &mut [f32]) -> f32 {
    let (h1, h2) = hidden_layers(p, x);
    let mut dy = [0.0f32; OUTPUTS];
    let mut sse = 0.0;
    for c in 0..OUTPUTS {
        let mut y = p[B3 + c];
        for k in 0..HIDDEN2 {
            y += p[W3 + c * HIDDEN2 + k] * h2[k];
        }
        dy[c] = 2.0 * (y - t[c]);
        sse += (y - t[c]) * (y - t[c]);
        grad[B3 + c] += dy[c];
        for k in 0..HIDDEN2 {
            grad[W3 + c * HIDDEN2 + k] += dy[c] * h2[k];
        }
    }
    let mut d2 = [0.0f32; HIDDEN2];
    for k in 0..HIDDEN2 {
        let back: f32 = (0..OUTPUTS).map(|c| p[W3 + c * HIDDEN2 + k] * dy[c]).sum();
        d2[k] = back * (1.0 - h2[k] * h2[k]);
        grad[B2 + k] += d2[k];
        for j in 0..HIDDEN1 {
            grad[W2 + k * HIDDEN1 + j] += d2[k] * h1[j];
        }
    }
    for j in 0..HIDDEN1 {
        let back: f32 = (0..HIDDEN2).map(|k| p[W2 + k * HIDDEN1 + j] * d2[k]).sum();
        let d1 = back * (1.0 - h1[j] * h1[j]);
        grad[B1 + j] += d1;
        for i in 0..INPUTS {
            grad[W1 + j * INPUTS + i] += d1 * x[i];
        }
    }
    sse
}

/// Adam for `seconds`; returns (seconds, validation MSE) every half second.
fn adam(train: &Dataset, val: &Dataset, initial: &[f32], lr: f32, seconds: f64) -> Vec<(f64, f64)> {
    const BATCH: usize = 1024;
    let (b1, b2, eps) = (0.9f32, 0.999f32, 1e-8f32);
    let mut p = initial.to_vec();
    let (mut m, mut v) = (vec![0.0f32; PARAMETERS], vec![0.0f32; PARAMETERS]);
    let mut grad = vec![0.0f32; PARAMETERS];
    let mut order: Vec<usize> = (0..train.len()).collect();
    let mut rng = Rng::new(1, 1);
    let start = Instant::now();
    let mut history = vec![(0.0, val.mse(&p))];
    let mut step = 0i32;
    let mut next_report = 0.5;
    'epochs: loop {
        rng.shuffle(&mut order);
        for batch in order.chunks(BATCH) {
            grad.fill(0.0);
            for &i in batch {
                add_gradient(&p, &train.inputs[i], &train.targets[i], &mut grad);
            }
            step += 1;
            let scale = 1.0 / (batch.len() * OUTPUTS) as f32;
            let (c1, c2) = (1.0 - b1.powi(step), 1.0 - b2.powi(step));
            for k in 0..PARAMETERS {
                let g = grad[k] * scale;
                m[k] = b1 * m[k] + (1.0 - b1) * g;
                v[k] = b2 * v[k] + (1.0 - b2) * g * g;
                p[k] -= lr * (m[k] / c1) / ((v[k] / c2).sqrt() + eps);
            }
            let t = start.elapsed().as_secs_f64();
            if t >= next_report {
                history.push((t, val.mse(&p)));
                next_report += 0.5;
                if t >= seconds {
                    break 'epochs;
                }
            }
        }
    }
    history
}

/// Levenberg–Marquardt's iterations, enough for its validation error to level off here.
const LM_ITERATIONS: u32 = 300;

fn best(history: &[(f64, f64)]) -> f64 {
    history.iter().map(|h| h.1).fold(f64::INFINITY, f64::min)
}

fn main() {
    let adam_seconds: f64 =
        std::env::args().skip_while(|a| a != "--adam-seconds").nth(1).and_then(|s| s.parse().ok()).unwrap_or(60.0);
    let scene = Scene::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/cornell-box")).expect("scene");
    let geometry = Geometry::new(&scene);
    let preview = BakeSettings::new(Quality::Preview, 1, &scene);
    let final_ = BakeSettings::new(Quality::Final, 1, &scene);
    let light = scene.moving_light.as_ref().expect("moving light");
    let configs = latin_hypercube(preview.configurations as usize, &light.bounds, &scene.camera_box.unwrap(), 1);
    let floor = scene.object_by_name("Floor").expect("Floor").id;
    let trace = rrf_baker::trace::TraceSettings { max_depth: 8, rr_depth: Some(5) };
    let samples: Vec<_> = configs
        .iter()
        .enumerate()
        .flat_map(|(i, c)| sample_configuration(&scene, &geometry, c, Aim::Sphere, 6000, 32, &trace, i as u64))
        .filter(|s| s.object == floor)
        .collect();
    let refs: Vec<_> = samples.iter().collect();
    let data = network_data(&scene, &final_, floor, Component::Direct, &refs);
    println!(
        "Floor direct light: {} training and {} validation samples (32 paths each); MSE in units of the target RMS",
        data.train.len(),
        data.validation.len()
    );
    let initial = initial_parameters(7, [0.0; OUTPUTS]);

    let mut sweep = Vec::new();
    for lr in [1e-3f32, 3e-3, 1e-2, 3e-2] {
        let h = adam(&data.train, &data.validation, &initial, lr, adam_seconds / 4.0);
        println!("adam lr {lr:<6} {:>4.0} s: best validation MSE {:.3e}", adam_seconds / 4.0, best(&h));
        sweep.push((best(&h), lr));
    }
    let lr = sweep.iter().min_by(|a, b| a.0.total_cmp(&b.0)).unwrap().1;
    let adam_history = adam(&data.train, &data.validation, &initial, lr, adam_seconds);
    let adam_final = best(&adam_history);
    println!("\nadam lr {lr}: validation MSE against time");
    for (t, e) in adam_history.iter().filter(|(t, _)| (*t as u64).is_multiple_of(5) && t.fract() < 0.5) {
        println!("  {t:>6.1} s  {e:.3e}");
    }

    // Run to a fixed count, not stopped by a patience rule: the question is how soon LM gets
    // there. Its validation error can rise for a while and then fall lower than before, so
    // the bake's stopping rule is run as well, to show where it would have stopped.
    let lm_with_patience = |patience| {
        lm::train(
            &data.train,
            &data.validation,
            initial.clone(),
            &LmSettings { max_iterations: LM_ITERATIONS, patience },
        )
    };
    let lm_result = lm_with_patience(LM_ITERATIONS);
    println!("\nLevenberg–Marquardt: validation MSE against time");
    for (t, e) in &lm_result.history {
        println!("  {t:>6.1} s  {e:.3e}");
    }
    let reached = lm_result.history.iter().find(|(_, e)| *e <= adam_final).map(|(t, _)| *t);
    println!(
        "\nAdam after {adam_seconds:.0} s: {adam_final:.3e}; LM best {:.3e} in {} iterations",
        lm_result.val_mse, lm_result.iterations
    );
    match reached {
        Some(t) => {
            println!("LM reached Adam's {adam_seconds:.0}-second error after {t:.1} s: {:.1}x sooner", adam_seconds / t)
        }
        None => println!("LM never reached Adam's {adam_seconds:.0}-second error"),
    }
    let stopped = lm_with_patience(bake::PATIENCE);
    let at = stopped.history.last().map_or(0.0, |h| h.0);
    println!(
        "With a bake's stopping rule (patience {}), LM stops after {} iterations ({at:.1} s) at best {:.3e}",
        bake::PATIENCE,
        stopped.iterations,
        stopped.val_mse
    );
}
