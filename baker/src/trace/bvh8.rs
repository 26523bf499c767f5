//! An eight-wide BVH for the path tracer: each step tests one ray against eight boxes, or
//! against eight triangles, in eight SIMD lanes (`wide::f32x8`: one AVX register where the
//! build targets AVX, as `.cargo/config.toml` has it, else two SSE2 or NEON registers), as
//! Embree's BVH8 with its eight-triangle leaves does.
//!
//! obvhs builds the binary tree (PLOC, reinsertion, SAH leaf collapse to at most eight
//! triangles); [`Bvh8::new`] pulls the levels below each node up into it until it has eight
//! children, and packs each leaf's triangles into one [`Triangles8`]. The triangle test is
//! obvhs's `RtTriangle::intersect` (Möller–Trumbore) done eight lanes at a time, operation for
//! operation, so a hit's distance is the same to the bit. Whether a ray that grazes an edge
//! hits can differ: where the build has FMA, glam fuses one product of the cross product in
//! `RtTriangle::intersect` and these lanes do not, which moves a barycentric by about 1e-8.
//! (The moving light's few triangles keep obvhs's own test, so bakes are unchanged by that.)

use glam::Vec3A;
use obvhs::aabb::Aabb;
use obvhs::bvh2::builder::build_bvh2_from_tris;
use obvhs::bvh2::Bvh2;
use obvhs::ray::Ray;
use obvhs::rt_triangle::RtTriangle;
use obvhs::triangle::Triangle;
use obvhs::BvhBuildParams;

use wide::f32x8 as F8;

/// Lanes per node and per leaf.
const WIDTH: usize = 8;

/// A child slot: a node index, a leaf index with [`LEAF`] set, or [`EMPTY`].
const LEAF: u32 = 1 << 31;
const EMPTY: u32 = u32::MAX;

/// Walk stack entries kept on the stack: enough for a tree 18 levels deep. A deeper tree's
/// walks use the heap.
const INLINE_STACK: usize = 127;

/// Eight child boxes, one per lane.
#[derive(Clone, Copy)]
struct Node {
    min: [F8; 3],
    max: [F8; 3],
    children: [u32; WIDTH],
    /// Bit `lane` set where `children[lane]` is not [`EMPTY`].
    present: u32,
}

/// Up to eight triangles, one per lane, in obvhs's `RtTriangle` form (`e1 = v0 - v1`,
/// `e2 = v2 - v0`, `ng = e1 × e2`). Unused lanes repeat lane 0, which can never win over it.
#[derive(Clone, Copy)]
struct Triangles8 {
    v0: [F8; 3],
    e1: [F8; 3],
    e2: [F8; 3],
    ng: [F8; 3],
    /// Each lane's triangle: its index in the slice given to [`Bvh8::new`].
    primitives: [u32; WIDTH],
}

pub struct Bvh8 {
    nodes: Vec<Node>,
    leaves: Vec<Triangles8>,
    /// Stack entries a walk can need at most: seven per level below the root, plus one.
    stack_size: usize,
}

/// The ray's values that every box and triangle test splats to all lanes.
struct Lanes {
    origin: [F8; 3],
    direction: [F8; 3],
    inv_direction: [F8; 3],
}

impl Lanes {
    fn new(ray: &Ray) -> Self {
        let splat = |v: Vec3A| [F8::splat(v.x), F8::splat(v.y), F8::splat(v.z)];
        Lanes { origin: splat(ray.origin), direction: splat(ray.direction), inv_direction: splat(ray.inv_direction) }
    }
}

/// `a × b` per lane, with glam's `Vec3A::cross` products.
#[inline(always)]
fn cross(a: &[F8; 3], b: &[F8; 3]) -> [F8; 3] {
    [a[1] * b[2] - b[1] * a[2], a[2] * b[0] - b[2] * a[0], a[0] * b[1] - b[0] * a[1]]
}

