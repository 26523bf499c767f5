//! Levenberg–Marquardt's normal equations, JᵀJ and Jᵀe, built from the network's layers.
//!
//! A residual's derivative by a weight of layer ℓ is a product of two short vectors' entries:
//! the output's derivative by the layer's pre-activations (δ: 20, 10 or 3 values) and the
//! layer's input with a 1 appended for the bias (ã: 14, 21 or 11 values). The block of JᵀJ
//! between layers ℓ and m is therefore
//!
//! ```text
//! Σ_samples Σ_outputs (δℓ ⊗ ãℓ)(δm ⊗ ãm)ᵀ  =  Σ_samples Dℓm ⊗ (ãℓ ãmᵀ),   Dℓm = Σ_outputs δℓ δmᵀ,
//! ```
//!
//! with the sum over the three outputs taken per sample, before the Kronecker product. Each
//! block is one matrix product of the samples' vec(D) by their vec(ãℓ ãmᵀ), and on the diagonal
//! blocks both factors are symmetric, so only their lower triangles enter. That is about 110,000
//! multiply-adds per sample against 410,000 for the product of the Jacobian's 3 rows per sample
//! by themselves: the same matrix, summed in another order.
//!
//! The products are in f32 (twice the SIMD width of f64) over at most [`GROUP_SAMPLES`]
//! samples; the groups are summed in f64, in order, so that the sum is the same whichever
//! threads computed them. Groups run in parallel, so the last network of a bake still trains
//! on every core.

use std::ops::Range;

use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, MatRef, Par};
use rayon::prelude::*;

use super::lm::Dataset;
use crate::network::{Hidden, B1, B2, B3, HIDDEN1, HIDDEN2, INPUTS, OUTPUTS, PARAMETERS, W1, W2, W3};

/// Samples per chunk: a chunk's factors of one block stay in the cache.
const CHUNK_SAMPLES: usize = 256;

/// Samples per group, whose share of JᵀJ is summed in f32.
const GROUP_SAMPLES: usize = 2048;

/// The widest δ and ã.
const MAX_DELTAS: usize = HIDDEN1;
const MAX_INPUTS: usize = HIDDEN1 + 1;

/// A layer: how many pre-activations (δ) and inputs with the bias's 1 (ã) it has, and where
/// the weight of pre-activation `j` and input `a` (the bias where `a` is the last input) sits
/// in the parameters.
struct Layer {
    deltas: usize,
    inputs: usize,
    parameter: fn(usize, usize) -> usize,
}

const LAYERS: [Layer; 3] = [
    Layer {
        deltas: HIDDEN1,
        inputs: INPUTS + 1,
        parameter: |j, a| if a < INPUTS { W1 + j * INPUTS + a } else { B1 + j },
    },
    Layer {
        deltas: HIDDEN2,
        inputs: HIDDEN1 + 1,
        parameter: |j, a| if a < HIDDEN1 { W2 + j * HIDDEN1 + a } else { B2 + j },
    },
    Layer {
        deltas: OUTPUTS,
        inputs: HIDDEN2 + 1,
        parameter: |j, a| if a < HIDDEN2 { W3 + j * HIDDEN2 + a } else { B3 + j },
    },
];

/// A chunk's factors: per layer, each output's δ and the layer's ã (padded to the widest
/// layer), and the samples' gains and residuals `gain · y − target`. One column per quantity,
/// one entry per sample, so that every loop over a chunk's samples runs in SIMD lanes.
struct Chunk {
    len: usize,
    /// Column [`Chunk::delta_column`]`(l, c, j)`: δ_j of layer `l` for output `c`.
    delta: Vec<f32>,
    /// Column `l * MAX_INPUTS + a`: ã_a of layer `l`.
    input: Vec<f32>,
    gain: Vec<f32>,
    residual: Vec<f32>,
}

