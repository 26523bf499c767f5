//! `rrf view`: the interactive walkthrough, in a window (winit) or headless, driven by the
//! keyboard and mouse or by a script.

pub mod controls;
pub mod exposure;
pub mod gpu;
pub mod panel;
pub mod script;
pub mod startup;
pub mod state;
pub mod window;

use std::collections::HashSet;
use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context as _, Result};

use crate::frame_stats::Stats;
use crate::gpu_scene::gbuffer_constants;
use gpu::ViewerGpu;
use panel::{FrameFacts, Panel};
use rrf_renderer::backend::present::Presenter;
use rrf_renderer::passes::network::Variant;
use script::{Action, Script, FRAME_SECONDS};
use startup::StartUp;
use state::{Held, ViewerState};

/// How a run ends and what it saves.
#[derive(Clone, Debug, Default)]
pub struct RunPlan {
    /// Events to play; none for an interactive run.
    pub script: Option<Script>,
    /// Frames to run; `None`: until the window closes (or the script ends).
    pub frames: Option<u64>,
    /// Where to save the last frame.
    pub screenshot: Option<PathBuf>,
    /// A folder to save every frame to, as `frame-00000.png` and on (for videos).
    pub record: Option<PathBuf>,
}

impl RunPlan {
    /// Whether time is script time (a fixed step per frame) rather than the wall clock, and
    /// the run ends by itself.
    pub fn scripted(&self) -> bool {
        self.script.is_some() || self.frames.is_some()
    }

    /// The frames the run lasts, if it ends by itself.
    fn last_frame(&self) -> Option<u64> {
        match (&self.script, self.frames) {
            (_, Some(n)) => Some(n),
            (Some(s), None) => Some(s.frames()),
            (None, None) => None,
        }
    }
}

/// What the session wants the window to do after a frame.
#[derive(Default)]
pub struct Requests {
    pub resize: Option<(u32, u32)>,
    pub quit: bool,
    /// What the panel asks of the window (the cursor's shape).
    pub platform: Option<egui::PlatformOutput>,
}

/// Frames between two readings of the automatic exposure's meter.
const METER_FRAMES: u64 = 4;

/// A viewer run, apart from the window: the state, input, script and statistics, and the
/// frame counter.
pub struct Session {
    pub state: ViewerState,
    pub panel: Panel,
    pub stats: Stats,
    pub held: HashSet<Held>,
    plan: RunPlan,
    /// Frames drawn so far.
    pub frame: u64,
    last_tick: Option<Instant>,
    /// A screenshot asked for by a key, taken with the next frame.
    pending_screenshot: Option<PathBuf>,
    screenshots_taken: u32,
    /// Start-up so far; the first frame ends it.
    startup: StartUp,
    /// Whether a frame with several lights was drawn.
    drew_several_lights: bool,
}

impl Session {
    pub fn new(state: ViewerState, panel: Panel, plan: RunPlan, startup: StartUp) -> Self {
        Session {
            state,
            panel,
            stats: Stats::default(),
            held: HashSet::new(),
            plan,
            frame: 0,
            last_tick: None,
            pending_screenshot: None,
            screenshots_taken: 0,
            startup,
            drew_several_lights: false,
        }
    }

    /// Asks for a screenshot with the next frame, to a new numbered file in the current
    /// folder.
    pub fn screenshot_key(&mut self) {
        self.screenshots_taken += 1;
        self.pending_screenshot = Some(PathBuf::from(format!("rrf-screenshot-{:03}.png", self.screenshots_taken)));
    }

