//! Training samples: Latin-hypercube configurations of (light position × viewpoint), rays
//! over the sphere from each viewpoint, and at every first hit on a non-emissive surface the
//! network inputs with direct and indirect radiance, each averaged over K paths.

use glam::Vec3;

use crate::network::{raw_inputs, reflectance, Component, INPUTS};
use crate::scene::{Aabb, Scene};
use crate::trace::integrator::{radiance_leaving, FirstVertex};
use crate::trace::sampling::{mix64, uniform_sphere, Rng};
use crate::trace::stratified::stratified_vertex_samples;
use crate::trace::{Geometry, Radiance, TraceSettings, World};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Configuration {
    pub light: Vec3,
    pub viewpoint: Vec3,
}

/// One training sample: raw network inputs and the two targets.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    pub object: u32,
    pub inputs: [f32; INPUTS],
    pub direct: [f32; 3],
    pub indirect: [f32; 3],
    /// The variance of each target's path average (direct, indirect; mean over the channels),
    /// estimated from the spread of its independent groups of paths (`NOISE_GROUPS`): the
    /// part of a network's squared error on this sample that no network can remove.
    pub noise: [f32; 2],
}

impl Sample {
    /// The radiance the `component` network learns from this sample.
    pub fn target(&self, component: Component) -> [f32; 3] {
        match component {
            Component::Direct => self.direct,
            Component::Indirect => self.indirect,
        }
    }

    /// The estimated variance of [`Sample::target`] (see `noise`).
    pub fn noise(&self, component: Component) -> f32 {
        self.noise[component as usize]
    }
}

/// `n` configurations stratified in each of the six dimensions (light x, y, z and viewpoint
/// x, y, z): a Latin hypercube, with the strata of each dimension shuffled independently.
pub fn latin_hypercube(n: usize, light: &Aabb, camera: &Aabb, seed: u64) -> Vec<Configuration> {
    let mut rng = Rng::new(seed, 0x4c48_5300);
    let mut columns: Vec<Vec<f32>> = Vec::with_capacity(6);
    for _ in 0..6 {
        let mut strata: Vec<usize> = (0..n).collect();
        rng.shuffle(&mut strata);
        columns.push(strata.iter().map(|&s| (s as f32 + rng.next_f32()) / n as f32).collect());
    }
    (0..n)
        .map(|i| Configuration {
            light: light.lerp(Vec3::new(columns[0][i], columns[1][i], columns[2][i])),
            viewpoint: camera.lerp(Vec3::new(columns[3][i], columns[4][i], columns[5][i])),
        })
        .collect()
}

/// Independent groups of paths per sample, each with its own stratified first vertex: the
/// spread of their means estimates the noise of the sample's targets ([`Sample::noise`]).
/// Few groups stratify best (each is a set of `paths / NOISE_GROUPS` points), and three
/// degrees of freedom per sample are enough where the noise is used: averaged over a
/// network's validation samples.
const NOISE_GROUPS: u32 = 4;

/// Separates the random streams of the stratified first vertices from the paths' own.
const STRATA_STREAM: u64 = 0x5742_a7a0_0000_0001;

/// Where a configuration's rays go.
#[derive(Clone, Copy)]
pub enum Aim<'a> {
    /// Uniformly over the sphere around the viewpoint: every sample where a ray first meets a
    /// surface.
    Sphere,
    /// At points drawn on one object by area, for objects that rays over the sphere rarely
    /// hit: samples only where that object is what the ray meets first.
    At(&'a SurfacePoints),
}

/// Samples of one configuration from `rays` rays aimed as `aim` says; the same arguments
/// always give the same samples.
#[allow(clippy::too_many_arguments)]
pub fn sample_configuration(
    scene: &Scene,
    geometry: &Geometry,
    config: &Configuration,
    aim: Aim,
    rays: u32,
    paths_per_sample: u32,
    trace: &TraceSettings,
    seed: u64,
) -> Vec<Sample> {
    let rays = sample_rays(scene, geometry, config, aim, 0..rays, paths_per_sample, trace, seed);
    rays.into_iter().map(|(_, sample)| sample).collect()
}