/// `a · b` per lane, summed in glam's `Vec3A::dot` order.
#[inline(always)]
fn dot(a: &[F8; 3], b: &[F8; 3]) -> F8 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

impl Node {
    /// Each child box's entry distance, and the mask of the lanes whose box the ray meets
    /// within `[tmin, tmax]`.
    #[inline(always)]
    fn hits(&self, ray: &Lanes, tmin: f32, tmax: f32) -> ([f32; WIDTH], u32) {
        let mut near = F8::splat(tmin);
        let mut far = F8::splat(tmax);
        for axis in 0..3 {
            let t0 = (self.min[axis] - ray.origin[axis]) * ray.inv_direction[axis];
            let t1 = (self.max[axis] - ray.origin[axis]) * ray.inv_direction[axis];
            near = near.fast_max(t0.fast_min(t1));
            far = far.fast_min(t0.fast_max(t1));
        }
        (near.to_array(), near.simd_le(far).to_bitmask() & self.present)
    }
}

impl Triangles8 {
    /// Each lane's hit distance, and the mask of the lanes hit within `[tmin, tmax]`.
    #[inline(always)]
    fn hits(&self, ray: &Lanes, tmin: f32, tmax: f32) -> ([f32; WIDTH], u32) {
        let c = [self.v0[0] - ray.origin[0], self.v0[1] - ray.origin[1], self.v0[2] - ray.origin[2]];
        let r = cross(&ray.direction, &c);
        let inv_det = F8::splat(1.0) / dot(&self.ng, &ray.direction);
        let u = dot(&r, &self.e2) * inv_det;
        let v = dot(&r, &self.e1) * inv_det;
        let w = F8::splat(1.0) - u - v;
        // `to_bitmask` of a number is its sign bits, as `f32::to_bits` reads them: -0.0 counts.
        let inside = !(u.to_bitmask() | v.to_bitmask() | w.to_bitmask());
        let t = dot(&self.ng, &c) * inv_det;
        let in_range = t.simd_ge(F8::splat(tmin)).to_bitmask() & t.simd_le(F8::splat(tmax)).to_bitmask();
        (t.to_array(), inside & inv_det.simd_ne(F8::ZERO).to_bitmask() & in_range & 0xff)
    }
}

/// The node being built: a binary node's index, or one of its leaves' primitives.
enum Part {
    Inner(usize),
    Leaf(Vec<u32>),
}

impl Bvh8 {
    /// Builds the tree over `triangles`; hits name a triangle by its index in this slice.
    pub fn new(triangles: &[Triangle]) -> Self {
        let mut bvh = Bvh8 { nodes: Vec::new(), leaves: Vec::new(), stack_size: 1 };
        if triangles.is_empty() {
            return bvh;
        }
        let params = BvhBuildParams { max_prims_per_leaf: WIDTH as u32, ..BvhBuildParams::medium_build() };
        let bvh2 = build_bvh2_from_tris(triangles, params, &mut Default::default());
        let root = bvh.part(&bvh2, 0);
        let depth = bvh.add_node(&bvh2, triangles, vec![root]);
        bvh.stack_size = (WIDTH - 1) * depth + 1;
        bvh
    }

    /// Binary node `index` as a child: a leaf if its subtree has eight triangles or fewer.
    fn part(&self, bvh2: &Bvh2, index: usize) -> Part {
        let mut primitives = Vec::new();
        let mut pending = vec![index];
        while let Some(i) = pending.pop() {
            let node = &bvh2.nodes[i];
            if node.is_leaf() {
                let first = node.first_index as usize;
                primitives.extend(&bvh2.primitive_indices[first..first + node.prim_count as usize]);
            } else {
                pending.extend([node.first_index as usize, node.first_index as usize + 1]);
            }
            if primitives.len() > WIDTH {
                return Part::Inner(index);
            }
        }
        Part::Leaf(primitives)
    }