impl Chunk {
    fn new() -> Self {
        let columns = |n: usize| vec![0.0; n * CHUNK_SAMPLES];
        let mut chunk = Chunk {
            len: 0,
            delta: columns(3 * OUTPUTS * MAX_DELTAS),
            input: columns(3 * MAX_INPUTS),
            gain: columns(1),
            residual: columns(OUTPUTS),
        };
        // The output layer's δ: ∂y_c/∂(its pre-activation c') is 1 where c = c', whatever the sample.
        for c in 0..OUTPUTS {
            chunk.delta[Self::range(Self::delta_column(2, c, c))].fill(1.0);
        }
        chunk
    }

    fn range(column: usize) -> Range<usize> {
        column * CHUNK_SAMPLES..(column + 1) * CHUNK_SAMPLES
    }

    fn delta_column(layer: usize, output: usize, j: usize) -> usize {
        (layer * OUTPUTS + output) * MAX_DELTAS + j
    }

    fn delta(&self, layer: usize, output: usize, j: usize) -> &[f32] {
        &self.delta[Self::range(Self::delta_column(layer, output, j))][..self.len]
    }

    fn input(&self, layer: usize, a: usize) -> &[f32] {
        &self.input[Self::range(layer * MAX_INPUTS + a)][..self.len]
    }

    /// Layer `l`'s ã of each sample of `rows` (the chunk's `len`): its values, then 1 (the
    /// bias's input).
    fn set_columns<'a, const W: usize>(&mut self, l: usize, rows: impl Iterator<Item = &'a [f32; W]> + Clone) {
        for a in 0..W {
            for (v, row) in self.input[Self::range(l * MAX_INPUTS + a)].iter_mut().zip(rows.clone()) {
                *v = row[a];
            }
        }
        self.input[Self::range(l * MAX_INPUTS + W)][..self.len].fill(1.0);
    }

    /// Fills the chunk with `train`'s `samples` (at most [`CHUNK_SAMPLES`]) at `params`, where
    /// their hidden activations are `hidden`.
    fn fill(&mut self, train: &Dataset, params: &[f32], hidden: &[Hidden<f32>], samples: Range<usize>) {
        self.len = samples.len();
        let n = self.len;
        // Column by column: a store per sample into each of the 60-odd columns, sample after
        // sample, missed the cache at every one.
        let rows = || samples.clone();
        self.set_columns(0, rows().map(|s| &train.inputs[s]));
        self.set_columns(1, rows().map(|s| &hidden[s].0));
        self.set_columns(2, rows().map(|s| &hidden[s].1));
        for (gain, s) in self.gain.iter_mut().zip(rows()) {
            *gain = train.gain(s);
        }
        for c in 0..OUTPUTS {
            for (r, s) in self.residual[Self::range(c)].iter_mut().zip(rows()) {
                *r = train.targets[s][c];
            }
        }
        let mut sum = [0.0f32; CHUNK_SAMPLES];
        for c in 0..OUTPUTS {
            // The output and its residual.
            sum[..n].fill(params[B3 + c]);
            for k in 0..HIDDEN2 {
                add_scaled(&mut sum[..n], params[W3 + c * HIDDEN2 + k], self.input(2, k));
            }
            let residual = &mut self.residual[Self::range(c)][..n];
            for ((r, y), g) in residual.iter_mut().zip(&sum).zip(&self.gain) {
                *r = g * y - *r;
            }
            // Back through the second tanh layer, then the first.
            for k in 0..HIDDEN2 {
                let w = params[W3 + c * HIDDEN2 + k];
                let h2 = &self.input[Self::range(MAX_INPUTS + MAX_INPUTS + k)];
                let column = Self::range(Self::delta_column(1, c, k));
                for (d, h) in self.delta[column][..n].iter_mut().zip(h2) {
                    *d = w * (1.0 - h * h);
                }
            }
            for j in 0..HIDDEN1 {
                sum[..n].fill(0.0);
                for k in 0..HIDDEN2 {
                    add_scaled(&mut sum[..n], params[W2 + k * HIDDEN1 + j], self.delta(1, c, k));
                }
                let h1 = &self.input[Self::range(MAX_INPUTS + j)];
                let column = Self::range(Self::delta_column(0, c, j));
                for ((d, s), h) in self.delta[column][..n].iter_mut().zip(&sum).zip(h1) {
                    *d = s * (1.0 - h * h);
                }
            }
        }
    }
}

