//! Training one object's networks of one component: a network over the whole object, and
//! where its validation error stays above what the noise of its targets explains, the paper's
//! kd-tree split ([`crate::partition`]): a network per half, recursively, up to the bake's
//! depth.

use glam::Vec3;

use super::lm::{self, initial_parameters, Dataset, LmSettings};
use super::samples::Sample;
use super::BakeSettings;
use crate::hash::Fnv64;
use crate::model::NetworkInfo;
use crate::network::{normalize, Component, Network, INPUTS, OUTPUTS, VIEW_INPUT, W3};
use crate::partition::Region;
use crate::scene::{Aabb, Scene};
use crate::trace::sampling::mix64;

/// Each half of a split learns from the samples in its box grown by this share of the box's
/// size on every side, so that both networks that meet at a split plane learned the light
/// across the band where they are blended ([`BakeSettings::blend_band`]).
pub const OVERLAP: f32 = 0.1;

/// The most the two halves of a split may differ where they meet: their mean squared
/// difference there, relative to the mean square of the parent's targets (0.05: an RMS step of
/// 22%). On the shipped scenes, diffuse surfaces' halves differ by up to 0.033 (the Cornell
/// box floor's direct light, across both blocks' shadows, from stratified paths); the gold
/// sphere's and the glossy floor's by 0.07 to 0.3.
const MAX_SEAM: f64 = 0.05;

/// A node of an object's kd-tree: its region and its part of the object's bounding box.
pub struct Node {
    pub region: Region,
    pub bounds: Aabb,
}

impl Node {
    /// The whole of `object`.
    pub fn root(scene: &Scene, object: u32) -> Node {
        Node { region: Region::default(), bounds: scene.objects[object as usize].bounds() }
    }

    /// The two halves, split at the midpoint of the longest side (the paper's rule).
    fn children(&self) -> [Node; 2] {
        let size = self.bounds.max - self.bounds.min;
        let axis = if size.x >= size.y && size.x >= size.z {
            0
        } else if size.y >= size.z {
            1
        } else {
            2
        };
        let at = 0.5 * (self.bounds.min[axis] + self.bounds.max[axis]);
        let (mut low, mut high) = (self.bounds, self.bounds);
        low.max[axis] = at;
        high.min[axis] = at;
        [
            Node { region: self.region.child(axis as u8, at, true), bounds: low },
            Node { region: self.region.child(axis as u8, at, false), bounds: high },
        ]
    }

    /// Where the node's samples come from: its box grown by [`OVERLAP`] towards the split
    /// planes that bound it, and without bound where no plane does.
    fn sample_box(&self) -> Aabb {
        let grow = (self.bounds.max - self.bounds.min) * OVERLAP;
        let (min, max) = self.region.bounds();
        let open = |bound: f32, grown: f32, infinity: f32| if bound.abs() == f32::MAX { infinity } else { grown };
        Aabb {
            min: Vec3::from_array(std::array::from_fn(|a| {
                open(min[a], self.bounds.min[a] - grow[a], f32::NEG_INFINITY)
            })),
            max: Vec3::from_array(std::array::from_fn(|a| open(max[a], self.bounds.max[a] + grow[a], f32::INFINITY))),
        }
    }
}

