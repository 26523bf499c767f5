//! The network's Jacobian against finite differences, Levenberg–Marquardt on a smooth
//! synthetic target, and training on samples that are not finite.

use rrf_baker::bake::lm::{initial_parameters, train, Dataset, LmSettings};
use rrf_baker::network::{
    forward, forward_rows, forward_with_jacobian, hidden_layers, Real, INPUTS, OUTPUTS, PARAMETERS,
};
use rrf_baker::trace::sampling::Rng;

#[test]
fn jacobian_matches_finite_differences() {
    let params: Vec<f64> = initial_parameters(3, [0.2, 0.1, 0.3]).iter().map(|&v| f64::from(v)).collect();
    let mut rng = Rng::new(1, 1);
    let x: [f64; INPUTS] = std::array::from_fn(|_| f64::from(2.0 * rng.next_f32() - 1.0));
    let mut jacobian = Box::new([[0.0; PARAMETERS]; OUTPUTS]);
    forward_with_jacobian(&params, &x, &mut jacobian);
    let mut scratch = Box::new([[0.0; PARAMETERS]; OUTPUTS]);
    for k in 0..PARAMETERS {
        let h = 1e-6;
        let mut plus = params.clone();
        plus[k] += h;
        let mut minus = params.clone();
        minus[k] -= h;
        let yp = forward_with_jacobian(&plus, &x, &mut scratch);
        let ym = forward_with_jacobian(&minus, &x, &mut scratch);
        for c in 0..OUTPUTS {
            let numeric = (yp[c] - ym[c]) / (2.0 * h);
            assert!((numeric - jacobian[c][k]).abs() < 1e-6, "∂y{c}/∂p{k}: {} vs {numeric}", jacobian[c][k]);
        }
    }
    // The f32 and f64 forward passes agree.
    let y64 = forward_with_jacobian(&params, &x, &mut scratch);
    let p32: Vec<f32> = params.iter().map(|&v| v as f32).collect();
    let y32 = forward(&p32, &x.map(|v| v as f32));
    for c in 0..OUTPUTS {
        assert!((y64[c] - f64::from(y32[c])).abs() < 1e-5);
    }
}

/// The batched forward pass gives every row the bits of the one-row pass: hidden activations
/// and outputs, over a count of rows that leaves a partial batch, with inputs from small to
/// saturating.
#[test]
fn forward_rows_matches_one_row_at_a_time_to_the_bit() {
    let params = initial_parameters(5, [0.4, -0.2, 0.1]);
    let mut rng = Rng::new(2, 9);
    let rows: Vec<[f32; INPUTS]> =
        (0..29).map(|r| std::array::from_fn(|_| (2.0 * rng.next_f32() - 1.0) * [1e-4, 1.0, 30.0][r % 3])).collect();
    let mut seen = 0;
    forward_rows(&params, &rows, |(h1, h2), y| {
        let x = &rows[seen];
        let (w1, w2) = hidden_layers(&params, x);
        let bits = |v: &[f32]| v.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(h1), bits(&w1), "row {seen}: first layer");
        assert_eq!(bits(h2), bits(&w2), "row {seen}: second layer");
        assert_eq!(bits(y), bits(&forward(&params, x)), "row {seen}: outputs");
        seen += 1;
    });
    assert_eq!(seen, rows.len());
}

/// The f32 activation, eight lanes at a time with the tail padded (a layer of 20 is 8 + 8 + 4),
/// stays within a few ulp of f64's tanh from 0 to saturation.
#[test]
fn f32_tanh_matches_f64() {
    let xs: Vec<f32> = (-24_000..=24_000).map(|i| i as f32 * 5e-4).chain([1e-30, -1e-8, 3e-4, 40.0, -1e6]).collect();
    for layer in xs.chunks(20) {
        let mut tanh = layer.to_vec();
        f32::tanh_all(&mut tanh);
        for (&x, &t) in layer.iter().zip(&tanh) {
            let exact = f64::from(x).tanh();
            let ulp = f64::from(f32::EPSILON) * exact.abs().max(f64::from(f32::MIN_POSITIVE));
            assert!((f64::from(t) - exact).abs() <= 4.0 * ulp, "tanh({x}) = {t}, not {exact}");
        }
    }
}

