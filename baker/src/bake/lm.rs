//! Levenberg–Marquardt training of one network.
//!
//! Each iteration accumulates JᵀJ (523 × 523) and Jᵀe over the training set in chunks of
//! rows, never holding the whole Jacobian, then solves `(JᵀJ + λI) δ = −Jᵀe` by Cholesky.
//! λ shrinks tenfold after a step that lowers the training error and grows tenfold until one
//! does (Levenberg's damping, as Hagan and Menhaj use it for networks; Marquardt's
//! `λ·diag(JᵀJ)` converged about twice as slowly on rrf's samples).
//! The parameters with the lowest error on the held-out validation set are kept; training
//! stops when that error has not improved for `patience` iterations.

use std::time::Instant;

use faer::linalg::matmul::matmul;
use faer::linalg::matmul::triangular::{self, BlockStructure};
use faer::linalg::solvers::Solve;
use faer::{Accum, Mat, Par, Side};

use crate::network::{
    forward, forward_with_jacobian, B1, B2, B3, HIDDEN1, HIDDEN2, INPUTS, OUTPUTS, PARAMETERS, W1, W2, W3,
};
use crate::trace::sampling::Rng;

/// Normalised inputs and (scaled) targets.
#[derive(Clone, Debug, Default)]
pub struct Dataset {
    pub inputs: Vec<[f32; INPUTS]>,
    pub targets: Vec<[f32; OUTPUTS]>,
    /// What each row's output is multiplied by before it is compared with its target (empty:
    /// 1 for every row). A leaf of a blended kd-tree fits its weight times its output to what
    /// the other leaves leave of the target.
    pub gains: Vec<f32>,
}

impl Dataset {
    pub fn len(&self) -> usize {
        self.inputs.len()
    }

    pub fn is_empty(&self) -> bool {
        self.inputs.is_empty()
    }

    /// Row `i`'s gain.
    fn gain(&self, i: usize) -> f32 {
        self.gains.get(i).copied().unwrap_or(1.0)
    }

    /// Mean squared error per channel of the network `params` on this set.
    pub fn mse(&self, params: &[f32]) -> f64 {
        if self.is_empty() {
            return 0.0;
        }
        let mut sum = 0.0f64;
        for (i, (x, t)) in self.inputs.iter().zip(&self.targets).enumerate() {
            let y = forward(params, x);
            for c in 0..OUTPUTS {
                let e = f64::from(self.gain(i) * y[c] - t[c]);
                sum += e * e;
            }
        }
        sum / (self.len() * OUTPUTS) as f64
    }
}

#[derive(Clone, Copy, Debug)]
pub struct LmSettings {
    pub max_iterations: u32,
    /// Stop after this many iterations without a better validation error.
    pub patience: u32,
}

#[derive(Clone, Debug)]
pub struct LmResult {
    pub params: Vec<f32>,
    pub train_mse: f64,
    pub val_mse: f64,
    pub iterations: u32,
    /// (seconds since start, validation MSE) after each iteration.
    pub history: Vec<(f64, f64)>,
}

/// Rows of the Jacobian per chunk.
const CHUNK_SAMPLES: usize = 256;

/// Nguyen–Widrow initialisation of the two tanh layers; a small random output layer whose
/// bias starts at the mean target.
pub fn initial_parameters(seed: u64, mean_target: [f32; OUTPUTS]) -> Vec<f32> {
    let mut rng = Rng::new(seed, 0x1417);
    let mut p = vec![0.0f32; PARAMETERS];
    let mut layer = |w: usize, b: usize, n_out: usize, n_in: usize| {
        let beta = 0.7 * (n_out as f32).powf(1.0 / n_in as f32);
        for j in 0..n_out {
            let row = &mut p[w + j * n_in..w + (j + 1) * n_in];
            row.iter_mut().for_each(|v| *v = rng.next_f32() - 0.5);
            let norm = row.iter().map(|v| v * v).sum::<f32>().sqrt().max(1e-6);
            row.iter_mut().for_each(|v| *v *= beta / norm);
        }
        for j in 0..n_out {
            p[b + j] = beta * (2.0 * rng.next_f32() - 1.0);
        }
    };
    layer(W1, B1, HIDDEN1, INPUTS);
    layer(W2, B2, HIDDEN2, HIDDEN1);
    for v in &mut p[W3..B3] {
        *v = 0.1 * (rng.next_f32() - 0.5);
    }
    p[B3..B3 + OUTPUTS].copy_from_slice(&mean_target);
    p
}