/// Input ranges for `object`'s networks, every leaf's the same: its bounding box for positions,
/// the light's box for the light, [-1, 1] for directions, [0, 1] for roughness. Shared by the
/// leaves so that a half starts from its parent's network as it is.
///
/// On an object whose every material is pure Lambert the light leaving a point is the same
/// towards every viewer, so the direction to the viewer gets the empty range [0, 0], which
/// [`normalize`] maps to 0 here and the renderer alike: its networks cannot learn a
/// dependence on the viewpoint that is only noise, and then get it wrong for viewpoints far
/// from those of training.
fn input_ranges(scene: &Scene, object: u32) -> ([f32; INPUTS], [f32; INPUTS]) {
    let (mut lo, mut hi) = ([-1.0f32; INPUTS], [1.0f32; INPUTS]);
    let o = &scene.objects[object as usize];
    if o.parts.iter().all(|p| scene.materials[p.material as usize].is_lambert()) {
        lo[VIEW_INPUT..VIEW_INPUT + 3].fill(0.0);
        hi[VIEW_INPUT..VIEW_INPUT + 3].fill(0.0);
    }
    let Aabb { min, max } = o.bounds();
    let light = scene.moving_light.as_ref().map(|l| l.bounds);
    for a in 0..3 {
        lo[a] = min[a];
        hi[a] = max[a];
        if let Some(b) = light {
            lo[6 + a] = b.min[a];
            hi[6 + a] = b.max[a];
        }
    }
    lo[12] = 0.0;
    hi[12] = 1.0;
    (lo, hi)
}

/// The training and validation sets of one network, normalised as the model records it.
pub struct NetworkData {
    pub train: Dataset,
    pub validation: Dataset,
    pub input_min: [f32; INPUTS],
    pub input_max: [f32; INPUTS],
    /// Targets are divided by this (their RMS).
    pub output_scale: f32,
    /// The mean of the validation targets' noise (their estimated variance, [`Sample::noise`]),
    /// in the units of the scaled targets: the validation MSE a perfect fit would have.
    pub validation_noise: f64,
}

/// A deterministic random subset of `samples` (those of `node`, [`lowest_keys`]), split into
/// training and validation sets ([`validation_flags`]).
pub fn network_data(
    scene: &Scene,
    settings: &BakeSettings,
    object: u32,
    component: Component,
    samples: &[&Sample],
) -> NetworkData {
    keyed_network_data(scene, settings, object, component, &keyed(settings, samples))
}

/// [`network_data`] of samples whose keys are hashed already.
fn keyed_network_data(
    scene: &Scene,
    settings: &BakeSettings,
    object: u32,
    component: Component,
    samples: &[Keyed],
) -> NetworkData {
    let order = lowest_keys(settings, samples.iter().map(|s| s.key));
    let (input_min, input_max) = input_ranges(scene, object);
    let target = |s: &Sample| s.target(component);
    let rms = {
        let sum: f64 = order.iter().flat_map(|&i| target(&samples[i])).map(|v| f64::from(v) * f64::from(v)).sum();
        ((sum / (order.len() * OUTPUTS) as f64).sqrt() as f32).max(1e-6)
    };
    let validates = validation_flags(settings, order.iter().map(|&i| samples[i].key));
    let (mut train, mut validation) = (Dataset::default(), Dataset::default());
    let mut noise = 0.0f64;
    for (&i, &validates) in order.iter().zip(&validates) {
        let s = &samples[i];
        let set = if validates {
            noise += f64::from(s.noise(component));
            &mut validation
        } else {
            &mut train
        };
        set.inputs.push(std::array::from_fn(|k| normalize(s.inputs[k], input_min[k], input_max[k])));
        set.targets.push(target(s).map(|v| v / rms));
    }
    let validation_noise = noise / validation.len().max(1) as f64 / (f64::from(rms) * f64::from(rms));
    NetworkData { train, validation, input_min, input_max, output_scale: rms, validation_noise }
}

/// `object`'s networks of `component` from its `samples`: one, or one per leaf of its kd-tree,
/// leaves in tree order (the low half first).
pub fn train_tree(
    scene: &Scene,
    settings: &BakeSettings,
    object: u32,
    component: Component,
    samples: &[&Sample],
) -> Vec<(Network, NetworkInfo)> {
    let tree = Tree { scene, settings, object, component };
    let root = Node::root(scene, object);
    let samples = keyed(settings, samples);
    let trained = train_network(tree, &root, &samples, None);
    let mut leaves = grow(tree, root, &samples, trained);
    if leaves.len() > 1 && settings.blend_band > 0.0 {
        fit_blend(tree, &samples, &mut leaves);
    }
    leaves
}

