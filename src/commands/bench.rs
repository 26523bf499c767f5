//! `rrf bench`: GPU time per pass from timestamp queries, median over frames.

use std::sync::LazyLock;
use std::time::Instant;

use anyhow::{bail, Result};
use clap::{Args, ValueEnum};
use rrf_baker::model::Model;
use rrf_baker::network::Component;
use rrf_baker::scene::{PlacedLight, Scene, View};
use rrf_renderer::backend::frames::{FrameLoop, FRAMES_IN_FLIGHT};
use rrf_renderer::frame::{Frame, FrameConstants, FrameOutput, Shown, TIMESTAMPS};
use rrf_renderer::{vk, Context, ContextOptions, Validation};
use serde_json::json;

use super::scene_args::SceneArgs;
use super::variant::VariantArg;
use crate::direct_mode::DirectMode;
use crate::frame_stats::{median, Stats};
use crate::lights::MAX_LIGHTS;
use crate::scene_frame::{FrameSettings, SceneFrame};

/// Frames run before timing starts.
const WARM_UP: usize = 2;

/// Multiply-adds of one 13 → 20 → 10 → 3 network per pixel lit by `lights` lights: the first
/// layer's 10 inputs other than the light once (10·20), then per light its 3 light inputs and
/// the rest (3·20 + 20·10 + 10·3); 490 for one light.
fn multiply_adds(lights: usize) -> f64 {
    200.0 + 290.0 * lights as f64
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum OutputArg {
    Radiance,
    Display,
    Both,
}

impl OutputArg {
    fn outputs(self) -> Vec<FrameOutput> {
        match self {
            OutputArg::Radiance => vec![FrameOutput::Radiance],
            OutputArg::Display => vec![FrameOutput::Display],
            OutputArg::Both => vec![FrameOutput::Radiance, FrameOutput::Display],
        }
    }
}

/// `--variant`: one variant, or all of them.
#[derive(Clone, Debug)]
pub struct Variants(pub Vec<VariantArg>);

fn parse_variants(s: &str) -> Result<Variants, String> {
    if s == "all" {
        return Ok(Variants(VariantArg::value_variants().to_vec()));
    }
    VariantArg::from_str(s, false).map(|v| Variants(vec![v])).map_err(|_| {
        let names: Vec<_> = VariantArg::value_variants().iter().map(|v| v.0.name()).collect();
        format!("expected one of {} or all", names.join(", "))
    })
}

/// `--help` text of `--lights`.
static LIGHTS_HELP: LazyLock<String> = LazyLock::new(|| {
    format!(
        "Numbers of lights to time, e.g. 1,2,4: copies of the moving light spread through its box (each 1 to \
         {MAX_LIGHTS}). With two or more, the cost of each extra light is printed."
    )
});

#[derive(Args, Debug)]
pub struct BenchArgs {
    #[command(flatten)]
    pub input: SceneArgs,
    /// A named view; default: the glTF camera.
    #[arg(long)]
    pub view: Option<String>,
    /// Frame size in pixels, each side 1 to 16384.
    #[arg(long, default_value = "512x512", value_name = "WxH")]
    pub size: String,
    /// Frames to time (after two warm-up frames), 1 to 100,000.
    #[arg(long, default_value_t = 30, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    pub frames: u32,
    /// Network pass variant to time: tiled, per-object, storage (see `rrf render --help`), or
    /// all of them one after the other.
    #[arg(long, default_value = "all", value_parser = parse_variants, value_name = "V|all")]
    pub variant: Variants,
    /// Which frame to time: `radiance` writes the direct, indirect and global radiance images
    /// then tonemaps one (rrf render, eval), `display` writes only the tonemapped display image
    /// (the walkthrough's frame), `both` times each.
    #[arg(long, value_enum, default_value_t = OutputArg::Both)]
    pub output: OutputArg,
    #[arg(long, default_value = "1", value_delimiter = ',', help = LIGHTS_HELP.as_str(),
          value_parser = clap::value_parser!(u32).range(1..=MAX_LIGHTS as i64))]
    pub lights: Vec<u32>,
    /// The device's fp32 peak in GFLOP/s, to report the fraction the network pass reaches.
    #[arg(long)]
    pub peak_gflops: Option<f64>,
    /// Print one line of JSON per variant.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: &BenchArgs) -> Result<()> {
    let (width, height) = crate::parse::parse_size(&args.size)?;
    let (scene, model) = args.input.load()?;
    let view = super::image_args::named_view(&scene, args.view.as_deref())?;
    args.input.direct.check(&scene, &model)?;
    // Timing runs without the validation layer unless RRF_VALIDATION asks for it.
    let mut options = ContextOptions::from_env();
    if std::env::var_os("RRF_VALIDATION").is_none() {
        options.validation = Validation::Off;
    }
    let ctx = Context::new(&options)?;
    let Some(period_ns) = ctx.info.limits.timestamp_period_ns else {
        bail!("{} cannot write timestamps on its queue", ctx.info.name);
    };
    let lights = args
        .lights
        .iter()
        .map(|&n| Ok((n, crate::lights::spread_lights(&scene, n as usize)?)))
        .collect::<Result<Vec<_>>>()?;
    let bench = Bench { ctx: &ctx, period_ns: f64::from(period_ns), scene: &scene, model: &model, args };
    let runs = args.variant.0.iter().flat_map(|&v| args.output.outputs().into_iter().map(move |o| (v, o)));
    let rows: Result<Vec<_>> = runs
        .map(|(variant, output)| {
            let rows = lights
                .iter()
                .map(|(_, lights)| {
                    let row = bench.variant(variant, output, &view, lights, width, height)?;
                    print_row(&row, args.json);
                    Ok(row)
                })
                .collect::<Result<Vec<_>>>()?;
            print_light_cost(&rows, args.json);
            Ok(rows)
        })
        .collect();
    let report = ctx.finish();
    rows?;
    if !report.is_clean() {
        bail!("Vulkan reported {} validation messages; leaked {:?}", report.validation_messages, report.leaked);
    }
    Ok(())
}

