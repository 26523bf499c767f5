//! Baking: training samples from the path tracer, then two networks per object.
//!
//! A bake writes its work to the cache as it goes: sampling in shards of a few
//! configurations, training one checkpoint per finished network, each file keyed by the scene
//! and every setting that shapes it ([`cache`]). A bake killed at any point and started again
//! keeps the finished shards and networks, computes the rest, and ends with a model file
//! byte-identical to an uninterrupted bake with the same seed: every shard and network is a
//! pure function of its key, and the model records no timings.
//!
//! The same property splits a bake across machines ([`BakePart`]): each stage (sampling, aimed
//! sampling, training) runs as disjoint shards that write only their own cache files into a
//! shared folder, and a merge reads them all and writes the model, the same bytes as a bake
//! on one machine.

mod cache;
pub mod lm;
pub mod lock;
mod normal_equations;
pub mod samples;
mod train;

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::time::Instant;

use rayon::prelude::*;
use serde::Serialize;

use crate::hash::Fnv64;
use crate::model::{Metadata, Model, NetworkInfo, Untrained, FORMAT_VERSION, INPUT_NAMES};
use crate::network::{Component, Network, HIDDEN1, HIDDEN2, OUTPUTS};
use crate::scene::{Aabb, BakeOverrides, Scene};
use crate::trace::integrator::non_finite_dropped;
use crate::trace::sampling::mix64;
use crate::trace::{Geometry, TraceSettings};
use glam::Vec3;
use samples::{latin_hypercube, sample_rays, Aim, Sample, SurfacePoints, SAMPLE_BYTES};
use serde::Deserialize;
use train::train_tree;
pub use train::{network_data, NetworkData, PATIENCE};

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Quality {
    /// Seconds; for CI.
    Test,
    /// A few minutes; for trying things.
    Preview,
    /// What ships.
    Final,
}

/// Which networks a bake trains.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Trained {
    /// A direct and an indirect network per object: for every renderer mode.
    #[default]
    Both,
    /// The indirect networks only, for analytic direct light (`--direct analytic`), which
    /// computes direct light instead of learning it: half the training.
    IndirectOnly,
}

impl Trained {
    fn is_both(&self) -> bool {
        *self == Trained::Both
    }

    /// Whether networks of `component` are trained.
    pub fn trains(self, component: Component) -> bool {
        self == Trained::Both || component == Component::Indirect
    }
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BakeSettings {
    pub quality: Quality,
    pub seed: u64,
    pub configurations: u32,
    pub rays_per_configuration: u32,
    /// Paths averaged into each sample's targets. Their noise variance falls as 1/paths, and
    /// training, whose cost is capped by `max_samples_per_network`, costs far more than
    /// tracing: at 32 paths the Cornell box's networks fitted the noise of their targets
    /// (held-out gi FLIP 0.081 against 0.064 at 256 paths, BENCHMARKS.md).
    pub paths_per_sample: u32,
    pub max_depth: u32,
    pub max_iterations: u32,
    /// Networks train on at most this many samples (a random subset of the object's).
    pub max_samples_per_network: usize,
    /// Objects with fewer samples get no network and are reported.
    pub min_samples: usize,
    /// Share of each object's samples held out for validation and early stopping.
    pub validation_fraction: f32,
    /// Configurations per shard file.
    pub shard_configurations: u32,
    /// The deepest an object's kd-tree may grow (0: one network per object and component).
    /// A network is split in two while its validation error is above its targets' noise (there
    /// is error a better fit could remove) and each half would have `min_samples`.
    pub split_depth: u32,
    /// The half-width of the band around each kd-tree cut across which the leaves that meet
    /// there are blended, and fitted together so that their blend matches the targets, as a
    /// share of a leaf's extent along the cut (the model records it:
    /// [`Metadata::blend_band`]). At most the share by which a leaf's samples reach past its
    /// cuts, so that every leaf learned the whole band.
    pub blend_band: f32,
    /// Which networks to train. Written to the model and the cache keys only when not both,
    /// so that bakes of both keep the bytes they had before this setting existed.
    #[serde(skip_serializing_if = "Trained::is_both")]
    pub trained: Trained,
}

impl BakeSettings {
    /// The preset for `quality`, with the scene's overrides applied.
    pub fn new(quality: Quality, seed: u64, scene: &Scene) -> Self {
        let mut s = match quality {
            Quality::Test => BakeSettings {
                quality,
                seed,
                configurations: 16,
                rays_per_configuration: 1500,
                paths_per_sample: 4,
                max_depth: 6,
                max_iterations: 15,
                max_samples_per_network: 1500,
                min_samples: 100,
                validation_fraction: 0.2,
                shard_configurations: 4,
                split_depth: 1,
                blend_band: train::OVERLAP,
                trained: Trained::Both,
            },
            Quality::Preview => BakeSettings {
                quality,
                seed,
                configurations: 96,
                rays_per_configuration: 2000,
                paths_per_sample: 32,
                max_depth: 8,
                max_iterations: 40,
                max_samples_per_network: 8000,
                min_samples: 200,
                validation_fraction: 0.15,
                shard_configurations: 8,
                split_depth: 1,
                blend_band: train::OVERLAP,
                trained: Trained::Both,
            },
            Quality::Final => BakeSettings {
                quality,
                seed,
                configurations: 256,
                rays_per_configuration: 4000,
                paths_per_sample: 256,
                max_depth: 8,
                max_iterations: 60,
                max_samples_per_network: 12000,
                min_samples: 400,
                validation_fraction: 0.15,
                shard_configurations: 8,
                split_depth: 2,
                blend_band: train::OVERLAP,
                trained: Trained::Both,
            },
        };
        let overrides = match quality {
            Quality::Test => &scene.bake.test,
            Quality::Preview => &scene.bake.preview,
            Quality::Final => &scene.bake.final_,
        };
        if let Some(BakeOverrides {
            configurations,
            rays_per_configuration,
            paths_per_sample,
            max_depth,
            max_iterations,
            split_depth,
            max_samples_per_network,
        }) = overrides
        {
            s.configurations = configurations.unwrap_or(s.configurations);
            s.rays_per_configuration = rays_per_configuration.unwrap_or(s.rays_per_configuration);
            s.paths_per_sample = paths_per_sample.unwrap_or(s.paths_per_sample);
            s.max_depth = max_depth.unwrap_or(s.max_depth);
            s.max_iterations = max_iterations.unwrap_or(s.max_iterations);
            s.split_depth = split_depth.unwrap_or(s.split_depth);
            s.max_samples_per_network = max_samples_per_network.map_or(s.max_samples_per_network, |n| n as usize);
        }
        s
    }