/// Refits the leaves of one tree so that their blend, not each leaf alone, matches the
/// targets across the bands where they meet: leaf by leaf (Gauss–Seidel, in tree order), each
/// leaf's weight times its output is fitted by Levenberg–Marquardt, from where it is, to what
/// the other leaves' weighted outputs leave of the targets, on the samples where its weight is
/// not 0. Inside its box, away from the bands, that is its own fit as before; in a band, it is
/// the share of the light that its neighbours do not already give. Each leaf keeps the
/// parameters with the lowest validation error of the blend, its starting ones included, and
/// records that error.
fn fit_blend(tree: Tree, samples: &[Keyed], leaves: &mut [(Network, NetworkInfo)]) {
    let Tree { settings, .. } = tree;
    for i in 0..leaves.len() {
        let own = leaves[i].0.blend;
        let near: Vec<(Keyed, f32)> =
            samples.iter().map(|&s| (s, own.weight(position(&s)))).filter(|&(_, w)| w > 0.0).collect();
        if near.iter().all(|&(_, w)| w == 1.0) {
            continue; // no sample in a band: the leaf's own fit is the blend's
        }
        let order = lowest_keys(settings, near.iter().map(|(s, _)| s.key));
        let validates = validation_flags(settings, order.iter().map(|&k| near[k].0.key));
        let network = &leaves[i].0;
        let rms = network.output_scale;
        let (mut train, mut validation) = (Dataset::default(), Dataset::default());
        let mut noise = 0.0f64;
        for (&k, &validates) in order.iter().zip(&validates) {
            let (s, weight) = near[k];
            if validates {
                noise += f64::from(s.noise(tree.component));
            }
            let p = position(&s);
            let others: Vec3 = leaves
                .iter()
                .enumerate()
                .filter(|&(j, _)| j != i)
                .map(|(_, (other, _))| (other.blend.weight(p), other))
                .filter(|&(w, _)| w > 0.0)
                .map(|(w, other)| other.evaluate(&s.inputs) * w)
                .sum();
            let rest = Vec3::from(s.target(tree.component)) - others;
            let set = if validates { &mut validation } else { &mut train };
            set.inputs
                .push(std::array::from_fn(|k| normalize(s.inputs[k], network.input_min[k], network.input_max[k])));
            set.targets.push((rest / rms).to_array());
            set.gains.push(weight);
        }
        let lm_settings = LmSettings { max_iterations: settings.max_iterations, patience: BLEND_PATIENCE };
        let result = lm::train(&train, &validation, network.params.clone(), &lm_settings);
        let (network, info) = &mut leaves[i];
        trained_on(network, info, result);
        info.samples = train.len() + validation.len();
        info.val_noise = noise / validation.len().max(1) as f64;
    }
}

/// The blend fit stops after this many iterations without a better validation error: it
/// starts from converged leaves, most of which the band changes little (with the leaves' own
/// 10, the Cornell box's bake spent 10 iterations on each of most of its 88 leaves for
/// nothing).
const BLEND_PATIENCE: u32 = 5;

/// A sample's place in every subset's order: a hash of its object and inputs under the bake's
/// seed. A node's subset is its samples with the lowest keys ([`lowest_keys`]), so a half's subset
/// holds every sample of its parent's that lies inside it, and the nodes of one object
/// together read not many more samples than those of its deepest level do.
fn key(settings: &BakeSettings, s: &Sample) -> u64 {
    let mut hash = Fnv64::default();
    hash.write(&s.object.to_le_bytes());
    s.inputs.iter().for_each(|v| hash.write(&v.to_le_bytes()));
    mix64(hash.0 ^ settings.seed)
}

/// A sample and its [`key`], hashed once for every node of a tree that holds the sample.
#[derive(Clone, Copy)]
struct Keyed<'a> {
    key: u64,
    sample: &'a Sample,
}