struct Bench<'a> {
    ctx: &'a Context,
    period_ns: f64,
    scene: &'a Scene,
    model: &'a Model,
    args: &'a BenchArgs,
}

impl Bench<'_> {
    /// Times one variant; returns its row.
    fn variant(
        &self,
        variant: VariantArg,
        output: FrameOutput,
        view: &View,
        lights: &[PlacedLight],
        width: u32,
        height: u32,
    ) -> Result<serde_json::Value> {
        let (ctx, scene, model, args) = (self.ctx, self.scene, self.model, self.args);
        let setup = Instant::now();
        let direct = args.input.direct.resolve(scene, Some(variant.0));
        direct.check(scene, model)?;
        let frame = SceneFrame::new(ctx, scene, model, variant.0, vk::Extent2D { width, height }, output, direct)?;
        let settings =
            FrameSettings { view: view.clone(), lights: lights.to_vec(), exposure_scale: 1.0, shown: Shown::Gi };
        let constants = frame.constants(&settings);
        // Listing the frame's passes makes the network pipelines that this view needs.
        let bytes_per_pixel = frame.gpu.bytes_per_pixel(ctx, &constants);
        let setup_ms = setup.elapsed().as_secs_f64() * 1e3;
        let measured = (|| -> Result<_> { Ok((bytes_per_pixel?, self.measure(&frame, &constants)?)) })();
        frame.destroy(ctx);
        let (bytes_per_pixel, (stats, objects)) = measured?;
        let [gbuffer, mirrors, network, tonemap, _rest] = &stats.gpu_ms;
        // Networks evaluated per frame: two per pixel of an object that has them.
        let trained: Vec<bool> = scene.objects.iter().map(|o| model.has(&o.name, Component::Direct)).collect();
        // Analytic direct light computes direct light instead of evaluating its network.
        let per_pixel = if direct == DirectMode::Analytic { 1 } else { 2 };
        let evaluations = per_pixel * objects.iter().filter(|&&id| id > 0 && trained[id as usize - 1]).count();
        let network_ms = median(network);
        let per_s = evaluations as f64 / (network_ms * 1e-3);
        let gflops = per_s * 2.0 * multiply_adds(lights.len()) * 1e-9;
        Ok(json!({
            "device": ctx.info.name,
            "variant": variant.0.name(),
            "output": match output {
                FrameOutput::Radiance => "radiance",
                FrameOutput::Display => "display",
            },
            "scene": scene.name,
            "width": width,
            "height": height,
            "lights": lights.len(),
            "direct": direct.name(),
            "frames": args.frames,
            "setup_ms": setup_ms,
            "gbuffer_ms": median(gbuffer),
            // The mirrors' G-buffers and merge steps, in a scene with planar mirrors.
            "mirrors_ms": (!scene.mirrors().is_empty()).then(|| median(mirrors)),
            "network_ms": network_ms,
            "tonemap_ms": median(tonemap),
            "frame_ms": median(&stats.frame_ms),
            "bytes_per_pixel": bytes_per_pixel,
            "networks_per_frame": evaluations,
            "network_pixels_per_s": per_s,
            "network_gflops": gflops,
            "peak_fraction": args.peak_gflops.map(|p| gflops / p),
        }))
    }
}

