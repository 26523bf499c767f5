//! `rrf eval`: the networks against the path tracer on held-out configurations, in numbers
//! (`metrics.json`) and pictures (one figure per configuration, `index.html`).

use std::path::PathBuf;

use anyhow::{bail, Context as _, Result};
use clap::Args;
use rrf_baker::glam::Vec3;
use rrf_baker::model::Model;
use rrf_baker::network::Component;
use rrf_baker::predict::predict_image;
use rrf_baker::scene::{EvalDefaults, PlacedLight, Scene};
use rrf_baker::trace::render::RenderSettings;
use rrf_baker::trace::sampling::mix64;
use rrf_baker::trace::{Camera, Geometry, TraceSettings, World};
use rrf_renderer::frame::{FrameOutput, Shown};
use rrf_renderer::passes::network::Variant;
use rrf_renderer::{vk, Context, ContextOptions};

use super::image_args::PixelFootprint;
use super::scene_args::SceneArgs;
use crate::direct_mode::DirectMode;
use crate::eval::configs::{held_out, EvalConfig};
use crate::eval::figure::{compose, Panel};
use crate::eval::metrics::{compare, Baselines, Metrics};
use crate::eval::reference_cache::{default_cache_dir, reference};
use crate::eval::report::{self, Camera as CameraReport, ComponentMetrics, ConfigReport, Report};
use crate::eval::seams::{pixel_hits, seams, Hit, Seam};
use crate::image_out::tonemap_rgb8;
use crate::progress::Progress;
use crate::scene_frame::{rgb, FrameSettings, SceneFrame};

const MAX_DEPTH: u32 = 8;
const RR_DEPTH: u32 = 5;
/// Separates the second reference's paths (the floor's) from the first's.
const FLOOR_STREAM: u64 = 0xf100_0000_0000_0001;

#[derive(Args, Debug)]
pub struct EvalArgs {
    #[command(flatten)]
    pub input: SceneArgs,
    /// Random configurations (Latin hypercube over the light and camera boxes), on top of one
    /// per named view of the sidecar; 0 to 10,000.
    #[arg(long, default_value_t = 6, value_parser = clap::value_parser!(u32).range(0..=10_000))]
    pub configs: u32,
    /// Samples per pixel of the path-traced references (cached under the scene's .cache/),
    /// 1 to 1,048,576. Default: the sidecar's `[eval] spp`, else 256.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=i64::from(MAX_SPP)))]
    pub spp: Option<u32>,
    /// Raise a configuration's reference spp until the floor (the FLIP of a second reference
    /// against the first) is below this, so that a FLIP target can be read: the floor falls
    /// about as spp^(-1/3) (measured on the shipped scenes), so each try renders both
    /// references at the spp that rule predicts (up to three tries, at most 1,048,576 spp).
    /// Try a third of the FLIP you want to judge.
    #[arg(long, value_name = "FLIP", value_parser = parse_floor)]
    pub floor_below: Option<f64>,
    /// Image size in pixels, each side 1 to 16384.
    #[arg(long, default_value = "256x256", value_name = "WxH")]
    pub size: String,
    /// Seed of the held-out configurations and of the references' paths, any 64-bit integer.
    /// Eval's configurations come from a stream that baking never uses, whatever the two seeds.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Predict with the CPU reference inference instead of the Vulkan renderer (the fallback
    /// when no Vulkan device is available).
    #[arg(long)]
    pub cpu: bool,
    /// Where to cache the references; default: .cache/references/ in the scene's folder.
    #[arg(long, value_name = "DIR")]
    pub cache: Option<PathBuf>,
    /// Where in its pixel each reference path starts. `centre` traces the ray whose hit the
    /// G-buffer rasterises, so the scores are the networks' error alone; `area` scores against
    /// antialiased references, which adds the raster's aliasing at edges and in textures (the
    /// protocol of evals before 2026-12-02).
    #[arg(long, value_enum, default_value_t = PixelFootprint::Centre)]
    pub footprint: PixelFootprint,
    /// Output folder: metrics.json, index.html and one PNG per configuration.
    #[arg(short, long)]
    pub output: PathBuf,
}