    fn trace(&self) -> TraceSettings {
        TraceSettings { max_depth: self.max_depth, rr_depth: Some(5) }
    }
}

/// Where a bake reports progress; called from worker threads.
pub trait BakeProgress: Sync {
    /// `done` of `total` configurations sampled (including resumed ones).
    fn sampled(&self, done: u64, total: u64);
    /// `done` of `total` networks trained.
    fn trained(&self, done: u64, total: u64);
}

#[derive(Debug, thiserror::Error)]
pub enum BakeError {
    #[error(
        "{}: cannot bake without the boxes the light and the viewer move in; write them in {} (README: Scenes), e.g.\n\n\
         [light]\nnode = \"Lamp\"            # the point light or emissive mesh node that moves\n\
         min = [-1.0, 2.0, -1.0]   # metres, world space\nmax = [1.0, 2.5, 1.0]\n\n\
         [camera]\nmin = [-2.0, 1.0, -2.0]\nmax = [2.0, 2.0, 2.0]\n",
        scene.display(), sidecar.display()
    )]
    NoDomains { scene: PathBuf, sidecar: PathBuf },
    #[error("{}: {problem}", path.display())]
    Io { path: PathBuf, problem: String },
    #[error(
        "{}: another bake ({}) is writing this model (it holds {}); let it finish, or give --wait to start when it has",
        model.display(), pid.map_or("process unknown".to_string(), |p| format!("process {p}")), lock.display()
    )]
    Locked { model: PathBuf, lock: PathBuf, pid: Option<u32> },
    #[error("{}: the bake would train no network: {cause}", scene.display())]
    NoNetworks { scene: PathBuf, cause: String },
    #[error(
        "{}: missing; run `rrf bake --stage {stage} --shard I/N` for every I first, with the same scene, seed and quality",
        path.display()
    )]
    MissingStage { path: PathBuf, stage: &'static str },
    #[error(
        "{}: {configurations} configurations × {rays} rays could make {:.1} GiB of samples, more than the {} GiB a bake may hold; lower them in the sidecar's [bake] section",
        scene.display(), *bytes as f64 / GIB, MAX_SAMPLE_BYTES / (1 << 30)
    )]
    TooLarge { scene: PathBuf, configurations: u32, rays: u32, bytes: u64 },
}

const GIB: f64 = (1u64 << 30) as f64;

/// The most sample memory a bake may need (every ray a hit): beyond it, the settings are a
/// mistake rather than a bake.
pub const MAX_SAMPLE_BYTES: u64 = 16 << 30;