/// The samples along the rays numbered `rays` of those [`sample_configuration`] casts, each
/// with its ray's number. A ray's sample is the same whichever other rays are cast with it.
/// With `paths_per_sample` 0 a sample is only located: its object and inputs, with targets
/// and noise 0.
#[allow(clippy::too_many_arguments)]
pub fn sample_rays(
    scene: &Scene,
    geometry: &Geometry,
    config: &Configuration,
    aim: Aim,
    rays: impl Iterator<Item = u32>,
    paths_per_sample: u32,
    trace: &TraceSettings,
    seed: u64,
) -> Vec<(u32, Sample)> {
    let world = World::new(scene, geometry, Some(config.light));
    rays.filter_map(|ray| {
        let mut rng = Rng::new(seed, u64::from(ray));
        let (dir, only) = match aim {
            Aim::Sphere => (uniform_sphere(rng.next_vec2()), None),
            Aim::At(target) => ((target.point(&mut rng)? - config.viewpoint).normalize_or_zero(), Some(target.object)),
        };
        if dir == Vec3::ZERO {
            return None;
        }
        Some((ray, sample_along(&world, config, dir, only, paths_per_sample, trace, seed, ray)?))
    })
    .collect()
}

/// Points on an object's surface, drawn uniformly by area.
pub struct SurfacePoints {
    object: u32,
    /// Corners of the object's triangles, and their cumulative areas.
    triangles: Vec<[Vec3; 3]>,
    cumulative: Vec<f32>,
}

impl SurfacePoints {
    pub fn new(scene: &Scene, object: u32) -> Self {
        let o = &scene.objects[object as usize];
        let triangles: Vec<[Vec3; 3]> = o.triangles.iter().map(|t| t.map(|i| o.positions[i as usize])).collect();
        let mut total = 0.0;
        let cumulative = triangles
            .iter()
            .map(|[a, b, c]| {
                total += 0.5 * (*b - *a).cross(*c - *a).length();
                total
            })
            .collect();
        SurfacePoints { object, triangles, cumulative }
    }

    pub fn object(&self) -> u32 {
        self.object
    }

    fn point(&self, rng: &mut Rng) -> Option<Vec3> {
        let total = *self.cumulative.last()?;
        let pick = rng.next_f32() * total;
        let i = self.cumulative.partition_point(|&c| c <= pick).min(self.triangles.len() - 1);
        let [a, b, c] = self.triangles[i];
        let (u, v) = (rng.next_f32(), rng.next_f32());
        let (u, v) = if u + v > 1.0 { (1.0 - u, 1.0 - v) } else { (u, v) };
        Some(a + (b - a) * u + (c - a) * v)
    }
}

