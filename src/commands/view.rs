//! `rrf view`: the interactive walkthrough, or a scripted run of it.

use std::path::PathBuf;
use std::sync::LazyLock;

use anyhow::{bail, Context as _, Result};
use clap::{Args, ValueEnum};
use rrf_renderer::{backend::swapchain, vk, Context, ContextOptions};

use super::image_args::named_view;
use super::scene_args::SceneArgs;
use super::variant::VariantArg;
use crate::direct_mode::DirectMode;
use crate::parse::parse_size;
use crate::viewer::controls::HELP_TEXT;
use crate::viewer::gpu::ViewerGpu;
use crate::viewer::panel::Panel;
use crate::viewer::script::Script;
use crate::viewer::startup::StartUp;
use crate::viewer::state::ViewerState;
use crate::viewer::{run_headless, window, RunPlan, Session};

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum PresentMode {
    /// Wait for vertical blank; no tearing (the default, offered everywhere).
    Fifo,
    /// Show the newest frame at vertical blank, replacing queued ones; no tearing.
    Mailbox,
    /// Show frames at once; may tear. For measuring frame rates above the display's.
    Immediate,
}

impl PresentMode {
    fn vk(self) -> vk::PresentModeKHR {
        match self {
            PresentMode::Fifo => vk::PresentModeKHR::FIFO,
            PresentMode::Mailbox => vk::PresentModeKHR::MAILBOX,
            PresentMode::Immediate => vk::PresentModeKHR::IMMEDIATE,
        }
    }
}

#[derive(Args, Debug)]
#[command(after_long_help = AFTER_HELP.as_str())]
pub struct ViewArgs {
    #[command(flatten)]
    pub input: SceneArgs,
    /// A named view to start from (see `rrf info SCENE`); default: the glTF camera.
    #[arg(long)]
    pub view: Option<String>,
    #[arg(long, help = crate::lights::LIGHT_HELP.as_str(), value_name = "POSITION[:color=R,G,B][:intensity=K]", allow_hyphen_values = true)]
    pub light: Vec<String>,
    /// Window size (or frame size when headless) in pixels, each side 1 to 16384.
    #[arg(long, default_value = "960x540", value_name = "WxH")]
    pub size: String,
    /// How the networks reach the shader (see `rrf render --help`).
    #[arg(long, value_enum, default_value_t = VariantArg::DEFAULT)]
    pub variant: VariantArg,
    /// Presentation mode; falls back to fifo where the display does not offer it.
    #[arg(long, value_enum, default_value_t = PresentMode::Fifo)]
    pub present_mode: PresentMode,
    /// Run this many frames, then exit (script time: 1/60 s per frame).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..=100_000_000))]
    pub frames: Option<u64>,
    /// Save the last frame to this PNG (with --frames or --script, or when headless).
    #[arg(long, value_name = "FILE.png")]
    pub screenshot: Option<PathBuf>,
    /// Save every frame to this folder as frame-00000.png, frame-00001.png, … (for a video:
    /// see the README).
    #[arg(long, value_name = "DIR")]
    pub record: Option<PathBuf>,
    /// Play a script of timed events (format below), then exit.
    #[arg(long, value_name = "FILE")]
    pub script: Option<PathBuf>,
    /// At exit, print frames, median and 99th-percentile frame time, GPU milliseconds per pass,
    /// peak memory and start-up seconds per phase, as one line of JSON on stdout.
    #[arg(long)]
    pub stats: bool,
    /// Start with the overlay hidden (O toggles it).
    #[arg(long)]
    pub no_overlay: bool,
    /// Show the settings panel (lights, exposure, component, trained boxes, GPU time) even in
    /// a run that ends by itself, where it is hidden by default. U toggles it.
    #[arg(long, conflicts_with = "no_panel")]
    pub panel: bool,
    /// Start with the settings panel hidden in an interactive window.
    #[arg(long)]
    pub no_panel: bool,
    /// Start with automatic exposure: the exposure follows the frame's median brightness.
    #[arg(long)]
    pub auto_exposure: bool,
    /// Render without a window even when a display is available.
    #[arg(long)]
    pub headless: bool,
}

/// `rrf view --help`'s text after the flags: the controls, the script format, headless runs.
static AFTER_HELP: LazyLock<String> =
    LazyLock::new(|| format!("Controls (H shows them in the window):\n{}\n{SCRIPT_HELP}", *HELP_TEXT));