/// What a bake (or a part of one) did; a stage's shard fills what it got to.
#[derive(Clone, Debug, Default, Serialize)]
pub struct BakeReport {
    /// Samples found; of them, those whose targets training reads, the only ones traced.
    pub samples: usize,
    pub traced_samples: usize,
    pub paths: u64,
    pub sample_seconds: f64,
    pub train_seconds: f64,
    /// Shards found finished on disk from an earlier, interrupted bake (or earlier stages).
    pub resumed_shards: usize,
    pub shards: usize,
    /// Networks trained or read back; of them, found trained on disk.
    pub networks: usize,
    pub resumed_networks: usize,
    /// Cache files with the right key whose contents did not match their checksum: recomputed.
    pub corrupt_files: usize,
    /// Path contributions this bake's sampling dropped as non-finite (0 in the shipped scenes).
    pub non_finite_dropped: u64,
    /// Objects that rays over the sphere rarely hit, which got rays aimed at them.
    pub aimed_objects: Vec<String>,
}

impl BakeReport {
    /// Counts the shard files of a pass this part computed or resumed (not those it only read).
    fn add_shards(&mut self, pass: &Sampled) {
        self.shards += pass.shards;
        self.resumed_shards += pass.resumed;
    }

    /// Records the sampling's time and dropped contributions, and the sample count so far.
    fn finish_sampling(&mut self, start: Instant, dropped_before: u64, corrupt: &AtomicUsize) {
        self.sample_seconds = start.elapsed().as_secs_f64();
        self.non_finite_dropped = non_finite_dropped() - dropped_before;
        self.corrupt_files = corrupt.load(Ordering::SeqCst);
    }
}

const SHARD_MAGIC: &[u8; 8] = b"RRFSHRD3";
const NETWORK_MAGIC: &[u8; 8] = b"RRFNETW2";

/// The trained networks of one object's component (one per kd-tree leaf) as their checkpoint
/// file holds them (JSON: f32 and f64 round-trip exactly).
#[derive(Serialize, Deserialize)]
struct Checkpoint {
    leaves: Vec<Leaf>,
}

#[derive(Serialize, Deserialize)]
struct Leaf {
    info: NetworkInfo,
    params: Vec<f32>,
}

/// The stages of a bake, in order; each needs every file of the ones before.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Stage {
    /// Rays over the sphere from every configuration's viewpoint.
    Sample,
    /// Rays aimed at the objects the first stage rarely hit.
    Aim,
    /// Two networks per object.
    Train,
}

impl Stage {
    pub fn name(self) -> &'static str {
        match self {
            Stage::Sample => "sample",
            Stage::Aim => "aim",
            Stage::Train => "train",
        }
    }
}

/// How much of a bake one process runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BakePart {
    /// Everything, computing what the cache lacks, then the model.
    Whole,
    /// Shard `index` of `count` of one stage: every `count`-th shard file (or network) from
    /// `index`, read from the cache if there; the earlier stages' files must all be there.
    Stage { stage: Stage, index: u32, count: u32 },
    /// Only the model, from a cache that every stage has filled.
    Merge,
}

/// What a part does with one stage's files.
#[derive(Clone, Copy)]
enum Work {
    /// Read what is there, compute the rest.
    All,
    /// Files `i` with `i % count == index`: read if there, else compute; leave the others.
    Share { index: usize, count: usize },
    /// Read every file; a missing one is an error.
    Read,
}

impl Work {
    fn mine(self, i: usize) -> bool {
        match self {
            Work::Share { index, count } => i % count == index,
            Work::All | Work::Read => true,
        }
    }
}

impl BakePart {
    /// What this part does in `stage`; `None` once its own stage is done.
    fn work(self, stage: Stage) -> Option<Work> {
        match self {
            BakePart::Whole => Some(Work::All),
            BakePart::Merge => Some(Work::Read),
            BakePart::Stage { stage: own, index, count } => match stage.cmp(&own) {
                std::cmp::Ordering::Less => Some(Work::Read),
                std::cmp::Ordering::Equal => Some(Work::Share { index: index as usize, count: count as usize }),
                std::cmp::Ordering::Greater => None,
            },
        }
    }
}

/// Bakes `scene`, keeping sample shards and trained networks in `cache` (created if needed).
pub fn bake(
    scene: &Scene,
    settings: &BakeSettings,
    cache: &Path,
    progress: &dyn BakeProgress,
) -> Result<(Model, BakeReport), BakeError> {
    let (model, report) = bake_part(scene, settings, cache, progress, BakePart::Whole)?;
    Ok((model.expect("a whole bake ends with a model"), report))
}

