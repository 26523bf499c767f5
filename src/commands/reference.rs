//! `rrf reference`: path-traced ground truth, by component.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Result;
use clap::Args;
use rrf_baker::scene::Scene;
use rrf_baker::trace::{render, Camera, Geometry, RenderSettings, TraceSettings, World};
use serde_json::json;

use super::image_args::{ImageArgs, PixelFootprint, RadianceTerm};
use crate::image_out::{check_output, write_image};
use crate::progress::Progress;

#[derive(Args, Debug)]
pub struct ReferenceArgs {
    #[arg(help = super::SCENE_HELP)]
    pub scene: PathBuf,
    #[command(flatten)]
    pub image: ImageArgs,
    /// Samples (paths) per pixel, 1 to 1,048,576.
    #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u32).range(1..=1 << 20))]
    pub spp: u32,
    /// Longest path in segments from the camera, 1 to 1024: 1 shows emitters only, 2 adds
    /// direct light.
    #[arg(long, default_value_t = 8, value_parser = clap::value_parser!(u32).range(1..=1024))]
    pub max_depth: u32,
    /// Russian roulette from this many segments on, up to 1024; 0 turns it off.
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(0..=1024))]
    pub rr_depth: u32,
    /// Which light to show.
    #[arg(long, value_enum, default_value_t = RadianceTerm::Gi)]
    pub component: RadianceTerm,
    /// Random seed, any 64-bit integer: the same seed gives the same image.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Where in its pixel each path starts: `area` (antialiased) or `centre` (the ray the
    /// renderer's G-buffer samples; what `rrf eval` scores against).
    #[arg(long, value_enum, default_value_t = PixelFootprint::Area)]
    pub footprint: PixelFootprint,
    /// Output: .exr (linear HDR) or .png (tonemapped).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Print one line of JSON with timings and throughput.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: &ReferenceArgs) -> Result<()> {
    let (width, height) = args.image.size()?;
    check_output(&args.output)?;
    let scene = Scene::load(&args.scene)?;
    for warning in &scene.warnings {
        eprintln!("warning: {warning}");
    }
    let view = args.image.resolve_view(&scene)?;
    let lights = args.image.lights(&scene)?;
    let geometry = Geometry::new(&scene);
    let world = World::with_lights(&scene, &geometry, &lights);
    let camera = Camera::new(&view, width as f32 / height as f32);
    let settings = RenderSettings {
        width,
        height,
        spp: args.spp,
        trace: TraceSettings { max_depth: args.max_depth, rr_depth: (args.rr_depth > 0).then_some(args.rr_depth) },
        seed: args.seed,
        footprint: args.footprint.into(),
    };

    let progress = Progress::new(u64::from(width) * u64::from(height), "path tracing", args.json);
    let start = Instant::now();
    let image = render(&world, &camera, &settings, &|n| progress.inc(n));
    let seconds = start.elapsed().as_secs_f64();
    progress.finish();

    let pixels = image.component(|r| args.component.pick(r));
    write_image(&args.output, width, height, &pixels, args.image.exposure)?;
    let paths = u64::from(width) * u64::from(height) * u64::from(args.spp);
    let summary = json!({
        "scene": scene.name,
        "view": view.name,
        "output": args.output,
        "width": width,
        "height": height,
        "spp": args.spp,
        "max_depth": args.max_depth,
        "component": format!("{:?}", args.component).to_lowercase(),
        "seed": args.seed,
        "footprint": args.footprint.name(),
        "paths": paths,
        "seconds": seconds,
        "paths_per_s": paths as f64 / seconds,
        "threads": rayon_threads(),
    });
    if args.json {
        println!("{summary}");
    } else {
        eprintln!(
            "wrote {} ({width}x{height}, {} spp) in {seconds:.2} s, {:.2} M paths/s",
            args.output.display(),
            args.spp,
            paths as f64 / seconds / 1e6
        );
    }
    Ok(())
}

fn rayon_threads() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}
