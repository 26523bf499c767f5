//! Training samples: Latin-hypercube configurations of (light position × viewpoint), rays
//! over the sphere from each viewpoint, and at every first hit on a non-emissive surface the
//! network inputs with direct and indirect radiance, each averaged over K paths.

use glam::Vec3;

use crate::network::{raw_inputs, reflectance, Component, INPUTS};
use crate::scene::{Aabb, Scene};
use crate::trace::integrator::radiance_leaving;
use crate::trace::sampling::{mix64, uniform_sphere, Rng};
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
    /// estimated from the spread of its paths: the part of a network's squared error on this
    /// sample that no network can remove.
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
    let world = World::new(scene, geometry, Some(config.light));
    (0..rays)
        .filter_map(|ray| {
            let mut rng = Rng::new(seed, u64::from(ray));
            let (dir, only) = match aim {
                Aim::Sphere => (uniform_sphere(rng.next_vec2()), None),
                Aim::At(target) => {
                    ((target.point(&mut rng)? - config.viewpoint).normalize_or_zero(), Some(target.object))
                }
            };
            if dir == Vec3::ZERO {
                return None;
            }
            sample_along(&world, config, dir, only, paths_per_sample, trace, seed, ray)
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
    let mut sum = Radiance::default();
    let mut squares = [Vec3::ZERO; 2];
    for path in 0..paths {
        let mut path_rng = Rng::new(seed ^ mix64(u64::from(ray) + 1), u64::from(path));
        let l = radiance_leaving(world, &si, -dir, trace, &mut path_rng);
        squares[0] += l.direct * l.direct;
        squares[1] += l.indirect * l.indirect;
        sum += l;
    }
    let n = paths.max(1) as f32;
    let mean = sum.scaled(1.0 / n);
    // The networks learn radiance over the surface's reflectance (`network::reflectance`).
    let r = reflectance(si.bsdf.base_color, si.bsdf.metallic, si.bsdf.specular);
    // The variance of the mean of n paths: the paths' sample variance over n.
    let noise = |squares: Vec3, mean: Vec3| {
        let variance = (squares / n - mean * mean).max(Vec3::ZERO) * (n / (n - 1.0).max(1.0));
        (variance / (n * r * r)).element_sum() / 3.0
    };
    Some(Sample {
        object: si.object,
        inputs: raw_inputs(si.position, -dir, config.light, si.shading_normal, si.roughness),
        direct: (mean.direct / r).to_array(),
        indirect: (mean.indirect / r).to_array(),
        noise: [noise(squares[0], mean.direct), noise(squares[1], mean.indirect)],
    })
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