/// Runs `part` of a bake of `scene` on `cache`: the model for [`BakePart::Whole`] and
/// [`BakePart::Merge`], `None` for a stage's shard, whose work is its cache files.
pub fn bake_part(
    scene: &Scene,
    settings: &BakeSettings,
    cache: &Path,
    progress: &dyn BakeProgress,
    part: BakePart,
) -> Result<(Option<Model>, BakeReport), BakeError> {
    let (Some(light), Some(camera)) = (&scene.moving_light, &scene.camera_box) else {
        return Err(BakeError::NoDomains { scene: scene.gltf_path.clone(), sidecar: scene.sidecar_file() });
    };
    let bytes = u64::from(settings.configurations) * u64::from(settings.rays_per_configuration) * SAMPLE_BYTES as u64;
    if bytes > MAX_SAMPLE_BYTES {
        return Err(BakeError::TooLarge {
            scene: scene.gltf_path.clone(),
            configurations: settings.configurations,
            rays: settings.rays_per_configuration,
            bytes,
        });
    }
    std::fs::create_dir_all(cache)
        .map_err(|e| BakeError::Io { path: cache.to_path_buf(), problem: format!("cannot create: {e}") })?;
    let geometry = Geometry::new(scene);
    let configs = latin_hypercube(settings.configurations as usize, &light.bounds, camera, settings.seed);

    // Where the samples are: rays over the sphere from every configuration's viewpoint, then
    // rays aimed at the objects that those rarely hit, located without paths.
    let start = Instant::now();
    let trace = settings.trace();
    let sphere_seed = |i: usize| mix64(settings.seed ^ mix64(i as u64 + 1));
    let sphere_rays = |i: usize, rays: &mut dyn Iterator<Item = u32>, paths: u32| {
        sample_rays(scene, &geometry, &configs[i], Aim::Sphere, rays, paths, &trace, sphere_seed(i))
    };
    let rays = settings.rays_per_configuration;
    let sphere_points: Vec<Vec<(u32, Sample)>> =
        (0..configs.len()).into_par_iter().map(|i| sphere_rays(i, &mut (0..rays), 0)).collect();
    let mut counts = vec![0usize; scene.objects.len()];
    sphere_points.iter().flatten().for_each(|(_, s)| counts[s.object as usize] += 1);
    let aimed: Vec<SurfacePoints> = scene
        .objects
        .iter()
        .filter(|o| learns(scene, o.id) && counts[o.id as usize] < AIM_BELOW * settings.min_samples)
        .map(|o| SurfacePoints::new(scene, o.id))
        .collect();
    let aimed_rays = (AIMED_RAYS * settings.min_samples).div_ceil(configs.len()) as u32;
    // A configuration's aimed rays: those at each aimed object in turn, numbered by object
    // (`target`) and ray.
    let aimed_samples = |i: usize, rays: &mut dyn Iterator<Item = (usize, u32)>, paths: u32| {
        let seed = mix64(settings.seed ^ mix64(i as u64 + 1) ^ AIMED_STREAM);
        let rays: Vec<(usize, u32)> = rays.collect();
        let mut samples = Vec::new();
        for (target, t) in aimed.iter().enumerate() {
            let seed = mix64(seed ^ u64::from(t.object()));
            let mine = rays.iter().filter(|(of, _)| *of == target).map(|&(_, ray)| ray);
            let found = sample_rays(scene, &geometry, &configs[i], Aim::At(t), mine, paths, &trace, seed);
            samples.extend(found.into_iter().map(|(ray, s)| ((target, ray), s)));
        }
        samples
    };
    let aimed_points: Vec<Vec<((usize, u32), Sample)>> = (0..configs.len())
        .into_par_iter()
        .map(|i| {
            let mut every = (0..aimed.len()).flat_map(|target| (0..aimed_rays).map(move |ray| (target, ray)));
            aimed_samples(i, &mut every, 0)
        })
        .collect();

    // The samples whose targets training reads: paths are traced for these alone.
    let points: Vec<Sample> =
        sphere_points.iter().flatten().map(|(_, s)| *s).chain(aimed_points.iter().flatten().map(|(_, s)| *s)).collect();
    let read = samples_read(scene, settings, &points);
    // Each configuration's rays to trace, taking `read` in order.
    fn selected<T>(rays: Vec<(T, Sample)>, read: &mut impl Iterator<Item = bool>) -> Vec<T> {
        rays.into_iter().filter(|_| read.next() == Some(true)).map(|(ray, _)| ray).collect()
    }
    let mut flags = read.iter().copied();
    let sphere_selected: Vec<Vec<u32>> = sphere_points.into_iter().map(|c| selected(c, &mut flags)).collect();
    let aimed_selected: Vec<Vec<(usize, u32)>> = aimed_points.into_iter().map(|c| selected(c, &mut flags)).collect();

    // Tracing, shard by shard.
    let dropped_before = non_finite_dropped();
    let corrupt = AtomicUsize::new(0);
    let settings_json = serde_json::to_string(&SamplingKey::from(settings)).expect("settings serialise");
    let shards = Shards {
        cache,
        objects: scene.objects.len(),
        key: cache_key(scene, &settings_json).0,
        shard_size: settings.shard_configurations.max(1) as usize,
        count: configs.len(),
        corrupt: &corrupt,
    };
    let done = AtomicU64::new(0);
    let sampled = |n: usize| {
        let d = done.fetch_add(n as u64, Ordering::SeqCst) + n as u64;
        progress.sampled(d, configs.len() as u64);
    };
    let mut report = BakeReport::default();
    let sample_work = part.work(Stage::Sample).expect("every part reads the first stage");
    let paths = settings.paths_per_sample;
    let sphere_key = selection_key(sphere_selected.iter().map(|c| c.iter().map(|&ray| (0, ray))));
    let sphere = shards.run("shard", &sphere_key, Stage::Sample, sample_work, &sampled, |i| {
        sphere_rays(i, &mut sphere_selected[i].iter().copied(), paths).into_iter().map(|(_, s)| s).collect()
    })?;
    if !matches!(sample_work, Work::Read) {
        report.add_shards(&sphere);
    }
    let Some(aim_work) = part.work(Stage::Aim) else {
        report.finish_sampling(start, dropped_before, &corrupt);
        return Ok((None, report));
    };
    let mut aimed_key: Vec<u8> = aimed.iter().flat_map(|t| t.object().to_le_bytes()).collect();
    aimed_key.extend(selection_key(aimed_selected.iter().map(|c| c.iter().copied())));
    let extra = match aimed.is_empty() {
        true => Sampled::default(),
        false => shards.run("aimed", &aimed_key, Stage::Aim, aim_work, &|_| {}, |i| {
            let found = aimed_samples(i, &mut aimed_selected[i].iter().copied(), paths);
            found.into_iter().map(|(_, s)| s).collect()
        })?,
    };
    if !matches!(aim_work, Work::Read) {
        report.add_shards(&extra);
    }
    report.aimed_objects = aimed.iter().map(|t| scene.objects[t.object() as usize].name.clone()).collect();
    report.finish_sampling(start, dropped_before, &corrupt);
    let Some(train_work) = part.work(Stage::Train) else {
        return Ok((None, report));
    };
    let mut traced = sphere.samples.into_iter().chain(extra.samples);
    let all: Vec<Sample> = points
        .iter()
        .zip(&read)
        .map(|(point, &read)| match read {
            true => traced.next().expect("a traced sample for every one read"),
            // Never read: NaN would poison any network that learned from it.
            false => Sample { direct: [f32::NAN; 3], indirect: [f32::NAN; 3], ..*point },
        })
        .collect();
    report.samples = all.len();
    report.traced_samples = read.iter().filter(|&&r| r).count();
    report.paths = report.traced_samples as u64 * u64::from(settings.paths_per_sample);

    // Training: two networks per object that has samples (one with `Trained::IndirectOnly`).
    let start = Instant::now();
    let lent = lend_samples(scene, settings, &all);
    let TrainingPlan { by_object, jobs, untrained, borrowed } = plan_training(scene, settings, &all, &lent)?;
    let mine: Vec<(u32, Component)> =
        jobs.iter().enumerate().filter(|(i, _)| train_work.mine(*i)).map(|(_, &job)| job).collect();
    let trainer = Trainer { scene, settings, cache, progress, work: train_work, corrupt: &corrupt };
    let (networks, resumed_networks) = trainer.train(&mine, &by_object)?;
    report.train_seconds = start.elapsed().as_secs_f64();
    report.resumed_networks = resumed_networks;
    report.networks = networks.len();
    report.corrupt_files = corrupt.into_inner();
    if matches!(train_work, Work::Share { .. }) {
        return Ok((None, report));
    }

    let metadata = Metadata {
        format_version: FORMAT_VERSION,
        scene: scene.name.clone(),
        scene_hash: format!("{:016x}", scene.content_hash),
        inputs: INPUT_NAMES.iter().map(|s| s.to_string()).collect(),
        layers: vec![HIDDEN1, HIDDEN2, OUTPUTS],
        activation: "tanh".into(),
        networks: networks.iter().map(|(_, info)| info.clone()).collect(),
        untrained,
        borrowed,
        bake: serde_json::to_value(settings).expect("settings serialise"),
        blend_band: settings.blend_band,
        checksum: String::new(),
    };
    let model = Model { metadata, networks: networks.into_iter().map(|(n, _)| n).collect() };
    Ok((Some(model), report))
}