/// `sum += scale · values`, entry by entry.
fn add_scaled(sum: &mut [f32], scale: f32, values: &[f32]) {
    for (s, v) in sum.iter_mut().zip(values) {
        *s += scale * v;
    }
}

/// The block of JᵀJ between layers `high` ≥ `low`: which products of δ entries (rows of its
/// factor matrix) and of ã entries (columns) it holds. On the diagonal both are lower
/// triangles of symmetric matrices.
struct Block {
    high: usize,
    low: usize,
    delta_pairs: Vec<(usize, usize)>,
    input_pairs: Vec<(usize, usize)>,
}

impl Block {
    fn new(high: usize, low: usize) -> Self {
        let (h, l) = (&LAYERS[high], &LAYERS[low]);
        let triangular = high == low;
        Block {
            high,
            low,
            delta_pairs: pairs(h.deltas, l.deltas, triangular),
            input_pairs: pairs(h.inputs, l.inputs, triangular),
        }
    }

    /// Writes this block's share of `sum` (its products summed over the samples: one row per
    /// δ pair, one column per ã pair) into the lower triangle of `jtj`. On the diagonal blocks
    /// an entry stands for two of JᵀJ, the ã pair either way round.
    fn scatter(&self, sum: MatRef<'_, f64>, jtj: &mut Mat<f64>) {
        let (high, low) = (&LAYERS[self.high], &LAYERS[self.low]);
        let mut set = |u: usize, v: usize, value: f64| jtj[(u.max(v), u.min(v))] = value;
        for (r, &(j, k)) in self.delta_pairs.iter().enumerate() {
            for (s, &(a, b)) in self.input_pairs.iter().enumerate() {
                let value = sum[(r, s)];
                set((high.parameter)(j, a), (low.parameter)(k, b), value);
                if self.high == self.low {
                    set((high.parameter)(j, b), (low.parameter)(k, a), value);
                }
            }
        }
    }
}

/// The index pairs `(i, j)`, `i < m`, `j < n`, row by row; only `j ≤ i` where `triangular`.
fn pairs(m: usize, n: usize, triangular: bool) -> Vec<(usize, usize)> {
    (0..m).flat_map(|i| (0..if triangular { i + 1 } else { n }).map(move |j| (i, j))).collect()
}

/// The six blocks of JᵀJ's lower triangle.
fn blocks() -> Vec<Block> {
    (0..3).flat_map(|high| (0..=high).map(move |low| Block::new(high, low))).collect()
}

/// JᵀJ (its lower triangle) and Jᵀe of `train`'s residuals at `params`, where its rows'
/// hidden activations are `hidden`.
pub fn normal_equations(train: &Dataset, params: &[f32], hidden: &[Hidden<f32>]) -> (Mat<f64>, Mat<f64>) {
    let blocks = blocks();
    let groups: Vec<GroupSums> = (0..train.len().div_ceil(GROUP_SAMPLES))
        .into_par_iter()
        .map(|g| {
            let samples = g * GROUP_SAMPLES..((g + 1) * GROUP_SAMPLES).min(train.len());
            group_sums(train, params, hidden, samples, &blocks)
        })
        .collect();
    let mut jtj = Mat::<f64>::zeros(PARAMETERS, PARAMETERS);
    let mut jte = Mat::<f64>::zeros(PARAMETERS, 1);
    for (b, block) in blocks.iter().enumerate() {
        let mut sum = Mat::<f64>::zeros(block.delta_pairs.len(), block.input_pairs.len());
        for (sums, _) in &groups {
            sum += sums[b].as_ref().map(|&v| f64::from(v));
        }
        block.scatter(sum.as_ref(), &mut jtj);
    }
    for (l, layer) in LAYERS.iter().enumerate() {
        for (_, gradient) in &groups {
            for j in 0..layer.deltas {
                for a in 0..layer.inputs {
                    jte[((layer.parameter)(j, a), 0)] += f64::from(gradient[l][(j, a)]);
                }
            }
        }
    }
    (jtj, jte)
}