    /// Adds a node holding `parts`, opening the largest inner parts until it has eight
    /// children; returns the depth of the subtree it roots.
    fn add_node(&mut self, bvh2: &Bvh2, triangles: &[Triangle], mut parts: Vec<Part>) -> usize {
        loop {
            let largest = parts
                .iter()
                .enumerate()
                .filter_map(|(k, p)| match p {
                    Part::Inner(i) => Some((k, bvh2.nodes[*i].aabb.half_area())),
                    Part::Leaf(_) => None,
                })
                .max_by(|a, b| a.1.total_cmp(&b.1));
            let Some((k, _)) = largest else { break };
            if parts.len() == WIDTH {
                break;
            }
            let Part::Inner(i) = parts.swap_remove(k) else { unreachable!("chosen among inner parts") };
            let first = bvh2.nodes[i].first_index as usize;
            parts.push(self.part(bvh2, first));
            parts.push(self.part(bvh2, first + 1));
        }
        let index = self.nodes.len();
        let mut depth = 1;
        let unused = Node { min: [F8::splat(0.0); 3], max: [F8::splat(0.0); 3], children: [EMPTY; WIDTH], present: 0 };
        self.nodes.push(unused);
        let mut min = [[f32::INFINITY; WIDTH]; 3];
        let mut max = [[f32::NEG_INFINITY; WIDTH]; 3];
        let mut children = [EMPTY; WIDTH];
        for (lane, part) in parts.into_iter().enumerate() {
            let (child, aabb) = match part {
                Part::Inner(i) => {
                    let aabb = bvh2.nodes[i].aabb;
                    let first = bvh2.nodes[i].first_index as usize;
                    let children = vec![self.part(bvh2, first), self.part(bvh2, first + 1)];
                    let child = self.nodes.len() as u32;
                    depth = depth.max(1 + self.add_node(bvh2, triangles, children));
                    (child, aabb)
                }
                Part::Leaf(primitives) => {
                    let aabb = primitives.iter().fold(Aabb::INVALID, |b, &p| b.union(&triangles[p as usize].aabb()));
                    self.leaves.push(pack(triangles, &primitives));
                    (LEAF | (self.leaves.len() as u32 - 1), aabb)
                }
            };
            children[lane] = child;
            for axis in 0..3 {
                min[axis][lane] = aabb.min[axis];
                max[axis][lane] = aabb.max[axis];
            }
        }
        self.nodes[index] = Node {
            min: min.map(F8::new),
            max: max.map(F8::new),
            children,
            present: children.iter().enumerate().fold(0, |m, (lane, &c)| m | u32::from(c != EMPTY) << lane),
        };
        depth
    }

    /// The closest hit in `[ray.tmin, ray.tmax]` that `accept(primitive, t)` takes, as
    /// (primitive, t). `accept` is asked only about a hit closer than the closest so far; of
    /// equally close hits, the first found wins.
    #[inline(always)]
    pub fn closest(&self, ray: &Ray, mut accept: impl FnMut(u32, f32) -> bool) -> Option<(u32, f32)> {
        let mut best = None;
        self.walk::<true>(ray, |walk, leaf| {
            let (t, mut hits) = leaf.hits(&walk.lanes, walk.tmin, walk.tmax);
            while hits != 0 {
                let lane = hits.trailing_zeros() as usize;
                hits &= hits - 1;
                let (primitive, t) = (leaf.primitives[lane], t[lane]);
                if t < walk.tmax && accept(primitive, t) {
                    best = Some((primitive, t));
                    walk.tmax = t;
                }
            }
            false
        });
        best
    }

