//! The input-space kd-tree of the RRF paper (Ren et al. 2013, §4.3), over surface position:
//! where one network cannot fit an object's light, the bake splits the object at the midpoint
//! of its longest side and trains a network per half, recursively. A leaf's [`Region`] is the
//! path of splits from the root, so the leaves of one tree partition all of space: every
//! point lies in exactly one of them, whatever its distance from the object.
//!
//! The tree is over position only, so the network of a pixel is known from the G-buffer
//! alone, the same for every light and viewpoint, and neighbouring pixels mostly share it.

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

    /// Whether the splits are well formed: axes 0 to 2 and finite positions.
    pub fn is_valid(&self) -> bool {
        self.0.iter().all(|s| s.axis < 3 && s.at.is_finite())
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
}