/// One group's sum of each block's products, and its Jᵀe per layer ([`accumulate_gradient`]),
/// in f32.
type GroupSums = (Vec<Mat<f32>>, [Mat<f32>; 3]);

/// [`GroupSums`] of `train`'s `samples`.
fn group_sums(
    train: &Dataset,
    params: &[f32],
    hidden: &[Hidden<f32>],
    samples: Range<usize>,
    blocks: &[Block],
) -> GroupSums {
    let mut sums: Vec<Mat<f32>> = blocks.iter().map(|b| Mat::zeros(b.delta_pairs.len(), b.input_pairs.len())).collect();
    let mut gradient = LAYERS.map(|l| Mat::zeros(l.deltas, l.inputs));
    let mut back = vec![0.0f32; MAX_DELTAS * CHUNK_SAMPLES];
    let widest = |pairs: fn(&Block) -> usize| blocks.iter().map(pairs).max().unwrap_or(0);
    // A block's factor matrices for the chunk: a column per pair, an entry per sample.
    let mut deltas = vec![0.0f32; widest(|b| b.delta_pairs.len()) * CHUNK_SAMPLES];
    let mut inputs = vec![0.0f32; widest(|b| b.input_pairs.len()) * CHUNK_SAMPLES];
    let mut chunk = Chunk::new();
    for start in samples.clone().step_by(CHUNK_SAMPLES) {
        chunk.fill(train, params, hidden, start..(start + CHUNK_SAMPLES).min(samples.end));
        let n = chunk.len;
        accumulate_gradient(&chunk, &mut gradient, &mut back);
        let gain2: Vec<f32> = chunk.gain[..n].iter().map(|g| g * g).collect();
        for (block, sum) in blocks.iter().zip(&mut sums) {
            let (rows, cols) = (block.delta_pairs.len(), block.input_pairs.len());
            for (column, &(j, k)) in deltas.chunks_exact_mut(CHUNK_SAMPLES).zip(&block.delta_pairs) {
                let [u0, u1, u2] = [0, 1, 2].map(|c| chunk.delta(block.high, c, j));
                let [v0, v1, v2] = [0, 1, 2].map(|c| chunk.delta(block.low, c, k));
                let (column, gain2) = (&mut column[..n], &gain2[..n]);
                for i in 0..n {
                    column[i] = gain2[i] * (u0[i] * v0[i] + u1[i] * v1[i] + u2[i] * v2[i]);
                }
            }
            for (column, &(a, b)) in inputs.chunks_exact_mut(CHUNK_SAMPLES).zip(&block.input_pairs) {
                let (column, u, v) = (&mut column[..n], chunk.input(block.high, a), chunk.input(block.low, b));
                for i in 0..n {
                    column[i] = u[i] * v[i];
                }
            }
            let deltas = MatRef::from_column_major_slice(&deltas[..rows * CHUNK_SAMPLES], CHUNK_SAMPLES, rows);
            let inputs = MatRef::from_column_major_slice(&inputs[..cols * CHUNK_SAMPLES], CHUNK_SAMPLES, cols);
            matmul(sum.as_mut(), Accum::Add, deltas.subrows(0, n).transpose(), inputs.subrows(0, n), 1.0, Par::Seq);
        }
    }
    (sums, gradient)
}