/// The sample at the first surface along `dir` from the viewpoint, if it is a learnable one
/// (and on `only`, when given): the network inputs, and direct and indirect radiance averaged
/// over `paths` paths.
#[allow(clippy::too_many_arguments)]
fn sample_along(
    world: &World,
    config: &Configuration,
    dir: Vec3,
    only: Option<u32>,
    paths: u32,
    trace: &TraceSettings,
    seed: u64,
    ray: u32,
) -> Option<Sample> {
    let hit = world.intersect(config.viewpoint, dir)?;
    let si = world.interaction(config.viewpoint, dir, hit);
    let material = &world.scene.materials[world.geometry.triangles[hit.triangle as usize].material as usize];
    // Emitters show their emission and mirrors what they reflect: they learn nothing. The
    // inside of a closed one-sided surface is never seen.
    if material.is_plain_emitter()
        || world.geometry.mirrors[si.object as usize].is_some()
        || (!si.front_face && !material.double_sided)
        || only.is_some_and(|o| o != si.object)
    {
        return None;
    }
    // Path `p` is point `p / groups` of group `p % groups`'s stratified set.
    let stream = seed ^ mix64(u64::from(ray) + 1);
    let groups = paths.clamp(1, NOISE_GROUPS) as usize;
    let mut strata_rng = Rng::new(stream, STRATA_STREAM);
    let strata: Vec<_> = (0..groups)
        .map(|g| stratified_vertex_samples((paths as usize + groups - 1 - g) / groups, &mut strata_rng))
        .collect();
    let mut sums = vec![Radiance::default(); groups];
    let vertex = FirstVertex::new(world, &si, -dir, trace);
    for path in 0..paths as usize {
        let mut path_rng = Rng::new(stream, path as u64);
        let first = &strata[path % groups][path / groups];
        sums[path % groups] += radiance_leaving(world, &vertex, Some(first), trace, &mut path_rng);
    }
    let mut total = Radiance::default();
    sums.iter().for_each(|&group| total += group);
    let mean = total.scaled(1.0 / paths.max(1) as f32);
    // The networks learn radiance over the surface's reflectance (`network::reflectance`).
    let r = reflectance(si.bsdf.base_color, si.bsdf.metallic, si.bsdf.specular);
    // The variance of the mean: the spread of the groups' means, which are independent
    // estimates (the paths within a group are not independent of each other), over their
    // number. It assumes groups of equal size; they differ by one path at most.
    let noise = |component: Component| {
        let g = groups as f32;
        let spread: Vec3 = (0..groups)
            .map(|k| {
                let d = part(&sums[k], component) / strata[k].len().max(1) as f32 - part(&mean, component);
                d * d
            })
            .sum();
        let variance = spread / (g * (g - 1.0)).max(1.0);
        (variance / (r * r)).element_sum() / 3.0
    };
    Some(Sample {
        object: si.object,
        inputs: raw_inputs(si.position, -dir, config.light, si.shading_normal, si.roughness),
        direct: (mean.direct / r).to_array(),
        indirect: (mean.indirect / r).to_array(),
        noise: Component::ALL.map(noise),
    })
}

/// The part of `radiance` that `component`'s networks learn.
fn part(radiance: &Radiance, component: Component) -> Vec3 {
    match component {
        Component::Direct => radiance.direct,
        Component::Indirect => radiance.indirect,
    }
}

/// Flat little-endian encoding of samples for shard files: per sample the object id (u32),
/// then 13 inputs, 3 direct, 3 indirect and 2 noise values (f32).
pub fn encode(samples: &[Sample]) -> Vec<u8> {
    let mut out = Vec::with_capacity(samples.len() * SAMPLE_BYTES);
    for s in samples {
        out.extend(s.object.to_le_bytes());
        for v in s.inputs.iter().chain(&s.direct).chain(&s.indirect).chain(&s.noise) {
            out.extend(v.to_le_bytes());
        }
    }
    out
}

pub const SAMPLE_BYTES: usize = 4 * (1 + INPUTS + 8);

/// Inverse of [`encode`]; `None` if the length is not a whole number of samples or a sample
/// names an object past `objects`.
pub fn decode(bytes: &[u8], objects: usize) -> Option<Vec<Sample>> {
    if !bytes.len().is_multiple_of(SAMPLE_BYTES) {
        return None;
    }
    let word = |b: &[u8], i: usize| [b[4 * i], b[4 * i + 1], b[4 * i + 2], b[4 * i + 3]];
    Some(
        bytes
            .chunks_exact(SAMPLE_BYTES)
            .map(|b| {
                let f = |i: usize| f32::from_le_bytes(word(b, i));
                Sample {
                    object: u32::from_le_bytes(word(b, 0)),
                    inputs: std::array::from_fn(|i| f(1 + i)),
                    direct: std::array::from_fn(|i| f(1 + INPUTS + i)),
                    indirect: std::array::from_fn(|i| f(4 + INPUTS + i)),
                    noise: std::array::from_fn(|i| f(7 + INPUTS + i)),
                }
            })
            .collect::<Vec<_>>(),
    )
    .filter(|samples| samples.iter().all(|s| (s.object as usize) < objects))
}