/// Which networks a bake trains, and on which samples.
struct TrainingPlan<'a> {
    /// Per object, its samples, and those it borrows from its neighbours.
    by_object: Vec<Vec<&'a Sample>>,
    /// (object, component) of every network to train, in a fixed order.
    jobs: Vec<(u32, Component)>,
    untrained: Vec<Untrained>,
    borrowed: Vec<Untrained>,
}

/// Per object, the samples it borrows from its neighbours (see [`borrow_samples`]) if it
/// learns and `all` holds fewer than `min_samples` of its own.
fn lend_samples(scene: &Scene, settings: &BakeSettings, all: &[Sample]) -> Vec<Option<Lent>> {
    let mut counts = vec![0usize; scene.objects.len()];
    all.iter().for_each(|s| counts[s.object as usize] += 1);
    let short = |id: u32| learns(scene, id) && counts[id as usize] < settings.min_samples;
    scene
        .objects
        .iter()
        .map(|o| short(o.id).then(|| borrow_samples(scene, all, o.id, settings.min_samples)).flatten())
        .collect()
}

/// The networks to train from `all` the samples: both components (or what
/// `settings.trained` keeps) of every object that learns and has `min_samples`, with the
/// samples `lent` to it where it has too few; an error that says why if there are none.
fn plan_training<'a>(
    scene: &Scene,
    settings: &BakeSettings,
    all: &'a [Sample],
    lent: &'a [Option<Lent>],
) -> Result<TrainingPlan<'a>, BakeError> {
    let mut by_object: Vec<Vec<&Sample>> = vec![Vec::new(); scene.objects.len()];
    for s in all {
        by_object[s.object as usize].push(s);
    }
    let mut untrained = Vec::new();
    let mut borrowed = Vec::new();
    let mut jobs = Vec::new();
    for object in &scene.objects {
        if !learns(scene, object.id) {
            continue; // emitters show their emission; no network
        }
        let own = by_object[object.id as usize].len();
        if own < settings.min_samples {
            match &lent[object.id as usize] {
                Some(lent) => {
                    by_object[object.id as usize].extend(&lent.samples);
                    borrowed.push(Untrained { object: object.name.clone(), samples: own, reason: lent.reason.clone() });
                }
                None => {
                    untrained.push(Untrained {
                        object: object.name.clone(),
                        samples: own,
                        reason: format!(
                            "{own} samples, and the whole bake fewer than the {} a network needs",
                            settings.min_samples
                        ),
                    });
                    continue;
                }
            }
        }
        for component in Component::ALL.into_iter().filter(|&c| settings.trained.trains(c)) {
            jobs.push((object.id, component));
        }
    }
    if jobs.is_empty() {
        let cause = if all.is_empty() {
            "no ray from the camera box reached the front of a surface: is the camera box inside the scene, \
             not behind a wall or outside a closed room?"
                .to_string()
        } else if !scene.objects.iter().any(|o| learns(scene, o.id)) {
            "every object is an emitter, and emitters get no network".to_string()
        } else {
            format!(
                "{} samples in all, but no object had the {} a network needs: the camera box sees too little of the \
                 scene, or the bake preset is too small",
                all.len(),
                settings.min_samples
            )
        };
        return Err(BakeError::NoNetworks { scene: scene.gltf_path.clone(), cause });
    }
    Ok(TrainingPlan { by_object, jobs, untrained, borrowed })
}