/// Makes the predictions: the Vulkan renderer (one frame for every configuration), or the
/// CPU inference.
enum Predictor {
    Gpu(Box<(Context, SceneFrame)>),
    /// The CPU inference, with direct light from where it says.
    Cpu(DirectMode),
}

/// The Vulkan context and the one frame every configuration renders with.
fn gpu_predictor(
    scene: &Scene,
    model: &Model,
    (width, height): (u32, u32),
    direct: DirectMode,
) -> Result<Box<(Context, SceneFrame)>> {
    let ctx = Context::new(&ContextOptions::from_env())?;
    let extent = vk::Extent2D { width, height };
    let frame = SceneFrame::new(&ctx, scene, model, Variant::Tiled, extent, FrameOutput::Radiance, direct)?;
    Ok(Box::new((ctx, frame)))
}

pub fn run(args: &EvalArgs) -> Result<()> {
    let (width, height) = crate::parse::parse_size(&args.size)?;
    let scene = Scene::load(&args.input.scene)?;
    let model_path = args.input.model.clone().unwrap_or_else(|| scene.model_file());
    let model = Model::load(&model_path, Some(&scene))?;
    let geometry = Geometry::new(&scene);
    let configs = held_out(&scene, &geometry, args.configs as usize, args.seed)?;
    std::fs::create_dir_all(&args.output).with_context(|| format!("cannot create {}", args.output.display()))?;

    // The GPU predictions use the tiled variant, which does everything the CPU inference does.
    let direct = args.input.direct.resolve(&scene, None);
    direct.check(&scene, &model)?;
    let predictor = if args.cpu {
        Predictor::Cpu(direct)
    } else {
        match gpu_predictor(&scene, &model, (width, height), direct) {
            Ok(gpu) => Predictor::Gpu(gpu),
            Err(e) => {
                eprintln!("warning: no Vulkan device ({e}); predicting with the CPU inference");
                Predictor::Cpu(direct)
            }
        }
    };
    let predictions = match &predictor {
        Predictor::Gpu(gpu) => format!(
            "{} (Vulkan, {} network pass, {} direct light)",
            gpu.0.info.name,
            Variant::Tiled.name(),
            direct.name()
        ),
        Predictor::Cpu(direct) => format!("the CPU reference inference ({} direct light)", direct.name()),
    };
    let cache = args.cache.clone().unwrap_or_else(|| default_cache_dir(&scene));
    let spp = args.spp.or(scene.eval.spp).unwrap_or(DEFAULT_SPP);
    let settings = RenderSettings {
        width,
        height,
        spp,
        trace: TraceSettings { max_depth: MAX_DEPTH, rr_depth: Some(RR_DEPTH) },
        seed: args.seed,
        footprint: args.footprint.into(),
    };
    eprintln!(
        "{} configurations of {} at {width}x{height}; references at {} spp, cached in {}",
        configs.len(),
        scene.name,
        spp,
        cache.display()
    );

    let evaluated: Result<Vec<ConfigReport>> = configs
        .iter()
        .enumerate()
        .map(|(i, config)| {
            let mut settings = settings;
            let mut tries = 0;
            let (truth, floor, cached) = loop {
                let progress = Progress::new(
                    u64::from(width * height),
                    &format!("reference {}/{} ({} spp)", i + 1, configs.len(), settings.spp),
                    false,
                );
                let (truth, cached) = reference(&scene, &geometry, config, &settings, &cache, &|n| progress.inc(n))?;
                progress.finish();
                // The floor: a second reference with independent paths, scored against the first.
                let progress = Progress::new(
                    u64::from(width * height),
                    &format!("second reference {}/{} ({} spp)", i + 1, configs.len(), settings.spp),
                    false,
                );
                let second = RenderSettings { seed: mix64(args.seed ^ FLOOR_STREAM), ..settings };
                let (twin, _) = reference(&scene, &geometry, config, &second, &cache, &|n| progress.inc(n))?;
                progress.finish();
                let floor = floor_metrics(&truth.pixels, &twin.pixels, width, height);
                let Some(limit) = args.floor_below else { break (truth, floor, cached) };
                if floor.flip < limit || tries == MAX_FLOOR_TRIES || settings.spp == MAX_SPP {
                    if floor.flip >= limit {
                        eprintln!(
                            "warning: {}: floor {:.4} still above {limit} at {} spp",
                            config.name, floor.flip, settings.spp
                        );
                    }
                    break (truth, floor, cached);
                }
                tries += 1;
                settings.spp = spp_for_floor(settings.spp, floor.flip, limit);
            };
            let predicted = predict(&predictor, &scene, &geometry, &model, config, width, height)?;
            let figure = format!("{:02}-{}.png", i, config.name);
            let hits = pixel_hits(&scene, &geometry, config, (width, height));
            // Analytic direct light has no cuts: only the indirect trees show.
            let components: &[Component] = match direct {
                DirectMode::Analytic => &[Component::Indirect],
                _ => &Component::ALL,
            };
            let cuts = Cuts { scene: &scene, model: &model, components, hits: &hits };
            let Scores { metrics, baselines, seams } =
                evaluate(&predicted, &truth.pixels, (width, height), settings.spp, cuts, &args.output.join(&figure))?;
            let worst_seam = seams.iter().max_by(|a, b| a.excess().total_cmp(&b.excess())).cloned();
            let seams_over_reference = seams.iter().filter(|s| s.excess() > 2.0 * s.reference_noise).count();
            eprintln!(
                "{:<16} gi relMSE {:.4} PSNR {:5.2} dB FLIP {:.4} HDR-FLIP {:.4} (floor {:.4} / {:.4} at {} spp; \
                 black {:.4}, mean colour {:.4}){}",
                config.name,
                metrics.gi.relmse,
                metrics.gi.psnr,
                metrics.gi.flip,
                metrics.gi.hdr_flip,
                floor.flip,
                floor.hdr_flip,
                settings.spp,
                baselines.black.flip,
                baselines.mean_colour.flip,
                if cached { " (cached reference)" } else { "" }
            );
            if let Some(s) = &worst_seam {
                eprintln!(
                    "{:<16} worst seam {} {} {}: {:+.2} levels (reference {:+.2} ± {:.2}, {} pixel pairs); {} of {} \
                     cuts step more than the reference",
                    "",
                    s.object,
                    s.component.name(),
                    s.cut,
                    s.predicted_step,
                    s.reference_step,
                    s.reference_noise,
                    s.pairs,
                    seams_over_reference,
                    seams.len()
                );
            }
            let v = &config.view;
            Ok(ConfigReport {
                name: config.name.clone(),
                camera: CameraReport { eye: v.eye.to_array(), target: v.target.to_array(), fov_y: v.fov_y },
                light: config.light.to_array(),
                figure,
                spp: settings.spp,
                reference_cached: cached,
                metrics,
                baselines,
                floor,
                worst_seam,
                seams_over_reference,
            })
        })
        .collect();
    if let Predictor::Gpu(gpu) = predictor {
        let (ctx, frame) = *gpu;
        frame.destroy(&ctx);
        let report = ctx.finish();
        if !report.is_clean() {
            bail!("Vulkan reported {} validation messages; leaked {:?}", report.validation_messages, report.leaked);
        }
    }
    let configs = evaluated?;
    let all: Vec<ComponentMetrics> = configs.iter().map(|c| c.metrics).collect();
    let mean = ComponentMetrics::mean(&all);
    let mean_baselines = Baselines::mean(configs.iter().map(|c| &c.baselines));
    let mean_floor = Metrics::mean(configs.iter().map(|c| &c.floor));
    let report = Report {
        scene: scene.name.clone(),
        model: model_path.display().to_string(),
        predictions,
        width,
        height,
        spp,
        max_depth: MAX_DEPTH,
        rr_depth: RR_DEPTH,
        seed: args.seed,
        footprint: args.footprint.name(),
        configs,
        mean,
        mean_baselines,
        mean_floor,
    };
    report::write(&args.output, &report)?;
    println!("{:<10} {:>10} {:>9} {:>8} {:>9}", "component", "relMSE", "PSNR dB", "FLIP", "HDR-FLIP");
    let line = |name: &str, m: Metrics, note: &str| {
        println!("{name:<10} {:>10.4} {:>9.2} {:>8.4} {:>9.4}{note}", m.relmse, m.psnr, m.flip, m.hdr_flip)
    };
    for (name, m) in [("gi", mean.gi), ("direct", mean.direct), ("indirect", mean.indirect)] {
        line(name, m, "");
    }
    for (name, m) in [("black", mean_baselines.black), ("mean colour", mean_baselines.mean_colour)] {
        line(name, m, "  (trivial prediction of gi)");
    }
    line("floor", mean_floor, "  (a second reference against the first)");
    eprintln!("wrote {}", args.output.join("index.html").display());
    Ok(())
}