/// A smooth function of 13 inputs, like shading: products and sines of a few of them.
fn target(x: &[f32; INPUTS]) -> [f32; OUTPUTS] {
    let a = 0.5 + 0.3 * (1.5 * x[0] + x[6]).sin() * (0.5 * x[9] + 0.5);
    let b = 0.3 + 0.2 * x[1] * x[7] + 0.1 * x[3];
    let c = 0.2 + 0.15 * (x[2] - x[8]).cos() * (x[11] + 1.0) / 2.0;
    [a, b, c]
}

fn dataset(n: usize, seed: u64) -> Dataset {
    let mut rng = Rng::new(seed, 2);
    let inputs: Vec<[f32; INPUTS]> = (0..n).map(|_| std::array::from_fn(|_| 2.0 * rng.next_f32() - 1.0)).collect();
    let targets = inputs.iter().map(target).collect();
    Dataset { inputs, targets, gains: Vec::new() }
}

#[test]
fn levenberg_marquardt_fits_a_smooth_function() {
    let (train_set, val_set) = (dataset(2000, 1), dataset(1000, 2));
    let variance = {
        let mean: f64 = val_set.targets.iter().flatten().map(|&v| f64::from(v)).sum::<f64>() / (3.0 * 1000.0);
        val_set.targets.iter().flatten().map(|&v| (f64::from(v) - mean).powi(2)).sum::<f64>() / 3000.0
    };
    let initial = initial_parameters(5, [0.5, 0.3, 0.2]);
    let start_mse = val_set.mse(&initial);
    let result = train(&train_set, &val_set, initial, &LmSettings { max_iterations: 25, patience: 8 });
    eprintln!(
        "target variance {variance:.4}, start {start_mse:.4}, after {} iterations: train {:.2e}, validation {:.2e}",
        result.iterations, result.train_mse, result.val_mse
    );
    assert!(result.val_mse < variance / 200.0, "validation MSE {} vs target variance {variance}", result.val_mse);
    assert_eq!(result.val_mse, val_set.mse(&result.params), "the kept parameters are the best validated");
    // Deterministic: the same data and seed give the same network.
    let again = train(
        &train_set,
        &val_set,
        initial_parameters(5, [0.5, 0.3, 0.2]),
        &LmSettings { max_iterations: 25, patience: 8 },
    );
    assert_eq!(again.params, result.params);
}

/// Training on data with a non-finite or huge value ends, without a hang, and keeps finite
/// parameters (before the fix, a failed Cholesky step raised λ forever).
#[test]
fn training_on_non_finite_samples_ends() {
    type Spoil = fn(&mut Dataset);
    let cases: [(&str, Spoil); 4] = [
        ("NaN target", |d| d.targets[3][1] = f32::NAN),
        ("infinite input", |d| d.inputs[7][2] = f32::INFINITY),
        ("huge input", |d| d.inputs[0][6] = 1e38),
        ("huge inputs everywhere", |d| d.inputs.iter_mut().for_each(|x| x[8] = -1e38)),
    ];
    for (what, spoil) in cases {
        let (done, wait) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            let (mut train_set, val_set) = (dataset(300, 1), dataset(100, 2));
            spoil(&mut train_set);
            let initial = initial_parameters(5, [0.5, 0.3, 0.2]);
            let result = train(&train_set, &val_set, initial, &LmSettings { max_iterations: 20, patience: 5 });
            let _ = done.send(result);
        });
        let result = wait
            .recv_timeout(std::time::Duration::from_secs(120))
            .unwrap_or_else(|_| panic!("{what}: training did not end within two minutes"));
        assert!(result.iterations <= 20, "{what}");
        assert!(result.params.iter().all(|p| p.is_finite()), "{what}: non-finite parameters kept");
    }
}