/// Which of `points` (every sample of a bake, located but not traced, in the bake's order)
/// training reads the targets of: [`train::targets_read`] of each object that gets networks,
/// on its samples and on those lent to it.
fn samples_read(scene: &Scene, settings: &BakeSettings, points: &[Sample]) -> Vec<bool> {
    let mut read = vec![false; points.len()];
    let lent = lend_samples(scene, settings, points);
    let Ok(plan) = plan_training(scene, settings, points, &lent) else {
        return read; // no network: training says why
    };
    let mut own: Vec<Vec<usize>> = vec![Vec::new(); scene.objects.len()];
    points.iter().enumerate().for_each(|(i, s)| own[s.object as usize].push(i));
    let mut objects: Vec<u32> = plan.jobs.iter().map(|&(object, _)| object).collect();
    objects.dedup();
    let read_by_object: Vec<Vec<usize>> = objects
        .into_par_iter()
        .map(|object| {
            let samples = &plan.by_object[object as usize];
            let borrowed = lent[object as usize].as_ref().filter(|_| samples.len() > own[object as usize].len());
            let sources: Vec<usize> =
                own[object as usize].iter().chain(borrowed.iter().flat_map(|l| &l.sources)).copied().collect();
            let targets = train::targets_read(scene, settings, object, samples);
            targets.iter().zip(sources).filter(|(&r, _)| r).map(|(_, source)| source).collect()
        })
        .collect();
    read_by_object.into_iter().flatten().for_each(|i| read[i] = true);
    read
}

/// Part of a tracing pass's cache key: which rays of each configuration it traces.
fn selection_key<I: Iterator<Item = (usize, u32)>>(configurations: impl Iterator<Item = I>) -> Vec<u8> {
    let mut key = Fnv64::default();
    for rays in configurations {
        for (target, ray) in rays {
            key.write(&(target as u64).to_le_bytes());
            key.write(&ray.to_le_bytes());
        }
        key.write(b";");
    }
    key.0.to_le_bytes().to_vec()
}

/// Trains (or reads back from the cache) the networks of a bake part's share of the jobs.
struct Trainer<'a> {
    scene: &'a Scene,
    settings: &'a BakeSettings,
    cache: &'a Path,
    progress: &'a dyn BakeProgress,
    work: Work,
    corrupt: &'a AtomicUsize,
}