    /// Whether any hit in `[ray.tmin, ray.tmax]` is one that `accept(primitive, t)` takes.
    #[inline(always)]
    pub fn any(&self, ray: &Ray, mut accept: impl FnMut(u32, f32) -> bool) -> bool {
        let mut found = false;
        // Any hit ends the walk, whichever box it is in: no need to sort the boxes.
        self.walk::<false>(ray, |walk, leaf| {
            let (t, mut hits) = leaf.hits(&walk.lanes, walk.tmin, walk.tmax);
            while hits != 0 && !found {
                let lane = hits.trailing_zeros() as usize;
                hits &= hits - 1;
                found = accept(leaf.primitives[lane], t[lane]);
            }
            found
        });
        found
    }

    /// Walks the ray through the tree, nearest box first if `NEAREST_FIRST` (else in any
    /// order), and calls `visit(walk, leaf)` at each leaf whose box it meets; `visit` may
    /// lower `walk.tmax`, and returns whether the walk is over.
    #[inline(always)]
    fn walk<const NEAREST_FIRST: bool>(&self, ray: &Ray, mut visit: impl FnMut(&mut Walk, &Triangles8) -> bool) {
        if self.nodes.is_empty() {
            return;
        }
        let mut inline = [(0u32, 0f32); INLINE_STACK];
        let mut heap = Vec::new();
        let stack: &mut [(u32, f32)] = if self.stack_size <= INLINE_STACK {
            &mut inline
        } else {
            heap.resize(self.stack_size, (0, 0.0));
            &mut heap
        };
        stack[0] = (0, ray.tmin);
        let mut walk = Walk { lanes: Lanes::new(ray), tmin: ray.tmin, tmax: ray.tmax };
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let (entry, near) = stack[top];
            if near > walk.tmax {
                // Its box starts beyond the closest hit found since it was pushed.
                continue;
            }
            if entry & LEAF != 0 {
                if visit(&mut walk, &self.leaves[(entry & !LEAF) as usize]) {
                    return;
                }
                continue;
            }
            let node = &self.nodes[entry as usize];
            let (near, mut hits) = node.hits(&walk.lanes, walk.tmin, walk.tmax);
            if !NEAREST_FIRST {
                while hits != 0 {
                    let lane = hits.trailing_zeros() as usize;
                    hits &= hits - 1;
                    stack[top] = (node.children[lane], near[lane]);
                    top += 1;
                }
                continue;
            }
            // Push the farthest first so that the nearest is popped next.
            let mut order = [(0.0f32, 0u32); WIDTH];
            let mut count = 0;
            while hits != 0 {
                let lane = hits.trailing_zeros() as usize;
                hits &= hits - 1;
                let mut k = count;
                while k > 0 && order[k - 1].0 < near[lane] {
                    order[k] = order[k - 1];
                    k -= 1;
                }
                order[k] = (near[lane], node.children[lane]);
                count += 1;
            }
            for &(near, child) in &order[..count] {
                stack[top] = (child, near);
                top += 1;
            }
        }
    }
}

/// The ray as its walk through the tree sees it: `tmax` shrinks as hits are found.
struct Walk {
    lanes: Lanes,
    tmin: f32,
    tmax: f32,
}

