//! `rrf bake`: training samples from the path tracer, then two networks per object (only the
//! indirect one for `--direct analytic`).

use std::path::{Path, PathBuf};

use anyhow::{anyhow, bail, Context, Result};
use clap::{Args, ValueEnum};
use rrf_baker::bake::lock::{BakeLock, Contended};
use rrf_baker::bake::{bake_part, BakePart, BakeProgress, BakeReport, BakeSettings, Quality, Stage, Trained};
use rrf_baker::model::Model;
use rrf_baker::scene::Scene;
use serde_json::json;

use crate::direct_mode::DirectMode;
use crate::progress::Progress;

#[derive(ValueEnum, Clone, Copy, Debug)]
pub enum QualityArg {
    /// Seconds; for CI and smoke tests.
    Test,
    /// A few minutes.
    Preview,
    /// The quality that ships.
    Final,
}

#[derive(Args, Debug)]
pub struct BakeArgs {
    #[arg(help = super::SCENE_HELP)]
    pub scene: PathBuf,
    /// Preset for the number of configurations, samples, paths and iterations; the scene's
    /// sidecar may override it ([bake.test], [bake.preview], [bake.final]).
    #[arg(long, value_enum, default_value_t = QualityArg::Final)]
    pub quality: QualityArg,
    /// Random seed, any 64-bit integer: the same seed gives the same model.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Model file to write (.safetensors); default: model.safetensors beside scene.gltf or
    /// scene.glb, X.safetensors beside any other X.gltf or X.glb. While it bakes, a lock on
    /// MODEL.lock keeps a second bake of the same model out (see --wait).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Keep the bake cache (MODEL.bake-cache/: sample shards and trained networks) after a
    /// successful bake. A bake that is interrupted (Ctrl-C, a kill, a crash) always keeps it,
    /// and the same command started again resumes from it and writes the same model.
    #[arg(long)]
    pub keep_samples: bool,
    /// When another bake is writing the same model, wait for it to end and then bake (resuming
    /// from what it left), instead of exiting with an error.
    #[arg(long)]
    pub wait: bool,
    /// Print one line of JSON with the figures of the bake.
    #[arg(long)]
    pub json: bool,
    /// The direct light the model is for: `learned` (and `auto`, which may pick either at
    /// run time) trains a direct and an indirect network per object; `analytic` trains only the indirect ones (half the training), for
    /// rendering with `--direct analytic` (a moving point or spot light only). Give the same
    /// value to every stage of a split bake.
    #[arg(long, value_enum, default_value_t = DirectMode::Learned)]
    pub direct: DirectMode,
    /// Run one stage of a bake split across processes or machines (a cluster's array jobs):
    /// `sample`, then `aim`, then `train`, each needing every shard of the stages before, then
    /// --merge. Needs --shard. Every process uses the same bake cache (MODEL.bake-cache/, on a
    /// shared file system) and writes only its own files there; a re-run shard writes the same
    /// bytes. README: "Bakes on a cluster".
    #[arg(long, value_enum, requires = "shard")]
    pub stage: Option<StageArg>,
    /// The share of --stage this process runs, I/N (0 <= I < N): every N-th shard file or
    /// network from the I-th.
    #[arg(long, value_parser = parse_shard, requires = "stage", value_name = "I/N")]
    pub shard: Option<(u32, u32)>,
    /// Write the model from a bake cache that every stage has filled: the same bytes as a bake
    /// in one process with the same seed.
    #[arg(long, conflicts_with_all = ["stage", "shard"])]
    pub merge: bool,
}

#[derive(ValueEnum, Clone, Copy, Debug)]
pub enum StageArg {
    /// Rays over the sphere from every configuration.
    Sample,
    /// Rays aimed at the objects that sampling rarely hit.
    Aim,
    /// The networks.
    Train,
}

/// `I/N` with 0 <= I < N <= 65,536.
fn parse_shard(text: &str) -> Result<(u32, u32), String> {
    let bad = || format!("{text:?}: expected I/N with 0 <= I < N <= 65536, e.g. 0/4");
    let (i, n) = text.split_once('/').ok_or_else(bad)?;
    let (i, n): (u32, u32) = (i.trim().parse().map_err(|_| bad())?, n.trim().parse().map_err(|_| bad())?);
    if i >= n || n > 65_536 {
        return Err(bad());
    }
    Ok((i, n))
}

struct Bars {
    sampling: Progress,
    training: Progress,
    /// [`HOLD_AFTER_NETWORKS`].
    hold_after: Option<u64>,
}