impl Trainer<'_> {
    /// The leaves of every (object, component) of `jobs`, in job order, each from its
    /// checkpoint if the cache holds a valid one, else trained on `by_object`'s samples and
    /// checkpointed; and how many networks were read back.
    fn train(
        &self,
        jobs: &[(u32, Component)],
        by_object: &[Vec<&Sample>],
    ) -> Result<(Vec<(Network, NetworkInfo)>, usize), BakeError> {
        let Trainer { scene, settings, cache, progress, work, corrupt } = *self;
        let trained = AtomicU64::new(0);
        let resumed_networks = AtomicUsize::new(0);
        let settings_key = serde_json::to_string(settings).expect("settings serialise");
        let networks: Vec<Vec<(Network, NetworkInfo)>> = jobs
            .par_iter()
            .map(|&(object, component)| {
                let mut key = cache_key(scene, &settings_key);
                key.write(&[component as u8]);
                key.write(&object.to_le_bytes());
                let path = cache.join(format!("network-{object:05}-{}.bin", component.name()));
                let checkpoint: Option<Vec<(Network, NetworkInfo)>> =
                    cache::read(&path, NETWORK_MAGIC, key.0, corrupt, |bytes| {
                        let Checkpoint { leaves } = serde_json::from_slice(bytes).ok()?;
                        leaves
                            .into_iter()
                            .map(|Leaf { info, params }| Some((info.network(params, settings.blend_band)?, info)))
                            .collect()
                    });
                let leaves = match checkpoint {
                    Some(resumed) => {
                        resumed_networks.fetch_add(resumed.len(), Ordering::SeqCst);
                        resumed
                    }
                    None if matches!(work, Work::Read) => {
                        return Err(BakeError::MissingStage { path, stage: Stage::Train.name() })
                    }
                    None => {
                        let leaves = train_tree(scene, settings, object, component, &by_object[object as usize]);
                        let checkpoint = Checkpoint {
                            leaves: leaves
                                .iter()
                                .map(|(n, info)| Leaf { info: info.clone(), params: n.params.clone() })
                                .collect(),
                        };
                        let json = serde_json::to_vec(&checkpoint).expect("checkpoint serialises");
                        cache::write(&path, NETWORK_MAGIC, key.0, &json)?;
                        leaves
                    }
                };
                let d = trained.fetch_add(1, Ordering::SeqCst) + 1;
                progress.trained(d, jobs.len() as u64);
                Ok(leaves)
            })
            .collect::<Vec<_>>()
            .into_iter()
            .collect::<Result<_, BakeError>>()?; // the first error in job order, the same on every run
        Ok((networks.into_iter().flatten().collect(), resumed_networks.into_inner()))
    }
}

/// The start of every cache file's key: the model format (it says what the samples' targets
/// are: radiance over reflectance now), the scene's content hash, and `settings` (JSON of the
/// settings that shape the file).
fn cache_key(scene: &Scene, settings: &str) -> Fnv64 {
    let mut key = Fnv64::default();
    key.write(&FORMAT_VERSION.to_le_bytes());
    key.write(&scene.content_hash.to_le_bytes());
    key.write(settings.as_bytes());
    key
}

/// Objects that got fewer samples than this many times `min_samples` from rays over the sphere
/// get rays aimed at them.
const AIM_BELOW: usize = 4;
/// Rays aimed at each such object, in all configurations together, in units of `min_samples`.
const AIMED_RAYS: usize = 16;
/// Separates the random streams of aimed rays from those of rays over the sphere.
const AIMED_STREAM: u64 = 0xa1e5_0000_0000_0001;

/// For `object`, short of the `min_samples` a network needs even after aimed rays (it is
/// hardly visible from the camera box), the samples of other objects nearest to its bounding
/// box that make up the difference, moved to the nearest point of its box, and what to
/// report: its networks then learn the light of the surfaces around it, an approximation that
/// never renders black. `None` if the whole bake has too few samples.
fn borrow_samples(scene: &Scene, all: &[Sample], object: u32, min_samples: usize) -> Option<Lent> {
    let own = all.iter().filter(|s| s.object == object).count();
    let wanted = min_samples - own;
    if all.len() - own < wanted {
        return None;
    }
    let Aabb { min, max } = scene.objects[object as usize].bounds();
    let position = |s: &Sample| Vec3::new(s.inputs[0], s.inputs[1], s.inputs[2]);
    let mut others: Vec<(f32, usize)> = all
        .iter()
        .enumerate()
        .filter(|(_, s)| s.object != object)
        .map(|(i, s)| ((position(s).clamp(min, max) - position(s)).length(), i))
        .collect();
    others.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let mut sources: Vec<&str> =
        others[..wanted].iter().map(|&(_, i)| scene.objects[all[i].object as usize].name.as_str()).collect();
    sources.sort_unstable();
    sources.dedup();
    let reason = format!(
        "{own} samples of its own, fewer than the {min_samples} a network needs even with rays aimed at it (it is \
         hardly visible from the camera box): its networks also learned the {wanted} samples nearest to it, on {}",
        sources.join(", ")
    );
    let sources: Vec<usize> = others[..wanted].iter().map(|&(_, i)| i).collect();
    let samples = sources
        .iter()
        .map(|&i| {
            let mut s = all[i];
            let moved = position(&s).clamp(min, max);
            s.inputs[..3].copy_from_slice(&moved.to_array());
            s
        })
        .collect();
    Some(Lent { samples, sources, reason })
}