/// The most tries of `--floor-below` after the first references, and the most spp.
const MAX_FLOOR_TRIES: u32 = 3;
const MAX_SPP: u32 = EvalDefaults::MAX_SPP;
/// The references' spp where neither the command line nor the sidecar names one.
const DEFAULT_SPP: u32 = 256;

fn parse_floor(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(v) if v > 0.0 && v < 1.0 => Ok(v),
        _ => Err(format!("{text:?}: a FLIP value between 0 and 1 (exclusive), e.g. 0.017")),
    }
}

/// The floor: the global image of `twin`, a second reference of independent paths, scored
/// against `truth`; below it, a prediction's error cannot be told from the references' noise.
fn floor_metrics(truth: &[rrf_baker::trace::Radiance], twin: &[rrf_baker::trace::Radiance], w: u32, h: u32) -> Metrics {
    let gi = |r: &[rrf_baker::trace::Radiance]| r.iter().map(|r| r.gi()).collect::<Vec<Vec3>>();
    compare(&gi(twin), &gi(truth), w, h).metrics
}

/// The spp at which a floor of `floor` at `spp` falls to `limit`, with a tenth to spare, in
/// whole multiples of 64. The floor falls as spp^(-1/3), not as the 1/sqrt(spp) of the
/// pixels' noise: FLIP's error saturates and is pooled over the image, and the shipped scenes'
/// floors fell as spp^(-0.34) to spp^(-0.35) between 256 and 3072 spp (BENCHMARKS.md).
fn spp_for_floor(spp: u32, floor: f64, limit: f64) -> u32 {
    let wanted = f64::from(spp) * (floor / limit).powi(3) * 1.1;
    let rounded = (wanted / 64.0).ceil() * 64.0;
    (rounded.min(f64::from(MAX_SPP)) as u32).max((spp + 1).min(MAX_SPP))
}