impl std::ops::Deref for Keyed<'_> {
    type Target = Sample;
    fn deref(&self) -> &Sample {
        self.sample
    }
}

/// `samples`, each with its key.
fn keyed<'a>(settings: &BakeSettings, samples: &[&'a Sample]) -> Vec<Keyed<'a>> {
    samples.iter().map(|&sample| Keyed { key: key(settings, sample), sample }).collect()
}

/// The samples a network learns from: of samples whose [`key`]s are `keys`, the positions of
/// the `max_samples_per_network` with the lowest, in key order: a deterministic random subset.
fn lowest_keys(settings: &BakeSettings, keys: impl Iterator<Item = u64>) -> Vec<usize> {
    let mut order: Vec<(u64, usize)> = keys.enumerate().map(|(i, k)| (k, i)).collect();
    order.sort_unstable();
    order.truncate(settings.max_samples_per_network);
    order.into_iter().map(|(_, i)| i).collect()
}

/// Which of a subset's samples, whose [`key`]s are `keys`, validate rather than train: a
/// `validation_fraction` of all samples, picked by the low bits of their key, so that a sample
/// validates in every network that holds it or in none, and no half validates on what its
/// parent trained on. At least one does (the first).
fn validation_flags(settings: &BakeSettings, keys: impl Iterator<Item = u64>) -> Vec<bool> {
    let low_bits = |k: u64| (k & 0xff_ffff) as f32 / (1u32 << 24) as f32;
    let mut flags: Vec<bool> = keys.map(|k| low_bits(k) < settings.validation_fraction).collect();
    if !flags.contains(&true) {
        if let Some(first) = flags.first_mut() {
            *first = true;
        }
    }
    flags
}

/// Which of `object`'s `samples` (in [`train_tree`]'s order) any tree that [`train_tree`] can
/// grow from them reads the targets of: the subsets of every node of the complete tree, down
/// to the bake's split depth, and of the blend fit of every node that could be a leaf. Only
/// the samples' positions decide it, so the bake traces paths for these samples alone.
pub fn targets_read(scene: &Scene, settings: &BakeSettings, object: u32, samples: &[&Sample]) -> Vec<bool> {
    let mut read = vec![false; samples.len()];
    let bounds = scene.objects[object as usize].bounds();
    let samples = keyed(settings, samples);
    let all: Vec<usize> = (0..samples.len()).collect();
    let mut nodes = vec![(Node::root(scene, object), all)];
    while let Some((node, within)) = nodes.pop() {
        for i in lowest_keys(settings, within.iter().map(|&i| samples[i].key)) {
            read[within[i]] = true;
        }
        if !node.region.is_whole() && settings.blend_band > 0.0 {
            // `fit_blend`'s samples: those of the whole object inside the leaf's blend box.
            let blend = node.region.blend_box(bounds.min, bounds.max, settings.blend_band);
            let near: Vec<usize> = (0..samples.len()).filter(|&i| blend.weight(position(&samples[i])) > 0.0).collect();
            for i in lowest_keys(settings, near.iter().map(|&i| samples[i].key)) {
                read[near[i]] = true;
            }
        }
        if (node.region.0.len() as u32) < settings.split_depth {
            let halves = node.children().map(|child| {
                let b = child.sample_box();
                let inside: Vec<usize> =
                    within.iter().copied().filter(|&i| b.contains(position(&samples[i]))).collect();
                (child, inside)
            });
            if halves.iter().all(|(_, inside)| inside.len() >= settings.min_samples) {
                nodes.extend(halves);
            }
        }
    }
    read
}

/// What one tree learns: an object's component, in a bake of `scene` with `settings`.
#[derive(Clone, Copy)]
struct Tree<'a> {
    scene: &'a Scene,
    settings: &'a BakeSettings,
    object: u32,
    component: Component,
}