#[cfg(test)]
mod tests {
    use std::path::Path;
    use std::sync::LazyLock;

    use super::*;

    /// Paths per sample in these tests: [`NOISE_GROUPS`] groups of 32 stratified points.
    const PATHS: u32 = 128;
    /// Independent bakes of each point's sample.
    const SEEDS: u64 = 24;

    /// What repeated bakes of one point's sample give, per component, in the units of its
    /// targets.
    struct Repeated {
        /// The mean over the channels of the targets: its mean over the bakes, and its
        /// variance across them.
        mean: f64,
        variance: f64,
        /// The targets' variance across the bakes, channel by channel, averaged over the
        /// channels: what [`Sample::noise`] estimates.
        channel_variance: f64,
        /// The mean of the noise the bakes declared.
        declared: f64,
        /// Paths traced independently of each other, as many as all the bakes traced: the
        /// mean over the channels of their mean, its variance between paths, and the paths'
        /// variance channel by channel, averaged over the channels.
        independent_mean: f64,
        path_variance: f64,
        path_channel_variance: f64,
    }

    /// [`repeated_samples`], computed once for the tests that read it.
    static REPEATED: LazyLock<Vec<[Repeated; 2]>> = LazyLock::new(repeated_samples);

    /// Points on the Cornell box's floor, walls and blocks, seen from one configuration; for
    /// each, [`SEEDS`] samples of [`PATHS`] paths, and as many paths traced independently.
    fn repeated_samples() -> Vec<[Repeated; 2]> {
        let scene = Scene::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/cornell-box")).unwrap();
        let geometry = Geometry::new(&scene);
        let config = Configuration { light: Vec3::new(0.3, 0.5, 0.3), viewpoint: Vec3::new(0.28, 0.3, -0.5) };
        let world = World::new(&scene, &geometry, Some(config.light));
        let trace = TraceSettings { max_depth: 8, rr_depth: Some(5) };
        let mut out = Vec::new();
        for ray in 0..48u32 {
            let at = Vec3::new(0.05 + 0.45 * (ray % 8) as f32 / 7.0, 0.02 + 0.5 * (ray / 8) as f32 / 5.0, 0.55);
            let dir = (at - config.viewpoint).normalize();
            let samples: Vec<Sample> = (0..SEEDS)
                .filter_map(|seed| sample_along(&world, &config, dir, None, PATHS, &trace, seed, ray))
                .collect();
            if samples.len() < SEEDS as usize {
                continue; // the light, or nothing
            }
            let si = world.interaction(config.viewpoint, dir, world.intersect(config.viewpoint, dir).unwrap());
            let r = reflectance(si.bsdf.base_color, si.bsdf.metallic, si.bsdf.specular);
            let vertex = FirstVertex::new(&world, &si, -dir, &trace);
            let independent: Vec<Radiance> = (0..SEEDS * u64::from(PATHS))
                .map(|p| radiance_leaving(&world, &vertex, None, &trace, &mut Rng::new(0x1d ^ u64::from(ray), p)))
                .collect();
            out.push(Component::ALL.map(|c| {
                let n = SEEDS as f64;
                let channel = |s: &Sample, k: usize| f64::from(s.target(c)[k]);
                let channel_mean = |k: usize| samples.iter().map(|s| channel(s, k)).sum::<f64>() / n;
                let variance_of = |value: &dyn Fn(&Sample) -> f64, mean: f64| {
                    samples.iter().map(|s| (value(s) - mean).powi(2)).sum::<f64>() / (n - 1.0)
                };
                let mean = (0..3).map(channel_mean).sum::<f64>() / 3.0;
                let target = |l: &Radiance| part(l, c) / r;
                let m = independent.len() as f64;
                let path_channel = |l: &Radiance, k: usize| f64::from(target(l)[k]);
                let path_channel_mean = |k: usize| independent.iter().map(|l| path_channel(l, k)).sum::<f64>() / m;
                let path_variance_of = |value: &dyn Fn(&Radiance) -> f64, mean: f64| {
                    independent.iter().map(|l| (value(l) - mean).powi(2)).sum::<f64>() / (m - 1.0)
                };
                let value = |l: &Radiance| f64::from(target(l).element_sum()) / 3.0;
                let independent_mean = independent.iter().map(value).sum::<f64>() / m;
                Repeated {
                    mean,
                    variance: variance_of(&|s| (0..3).map(|k| channel(s, k)).sum::<f64>() / 3.0, mean),
                    channel_variance: (0..3).map(|k| variance_of(&|s| channel(s, k), channel_mean(k))).sum::<f64>()
                        / 3.0,
                    declared: samples.iter().map(|s| f64::from(s.noise(c))).sum::<f64>() / n,
                    independent_mean,
                    path_variance: path_variance_of(&value, independent_mean),
                    path_channel_variance: (0..3)
                        .map(|k| path_variance_of(&|l| path_channel(l, k), path_channel_mean(k)))
                        .sum::<f64>()
                        / 3.0,
                }
            }));
        }
        assert!(out.len() > 30, "{} points", out.len());
        out
    }

