//! `rrf render`: one frame from a baked model.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{bail, Result};
use clap::Args;
use rrf_baker::model::Model;
use rrf_baker::predict::predict_image;
use rrf_baker::scene::Scene;
use rrf_baker::trace::{Camera, Geometry, World};

use super::bake::default_model_path;
use super::view_args::{Component, ViewArgs};
use crate::image_out::write_image;

#[derive(Args, Debug)]
pub struct RenderArgs {
    #[command(flatten)]
    pub view: ViewArgs,
    /// Model file; default: model.safetensors in the scene's folder.
    #[arg(long)]
    pub model: Option<PathBuf>,
    /// Which light to show.
    #[arg(long, value_enum, default_value_t = Component::Gi)]
    pub component: Component,
    /// Evaluate the networks on the CPU with the baker's reference inference (primary hits
    /// by ray casting) instead of on the GPU.
    #[arg(long)]
    pub cpu: bool,
    /// Output: .exr (linear HDR) or .png (tonemapped).
    #[arg(short, long)]
    pub output: PathBuf,
}

pub fn run(args: &RenderArgs) -> Result<()> {
    if !args.cpu {
        bail!("the Vulkan network pass is not built yet; render on the CPU with --cpu");
    }
    let (width, height) = args.view.size()?;
    let scene = Scene::load(&args.view.scene)?;
    let model_path = args.model.clone().unwrap_or_else(|| default_model_path(&scene));
    let model = Model::load(&model_path, Some(&scene))?;
    for u in &model.metadata.untrained {
        eprintln!("warning: {} has no network ({}); it renders black", u.object, u.reason);
    }
    let view = args.view.resolve_view(&scene)?;
    let light = args.view.light_position(&scene)?;
    let geometry = Geometry::new(&scene);
    let world = World::new(&scene, &geometry, light);
    let camera = Camera::new(&view, width as f32 / height as f32);
    let start = Instant::now();
    let image = predict_image(&world, &camera, &model, width, height);
    let seconds = start.elapsed().as_secs_f64();
    let pixels = image.component(|r| args.component.pick(r));
    write_image(&args.output, width, height, &pixels, args.view.exposure)?;
    eprintln!("wrote {} ({width}x{height}, CPU inference, {:.0} ms)", args.output.display(), seconds * 1e3);
    Ok(())
}