    /// Advances time, plays the frame's script events, runs the panel on the window's `input`
    /// (none headless), and draws the frame. Returns what the window should do next.
    pub fn step(
        &mut self,
        gpu: &mut ViewerGpu,
        presenter: Option<&mut Presenter>,
        overlay_scale: u32,
        input: Option<egui::RawInput>,
    ) -> Result<Requests> {
        let mut requests = Requests::default();
        let (dt, t) = if self.plan.scripted() {
            (FRAME_SECONDS, self.frame as f64 * FRAME_SECONDS)
        } else {
            let now = Instant::now();
            let dt = self.last_tick.replace(now).map_or(0.0, |last| (now - last).as_secs_f64().min(0.25));
            (dt, self.frame as f64 * FRAME_SECONDS)
        };
        let mut screenshots: Vec<PathBuf> = self.pending_screenshot.take().into_iter().collect();
        if let Some(dir) = &self.plan.record {
            screenshots.push(dir.join(format!("frame-{:05}.png", self.frame)));
        }
        if let Some(script) = &self.plan.script {
            for event in script.due(self.frame) {
                match &event.action {
                    Action::Resize(w, h) => requests.resize = Some((*w, *h)),
                    Action::Screenshot(path) => screenshots.push(path.clone()),
                    Action::Quit => requests.quit = true,
                    Action::Panel(on) => self.panel.shown = *on,
                    Action::Boxes(on) => self.panel.boxes = *on,
                    action => {
                        self.state.apply(action, t).with_context(|| format!("script event at {} s", event.time))?
                    }
                }
            }
        }
        self.state.update(&self.held, dt as f32, t);
        // The panel after the frame's moves, so that its outlines are of the view it draws.
        let extent = gpu.extent();
        let input = input.unwrap_or_else(|| headless_input(extent, t, gpu.max_texture_side()));
        let ppp = extent.width as f32 / input.screen_rect.map_or(extent.width as f32, |r| r.width()).max(1.0);
        let aspect = extent.width as f32 / extent.height as f32;
        let facts = FrameFacts {
            view_projection: gbuffer_constants(&self.state.view(), aspect, None).view_projection,
            timed: gpu.timed(),
            mirrors: gpu.has_mirrors(),
        };
        let (ui, platform) = self.panel.run(input, &mut self.state, &self.stats, &facts);
        requests.platform = Some(platform);
        if let (true, Some(stops)) = (self.state.auto_exposure, gpu.take_metered()) {
            self.state.exposure_step(stops);
        }
        if self.state.direct != gpu.direct() {
            // Remakes the frame: its network pipelines are made again as they come into view.
            if let Err(e) = gpu.set_direct(self.state.direct) {
                self.state.light_note = Some(format!("{e:#}"));
                self.state.direct = gpu.direct();
            }
        }
        // The meter reads the columns left of the panel.
        let meter = (self.state.auto_exposure && self.frame.is_multiple_of(METER_FRAMES))
            .then(|| (self.panel.left_edge() * ppp).round().clamp(1.0, extent.width as f32) as u32);
        let last = self.plan.last_frame().is_some_and(|n| self.frame + 1 >= n);
        if let (true, Some(path)) = (last, &self.plan.screenshot) {
            screenshots.push(path.clone());
        }
        if self.state.lights.len() > 1 && !std::mem::replace(&mut self.drew_several_lights, true) {
            // The pause that follows would otherwise look like a hang (BENCHMARKS.md, "Start-up
            // and memory").
            if gpu.variant() != Variant::Storage {
                eprintln!("first frame with several lights: making their network pipelines (once)");
            }
        }
        gpu.draw(&self.state, &mut self.stats, presenter, overlay_scale, &ui, screenshots, meter)?;
        if self.frame == 0 {
            // Once: start-up ends when the first frame is finished, not when it is submitted.
            gpu.wait_idle()?;
            self.startup.phase("first frame");
            eprintln!("{}", self.startup.line());
        }
        self.frame += 1;
        report_saved(gpu)?;
        requests.quit |= last;
        Ok(requests)
    }

    /// Whether the run is scripted or counted, so that it must go on even while unseen.
    pub fn ends_by_itself(&self) -> bool {
        self.plan.scripted()
    }

    /// The `--stats` summary.
    pub fn summary(&self) -> serde_json::Value {
        let mut summary = self.stats.summary(self.frame);
        summary["start_s"] = self.startup.json();
        summary
    }
}

/// Prints the screenshots written since the last call; fails on one that could not be.
pub fn report_saved(gpu: &ViewerGpu) -> Result<()> {
    for saved in gpu.take_saved() {
        eprintln!("saved screenshot {}", saved?.display());
    }
    Ok(())
}

/// The panel's input without a window: no events, a screen of the frame's size (one point a
/// pixel), and script time.
fn headless_input(extent: rrf_renderer::vk::Extent2D, t: f64, max_texture_side: usize) -> egui::RawInput {
    let size = egui::vec2(extent.width as f32, extent.height as f32);
    egui::RawInput {
        screen_rect: Some(egui::Rect::from_min_size(egui::Pos2::ZERO, size)),
        time: Some(t),
        max_texture_side: Some(max_texture_side),
        ..Default::default()
    }
}

/// Runs a session without a window: frames go to the display image only (screenshots read it).
pub fn run_headless(gpu: &mut ViewerGpu, session: &mut Session) -> Result<()> {
    loop {
        let requests = session.step(gpu, None, 1, None)?;
        if let Some((w, h)) = requests.resize {
            gpu.resize(rrf_renderer::vk::Extent2D { width: w, height: h })?;
        }
        if requests.quit {
            return Ok(());
        }
    }
}