const SCRIPT_HELP: &str = "\
Script format (--script): one event per line, TIME COMMAND ARGUMENTS, TIME in seconds of script
time, which advances by 1/60 s per frame whatever the frame rate; # starts a comment.
  camera X,Y,Z X,Y,Z [over S]    eye and target; with `over`, move there in S seconds
  light X,Y,Z [over S]           the selected light (kept inside its trained box)
  add-light X,Y,Z[:color=R,G,B][:intensity=K]   add a light and select it
  select-light N                 select light N (from 1)
  remove-light                   remove the selected light (not the last)
  light-color R,G,B [intensity K]   the selected light's colour (each 0 to 1) and intensity
  component gi|direct|indirect   which light is shown
  direct learned|analytic        where direct light comes from (the frame is made again)
  exposure EV|auto               exposure in stops, or automatic
  resize WxH                     window (or headless frame) size in pixels
  screenshot FILE.png            save the frame as shown
  overlay on|off                 show or hide the overlay
  panel on|off                   show or hide the settings panel
  boxes on|off                   outline the light's and the camera's trained boxes
  quit                           end here (otherwise one frame after the last event)
scenes/NAME/demo.txt is a demo script for each shipped scene.

Without a display (no DISPLAY or WAYLAND_DISPLAY), or with --headless, frames are rendered
without a window; with neither --frames nor --script, one frame is saved to --screenshot
(default view.png).";

pub fn run(args: &ViewArgs) -> Result<()> {
    let mut startup = StartUp::start();
    let size = parse_size(&args.size)?;
    let script = args.script.as_deref().map(Script::load).transpose()?;
    if let Some(path) = &args.screenshot {
        if !path.to_string_lossy().to_ascii_lowercase().ends_with(".png") {
            bail!("--screenshot {}: the file must end in .png", path.display());
        }
    }
    let (scene, model) = args.input.load()?;
    startup.phase("scene and model");
    let view = named_view(&scene, args.view.as_deref())?;
    let lights = crate::lights::lights_from_args(&scene, &args.light)?;
    let direct = args.input.direct.resolve(&scene, Some(args.variant.0));
    direct.check(&scene, &model)?;
    let mut state = ViewerState::new(&scene, view, lights);
    state.overlay = !args.no_overlay;
    state.direct = direct;
    if let Some(dir) = &args.record {
        std::fs::create_dir_all(dir).with_context(|| format!("--record: cannot create {}", dir.display()))?;
    }
    let mut plan =
        RunPlan { script, frames: args.frames, screenshot: args.screenshot.clone(), record: args.record.clone() };

    let no_display = std::env::var_os("DISPLAY").is_none() && std::env::var_os("WAYLAND_DISPLAY").is_none();
    let event_loop = if args.headless || no_display {
        None
    } else {
        match window::event_loop() {
            Ok(event_loop) => Some(event_loop),
            Err(e) => {
                eprintln!("warning: {e:#}");
                None
            }
        }
    };
    if event_loop.is_none() && !args.headless {
        eprintln!(
            "no display to open a window on (DISPLAY and WAYLAND_DISPLAY are unset or unusable); rendering headless"
        );
    }
    if event_loop.is_some() && !plan.scripted() && plan.screenshot.is_some() {
        bail!("--screenshot saves the last frame of a run that ends by itself: add --frames N or --script FILE (in the window, P saves a screenshot)");
    }
    if event_loop.is_none() && !plan.scripted() {
        // One picture of the scene: an overlay of one frame's statistics would say nothing.
        plan.frames = Some(1);
        plan.screenshot.get_or_insert_with(|| PathBuf::from("view.png"));
        state.overlay = false;
    }

    let mut options = ContextOptions::from_env();
    if let Some(event_loop) = &event_loop {
        options.instance_extensions = window::instance_extensions(event_loop)?;
        options.device_extensions = swapchain::DEVICE_EXTENSIONS.to_vec();
    }
    let ctx = Context::new(&options).context("cannot start Vulkan (`rrf info` says more)")?;
    startup.phase("Vulkan");
    let extent = vk::Extent2D { width: size.0, height: size.1 };
    eprintln!("{} on {} ({} network pass)", scene.name, ctx.info.name, args.variant.0.name());
    let title = format!("rrf view: {}", scene.name);
    let mut gpu = ViewerGpu::new(ctx, scene, model, (args.variant.0, direct), extent)?;
    startup.phase("frame set-up");
    state.direct_choices = [DirectMode::Learned, DirectMode::Analytic]
        .into_iter()
        .map(|mode| (mode, gpu.direct_allowed(mode).map_err(|e| format!("{e:#}"))))
        .collect();
    let panel_shown = args.panel || (event_loop.is_some() && !plan.scripted() && !args.no_panel);
    // The panel names the keys; the overlay's list of them starts hidden beside it.
    state.help = !panel_shown;
    state.auto_exposure = args.auto_exposure;
    let panel = Panel::new(panel_shown);
    let mut session = Session::new(state, panel, plan, startup);
    let ran = match event_loop {
        Some(event_loop) => window::run(event_loop, &mut gpu, &mut session, title, size, args.present_mode.vk()),
        None => run_headless(&mut gpu, &mut session),
    };
    let summary = session.summary();
    let finished = gpu.finish();
    ran?;
    finished?;
    if args.stats {
        println!("{summary}");
    }
    Ok(())
}