/// For tests: with `RRF_BAKE_HOLD_AFTER_NETWORKS=N` a bake stops making progress once N of its
/// networks are done (trained and in the cache, or resumed from it) and waits until it is
/// killed or interrupted, so that a test interrupts it at a known point instead of racing it.
/// As at most the cache's networks can be resumed, holding after one more than the cache
/// holds means at least one network was trained and written.
const HOLD_AFTER_NETWORKS: &str = "RRF_BAKE_HOLD_AFTER_NETWORKS";

impl BakeProgress for Bars {
    fn sampled(&self, done: u64, total: u64) {
        self.sampling.set(done, total);
    }

    fn trained(&self, done: u64, total: u64) {
        self.training.set(done, total);
        if self.hold_after.is_some_and(|n| done >= n) {
            loop {
                std::thread::park();
            }
        }
    }
}

/// The model to render `scene` with (`path`, or the scene's own), checked against the scene,
/// with a warning for each object it has no network for or whose networks borrowed samples.
pub fn model_to_render(scene: &Scene, path: Option<&Path>) -> Result<Model> {
    let path = path.map_or_else(|| scene.model_file(), Path::to_path_buf);
    let model = Model::load(&path, Some(scene))?;
    for u in &model.metadata.untrained {
        eprintln!("warning: {} has no network ({}); it renders black", u.object, u.reason);
    }
    for u in &model.metadata.borrowed {
        eprintln!("warning: {}'s light is approximate: it has {}", u.object, u.reason);
    }
    Ok(model)
}

/// A model goes to a `.safetensors` file in a folder that exists, never over the scene.
fn check_output(output: &Path) -> Result<()> {
    if output.extension().and_then(|e| e.to_str()) != Some("safetensors") {
        bail!("{}: a model file must end in .safetensors", output.display());
    }
    let folder = output.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    if !folder.is_dir() {
        bail!("{}: the folder {} does not exist", output.display(), folder.display());
    }
    Ok(())
}

/// What a stage's shard did, in a line (of JSON with `--json`).
fn report_stage(args: &BakeArgs, cache: &Path, part: BakePart, report: &BakeReport) -> Result<()> {
    let BakePart::Stage { stage, index, count } = part else { return Ok(()) };
    if args.json {
        let line = json!({
            "stage": stage.name(), "shard": index, "shards": count, "cache": cache,
            "sample_files": report.shards, "sample_files_found": report.resumed_shards,
            "networks": report.networks, "networks_found": report.resumed_networks,
            "corrupt_cache_files": report.corrupt_files,
        });
        println!("{line}");
        return Ok(());
    }
    let (done, found, what) = match stage {
        Stage::Sample | Stage::Aim => (report.shards, report.resumed_shards, "sample files"),
        Stage::Train => (report.networks, report.resumed_networks, "networks"),
    };
    eprintln!(
        "stage {} shard {index}/{count}: {done} {what} in {} ({found} were there already)",
        stage.name(),
        cache.display()
    );
    Ok(())
}

/// What `--wait` says while another bake holds the model.
fn announce_wait(holder: Option<u32>) {
    match holder {
        Some(pid) => eprintln!("waiting for the bake of process {pid}, which is writing this model"),
        None => eprintln!("waiting for another bake, which is writing this model"),
    }
}

/// Ctrl-C ends the bake at once: everything finished is already in the cache (every cache
/// file is written whole or not at all), so nothing is lost. Says how to resume.
fn stop_on_ctrl_c(lock: Option<PathBuf>, cache: &Path) {
    let command: Vec<String> = std::iter::once("rrf".to_string()).chain(std::env::args().skip(1)).collect();
    let message = format!(
        "\ninterrupted: finished samples and networks are kept in {}; to resume, run the same command again:\n  {}",
        cache.display(),
        command.join(" ")
    );
    let handler = move || {
        if let Some(lock) = &lock {
            let _ = std::fs::remove_file(lock);
        }
        eprintln!("{message}");
        std::process::exit(130);
    };
    if let Err(e) = ctrlc::set_handler(handler) {
        eprintln!("warning: cannot catch Ctrl-C ({e}); an interrupted bake still resumes");
    }
}

