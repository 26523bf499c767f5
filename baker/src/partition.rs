//! The input-space kd-tree of the RRF paper (Ren et al. 2013, §4.3), over surface position:
//! where one network cannot fit an object's light, the bake splits the object at the midpoint
//! of its longest side and trains a network per half, recursively. A leaf's [`Region`] is the
//! path of splits from the root, so the leaves of one tree partition all of space: every
//! point lies in exactly one of them, whatever its distance from the object.
//!
//! The tree is over position only, so the network of a pixel is known from the G-buffer
//! alone, the same for every light and viewpoint, and neighbouring pixels mostly share it.
//!
//! Leaves blend across their cuts ([`BlendBox`]): in a band around each cut the prediction is
//! the sum of the leaves that meet there, weighted by a smoothstep across the band, so that it
//! is continuous everywhere. The weights of a tree's leaves sum to one at every point (at a
//! corner of several cuts, a leaf's weight is the product of its cuts' weights).

use glam::Vec3;
use serde::{Deserialize, Serialize};

/// One side of a split plane: positions with `p[axis] < at` (`below`) or `p[axis] >= at`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Split {
    pub axis: u8,
    pub at: f32,
    pub below: bool,
}

impl Split {
    fn contains(&self, p: Vec3) -> bool {
        let x = p[self.axis as usize];
        if self.below {
            x < self.at
        } else {
            x >= self.at
        }
    }
}

/// A leaf of the kd-tree: the splits on the way from the root. The root (no split) is all
/// of space.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(transparent)]
pub struct Region(pub Vec<Split>);

impl Region {
    pub fn is_whole(&self) -> bool {
        self.0.is_empty()
    }

    pub fn contains(&self, p: Vec3) -> bool {
        self.0.iter().all(|s| s.contains(p))
    }

    /// The region's box, half-open (`min <= p < max`), with `±f32::MAX` where no split bounds
    /// it, so that a finite point is inside exactly when [`Region::contains`] says so.
    pub fn bounds(&self) -> ([f32; 3], [f32; 3]) {
        let (mut min, mut max) = ([-f32::MAX; 3], [f32::MAX; 3]);
        for s in &self.0 {
            let a = s.axis as usize;
            if s.below {
                max[a] = max[a].min(s.at);
            } else {
                min[a] = min[a].max(s.at);
            }
        }
        (min, max)
    }

    /// The half of this region on one side of `at` on `axis`.
    pub fn child(&self, axis: u8, at: f32, below: bool) -> Region {
        let mut splits = self.0.clone();
        splits.push(Split { axis, at, below });
        Region(splits)
    }

    /// The region in a tensor name: `/x<0.25/z>=0.5` (empty for the root).
    pub fn path(&self) -> String {
        self.0
            .iter()
            .map(|s| format!("/{}{}{}", ["x", "y", "z"][s.axis as usize], ["<", ">="][usize::from(!s.below)], s.at))
            .collect()
    }

    /// The region's box with a blend band around each of its cut faces: `band` times the
    /// extent of the leaf's node along the cut's axis on either side of the cut. `object_min`
    /// and `object_max` are the object's bounding box, the root node that the bake split at
    /// the midpoint of the longest side, node by node, so that a cut's node is known from the
    /// splits above it. A `band` of 0 is the hard cut of [`Region::contains`].
    pub fn blend_box(&self, object_min: Vec3, object_max: Vec3, band: f32) -> BlendBox {
        let (mut node_min, mut node_max) = (object_min, object_max);
        let (min, max) = self.bounds();
        let mut blend = BlendBox { min, max, min_band: [0.0; 3], max_band: [0.0; 3] };
        for s in &self.0 {
            let a = s.axis as usize;
            // The same band on both sides of a cut, so that the two sides' weights sum to one.
            let half = band * 0.5 * (node_max[a] - node_min[a]).max(0.0);
            if s.below {
                blend.max_band[a] = half;
                node_max[a] = s.at;
            } else {
                blend.min_band[a] = half;
                node_min[a] = s.at;
            }
        }
        blend
    }

