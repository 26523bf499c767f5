//! `rrf render`: one frame from a baked model.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{bail, Result};
use clap::Args;
use rrf_baker::glam::Vec3;
use rrf_baker::model::Model;
use rrf_baker::predict::predict_image;
use rrf_baker::scene::{PlacedLight, Scene, View};
use rrf_baker::trace::{Camera, Geometry, World};
use rrf_renderer::frame::{FrameOutput, Shown};
use rrf_renderer::{vk, Context, ContextOptions};

use super::image_args::{ImageArgs, RadianceTerm};
use super::scene_args::SceneArgs;
use super::variant::VariantArg;
use crate::direct_mode::DirectMode;
use crate::image_out::{check_output, write_image};
use crate::scene_frame::{rgb, FrameSettings, SceneFrame};

#[derive(Args, Debug)]
pub struct RenderArgs {
    #[command(flatten)]
    pub input: SceneArgs,
    #[command(flatten)]
    pub image: ImageArgs,
    /// Which light to show.
    #[arg(long, value_enum, default_value_t = RadianceTerm::Gi)]
    pub component: RadianceTerm,
    /// How the networks reach the shader (GPU only).
    #[arg(long, value_enum, default_value_t = VariantArg::DEFAULT)]
    pub variant: VariantArg,
    /// Evaluate the networks on the CPU with the baker's reference inference (primary hits
    /// by ray casting) instead of on the Vulkan device (G-buffer pass, then network pass).
    #[arg(long)]
    pub cpu: bool,
    /// Output: .exr (linear HDR) or .png (tonemapped).
    #[arg(short, long)]
    pub output: PathBuf,
}

pub fn run(args: &RenderArgs) -> Result<()> {
    let (width, height) = args.image.size()?;
    check_output(&args.output)?;
    let (scene, model) = args.input.load()?;
    let view = args.image.resolve_view(&scene)?;
    let lights = args.image.lights(&scene)?;
    let direct = args.input.direct.resolve(&scene, (!args.cpu).then_some(args.variant.0));
    direct.check(&scene, &model)?;
    let start = Instant::now();
    let (pixels, how) = if args.cpu {
        let geometry = Geometry::new(&scene);
        let world = World::with_lights(&scene, &geometry, &lights);
        let camera = Camera::new(&view, width as f32 / height as f32);
        let image = predict_image(&world, &camera, &model, (width, height), direct.cpu(&scene));
        (image.component(|r| args.component.pick(r)), "CPU inference".to_string())
    } else {
        let target = GpuTarget { variant: args.variant, direct, size: (width, height) };
        gpu_render(&scene, &model, &target, &view, lights, args.component)?
    };
    let seconds = start.elapsed().as_secs_f64();
    write_image(&args.output, width, height, &pixels, args.image.exposure)?;
    eprintln!("wrote {} ({width}x{height}, {how}, {:.0} ms)", args.output.display(), seconds * 1e3);
    Ok(())
}

/// How a frame is made on the Vulkan device, and its size.
struct GpuTarget {
    variant: VariantArg,
    direct: DirectMode,
    size: (u32, u32),
}

/// Renders on the Vulkan device; returns the pixels and which device did it.
fn gpu_render(
    scene: &Scene,
    model: &Model,
    target: &GpuTarget,
    view: &View,
    lights: Vec<PlacedLight>,
    component: RadianceTerm,
) -> Result<(Vec<Vec3>, String)> {
    let (variant, (width, height)) = (target.variant, target.size);
    let ctx = Context::new(&ContextOptions::from_env())?;
    let extent = vk::Extent2D { width, height };
    let frame = SceneFrame::new(&ctx, scene, model, variant.0, extent, FrameOutput::Radiance, target.direct)?;
    let settings = FrameSettings { view: view.clone(), lights, exposure_scale: 1.0, shown: Shown::Gi };
    let rendered = frame.render(&ctx, &settings);
    frame.destroy(&ctx);
    let device = format!("{}, {} network pass", ctx.info.name, variant.0.name());
    let report = ctx.finish();
    if !report.is_clean() {
        bail!(
            "Vulkan reported {} validation messages (printed above); leaked {:?}",
            report.validation_messages,
            report.leaked
        );
    }
    let rendered = rendered?;
    let rgba = match component {
        RadianceTerm::Gi => &rendered.gi,
        RadianceTerm::Direct => &rendered.direct,
        RadianceTerm::Indirect => &rendered.indirect,
        RadianceTerm::Emitted => bail!("--component emitted is only available from `rrf reference`"),
    };
    Ok((rgb(rgba), device))
}
