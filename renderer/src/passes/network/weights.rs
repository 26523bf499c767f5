//! One network as the baker trained it, where on its object it applies ([`LeafBlend`]), and
//! the same network with its input normalisation and output scale folded into its weights: the
//! form every variant's shader evaluates.

use super::layout::{B1, HIDDEN1, INPUTS, W3};

/// One network as the baker trained it.
#[derive(Clone, Copy)]
pub struct NetworkWeights<'a> {
    pub params: &'a [f32],
    pub input_min: [f32; INPUTS],
    pub input_max: [f32; INPUTS],
    pub output_scale: f32,
    /// Where on its object the network applies, and how it blends with its neighbours.
    pub blend: LeafBlend,
}

/// A kd-tree leaf's weight over space (the baker's `partition::BlendBox` as plain data): 1
/// in its half-open box `min <= p < max` away from its faces, 0 outside the box grown by the
/// bands, and a smoothstep across the band of half-width `min_band` or `max_band` around each
/// face (0: a hard cut). `±f32::MAX` and no band where a side is unbounded.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LeafBlend {
    pub min: [f32; 3],
    pub max: [f32; 3],
    pub min_band: [f32; 3],
    pub max_band: [f32; 3],
}

impl LeafBlend {
    /// A network that covers all of its object.
    pub const WHOLE: LeafBlend =
        LeafBlend { min: [-f32::MAX; 3], max: [f32::MAX; 3], min_band: [0.0; 3], max_band: [0.0; 3] };

    /// Whether the leaf blends with a neighbour somewhere.
    pub(super) fn has_band(&self) -> bool {
        self.min_band.iter().chain(&self.max_band).any(|&b| b > 0.0)
    }

    /// The leaf's entry in the unit table (`network_units.glsl`).
    pub(super) fn table(&self) -> impl Iterator<Item = f32> + '_ {
        self.min.iter().chain(&self.max).chain(&self.min_band).chain(&self.max_band).copied()
    }
}

impl NetworkWeights<'_> {
    /// The network with its input normalisation and output scale folded in.
    pub(super) fn folded(&self) -> Vec<f32> {
        fold(self.params, &self.input_min, &self.input_max, self.output_scale)
    }
}

/// A network that takes raw inputs: the input normalisation (the baker's `normalize`, an
/// affine map per input) folded into the first layer and the output scale into the last.
/// Computed in f64, so the result differs from the unfolded network only by f32 rounding.
fn fold(params: &[f32], input_min: &[f32; INPUTS], input_max: &[f32; INPUTS], output_scale: f32) -> Vec<f32> {
    let mut out = params.to_vec();
    for j in 0..HIDDEN1 {
        let mut bias = f64::from(params[B1 + j]);
        for i in 0..INPUTS {
            let (lo, hi) = (f64::from(input_min[i]), f64::from(input_max[i]));
            let range = hi - lo;
            // normalize(x) = a x + b, or 0 for a constant input (range ≤ 1e-6, as in the baker).
            let (a, b) = if range > 1e-6 { (2.0 / range, -2.0 * lo / range - 1.0) } else { (0.0, 0.0) };
            let w = f64::from(params[j * INPUTS + i]);
            out[j * INPUTS + i] = (w * a) as f32;
            bias += w * b;
        }
        out[B1 + j] = bias as f32;
    }
    for p in &mut out[W3..] {
        *p = (f64::from(*p) * f64::from(output_scale)) as f32;
    }
    out
}

#[cfg(test)]
mod tests {
    use rrf_baker::network::{forward, normalize};

    use super::*;
    use crate::passes::network::layout::{OUTPUTS, PARAMETERS};

    /// A deterministic stream of numbers in [-1, 1).
    fn numbers(seed: u64) -> impl FnMut() -> f32 {
        let mut state = seed;
        move || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((state >> 40) as f32 / (1u64 << 24) as f32) * 2.0 - 1.0
        }
    }

    #[test]
    fn a_folded_network_on_raw_inputs_is_the_bakers_network_on_normalised_ones() {
        let mut next = numbers(7);
        let params: Vec<f32> = (0..PARAMETERS).map(|_| next()).collect();
        let input_min: [f32; INPUTS] = std::array::from_fn(|_| 3.0 * next());
        let mut input_max: [f32; INPUTS] = std::array::from_fn(|i| input_min[i] + 0.5 + 2.0 * next().abs());
        input_max[12] = input_min[12]; // a constant input, which normalises to 0
        let output_scale = 2.5;
        let folded = fold(&params, &input_min, &input_max, output_scale);
        for _ in 0..100 {
            let raw: [f32; INPUTS] =
                std::array::from_fn(|i| input_min[i] + (input_max[i] - input_min[i] + 0.1) * next().abs());
            let normalised: [f32; INPUTS] = std::array::from_fn(|i| normalize(raw[i], input_min[i], input_max[i]));
            let expected = forward(&params, &normalised).map(|y| y * output_scale);
            let got = forward(&folded, &raw);
            for c in 0..OUTPUTS {
                assert!(
                    (got[c] - expected[c]).abs() < 1e-4 * (1.0 + expected[c].abs()),
                    "{got:?} against {expected:?}"
                );
            }
        }
    }
}