/// JᵀJ, Jᵀe and the training MSE at `params`, accumulated chunk by chunk.
fn normal_equations(train: &Dataset, params: &[f64]) -> (Mat<f64>, Mat<f64>, f64) {
    let mut jtj = Mat::<f64>::zeros(PARAMETERS, PARAMETERS);
    let mut jte = Mat::<f64>::zeros(PARAMETERS, 1);
    // Jᵀ of one chunk, column per residual, so that each Jacobian row is written contiguously.
    let mut jt = Mat::<f64>::zeros(PARAMETERS, CHUNK_SAMPLES * OUTPUTS);
    let mut e = Mat::<f64>::zeros(CHUNK_SAMPLES * OUTPUTS, 1);
    let mut grads = Box::new([[0.0f64; PARAMETERS]; OUTPUTS]);
    let mut sse = 0.0;
    for start in (0..train.len()).step_by(CHUNK_SAMPLES) {
        let end = (start + CHUNK_SAMPLES).min(train.len());
        let rows = (end - start) * OUTPUTS;
        for (n, s) in (start..end).enumerate() {
            let x: [f64; INPUTS] = train.inputs[s].map(f64::from);
            let y = forward_with_jacobian(params, &x, &mut grads);
            let gain = f64::from(train.gain(s));
            for c in 0..OUTPUTS {
                let col = n * OUTPUTS + c;
                let residual = gain * y[c] - f64::from(train.targets[s][c]);
                e[(col, 0)] = residual;
                sse += residual * residual;
                let column = jt.col_mut(col).try_as_col_major_mut().expect("contiguous column").as_slice_mut();
                column.iter_mut().zip(&grads[c]).for_each(|(j, g)| *j = gain * g);
            }
        }
        let jt_chunk = jt.as_ref().subcols(0, rows);
        // Only the lower triangle: JᵀJ is symmetric and the Cholesky reads no more.
        triangular::matmul(
            jtj.as_mut(),
            BlockStructure::TriangularLower,
            Accum::Add,
            jt_chunk,
            BlockStructure::Rectangular,
            jt_chunk.transpose(),
            BlockStructure::Rectangular,
            1.0,
            Par::Seq,
        );
        matmul(jte.as_mut(), Accum::Add, jt_chunk, e.as_ref().subrows(0, rows), 1.0, Par::Seq);
    }
    (jtj, jte, sse / (train.len() * OUTPUTS).max(1) as f64)
}

/// The damping past which Levenberg–Marquardt gives up: the step is then a vanishing
/// gradient-descent step.
const LAMBDA_MAX: f64 = 1e10;

pub fn train(train: &Dataset, validation: &Dataset, initial: Vec<f32>, settings: &LmSettings) -> LmResult {
    let start = Instant::now();
    let to_f32 = |p: &[f64]| p.iter().map(|&v| v as f32).collect::<Vec<f32>>();
    let mut params: Vec<f64> = initial.iter().map(|&v| f64::from(v)).collect();
    let mut best = initial.clone();
    let mut best_val = validation.mse(&best);
    let mut lambda = 1e-2;
    let mut since_best = 0;
    let mut history = Vec::new();
    let mut iterations = 0;
    'outer: while iterations < settings.max_iterations && since_best < settings.patience {
        iterations += 1;
        let (jtj, jte, _) = normal_equations(train, &params);
        // Non-finite samples make non-finite normal equations: no step can be trusted, so
        // training stops with the best parameters so far.
        let finite = |m: &Mat<f64>| (0..m.nrows()).all(|i| (0..m.ncols()).all(|j| m[(i, j)].is_finite()));
        if !finite(&jtj) || !finite(&jte) {
            break;
        }
        // Steps are accepted on the loss of the f32 network that is kept, in one precision.
        let loss = train.mse(&to_f32(&params));
        loop {
            // Every retry raises λ; past the limit no step helps and training stops.
            if lambda > LAMBDA_MAX {
                break 'outer;
            }
            let mut a = jtj.clone();
            for i in 0..PARAMETERS {
                a[(i, i)] += lambda;
            }
            let Ok(llt) = a.llt(Side::Lower) else {
                lambda *= 10.0;
                continue;
            };
            let step = llt.solve(jte.as_ref());
            let candidate: Vec<f64> = params.iter().enumerate().map(|(i, p)| p - step[(i, 0)]).collect();
            let candidate_loss = train.mse(&to_f32(&candidate));
            if candidate_loss.is_finite() && candidate_loss < loss {
                params = candidate;
                lambda = (lambda / 10.0).max(1e-9);
                break;
            }
            lambda *= 10.0;
        }
        let current = to_f32(&params);
        let val = validation.mse(&current);
        history.push((start.elapsed().as_secs_f64(), val));
        if val < best_val * (1.0 - 1e-4) {
            best_val = val;
            best = current;
            since_best = 0;
        } else {
            since_best += 1;
        }
    }
    LmResult { train_mse: train.mse(&best), val_mse: best_val, params: best, iterations, history }
}
