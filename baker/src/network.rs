//! The radiance regression function: a 13 → 20 tanh → 10 tanh → 3 linear network, its input
//! encoding, and the CPU reference inference. The GLSL that evaluates networks on the GPU
//! (`shaders-glsl/include/network.glsl`) follows `Network::evaluate` line for line.

use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::partition::{BlendBox, Region};

#[path = "network_layout.rs"]
mod layout;
pub use layout::*;

/// Which light a network learns.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Component {
    Direct,
    Indirect,
}

impl Component {
    pub const ALL: [Component; 2] = [Component::Direct, Component::Indirect];

    pub fn name(self) -> &'static str {
        match self {
            Component::Direct => "direct",
            Component::Indirect => "indirect",
        }
    }
}

/// What the networks' outputs are multiplied by: the surface's reflectance, per channel, its
/// diffuse albedo `baseColor · (1 − metallic)` plus its specular reflectance at normal incidence
/// `mix(0.04 · specular, baseColor, metallic)` (at least [`MIN_REFLECTANCE`]). The networks learn
/// radiance divided by it, so that a texture's detail comes from the texture at run time and
/// the networks learn only the smooth light (as the RRF paper does for textured surfaces, and
/// neural radiance caches by "demodulating" albedo). The GLSL twin is in `network_inputs.glsl`.
pub fn reflectance(base_color: Vec3, metallic: f32, specular: f32) -> Vec3 {
    let diffuse = base_color * (1.0 - metallic);
    let f0 = Vec3::splat(0.04 * specular).lerp(base_color, metallic);
    (diffuse + f0).max(Vec3::splat(MIN_REFLECTANCE))
}

/// The network's raw inputs, before normalisation: surface position (3), direction towards
/// the viewer (3), light position (3), shading normal (3), roughness (1).
pub fn raw_inputs(position: Vec3, to_viewer: Vec3, light: Vec3, normal: Vec3, roughness: f32) -> [f32; INPUTS] {
    [
        position.x,
        position.y,
        position.z,
        to_viewer.x,
        to_viewer.y,
        to_viewer.z,
        light.x,
        light.y,
        light.z,
        normal.x,
        normal.y,
        normal.z,
        roughness,
    ]
}

/// One trained network with what is needed to use it.
#[derive(Clone, Debug, PartialEq)]
pub struct Network {
    pub object: String,
    pub component: Component,
    /// Where on the object the network applies: a leaf of the object's kd-tree, or all of it.
    pub region: Region,
    /// Its weight among its tree's leaves: the region, blended across its cuts.
    pub blend: BlendBox,
    /// Input `i` maps `[input_min[i], input_max[i]]` to `[-1, 1]`.
    pub input_min: [f32; INPUTS],
    pub input_max: [f32; INPUTS],
    /// The network predicts radiance / `output_scale`.
    pub output_scale: f32,
    pub params: Vec<f32>,
}

/// Maps `x` from `[lo, hi]` to `[-1, 1]`; a constant input (lo == hi) maps to 0.
pub fn normalize(x: f32, lo: f32, hi: f32) -> f32 {
    let range = hi - lo;
    if range > 1e-6 {
        2.0 * (x - lo) / range - 1.0
    } else {
        0.0
    }
}

impl Network {
    /// Radiance (linear RGB) for raw inputs.
    pub fn evaluate(&self, raw: &[f32; INPUTS]) -> Vec3 {
        let mut x = [0.0f32; INPUTS];
        for i in 0..INPUTS {
            x[i] = normalize(raw[i], self.input_min[i], self.input_max[i]);
        }
        let y = forward(&self.params, &x);
        Vec3::from(y) * self.output_scale
    }
}

/// An object's component at raw inputs: the sum of its kd-tree's `leaves`, each weighted by
/// its blend weight at the input position (one leaf away from the cuts).
pub fn evaluate_blended(leaves: &[&Network], raw: &[f32; INPUTS]) -> Vec3 {
    let position = Vec3::new(raw[0], raw[1], raw[2]);
    leaves
        .iter()
        .map(|n| (n.blend.weight(position), n))
        .filter(|&(w, _)| w > 0.0)
        .map(|(w, n)| n.evaluate(raw) * w)
        .sum()
}

/// The float types the network runs in: f32 for inference and training, eight f32 lanes for
/// eight rows at once ([`forward_rows`]), f64 where a test needs the precision (finite
/// differences).
pub trait Real: Copy + std::ops::Mul<Output = Self> + std::ops::Sub<Output = Self> + std::ops::AddAssign {
    const ZERO: Self;
    const ONE: Self;
    /// A layer's activation: tanh of every value, in place.
    fn tanh_all(values: &mut [Self]);
}

impl Real for f32 {
    const ZERO: Self = 0.0;
    const ONE: Self = 1.0;
    /// Eight values at a time through `wide`'s tanh (a few ulp from the C library's, which
    /// takes a quarter of training's time one value at a time).
    fn tanh_all(values: &mut [Self]) {
        for chunk in values.chunks_mut(8) {
            let mut lanes = [0.0; 8];
            lanes[..chunk.len()].copy_from_slice(chunk);
            let tanh = wide::f32x8::from(lanes).tanh().to_array();
            chunk.copy_from_slice(&tanh[..chunk.len()]);
        }
    }
}