/// Per-pixel predicted radiance of one configuration: direct, indirect, global.
struct Predicted {
    direct: Vec<Vec3>,
    indirect: Vec<Vec3>,
    gi: Vec<Vec3>,
}

fn predict(
    predictor: &Predictor,
    scene: &Scene,
    geometry: &Geometry,
    model: &Model,
    config: &EvalConfig,
    width: u32,
    height: u32,
) -> Result<Predicted> {
    match predictor {
        Predictor::Cpu(direct) => {
            let world = World::new(scene, geometry, Some(config.light));
            let camera = Camera::new(&config.view, width as f32 / height as f32);
            let image = predict_image(&world, &camera, model, (width, height), direct.cpu(scene));
            Ok(Predicted {
                direct: image.component(|r| r.direct),
                indirect: image.component(|r| r.indirect),
                gi: image.component(|r| r.gi()),
            })
        }
        Predictor::Gpu(gpu) => {
            let (ctx, frame) = &**gpu;
            let settings = FrameSettings {
                view: config.view.clone(),
                lights: vec![PlacedLight { position: config.light, scale: Vec3::ONE }],
                exposure_scale: 1.0,
                shown: Shown::Gi,
            };
            let pixels = frame.render(ctx, &settings)?;
            Ok(Predicted { direct: rgb(&pixels.direct), indirect: rgb(&pixels.indirect), gi: rgb(&pixels.gi) })
        }
    }
}