/// A trained network, its record, what of its validation error is its own (above its
/// targets' noise), relative to the mean square of its targets (what decides a split), and the
/// data it learned from, to train it further if it becomes a leaf.
struct Trained {
    network: Network,
    info: NetworkInfo,
    excess: f64,
    data: NetworkData,
    converged: bool,
}

/// Iterations of a network that may still be split: a share of the bake's `max_iterations`.
/// It only decides the split and starts its halves, which train on from it; a node that is
/// not split trains on to the full count ([`finish`]). On the Cornell box's depth-3 trees,
/// training the inner nodes to the full count was more than half of a bake's training time.
fn inner_iterations(settings: &BakeSettings) -> u32 {
    settings.max_iterations.div_ceil(4)
}

/// The iterations `node`'s network gets before the split is decided: all of them where it
/// cannot be split.
fn budget(settings: &BakeSettings, node: &Node) -> u32 {
    if node.region.0.len() as u32 >= settings.split_depth {
        settings.max_iterations
    } else {
        inner_iterations(settings)
    }
}

/// `trained` as a leaf: trained on, from where it is, to the bake's `max_iterations` in all,
/// unless it has already converged.
fn finish(tree: Tree, trained: Trained) -> (Network, NetworkInfo) {
    let Trained { mut network, mut info, data, converged, .. } = trained;
    let left = tree.settings.max_iterations.saturating_sub(info.iterations);
    if converged || left == 0 {
        return (network, info);
    }
    let settings = LmSettings { max_iterations: left, patience: PATIENCE };
    let result = lm::train(&data.train, &data.validation, network.params.clone(), &settings);
    trained_on(&mut network, &mut info, result);
    (network, info)
}

/// `network` after more Levenberg–Marquardt iterations: their parameters, and its record's
/// errors (in radiance units) and iteration count.
fn trained_on(network: &mut Network, info: &mut NetworkInfo, result: lm::LmResult) {
    let scale2 = f64::from(network.output_scale) * f64::from(network.output_scale);
    network.params = result.params;
    info.train_mse = result.train_mse * scale2;
    info.val_mse = result.val_mse * scale2;
    info.iterations += result.iterations;
}

/// A network's training stops after this many iterations without a better validation error.
pub const PATIENCE: u32 = 10;

/// The leaves under `node`, whose network is `trained`: the node itself, or its two halves,
/// each grown in turn. A node is split while the tree may grow, its network's error is above
/// its targets' noise, each half has `min_samples`, and the halves agree where they meet
/// ([`MAX_SEAM`]).
fn grow(tree: Tree, node: Node, samples: &[Keyed], trained: Trained) -> Vec<(Network, NetworkInfo)> {
    let depth = node.region.0.len() as u32;
    if depth >= tree.settings.split_depth || trained.excess <= 0.0 {
        return vec![finish(tree, trained)];
    }
    let halves = node.children().map(|child| {
        let b = child.sample_box();
        let inside: Vec<Keyed> = samples.iter().copied().filter(|s| b.contains(position(s))).collect();
        (child, inside)
    });
    if halves.iter().any(|(_, inside)| inside.len() < tree.settings.min_samples) {
        return vec![finish(tree, trained)];
    }
    let [(low, low_samples), (high, high_samples)] = halves;
    let half = |node: &Node, samples: &[Keyed]| train_network(tree, node, samples, Some(&trained.network));
    let (low_trained, high_trained) = rayon::join(|| half(&low, &low_samples), || half(&high, &high_samples));
    // Where the halves meet, both learned the same samples; halves that disagree there would
    // trade a smooth error for a visible seam (a mirror's halves do: their reflections differ).
    let (low_box, high_box) = (low.sample_box(), high.sample_box());
    let shared =
        samples.iter().map(|s| s.sample).filter(|s| low_box.contains(position(s)) && high_box.contains(position(s)));
    let seam = disagreement(&low_trained.network, &high_trained.network, shared, trained.network.output_scale);
    if seam > MAX_SEAM {
        return vec![finish(tree, trained)];
    }
    let (mut leaves, high) =
        rayon::join(|| grow(tree, low, &low_samples, low_trained), || grow(tree, high, &high_samples, high_trained));
    leaves.extend(high);
    leaves
}