    /// The noise a sample declares is the variance its targets have from bake to bake,
    /// although its paths are not independent of each other: the spread of its independent
    /// groups' means measures it, where the paths' own spread would count the variance that
    /// stratification removed.
    #[test]
    fn declared_noise_is_the_variance_between_bakes() {
        let points = &*REPEATED;
        for (c, component) in Component::ALL.iter().enumerate() {
            let variance: f64 = points.iter().map(|p| p[c].channel_variance).sum();
            let declared: f64 = points.iter().map(|p| p[c].declared).sum();
            let ratio = declared / variance;
            assert!((0.8..1.25).contains(&ratio), "{component:?}: declared {declared:.3e}, found {variance:.3e}");
        }
    }

    /// Stratified first vertices leave the targets' expectation as it was: each point's mean
    /// over the bakes agrees with independent paths' mean within their noise (chi-square over
    /// the points and components, at the 0.1% level).
    #[test]
    fn stratified_targets_keep_their_expectation() {
        let points = &*REPEATED;
        let (mut chi2, mut dof) = (0.0, 0);
        for p in points.iter().flatten() {
            let variance = (p.variance + p.path_variance / f64::from(PATHS)) / SEEDS as f64;
            if variance > 0.0 {
                chi2 += (p.mean - p.independent_mean).powi(2) / variance;
                dof += 1;
            }
        }
        // The 99.9% quantile of chi-square (Wilson–Hilferty).
        let k = f64::from(dof);
        let limit = k * (1.0 - 2.0 / (9.0 * k) + 3.09 * (2.0 / (9.0 * k)).sqrt()).powi(3);
        assert!(chi2 < limit, "chi-square {chi2:.1} over {dof} degrees of freedom, limit {limit:.1}");
    }

    /// And they vary less from bake to bake than the mean of as many independent paths does.
    #[test]
    fn stratified_targets_are_less_noisy() {
        let points = &*REPEATED;
        for (c, component) in Component::ALL.iter().enumerate() {
            let stratified: f64 = points.iter().map(|p| p[c].channel_variance).sum();
            let independent: f64 = points.iter().map(|p| p[c].path_channel_variance / f64::from(PATHS)).sum();
            assert!(stratified < 0.8 * independent, "{component:?}: {stratified:.3e} against {independent:.3e}");
        }
    }
}