/// What one configuration scores: per component, trivial predictions of the global image, and
/// the steps across the kd-tree's cuts.
struct Scores {
    metrics: ComponentMetrics,
    baselines: Baselines,
    seams: Vec<Seam>,
}

/// What the seams are measured on: the scene, the model's trees and each pixel's surface.
#[derive(Clone, Copy)]
struct Cuts<'a> {
    scene: &'a Scene,
    model: &'a Model,
    /// The components whose networks the predictions use.
    components: &'a [Component],
    hits: &'a [Option<Hit>],
}

/// The configuration's scores against the reference `truth`, and its figure written to
/// `figure`.
fn evaluate(
    p: &Predicted,
    truth: &[rrf_baker::trace::Radiance],
    (width, height): (u32, u32),
    spp: u32,
    cuts: Cuts,
    figure: &std::path::Path,
) -> Result<Scores> {
    let pick = |f: fn(&rrf_baker::trace::Radiance) -> Vec3| truth.iter().map(f).collect::<Vec<Vec3>>();
    let (true_direct, true_indirect, true_gi) = (pick(|r| r.direct), pick(|r| r.indirect), pick(|r| r.gi()));
    let gi = compare(&p.gi, &true_gi, width, height);
    let direct = compare(&p.direct, &true_direct, width, height);
    let indirect = compare(&p.indirect, &true_indirect, width, height);
    let metrics = ComponentMetrics { gi: gi.metrics, direct: direct.metrics, indirect: indirect.metrics };

    let mut images = [&p.direct, &p.indirect, &p.gi, &true_gi, &p.gi].map(|pixels| tonemap_rgb8(pixels, 0.0));
    let (seams, on_cut) =
        seams(cuts.scene, cuts.model, cuts.components, cuts.hits, &images[2], &images[3], (width, height));
    // The last panel: the prediction with the pixels that straddle a cut in magenta.
    for (rgb, _) in images[4].chunks_exact_mut(3).zip(&on_cut).filter(|(_, &cut)| cut) {
        rgb.copy_from_slice(&[255, 0, 255]);
    }
    let reference_label = format!("reference {spp}spp");
    let labels = ["pred. direct", "pred. indirect", "pred. global", reference_label.as_str(), "kd-tree cuts"];
    let panels: Vec<Panel> = labels.iter().zip(&images).map(|(label, rgb)| Panel { label, rgb }).collect();
    let footer: Vec<String> = [("global", metrics.gi), ("direct", metrics.direct), ("indirect", metrics.indirect)]
        .iter()
        .map(|(name, m)| {
            format!(
                "{name:<8} relMSE {:.4}  PSNR {:5.2} dB  FLIP {:.4}  HDR-FLIP {:.4}",
                m.relmse, m.psnr, m.flip, m.hdr_flip
            )
        })
        .collect();
    compose(&panels, &gi.flip_map, width, height, &footer)
        .save(figure)
        .with_context(|| format!("cannot write {}", figure.display()))?;
    Ok(Scores { metrics, baselines: Baselines::of(&true_gi, width, height), seams })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spp_for_a_floor_follows_the_cube_root_rule() {
        // The Cornell box's floor, 0.038 at 256 spp, down to 0.0167:
        // (0.038 / 0.0167)³ × 1.1 × 256 = 3318, up to 3328. Measured: 0.0185 at 2048 spp (the
        // square-root rule's 1472 fell short) and 0.0162 at 3072.
        assert_eq!(spp_for_floor(256, 0.038, 0.0167), 3328);
        assert_eq!(spp_for_floor(1 << 20, 0.5, 0.01), MAX_SPP);
        assert!(spp_for_floor(64, 0.0101, 0.01) > 64, "always more than before");
    }
}