    /// Whether the splits are well formed: axes 0 to 2 and finite positions.
    pub fn is_valid(&self) -> bool {
        self.0.iter().all(|s| s.axis < 3 && s.at.is_finite())
    }
}

/// The most a blend band may be, as a share of a node's extent: up to it, the bands of two
/// parallel cuts of one tree never overlap (a node's cut lies a quarter of its parent's extent
/// from the parent's, and the two bands together are at most 1.5 × `band` of the parent's),
/// so that a leaf's weight depends only on the faces of its box, and the leaves' weights sum
/// to one.
pub const MAX_BLEND_BAND: f32 = 0.15;

/// A kd-tree leaf's weight over space: 1 inside its box away from its cut faces, 0 outside
/// the box grown by the bands, and a smoothstep across each band, falling where its sibling's
/// rises, so that the two sum to one. A face without a band is a hard, half-open cut. The
/// renderer's twin is `leaf_weight` in `network_units.glsl`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BlendBox {
    pub min: [f32; 3],
    pub max: [f32; 3],
    /// The half-width of the band around each face; 0 at a hard cut or an unbounded side.
    pub min_band: [f32; 3],
    pub max_band: [f32; 3],
}

impl BlendBox {
    pub fn weight(&self, p: Vec3) -> f32 {
        let mut w = 1.0;
        for a in 0..3 {
            w *= rising(p[a], self.min[a], self.min_band[a]) * (1.0 - rising(p[a], self.max[a], self.max_band[a]));
        }
        w
    }

    /// The half-open box outside which the weight is 0.
    pub fn support(&self) -> ([f32; 3], [f32; 3]) {
        (
            std::array::from_fn(|a| self.min[a] - self.min_band[a]),
            std::array::from_fn(|a| self.max[a] + self.max_band[a]),
        )
    }
}

/// 0 below the band `at ± band`, 1 above it, a smoothstep (3t² − 2t³) across it; without a
/// band, the step `x >= at`.
fn rising(x: f32, at: f32, band: f32) -> f32 {
    if band > 0.0 {
        let t = ((x - (at - band)) / (2.0 * band)).clamp(0.0, 1.0);
        t * t * (3.0 - 2.0 * t)
    } else if x >= at {
        1.0
    } else {
        0.0
    }
}