/// Adds a chunk's share of Jᵀe to `gradient` (per layer, one row per δ, one column per ã):
/// `Σ_samples (gain · Σ_c e_c δℓ_c[j]) ãℓ[a]`, a matrix product of the first factor's columns
/// by the layer's inputs.
fn accumulate_gradient(chunk: &Chunk, gradient: &mut [Mat<f32>; 3], back: &mut [f32]) {
    let n = chunk.len;
    for (l, (layer, gradient)) in LAYERS.iter().zip(gradient).enumerate() {
        for (j, back) in back.chunks_exact_mut(CHUNK_SAMPLES).take(layer.deltas).enumerate() {
            let back = &mut back[..n];
            back.fill(0.0);
            for c in 0..OUTPUTS {
                let (delta, residual, gain) = (chunk.delta(l, c, j), &chunk.residual[Chunk::range(c)], &chunk.gain);
                for i in 0..n {
                    back[i] += gain[i] * residual[i] * delta[i];
                }
            }
        }
        let back = MatRef::from_column_major_slice(&back[..layer.deltas * CHUNK_SAMPLES], CHUNK_SAMPLES, layer.deltas);
        let inputs = &chunk.input[l * MAX_INPUTS * CHUNK_SAMPLES..(l * MAX_INPUTS + layer.inputs) * CHUNK_SAMPLES];
        let inputs = MatRef::from_column_major_slice(inputs, CHUNK_SAMPLES, layer.inputs);
        matmul(gradient.as_mut(), Accum::Add, back.subrows(0, n).transpose(), inputs.subrows(0, n), 1.0, Par::Seq);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bake::lm::initial_parameters;
    use crate::network::{forward_with_jacobian, hidden_layers};
    use crate::trace::sampling::Rng;

    /// The normal equations equal those of the Jacobian's rows multiplied out one by one in
    /// f64 (`network::forward_with_jacobian`, which its own test checks against finite
    /// differences), over several groups, with gains.
    #[test]
    fn match_the_jacobians_rows_multiplied_out() {
        let mut rng = Rng::new(7, 3);
        let mut data = Dataset::default();
        for _ in 0..GROUP_SAMPLES + 700 {
            data.inputs.push(std::array::from_fn(|_| 2.0 * rng.next_f32() - 1.0));
            data.targets.push(std::array::from_fn(|_| rng.next_f32()));
            data.gains.push(0.2 + rng.next_f32());
        }
        let params = initial_parameters(11, [0.3, 0.5, 0.2]);
        let hidden: Vec<_> = data.inputs.iter().map(|x| hidden_layers(&params, x)).collect();
        let (jtj, jte) = normal_equations(&data, &params, &hidden);

        let p64: Vec<f64> = params.iter().map(|&v| f64::from(v)).collect();
        let mut want_jtj = vec![vec![0.0f64; PARAMETERS]; PARAMETERS];
        let mut want_jte = vec![0.0f64; PARAMETERS];
        let mut rows = Box::new([[0.0f64; PARAMETERS]; OUTPUTS]);
        for s in 0..data.len() {
            let gain = f64::from(data.gains[s]);
            let y = forward_with_jacobian(&p64, &data.inputs[s].map(f64::from), &mut rows);
            for c in 0..OUTPUTS {
                let e = gain * y[c] - f64::from(data.targets[s][c]);
                for u in 0..PARAMETERS {
                    want_jte[u] += gain * rows[c][u] * e;
                    for v in 0..=u {
                        want_jtj[u][v] += gain * gain * rows[c][u] * rows[c][v];
                    }
                }
            }
        }
        let largest = want_jtj.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        let mut worst = 0.0f64;
        for u in 0..PARAMETERS {
            for v in 0..=u {
                worst = worst.max((jtj[(u, v)] - want_jtj[u][v]).abs() / largest);
            }
        }
        assert!(worst < 1e-6, "JᵀJ differs by {worst} of its largest entry");
        let largest = want_jte.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let worst = (0..PARAMETERS).map(|u| (jte[(u, 0)] - want_jte[u]).abs() / largest).fold(0.0, f64::max);
        assert!(worst < 1e-6, "Jᵀe differs by {worst} of its largest entry");
    }
}
