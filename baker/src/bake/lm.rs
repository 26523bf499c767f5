//! Levenberg–Marquardt training of one network.
//!
//! Each iteration accumulates JᵀJ (523 × 523) and Jᵀe over the training set, never holding
//! the whole Jacobian ([`super::normal_equations`]), then solves `(JᵀJ + λI) δ = −Jᵀe` by Cholesky.
//! λ shrinks tenfold after a step that lowers the training error and grows tenfold until one
//! does (Levenberg's damping, as Hagan and Menhaj use it for networks; Marquardt's
//! `λ·diag(JᵀJ)` converged about twice as slowly on rrf's samples).
//! The parameters with the lowest error on the held-out validation set are kept; training
//! stops when that error has not improved for `patience` iterations.
//!
//! Checking a step evaluates the network on every training row at the new parameters; when the
//! step is taken, that evaluation's loss and hidden activations serve the next iteration, so
//! its normal equations run no tanh.

use std::time::Instant;

use faer::linalg::solvers::Solve;
use faer::{Mat, Side};

use super::normal_equations::normal_equations;
use crate::network::{forward_rows, Hidden, B1, B2, B3, HIDDEN1, HIDDEN2, INPUTS, OUTPUTS, PARAMETERS, W1, W2, W3};
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
    pub(super) fn gain(&self, i: usize) -> f32 {
        self.gains.get(i).copied().unwrap_or(1.0)
    }

    /// Mean squared error per channel of the network `params` on this set.
    pub fn mse(&self, params: &[f32]) -> f64 {
        self.mse_of(params, |_| {})
    }

    /// [`Dataset::mse`], keeping each row's hidden activations in `hidden` for the Jacobian
    /// at the same parameters.
    fn mse_keeping_hidden(&self, params: &[f32], hidden: &mut Vec<Hidden<f32>>) -> f64 {
        hidden.clear();
        self.mse_of(params, |h| hidden.push(*h))
    }

    /// Mean squared error per channel of the network `params`, row by row in order, passing
    /// each row's hidden activations to `keep`.
    fn mse_of(&self, params: &[f32], mut keep: impl FnMut(&Hidden<f32>)) -> f64 {
        if self.is_empty() {
            return 0.0;
        }
        let mut sum = 0.0f64;
        let mut row = 0;
        forward_rows(params, &self.inputs, |h, y| {
            for (y, t) in y.iter().zip(&self.targets[row]) {
                let e = f64::from(self.gain(row) * y - t);
                sum += e * e;
            }
            keep(h);
            row += 1;
        });
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
    /// Whether training stopped because the validation error stopped improving (or no step
    /// could lower the training error), not because it ran out of iterations: more
    /// iterations would not help.
    pub converged: bool,
    /// (seconds since start, validation MSE) after each iteration.
    pub history: Vec<(f64, f64)>,
}

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

/// The damping past which Levenberg–Marquardt gives up: the step is then a vanishing
/// gradient-descent step.
const LAMBDA_MAX: f64 = 1e10;

pub fn train(train: &Dataset, validation: &Dataset, initial: Vec<f32>, settings: &LmSettings) -> LmResult {
    let start = Instant::now();
    let mut params = initial.clone();
    let mut best = initial;
    let mut best_val = validation.mse(&best);
    let mut lambda = 1e-2;
    let mut since_best = 0;
    let mut history = Vec::new();
    let mut iterations = 0;
    let mut converged = false;
    // The training loss and hidden activations at `params`, and the loss at `best`: computed
    // once, then carried over from the accepted steps.
    let (mut hidden, mut candidate_hidden) = (Vec::new(), Vec::new());
    let mut loss = train.mse_keeping_hidden(&params, &mut hidden);
    let mut best_loss = loss;
    'outer: while iterations < settings.max_iterations {
        if since_best >= settings.patience {
            converged = true;
            break;
        }
        iterations += 1;
        let (jtj, jte) = normal_equations(train, &params, &hidden);
        // Non-finite samples make non-finite normal equations: no step can be trusted, so
        // training stops with the best parameters so far.
        let finite = |m: &Mat<f64>| (0..m.nrows()).all(|i| (0..m.ncols()).all(|j| m[(i, j)].is_finite()));
        if !finite(&jtj) || !finite(&jte) {
            converged = true;
            break;
        }
        loop {
            // Every retry raises λ; past the limit no step helps and training stops.
            if lambda > LAMBDA_MAX {
                converged = true;
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
            let candidate: Vec<f32> =
                params.iter().enumerate().map(|(i, &p)| (f64::from(p) - step[(i, 0)]) as f32).collect();
            let candidate_loss = train.mse_keeping_hidden(&candidate, &mut candidate_hidden);
            if candidate_loss.is_finite() && candidate_loss < loss {
                params = candidate;
                loss = candidate_loss;
                std::mem::swap(&mut hidden, &mut candidate_hidden);
                lambda = (lambda / 10.0).max(1e-9);
                break;
            }
            lambda *= 10.0;
        }
        let val = validation.mse(&params);
        history.push((start.elapsed().as_secs_f64(), val));
        if val < best_val * (1.0 - 1e-4) {
            best_val = val;
            best = params.clone();
            best_loss = loss;
            since_best = 0;
        } else {
            since_best += 1;
        }
    }
    LmResult { train_mse: best_loss, val_mse: best_val, params: best, iterations, converged, history }
}