pub fn run(args: &BakeArgs) -> Result<()> {
    let scene = Scene::load(&args.scene)?;
    for warning in &scene.warnings {
        eprintln!("warning: {warning}");
    }
    let quality = match args.quality {
        QualityArg::Test => Quality::Test,
        QualityArg::Preview => Quality::Preview,
        QualityArg::Final => Quality::Final,
    };
    let mut settings = BakeSettings::new(quality, args.seed, &scene);
    if args.direct == DirectMode::Analytic {
        args.direct.check_scene(&scene)?;
        settings.trained = Trained::IndirectOnly;
    }
    let output = args.output.clone().unwrap_or_else(|| scene.model_file());
    check_output(&output)?;
    let cache = output.with_extension("bake-cache");
    let part = match (args.stage, args.shard, args.merge) {
        (Some(stage), Some((index, count)), _) => {
            let stage = match stage {
                StageArg::Sample => Stage::Sample,
                StageArg::Aim => Stage::Aim,
                StageArg::Train => Stage::Train,
            };
            BakePart::Stage { stage, index, count }
        }
        (_, _, true) => BakePart::Merge,
        _ => BakePart::Whole,
    };
    // Shards of a stage run side by side and write only their own cache files; the model is
    // written by one process, under the lock.
    let lock = match part {
        BakePart::Stage { .. } => None,
        BakePart::Whole | BakePart::Merge => {
            let contended = if args.wait { Contended::Wait(announce_wait) } else { Contended::Refuse };
            Some(BakeLock::acquire(&output, contended)?)
        }
    };
    stop_on_ctrl_c(lock.as_ref().map(|l| l.path().to_path_buf()), &cache);
    let hold_after = match std::env::var(HOLD_AFTER_NETWORKS) {
        Ok(n) => Some(n.parse().map_err(|_| anyhow!("{HOLD_AFTER_NETWORKS}={n:?}: expected a count of networks"))?),
        Err(_) => None,
    };
    let bars = Bars {
        sampling: Progress::new(u64::from(settings.configurations), "sampling", args.json),
        training: Progress::new(1, "training", args.json),
        hold_after,
    };
    let (model, report) = bake_part(&scene, &settings, &cache, &bars, part)?;
    bars.sampling.finish();
    bars.training.finish();
    let Some(model) = model else {
        return report_stage(args, &cache, part, &report);
    };
    model.save(&output)?;
    if !args.keep_samples {
        std::fs::remove_dir_all(&cache).with_context(|| format!("cannot remove {}", cache.display()))?;
    }
    drop(lock);

    let networks: Vec<_> = model
        .metadata
        .networks
        .iter()
        .map(|n| {
            json!({
                "object": n.object, "component": n.component, "region": n.region, "samples": n.samples,
                "train_mse": n.train_mse, "val_mse": n.val_mse, "val_noise": n.val_noise,
                "iterations": n.iterations,
            })
        })
        .collect();
    if args.json {
        let line = json!({
            "scene": scene.name,
            "output": output,
            "quality": quality,
            "seed": args.seed,
            "samples": report.samples,
            "traced_samples": report.traced_samples,
            "paths": report.paths,
            "sample_seconds": report.sample_seconds,
            "train_seconds": report.train_seconds,
            "resumed_shards": report.resumed_shards,
            "resumed_networks": report.resumed_networks,
            "corrupt_cache_files": report.corrupt_files,
            "non_finite_dropped": report.non_finite_dropped,
            "aimed_objects": report.aimed_objects,
            "networks": networks,
            "untrained": model.metadata.untrained,
            "borrowed": model.metadata.borrowed,
        });
        println!("{line}");
        return Ok(());
    }
    let resumed = |done: usize, of: usize, what: &str| match done {
        0 => String::new(),
        _ => format!(" ({done} of {of} {what} resumed from {})", cache.display()),
    };
    eprintln!(
        "found {} samples, traced the {} that training reads ({} paths) in {:.1} s{}; trained {} networks in {:.1} s{}",
        report.samples,
        report.traced_samples,
        report.paths,
        report.sample_seconds,
        resumed(report.resumed_shards, report.shards, "shards"),
        model.networks.len(),
        report.train_seconds,
        resumed(report.resumed_networks, model.networks.len(), "networks"),
    );
    if report.corrupt_files > 0 {
        eprintln!("warning: {} damaged files in the bake cache were recomputed", report.corrupt_files);
    }
    if report.non_finite_dropped > 0 {
        eprintln!(
            "warning: the path tracer dropped {} non-finite contributions (degenerate geometry or materials?)",
            report.non_finite_dropped
        );
    }
    eprintln!(
        "\n  {:<18} {:<9} {:<24} {:>8} {:>11} {:>11} {:>11} {:>5}",
        "object", "component", "region", "samples", "train MSE", "val MSE", "val noise", "iter"
    );
    for n in &model.metadata.networks {
        let region = if n.region.is_whole() { "all".to_string() } else { n.region.path()[1..].to_string() };
        eprintln!(
            "  {:<18} {:<9} {:<24} {:>8} {:>11.3e} {:>11.3e} {:>11.3e} {:>5}",
            n.object,
            n.component.name(),
            region,
            n.samples,
            n.train_mse,
            n.val_mse,
            n.val_noise,
            n.iterations
        );
    }
    for u in &model.metadata.untrained {
        eprintln!("  warning: {} has no network: {}", u.object, u.reason);
    }
    for u in &model.metadata.borrowed {
        eprintln!("  warning: {} has {}", u.object, u.reason);
    }
    eprintln!("\nwrote {}", output.display());
    Ok(())
}
