//! Stratified random numbers for the first vertex of many paths that leave the same surface
//! point, as a bake's sample averages them: randomised quasi-Monte Carlo.
//!
//! Each of the vertex's two-dimensional decisions (where on a light to aim next-event
//! estimation, which direction to continue in) takes the points of a Sobol' (0, 2)-sequence
//! under a random digital shift, and each one-dimensional decision (which light, which BSDF
//! lobe) one point per stratum of `[0, 1)`. Every number is still uniform, so every path's
//! estimate keeps its expectation, but together the paths cover each decision's domain
//! evenly: on the Cornell box a 128-path average has a quarter of the direct light's variance
//! and two thirds of the indirect light's (`docs/experiments/stratified-first-vertex.md`).

use glam::Vec2;

use super::sampling::{unit_f32, Rng};

/// The random numbers a path uses at one scattering vertex.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VertexSamples {
    /// Which light next-event estimation samples.
    pub light_pick: f32,
    /// Where on it.
    pub light: Vec2,
    /// Which BSDF lobe the path continues by.
    pub lobe: f32,
    /// Which direction in it.
    pub direction: Vec2,
}

/// Point `i` of the two-dimensional Sobol' sequence as 32-bit fractions: the van der Corput
/// sequence in base 2 and Sobol's second dimension. Any 2^m consecutive points from a
/// multiple of 2^m form a (0, m, 2)-net: each box of `[0, 1)²` with sides 2^-a by 2^-(m-a)
/// holds exactly one point.
fn sobol_2d(i: u32) -> (u32, u32) {
    let (mut y, mut v, mut bits) = (0u32, 1u32 << 31, i);
    while bits != 0 {
        if bits & 1 != 0 {
            y ^= v;
        }
        bits >>= 1;
        v ^= v >> 1;
    }
    (i.reverse_bits(), y)
}

/// `count` vertex samples that stratify each decision of the vertex, from `rng`. Each two-
/// dimensional decision takes the first `count` points of the Sobol' sequence, shifted by its
/// own random XOR (which keeps the net's strata); the direction takes them in a random order,
/// so that it is independent of the light point it is paired with. Each one-dimensional
/// decision takes one uniform point in each of `count` equal strata, in a random order.
pub fn stratified_vertex_samples(count: usize, rng: &mut Rng) -> Vec<VertexSamples> {
    let (light_shift, direction_shift) = ([rng.next_u32(), rng.next_u32()], [rng.next_u32(), rng.next_u32()]);
    let shuffled = |rng: &mut Rng| {
        let mut order: Vec<u32> = (0..count as u32).collect();
        rng.shuffle(&mut order);
        order
    };
    let (direction_order, pick_order, lobe_order) = (shuffled(rng), shuffled(rng), shuffled(rng));
    let net = |i: u32, [sx, sy]: [u32; 2]| {
        let (x, y) = sobol_2d(i);
        Vec2::new(unit_f32(x ^ sx), unit_f32(y ^ sy))
    };
    let stratum = |k: u32, rng: &mut Rng| ((k as f32 + rng.next_f32()) / count as f32).min(1.0 - f32::EPSILON / 2.0);
    (0..count)
        .map(|i| VertexSamples {
            light_pick: stratum(pick_order[i], rng),
            light: net(i as u32, light_shift),
            lobe: stratum(lobe_order[i], rng),
            direction: net(direction_order[i], direction_shift),
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The first 2^m points, shifted by any XOR, put exactly one point in every box of every
    /// shape 2^-a × 2^-(m-a): the net property that the variance reduction rests on.
    #[test]
    fn sobol_points_form_a_net_under_any_shift() {
        let mut rng = Rng::new(5, 0);
        for m in 0..=10u32 {
            let shift = [rng.next_u32(), rng.next_u32()];
            for a in 0..=m {
                let mut seen = vec![false; 1 << m];
                for i in 0..1u32 << m {
                    let (x, y) = sobol_2d(i);
                    let (x, y) = (u64::from(x ^ shift[0]), u64::from(y ^ shift[1]));
                    let (column, row) = ((x >> (32 - a)) as usize, (y >> (32 - (m - a))) as usize);
                    let box_index = (column << (m - a)) | row;
                    assert!(!seen[box_index], "m {m}, a {a}: box {box_index} holds two points");
                    seen[box_index] = true;
                }
            }
        }
    }

    /// For a power of two `count`, every one-dimensional decision puts one number in each of
    /// `count` strata, and every two-dimensional one a point in each of `count` columns and in
    /// each of `count` rows.
    #[test]
    fn every_decision_is_stratified() {
        let mut rng = Rng::new(9, 1);
        for count in [1usize, 2, 8, 64, 512] {
            let samples = stratified_vertex_samples(count, &mut rng);
            let strata = |values: Vec<f32>| {
                let mut hit = vec![0; count];
                values.iter().for_each(|&v| {
                    assert!((0.0..1.0).contains(&v), "{v}");
                    hit[(v * count as f32) as usize] += 1;
                });
                hit.iter().all(|&h| h == 1)
            };
            for (name, values) in [
                ("light pick", samples.iter().map(|s| s.light_pick).collect::<Vec<_>>()),
                ("lobe", samples.iter().map(|s| s.lobe).collect()),
                ("light x", samples.iter().map(|s| s.light.x).collect()),
                ("light y", samples.iter().map(|s| s.light.y).collect()),
                ("direction x", samples.iter().map(|s| s.direction.x).collect()),
                ("direction y", samples.iter().map(|s| s.direction.y).collect()),
            ] {
                assert!(strata(values), "{count} samples: {name} is not stratified");
            }
        }
    }
}