/// The samples an object borrows ([`borrow_samples`]): copies moved onto its box, the
/// positions in the bake's samples of those they were copied from, and what to report.
struct Lent {
    samples: Vec<Sample>,
    sources: Vec<usize>,
    reason: String,
}

/// Whether `object` gets networks: every object but pure emitters, which show their emission,
/// and planar mirrors, which show what they reflect (`scene/mirror.rs`).
fn learns(scene: &Scene, object: u32) -> bool {
    let parts = &scene.objects[object as usize].parts;
    parts.iter().any(|p| !scene.materials[p.material as usize].is_plain_emitter()) && !scene.is_mirror(object)
}

/// The samples of one sampling pass, and how many of its shards came from the cache.
#[derive(Default)]
struct Sampled {
    samples: Vec<Sample>,
    resumed: usize,
    shards: usize,
}

/// A bake's sampling passes: each runs over every configuration, in shards of a few, each
/// shard a cache file keyed by the scene, the sampling settings and the pass.
struct Shards<'a> {
    cache: &'a Path,
    objects: usize,
    key: u64,
    shard_size: usize,
    count: usize,
    corrupt: &'a AtomicUsize,
}

impl Shards<'_> {
    /// Runs `sample` on every configuration, in shards named `NAME-00000.bin` (`pass` tells
    /// passes of the same name apart in their key), reading finished shards back from the
    /// cache, as much of it as `work` says (`stage` names it in errors); `done(n)` after every
    /// `n` configurations.
    fn run(
        &self,
        name: &str,
        pass: &[u8],
        stage: Stage,
        work: Work,
        done: &(dyn Fn(usize) + Sync),
        sample: impl Fn(usize) -> Vec<Sample> + Sync,
    ) -> Result<Sampled, BakeError> {
        let shard_count = self.count.div_ceil(self.shard_size);
        let shards: Vec<(Vec<Sample>, bool)> = (0..shard_count)
            .filter(|&shard| work.mine(shard))
            .collect::<Vec<_>>()
            .into_par_iter()
            .map(|shard| {
                let range = shard * self.shard_size..((shard + 1) * self.shard_size).min(self.count);
                let mut key = Fnv64(self.key);
                key.write(name.as_bytes());
                key.write(pass);
                key.write(&(shard as u64).to_le_bytes());
                let path = self.cache.join(format!("{name}-{shard:05}.bin"));
                if let Some(samples) =
                    cache::read(&path, SHARD_MAGIC, key.0, self.corrupt, |b| samples::decode(b, self.objects))
                {
                    done(range.len());
                    return Ok((samples, true));
                }
                if let Work::Read = work {
                    return Err(BakeError::MissingStage { path, stage: stage.name() });
                }
                let mut samples = Vec::new();
                for i in range {
                    samples.extend(sample(i));
                    done(1);
                }
                cache::write(&path, SHARD_MAGIC, key.0, &samples::encode(&samples))?;
                Ok((samples, false))
            })
            .collect::<Vec<_>>()
            .into_iter()
            .collect::<Result<_, BakeError>>()?; // the first error in shard order, the same on every run
        let resumed = shards.iter().filter(|(_, resumed)| *resumed).count();
        let count = shards.len();
        Ok(Sampled { samples: shards.into_iter().flat_map(|(s, _)| s).collect(), resumed, shards: count })
    }
}

/// Everything that shapes the samples of a shard (not the training settings).
#[derive(Serialize)]
struct SamplingKey {
    seed: u64,
    configurations: u32,
    rays_per_configuration: u32,
    paths_per_sample: u32,
    max_depth: u32,
    shard_configurations: u32,
    format: u32,
}

impl From<&BakeSettings> for SamplingKey {
    fn from(s: &BakeSettings) -> Self {
        SamplingKey {
            seed: s.seed,
            configurations: s.configurations,
            rays_per_configuration: s.rays_per_configuration,
            paths_per_sample: s.paths_per_sample,
            max_depth: s.max_depth,
            shard_configurations: s.shard_configurations,
            format: 2,
        }
    }
}