/// Whether `regions` are the leaves of one kd-tree, so that every point lies in exactly one:
/// either the root alone, or all on the two sides of the same first split, each side in turn
/// the leaves of a tree.
pub fn is_partition(regions: &[&[Split]]) -> bool {
    match regions {
        [] => false,
        [[]] => true,
        _ => {
            let Some(first) = regions[0].first() else { return false };
            let same_plane = |s: &Split| s.axis == first.axis && s.at == first.at;
            if !regions.iter().all(|r| r.first().is_some_and(same_plane)) {
                return false;
            }
            let side =
                |below: bool| regions.iter().filter(|r| r[0].below == below).map(|r| &r[1..]).collect::<Vec<_>>();
            is_partition(&side(true)) && is_partition(&side(false))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn leaves_of_a_tree_partition_space() {
        let root = Region::default();
        let (low, high) = (root.child(0, 0.5, true), root.child(0, 0.5, false));
        let (a, b) = (high.child(2, 0.25, true), high.child(2, 0.25, false));
        let leaves = [&low, &a, &b];
        assert!(is_partition(&leaves.map(|r| r.0.as_slice())));
        for p in [Vec3::new(0.5, 0.0, 0.25), Vec3::new(-9.0, 3.0, 9.0), Vec3::new(0.7, 1.0, 0.1)] {
            assert_eq!(leaves.iter().filter(|r| r.contains(p)).count(), 1, "{p}");
            for r in leaves {
                let (min, max) = r.bounds();
                let in_box = (0..3).all(|i| min[i] <= p[i] && p[i] < max[i]);
                assert_eq!(in_box, r.contains(p));
            }
        }
        assert_eq!(a.path(), "/x>=0.5/z<0.25");
        assert!(!is_partition(&[low.0.as_slice(), a.0.as_slice()]), "a gap");
        assert!(!is_partition(&[root.0.as_slice(), low.0.as_slice()]), "an overlap");
        assert!(!is_partition(&[low.0.as_slice(), root.child(1, 0.5, false).0.as_slice()]), "different planes");
    }

    /// The leaves of a tree over the unit cube split as the bake splits (at midpoints), nested
    /// on one axis and crossed on another.
    fn blended_leaves(band: f32) -> Vec<BlendBox> {
        let root = Region::default();
        let (low, high) = (root.child(0, 0.5, true), root.child(0, 0.5, false));
        let (low_low, low_high) = (low.child(0, 0.25, true), low.child(0, 0.25, false));
        let (high_low, high_high) = (high.child(1, 0.5, true), high.child(1, 0.5, false));
        [low_low, low_high, high_low, high_high].iter().map(|r| r.blend_box(Vec3::ZERO, Vec3::ONE, band)).collect()
    }

    #[test]
    fn blend_weights_are_a_partition_of_unity() {
        let leaves = blended_leaves(MAX_BLEND_BAND);
        assert_eq!(leaves[2].min_band[0], 0.075, "half of the root's extent times the band");
        assert_eq!(leaves[1].min_band[0], 0.0375, "a quarter of it");
        let mut rng = crate::trace::sampling::Rng::new(7, 0);
        for _ in 0..10_000 {
            let p = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 1.2 - 0.1;
            let weights: Vec<f32> = leaves.iter().map(|l| l.weight(p)).collect();
            let sum: f32 = weights.iter().sum();
            assert!((sum - 1.0).abs() < 1e-6, "{p}: {weights:?}");
            for (l, w) in leaves.iter().zip(&weights) {
                let (min, max) = l.support();
                let inside = (0..3).all(|a| min[a] <= p[a] && p[a] < max[a]);
                assert!(inside || *w == 0.0, "{p}: weight {w} outside the support");
            }
        }
        // At the root's cut the two sides weigh a half each, and the corner of the cuts at
        // x = 0.5 and y = 0.5 shares it out in quarters.
        let w = |p: Vec3| leaves.iter().map(|l| l.weight(p)).collect::<Vec<_>>();
        let near = |a: Vec<f32>, b: [f32; 4]| a.iter().zip(b).all(|(a, b)| (a - b).abs() < 1e-6);
        assert!(near(w(Vec3::new(0.5, 0.2, 0.5)), [0.0, 0.5, 0.5, 0.0]));
        assert!(near(w(Vec3::new(0.5, 0.5, 0.5)), [0.0, 0.5, 0.25, 0.25]));
        // The weight is continuous: no step larger than the smoothstep's slope allows.
        let mut previous = w(Vec3::new(0.0, 0.7, 0.5));
        for i in 1..=1000 {
            let now = w(Vec3::new(i as f32 / 1000.0, 0.7, 0.5));
            for (a, b) in previous.iter().zip(&now) {
                assert!((a - b).abs() < 0.03, "step at x = {}", i as f32 / 1000.0);
            }
            previous = now;
        }
    }

    #[test]
    fn a_blend_band_of_zero_is_the_hard_cut() {
        let leaves = blended_leaves(0.0);
        let regions = [(0, 0.25, true), (0, 0.25, false)];
        let root = Region::default().child(0, 0.5, true);
        for p in [Vec3::new(0.25, 0.1, 0.1), Vec3::new(0.2499, 0.1, 0.1), Vec3::new(0.5, 0.5, 0.5)] {
            for (leaf, &(axis, at, below)) in leaves.iter().zip(&regions) {
                assert_eq!(leaf.weight(p), f32::from(u8::from(root.child(axis, at, below).contains(p))), "{p}");
            }
        }
    }
}