/// The mean squared difference of networks `a` and `b` on `samples`, per channel, relative to
/// `scale`².
fn disagreement<'a>(a: &Network, b: &Network, samples: impl Iterator<Item = &'a Sample>, scale: f32) -> f64 {
    let (mut sum, mut count) = (0.0f64, 0usize);
    for s in samples {
        let d = a.evaluate(&s.inputs) - b.evaluate(&s.inputs);
        sum += f64::from(d.length_squared()) / OUTPUTS as f64;
        count += 1;
    }
    sum / count.max(1) as f64 / (f64::from(scale) * f64::from(scale))
}

fn position(s: &Sample) -> Vec3 {
    Vec3::new(s.inputs[0], s.inputs[1], s.inputs[2])
}

/// One network on `node`'s samples, for [`budget`] iterations.
///
/// A half of a split starts from its `parent`'s network (the same input ranges, the output
/// rescaled to its own targets), so that Levenberg–Marquardt, which keeps the parameters with
/// the best validation error, refines the parent where the half's samples ask for it and
/// elsewhere stays near the parent, which learned from all of the object's samples.
fn train_network(tree: Tree, node: &Node, samples: &[Keyed], parent: Option<&Network>) -> Trained {
    let Tree { scene, settings, object, component } = tree;
    let data = keyed_network_data(scene, settings, object, component, samples);
    let rms = data.output_scale;
    let initial = match parent {
        Some(parent) => {
            let mut p = parent.params.clone();
            p[W3..].iter_mut().for_each(|v| *v *= parent.output_scale / rms);
            p
        }
        None => {
            let mut mean = [0.0f32; OUTPUTS];
            for t in &data.train.targets {
                (0..OUTPUTS).for_each(|c| mean[c] += t[c] / data.train.len() as f32);
            }
            initial_parameters(mix64(settings.seed ^ (u64::from(object) << 8) ^ component as u64), mean)
        }
    };
    let lm_settings = LmSettings { max_iterations: budget(settings, node), patience: PATIENCE };
    let result = lm::train(&data.train, &data.validation, initial, &lm_settings);
    // Errors in radiance units.
    let scale2 = f64::from(rms) * f64::from(rms);
    let info = NetworkInfo {
        object: scene.objects[object as usize].name.clone(),
        component,
        region: node.region.clone(),
        input_min: data.input_min.to_vec(),
        input_max: data.input_max.to_vec(),
        target_transform: "scale".into(),
        output_scale: rms,
        samples: data.train.len() + data.validation.len(),
        train_mse: result.train_mse * scale2,
        val_mse: result.val_mse * scale2,
        val_noise: data.validation_noise * scale2,
        iterations: result.iterations,
    };
    let network =
        info.network(result.params, settings.blend_band).expect("13 input ranges and one network's parameters");
    Trained { network, info, excess: result.val_mse - data.validation_noise, data, converged: result.converged }
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use super::*;
    use crate::bake::{BakeSettings, Quality};
    use crate::network::raw_inputs;
    use crate::trace::sampling::Rng;

    /// The Cornell box and its back wall, a plane whose longest side (x) the first cut halves.
    fn back_wall() -> (Scene, u32) {
        let scene = Scene::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/cornell-box")).unwrap();
        let wall = scene.object_by_name("BackWall").unwrap().id;
        (scene, wall)
    }

    /// `n` direct-light samples spread uniformly over `object`'s box: a ramp along x that any
    /// network fits ([`samples_of`]), plus Gaussian noise of standard deviation `sigma` per channel, each sample
    /// declaring the variance `declared` as its noise.
    fn samples(scene: &Scene, object: u32, n: usize, sigma: f32, declared: f32) -> Vec<Sample> {
        samples_of(scene, object, n, sigma, declared, |p, _| 0.3 + 0.5 * p.x)
    }

    /// `n` direct-light samples of `light(p, l)`, where `p` is the position and `l` the
    /// light's, each in [0, 1]³ over `object`'s box and the light's box.
    fn samples_of(
        scene: &Scene,
        object: u32,
        n: usize,
        sigma: f32,
        declared: f32,
        light_at: impl Fn(Vec3, Vec3) -> f32,
    ) -> Vec<Sample> {
        let Aabb { min, max } = scene.objects[object as usize].bounds();
        let light = scene.moving_light.as_ref().unwrap().bounds;
        let mut rng = Rng::new(17, 0);
        let mut gaussian = || {
            let (u, v) = (rng.next_f32().max(1e-7), rng.next_f32());
            (-2.0 * u.ln()).sqrt() * (std::f32::consts::TAU * v).cos()
        };
        (0..n)
            .map(|i| {
                let t = |k: usize| ((i * 7919 + k * 104_729) % n) as f32 / n as f32;
                let p = min + (max - min) * Vec3::new((i as f32 + 0.5) / n as f32, t(1), t(2));
                let l = light.min + (light.max - light.min) * Vec3::new(t(3), t(4), t(5));
                let value = light_at((p - min) / (max - min), (l - light.min) / (light.max - light.min));
                Sample {
                    object,
                    inputs: raw_inputs(p, Vec3::new(0.0, 0.0, -1.0), l, Vec3::new(0.0, 0.0, -1.0), 1.0),
                    direct: [0; 3].map(|_| value + sigma * gaussian()),
                    indirect: [value; 3],
                    noise: [declared, 0.0],
                }
            })
            .collect()
    }

    fn settings(scene: &Scene) -> BakeSettings {
        let mut s = BakeSettings::new(Quality::Test, 1, scene);
        s.max_iterations = 30;
        s.split_depth = 1;
        s
    }

    fn leaves(scene: &Scene, settings: &BakeSettings, object: u32, samples: &[Sample]) -> Vec<(Network, NetworkInfo)> {
        let refs: Vec<&Sample> = samples.iter().collect();
        train_tree(scene, settings, object, Component::Direct, &refs)
    }

    /// A tree trains to the same networks when the targets of the samples that
    /// [`targets_read`] leaves out are NaN, which would poison any network that learned from
    /// them: a depth-2 tree with blended leaves, on subsets of at most 300 of each node's samples.
    #[test]
    fn training_reads_no_target_but_those_selected() {
        let (scene, wall) = back_wall();
        let mut settings = settings(&scene);
        settings.split_depth = 2;
        settings.max_samples_per_network = 300;
        settings.min_samples = 100;
        let sigma = 0.05f32;
        let full = samples_of(&scene, wall, 5000, sigma, 0.1 * sigma * sigma, |p, l| 0.3 + 0.5 * p.x * p.y + 0.2 * l.z);
        let refs: Vec<&Sample> = full.iter().collect();
        let read = targets_read(&scene, &settings, wall, &refs);
        let unread = read.iter().filter(|&&r| !r).count();
        assert!(unread > full.len() / 10, "only {unread} of {} samples left out", full.len());
        let selected: Vec<Sample> = full
            .iter()
            .zip(&read)
            .map(|(s, &read)| if read { *s } else { Sample { direct: [f32::NAN; 3], ..*s } })
            .collect();
        let want = leaves(&scene, &settings, wall, &full);
        assert!(want.len() > 2, "the tree splits twice: {} leaves", want.len());
        let got = leaves(&scene, &settings, wall, &selected);
        assert_eq!(got.len(), want.len());
        for ((g, gi), (w, wi)) in got.iter().zip(&want) {
            assert_eq!((&g.params, gi), (&w.params, wi));
        }
    }

    /// A node is split exactly when its network's error is above the noise its samples
    /// declare: the same noisy ramp stays whole when the samples declare more noise than it
    /// has, and is split when they declare less.
    #[test]
    fn nodes_split_only_where_the_error_is_above_the_noise() {
        let (scene, wall) = back_wall();
        let sigma = 0.1f32;
        let settings = settings(&scene);
        let declared_high = samples(&scene, wall, 1500, sigma, 1.5 * sigma * sigma);
        assert_eq!(leaves(&scene, &settings, wall, &declared_high).len(), 1, "noise declared above the error");
        let declared_low = samples(&scene, wall, 1500, sigma, 0.5 * sigma * sigma);
        assert_eq!(leaves(&scene, &settings, wall, &declared_low).len(), 2, "noise declared below the error");
    }

    /// A split whose halves disagree where they meet is not made, though the noise rule and
    /// `min_samples` allow it: stripes across the wall, finer than a 20-10 network can hold,
    /// which each half approximates its own way (their mean squared difference in the shared
    /// band is 0.11 of the targets' mean square, against [`MAX_SEAM`]'s 0.03).
    #[test]
    fn nodes_split_only_where_the_halves_agree() {
        let (scene, wall) = back_wall();
        let settings = settings(&scene);
        let stripes = samples_of(&scene, wall, 3000, 0.01, 1e-4, |p, l| 0.5 + 0.4 * (30.0 * p.x + 10.0 * l.x).sin());
        let whole = leaves(&scene, &settings, wall, &stripes);
        assert_eq!(whole.len(), 1, "halves that disagree");
        let info = &whole[0].1;
        assert!(info.val_mse > 10.0 * info.val_noise, "the noise rule asks for a split: {info:?}");
        assert!(stripes.len() / 2 > settings.min_samples, "each half has enough samples");
    }

    /// A split that would leave a half with fewer than `min_samples` samples is not made.
    #[test]
    fn nodes_split_only_into_halves_with_enough_samples() {
        let (scene, wall) = back_wall();
        let mut settings = settings(&scene);
        let sigma = 0.1f32;
        let noisy = samples(&scene, wall, 1500, sigma, 0.5 * sigma * sigma);
        // Each half holds 55% of the samples: its half and a band of 10% of its size.
        settings.min_samples = 800;
        assert_eq!(leaves(&scene, &settings, wall, &noisy).len(), 2);
        settings.min_samples = 850;
        assert_eq!(leaves(&scene, &settings, wall, &noisy).len(), 1);
    }

    /// Each half learns from its own half of the object and a band across the cut 10% of the
    /// half's size deep, so the halves' sample sets overlap.
    #[test]
    fn halves_learn_from_a_band_across_the_cut() {
        let (scene, wall) = back_wall();
        let mut settings = settings(&scene);
        settings.blend_band = 0.0; // no blend fit, which draws its own samples
        let sigma = 0.1f32;
        let noisy = samples(&scene, wall, 1500, sigma, 0.5 * sigma * sigma);
        let halves = leaves(&scene, &settings, wall, &noisy);
        assert_eq!(halves.len(), 2);
        let Aabb { min, max } = scene.objects[wall as usize].bounds();
        let at = 0.5 * (min.x + max.x);
        let band = 0.1 * (at - min.x);
        for (network, info) in &halves {
            let cut = info.region.0[0];
            assert_eq!((cut.axis, cut.at), (0, at), "{:?}", network.region);
            let inside = noisy
                .iter()
                .filter(|s| if cut.below { s.inputs[0] <= at + band } else { s.inputs[0] >= at - band })
                .count();
            assert_eq!(info.samples, inside, "below: {}", cut.below);
            assert!(inside > 1500 / 2 + 50, "{inside} samples");
        }
    }
}