impl Real for wide::f32x8 {
    const ZERO: Self = wide::f32x8::ZERO;
    const ONE: Self = wide::f32x8::ONE;
    /// Each lane's tanh: the function f32's `tanh_all` applies, lane for lane.
    fn tanh_all(values: &mut [Self]) {
        for v in values {
            *v = v.tanh();
        }
    }
}

impl Real for f64 {
    const ZERO: Self = 0.0;
    const ONE: Self = 1.0;
    fn tanh_all(values: &mut [Self]) {
        for v in values {
            *v = v.tanh();
        }
    }
}

/// The activations of the two tanh layers.
pub type Hidden<T> = ([T; HIDDEN1], [T; HIDDEN2]);

/// The two tanh layers on normalised inputs.
pub fn hidden_layers<T: Real>(p: &[T], x: &[T; INPUTS]) -> Hidden<T> {
    // Each unit's sum is its bias plus its inputs' terms in input order. The loop over inputs
    // is the outer one so that the units' sums advance together rather than one after
    // another, each add waiting on the last.
    let mut h1: [T; HIDDEN1] = std::array::from_fn(|j| p[B1 + j]);
    for (i, &x) in x.iter().enumerate() {
        for (j, s) in h1.iter_mut().enumerate() {
            *s += p[W1 + j * INPUTS + i] * x;
        }
    }
    T::tanh_all(&mut h1);
    let mut h2: [T; HIDDEN2] = std::array::from_fn(|k| p[B2 + k]);
    for (j, &h) in h1.iter().enumerate() {
        for (k, s) in h2.iter_mut().enumerate() {
            *s += p[W2 + k * HIDDEN1 + j] * h;
        }
    }
    T::tanh_all(&mut h2);
    (h1, h2)
}

/// The network on `rows` of normalised inputs, eight rows at a time, a row per SIMD lane:
/// `each(hidden, outputs)` is called for every row in order. It runs [`hidden_layers`] and
/// [`output_layer`] themselves on lanes, with every parameter in all eight, so a row's values
/// are those of the one-row pass to the bit. One row at a time, the 20 and 10 units of a layer
/// fill the tanh's eight lanes only partly, and the sums need shuffles.
pub fn forward_rows(p: &[f32], rows: &[[f32; INPUTS]], mut each: impl FnMut(&Hidden<f32>, &[f32; OUTPUTS])) {
    use wide::f32x8 as F8;
    let lanes: Vec<F8> = p.iter().map(|&v| F8::splat(v)).collect();
    for batch in rows.chunks(8) {
        // Lanes past the last row compute on zeros and are dropped.
        let x: [F8; INPUTS] =
            std::array::from_fn(|i| F8::new(std::array::from_fn(|r| batch.get(r).map_or(0.0, |x| x[i]))));
        let (h1, h2) = hidden_layers(&lanes, &x);
        let y = output_layer(&lanes, &h2);
        let (h1, h2, y) = (h1.map(F8::to_array), h2.map(F8::to_array), y.map(F8::to_array));
        for r in 0..batch.len() {
            each(&(h1.map(|h| h[r]), h2.map(|h| h[r])), &y.map(|y| y[r]));
        }
    }
}

/// The network on normalised inputs.
pub fn forward(p: &[f32], x: &[f32; INPUTS]) -> [f32; OUTPUTS] {
    output_layer(p, &hidden_layers(p, x).1)
}

/// The linear output layer on the second tanh layer's activations `h2`.
pub fn output_layer<T: Real>(p: &[T], h2: &[T; HIDDEN2]) -> [T; OUTPUTS] {
    let mut y = [T::ZERO; OUTPUTS];
    for c in 0..OUTPUTS {
        let mut s = p[B3 + c];
        for k in 0..HIDDEN2 {
            s += p[W3 + c * HIDDEN2 + k] * h2[k];
        }
        y[c] = s;
    }
    y
}

/// The network and its Jacobian: `jacobian[c]` is ∂y_c/∂params (length [`PARAMETERS`]).
pub fn forward_with_jacobian<T: Real>(
    p: &[T],
    x: &[T; INPUTS],
    jacobian: &mut [[T; PARAMETERS]; OUTPUTS],
) -> [T; OUTPUTS] {
    let (h1, h2) = hidden_layers(p, x);
    let mut y = [T::ZERO; OUTPUTS];
    for c in 0..OUTPUTS {
        let g = &mut jacobian[c];
        g.fill(T::ZERO);
        let mut s = p[B3 + c];
        for k in 0..HIDDEN2 {
            s += p[W3 + c * HIDDEN2 + k] * h2[k];
            g[W3 + c * HIDDEN2 + k] = h2[k];
        }
        g[B3 + c] = T::ONE;
        y[c] = s;
        // Back through layer 2 and layer 1.
        let mut d2 = [T::ZERO; HIDDEN2];
        for k in 0..HIDDEN2 {
            d2[k] = p[W3 + c * HIDDEN2 + k] * (T::ONE - h2[k] * h2[k]);
            g[B2 + k] = d2[k];
            for j in 0..HIDDEN1 {
                g[W2 + k * HIDDEN1 + j] = d2[k] * h1[j];
            }
        }
        for j in 0..HIDDEN1 {
            let mut d1 = T::ZERO;
            for k in 0..HIDDEN2 {
                d1 += p[W2 + k * HIDDEN1 + j] * d2[k];
            }
            d1 = d1 * (T::ONE - h1[j] * h1[j]);
            g[B1 + j] = d1;
            for i in 0..INPUTS {
                g[W1 + j * INPUTS + i] = d1 * x[i];
            }
        }
    }
    y
}