/// `primitives` (one to eight) as one SIMD leaf.
fn pack(triangles: &[Triangle], primitives: &[u32]) -> Triangles8 {
    let lanes: [u32; WIDTH] = std::array::from_fn(|lane| primitives.get(lane).copied().unwrap_or(primitives[0]));
    let rt = lanes.map(|p| RtTriangle::from(&triangles[p as usize]));
    let gather = |field: fn(&RtTriangle) -> Vec3A| {
        [0, 1, 2].map(|axis| F8::new(std::array::from_fn(|lane| field(&rt[lane])[axis])))
    };
    Triangles8 {
        v0: gather(|t| t.v0),
        e1: gather(|t| t.e1),
        e2: gather(|t| t.e2),
        ng: gather(|t| t.ng),
        primitives: lanes,
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3A;
    use obvhs::rt_triangle::RtTriangle;

    use super::*;
    use crate::trace::sampling::Rng;

    fn random_point(rng: &mut Rng, scale: f32) -> Vec3A {
        Vec3A::new(rng.next_f32() - 0.5, rng.next_f32() - 0.5, rng.next_f32() - 0.5) * scale
    }

    /// Small random triangles in a box, and some large ones across it.
    fn soup(count: usize, rng: &mut Rng) -> Vec<Triangle> {
        (0..count)
            .map(|k| {
                let size = if k % 17 == 0 { 4.0 } else { 0.3 };
                let centre = random_point(rng, 4.0);
                Triangle {
                    v0: centre + random_point(rng, size),
                    v1: centre + random_point(rng, size),
                    v2: centre + random_point(rng, size),
                }
            })
            .collect()
    }

    /// The independent answer: every triangle tested by obvhs's own `RtTriangle`.
    fn brute_force(triangles: &[Triangle], ray: &Ray, accept: impl Fn(u32) -> bool) -> Option<(u32, f32)> {
        let mut best: Option<(u32, f32)> = None;
        for (i, t) in triangles.iter().enumerate() {
            let d = RtTriangle::from(t).intersect(ray);
            if d < best.map_or(ray.tmax, |b| b.1) && accept(i as u32) {
                best = Some((i as u32, d));
            }
        }
        best
    }

    /// Random rays against `bvh` and against every triangle: the same closest distance to the
    /// bit, and the same answer to "anything there?". Odd-numbered triangles are "alpha-masked
    /// away" for half of the rays.
    fn matches_brute_force(bvh: &Bvh8, triangles: &[Triangle], rng: &mut Rng) {
        let count = triangles.len();
        for k in 0..2000 {
            let origin = random_point(rng, 10.0);
            let direction = (random_point(rng, 1.0) - origin * 0.05).normalize();
            let tmax = if k % 3 == 0 { 2.0 } else { f32::INFINITY };
            let ray = Ray::new(origin, direction, 0.0, tmax);
            let skip_odd = k % 2 == 0;
            let accept = |p: u32| !(skip_odd && p % 2 == 1);
            let expected = brute_force(triangles, &ray, accept);
            let found = bvh.closest(&ray, |p, _| accept(p));
            assert_eq!(found.map(|h| h.1.to_bits()), expected.map(|h| h.1.to_bits()), "{count} triangles, ray {k}");
            if let (Some(f), Some(e)) = (found, expected) {
                // Equal distances can come from two triangles (a shared edge).
                let t = RtTriangle::from(&triangles[f.0 as usize]).intersect(&ray);
                assert_eq!(t.to_bits(), e.1.to_bits(), "{count} triangles, ray {k}");
            }
            assert_eq!(bvh.any(&ray, |p, _| accept(p)), expected.is_some(), "{count} triangles, ray {k}");
        }
    }

    #[test]
    fn closest_and_any_hit_match_testing_every_triangle() {
        let mut rng = Rng::new(7, 0);
        for count in [1, 3, 8, 9, 17, 80, 2000] {
            let triangles = soup(count, &mut rng);
            matches_brute_force(&Bvh8::new(&triangles), &triangles, &mut rng);
        }
    }

    #[test]
    fn a_walk_too_deep_for_the_inline_stack_uses_the_heap() {
        let mut rng = Rng::new(8, 0);
        let triangles = soup(2000, &mut rng);
        let mut bvh = Bvh8::new(&triangles);
        assert!(bvh.stack_size <= INLINE_STACK);
        bvh.stack_size = INLINE_STACK + 1;
        matches_brute_force(&bvh, &triangles, &mut rng);
    }

    #[test]
    fn an_empty_scene_has_no_hits() {
        let bvh = Bvh8::new(&[]);
        let ray = Ray::new(Vec3A::ZERO, Vec3A::X, 0.0, f32::INFINITY);
        assert!(bvh.closest(&ray, |_, _| true).is_none());
        assert!(!bvh.any(&ray, |_, _| true));
    }
}