impl Bench<'_> {
    /// The timings of frames of `constants`, and the object ids of their pixels.
    fn measure(&self, frame: &SceneFrame, constants: &FrameConstants) -> Result<(Stats, Vec<u32>)> {
        let stats = self.time_frames(&frame.gpu, constants)?;
        Ok((stats, frame.gpu.read_objects(self.ctx)?))
    }

    /// Runs warm-up and timed frames with [`FRAMES_IN_FLIGHT`] in flight. Returns, per timed
    /// frame, the GPU milliseconds of each timed interval (`rrf_renderer::frame::TIMED_PASSES`) and the
    /// CPU milliseconds from the frame's start to the next's.
    fn time_frames(&self, frame: &Frame, constants: &FrameConstants) -> Result<Stats> {
        let ctx = self.ctx;
        let frames = self.args.frames as usize;
        let mut ring = FrameLoop::new(ctx, TIMESTAMPS)?;
        let timed = (|| -> Result<_> {
            let mut stats = Stats::default();
            // The last FRAMES_IN_FLIGHT frames only deliver the timestamps of the ones before.
            for i in 0..WARM_UP + frames + FRAMES_IN_FLIGHT {
                let stamps = ring.begin(ctx)?;
                stats.frame_started();
                let stamped_frame = i.checked_sub(FRAMES_IN_FLIGHT);
                if let (Some(stamps), Some(f)) = (stamps, stamped_frame) {
                    if f >= WARM_UP {
                        stats.add_timestamps(&stamps, self.period_ns);
                    }
                }
                frame.draw(ctx, &mut ring, None, constants, None, vec![], None)?;
            }
            // Interval k runs from frame k to frame k + 1: keep those of the timed frames.
            stats.frame_ms.truncate(WARM_UP + frames);
            stats.frame_ms.drain(..WARM_UP);
            Ok(stats)
        })();
        ring.destroy(ctx);
        timed
    }
}

fn print_row(row: &serde_json::Value, json: bool) {
    if json {
        println!("{row}");
        return;
    }
    let f = |key: &str| row[key].as_f64().unwrap_or_default();
    let s = |key: &str| row[key].as_str().unwrap_or_default().to_string();
    println!(
        "{} {} ({} frame, {} light{}) on {}, {}x{}, median of {} frames (set-up with the view's pipelines {:.0} ms):\n  \
         G-buffer {:.2} ms,{} network {:.2} ms, tonemap {:.2} ms; frame {:.2} ms (CPU, start to start, {} frames in flight)\n  \
         {:.1} M network-pixels/s ({:.1} GFLOP/s{}); {} image bytes per pixel",
        s("scene"),
        s("variant"),
        s("output"),
        row["lights"],
        if row["lights"].as_u64() == Some(1) { "" } else { "s" },
        s("device"),
        row["width"],
        row["height"],
        row["frames"],
        f("setup_ms"),
        f("gbuffer_ms"),
        row["mirrors_ms"].as_f64().map(|ms| format!(" mirrors {ms:.2} ms,")).unwrap_or_default(),
        f("network_ms"),
        f("tonemap_ms"),
        f("frame_ms"),
        FRAMES_IN_FLIGHT,
        f("network_pixels_per_s") / 1e6,
        f("network_gflops"),
        row["peak_fraction"].as_f64().map(|p| format!(", {:.1}% of peak", 100.0 * p)).unwrap_or_default(),
        row["bytes_per_pixel"],
    );
}

/// The network pass's cost of each light beyond the first, from the rows of one variant and
/// output at different light counts: the slope between the fewest and the most lights.
fn print_light_cost(rows: &[serde_json::Value], json: bool) {
    let point = |row: &serde_json::Value| (row["lights"].as_f64().unwrap_or(1.0), row["network_ms"].as_f64());
    let (Some(first), Some(last)) =
        (rows.iter().min_by_key(|r| r["lights"].as_u64()), rows.iter().max_by_key(|r| r["lights"].as_u64()))
    else {
        return;
    };
    let ((n0, Some(t0)), (n1, Some(t1))) = (point(first), point(last)) else { return };
    if n1 <= n0 {
        return;
    }
    let per_light = (t1 - t0) / (n1 - n0);
    if json {
        println!(
            "{}",
            json!({
                "variant": first["variant"],
                "output": first["output"],
                "lights_from": n0,
                "lights_to": n1,
                "network_ms_per_extra_light": per_light,
            })
        );
    } else {
        println!(
            "  {} ({} frame): network pass {:+.3} ms per light beyond the first ({} → {} lights: {:.2} → {:.2} ms)",
            first["variant"].as_str().unwrap_or_default(),
            first["output"].as_str().unwrap_or_default(),
            per_light,
            n0,
            n1,
            t0,
            t1
        );
    }
}
