//! The viewer's GPU side: one [`SceneFrame`], the settings panel's UI pass, frames in flight,
//! and what is read back once a frame has finished: screenshots, the exposure meter.

use std::cell::{Cell, RefCell};
use std::path::PathBuf;
use std::rc::Rc;

use anyhow::{Context as _, Result};
use rrf_baker::atomic_file::write_atomically;
use rrf_baker::model::Model;
use rrf_baker::scene::Scene;
use rrf_renderer::backend::frames::{Deferred, FrameLoop};
use rrf_renderer::backend::present::Presenter;
use rrf_renderer::frame::{Drawn, FrameOutput, TIMESTAMPS};
use rrf_renderer::passes::network::Variant;
use rrf_renderer::passes::ui::{UiFrame, UiPass};
use rrf_renderer::{vk, Buffer, Context, Destroy};

use super::state::ViewerState;
use crate::direct_mode::DirectMode;
use crate::frame_stats::Stats;
use crate::scene_frame::SceneFrame;
use crate::shaders;

pub struct ViewerGpu {
    pub ctx: Context,
    /// What the frame is made from, to make it again with other direct light.
    scene: Scene,
    model: Model,
    direct: DirectMode,
    frame: Option<SceneFrame>,
    ui: Option<UiPass>,
    ring: Option<FrameLoop>,
    /// Nanoseconds per timestamp tick; `None` when the queue cannot write timestamps.
    period_ns: Option<f64>,
    /// Screenshots are written once their frame has finished, by work the frame loop defers
    /// until then; their outcome lands here.
    saved: Rc<RefCell<Vec<Result<PathBuf>>>>,
    /// The exposure change the last metered frame asks for ([`super::exposure`]).
    metered: Rc<Cell<Option<f32>>>,
}

impl ViewerGpu {
    /// The frame for `scene` at `extent`, with frames in flight.
    pub fn new(
        ctx: Context,
        scene: Scene,
        model: Model,
        (variant, direct): (Variant, DirectMode),
        extent: vk::Extent2D,
    ) -> Result<Self> {
        // Each part is destroyed again if a later one cannot be made.
        let frame = ctx.guard(SceneFrame::new(&ctx, &scene, &model, variant, extent, FrameOutput::Display, direct)?);
        let ui = ctx.guard(UiPass::new(&ctx, shaders::UI_VERT, shaders::UI_FRAG)?);
        let ring = FrameLoop::new(&ctx, TIMESTAMPS)?;
        let (frame, ui) = (frame.keep(), ui.keep());
        let period_ns = ctx.info.limits.timestamp_period_ns.map(f64::from);
        Ok(ViewerGpu {
            ctx,
            scene,
            model,
            direct,
            frame: Some(frame),
            ui: Some(ui),
            ring: Some(ring),
            period_ns,
            saved: Rc::default(),
            metered: Rc::default(),
        })
    }

    fn parts(&mut self) -> (&Context, &mut SceneFrame, &mut FrameLoop) {
        (&self.ctx, self.frame.as_mut().expect("live until finish"), self.ring.as_mut().expect("live until finish"))
    }

    /// Where the frame's direct light comes from.
    pub fn direct(&self) -> DirectMode {
        self.direct
    }

    /// Whether the frame can be made with direct light from `direct`: whether the scene, the
    /// model and the network pass allow it.
    pub fn direct_allowed(&self, direct: DirectMode) -> Result<()> {
        direct.check(&self.scene, &self.model)?;
        direct.check_variant(self.variant())
    }

    /// Makes the frame again with direct light from `direct`, after the frames in flight have
    /// finished. On failure the frame stays as it was.
    pub fn set_direct(&mut self, direct: DirectMode) -> Result<()> {
        self.direct_allowed(direct)?;
        let (variant, extent) = (self.variant(), self.extent());
        let ctx = &self.ctx;
        self.ring.as_mut().expect("live until finish").wait_all(ctx)?;
        let made = SceneFrame::new(ctx, &self.scene, &self.model, variant, extent, FrameOutput::Display, direct)?;
        let old = self.frame.replace(made).expect("live until finish");
        self.frame.as_ref().expect("just made").gpu.carry_states(&old.gpu);
        old.destroy(ctx);
        self.direct = direct;
        Ok(())
    }

    /// The exposure change in stops that the last metered frame asks for, once.
    pub fn take_metered(&self) -> Option<f32> {
        self.metered.take()
    }

    /// Whether the scene has mirrors, whose reflections frames draw.
    pub fn has_mirrors(&self) -> bool {
        self.frame.as_ref().expect("live until finish").has_mirrors()
    }

    /// Whether frames write timestamps, for GPU time per pass.
    pub fn timed(&self) -> bool {
        self.period_ns.is_some()
    }

    /// The largest texture side the device takes, for the panel's font atlas.
    pub fn max_texture_side(&self) -> usize {
        self.ctx.info.limits.max_image_dimension_2d as usize
    }

    pub fn variant(&self) -> Variant {
        self.frame.as_ref().expect("live until finish").gpu.variant()
    }

    pub fn extent(&self) -> vk::Extent2D {
        self.frame.as_ref().expect("live until finish").gpu.extent()
    }

    /// Makes the frame `extent` big, after the frames in flight have finished.
    pub fn resize(&mut self, extent: vk::Extent2D) -> Result<()> {
        if extent == self.extent() {
            return Ok(());
        }
        let (ctx, frame, ring) = self.parts();
        ring.wait_all(ctx)?;
        Ok(frame.gpu.resize(ctx, extent)?)
    }

    /// Waits until every frame drawn so far has finished.
    pub fn wait_idle(&mut self) -> Result<()> {
        let (ctx, _, ring) = self.parts();
        Ok(ring.wait_all(ctx)?)
    }

    /// Screenshots written since the last call, or the errors that stopped them.
    pub fn take_saved(&self) -> Vec<Result<PathBuf>> {
        std::mem::take(&mut self.saved.borrow_mut())
    }

    /// Fits the presenter's swapchain to the window's `size` (in pixels) and the frame to the
    /// swapchain. Returns `false` when there is nothing to draw to (a minimised window).
    pub fn fit(&mut self, presenter: &mut Presenter, size: (u32, u32)) -> Result<bool> {
        let (ctx, _, ring) = self.parts();
        match presenter.fit(ctx, ring, size)? {
            Some(extent) => self.resize(extent).map(|()| true),
            None => Ok(false),
        }
    }

    /// Draws one frame of `state` with the panel's `ui` over it (presented in a window, with
    /// a `presenter`), and saves it as shown to each PNG of `screenshots` once the GPU has
    /// finished it. With `meter`, measures the brightness of the frame's first `meter`
    /// columns for automatic exposure ([`ViewerGpu::take_metered`]).
    #[allow(clippy::too_many_arguments)]
    pub fn draw(
        &mut self,
        state: &ViewerState,
        stats: &mut Stats,
        presenter: Option<&mut Presenter>,
        overlay_scale: u32,
        ui: &UiFrame,
        screenshots: Vec<PathBuf>,
        meter: Option<u32>,
    ) -> Result<()> {
        let (period_ns, saved, metered) = (self.period_ns, self.saved.clone(), self.metered.clone());
        let ctx = &self.ctx;
        let frame = self.frame.as_mut().expect("live until finish");
        let ring = self.ring.as_mut().expect("live until finish");
        let ui_pass = self.ui.as_mut().expect("live until finish");
        let stamps = ring.begin(ctx)?;
        stats.frame_started();
        if let (Some(stamps), Some(period)) = (stamps, period_ns) {
            stats.add_timestamps(&stamps, period);
        }
        let constants = frame.constants(&state.settings());
        let reflected = frame.has_mirrors().then_some(constants.mirrors.len());
        let grid = state.overlay.then(|| state.overlay_text(stats, &ctx.info.name, reflected));
        let slot = ring.slot();
        for image in ui_pass.prepare(ctx, slot, ui, &mut || ring.wait_all(ctx))? {
            frame.gpu.forget(image);
        }
        let ldr = frame.gpu.ldr();
        let read_back = !screenshots.is_empty() || meter.is_some();
        let buffer = read_back.then(|| ctx.create_readback_buffer(ldr)).transpose()?;
        let overlay = grid.as_ref().map(|g| (g, overlay_scale));
        let ui_passes = ui_pass.passes(ctx, ldr, slot, ui)?;
        let drawn = frame.gpu.draw(ctx, ring, presenter, &constants, overlay, ui_passes, buffer.as_ref());
        if !matches!(drawn, Ok(Drawn::Skipped)) {
            let staging = ui_pass.submitted();
            ring.defer(Box::new(move |ctx: &Context| staging.destroy(ctx)));
        }
        match (buffer, &drawn) {
            (None, _) => {}
            (Some(buffer), Ok(Drawn::Submitted)) => {
                let meter = meter.map(|columns| (columns, metered));
                ring.defer(read_when_done(buffer, screenshots, meter, ldr.extent, saved))
            }
            // Never submitted: nothing uses it.
            (Some(buffer), Ok(Drawn::Skipped)) => ctx.destroy_buffer(buffer),
            // Maybe submitted: destroyed once the frame is done.
            (Some(buffer), Err(_)) => ring.defer(Box::new(move |ctx: &Context| ctx.destroy_buffer(buffer))),
        }
        drawn?;
        Ok(())
    }

    /// Waits for every frame and for presentation, then destroys the presenter's swapchain
    /// and surface.
    pub fn retire(&mut self, presenter: Presenter) -> Result<()> {
        let (ctx, _, ring) = self.parts();
        Ok(presenter.retire(ctx, ring)?)
    }

    /// Waits for every frame, writes pending screenshots, and tears everything down. Returns
    /// the context's teardown report as an error if it is not clean.
    pub fn finish(mut self) -> Result<()> {
        let ring = self.ring.take().expect("live until finish");
        // Runs the work deferred to the end of each frame: screenshots of the last frames.
        ring.destroy(&self.ctx);
        self.ui.take().destroy(&self.ctx);
        let saved = super::report_saved(&self);
        if let Some(frame) = self.frame.take() {
            frame.destroy(&self.ctx);
        }
        let report = self.ctx.finish();
        saved?;
        if !report.is_clean() {
            anyhow::bail!(
                "Vulkan reported {} validation messages (printed above); leaked {:?}",
                report.validation_messages,
                report.leaked
            );
        }
        Ok(())
    }
}

/// Work for the frame loop to do once the frame that copied its display image (`extent`) to
/// `buffer` has finished: write it to each of `paths` and report each outcome in `saved`;
/// with `meter`, put the exposure change it asks for there; and destroy the buffer.
fn read_when_done(
    buffer: Buffer,
    paths: Vec<PathBuf>,
    meter: Option<(u32, Rc<Cell<Option<f32>>>)>,
    extent: vk::Extent2D,
    saved: Rc<RefCell<Vec<Result<PathBuf>>>>,
) -> Deferred {
    Box::new(move |ctx: &Context| {
        for path in paths {
            let rgba = buffer.mapped().context("the screenshot buffer is not host-visible");
            saved.borrow_mut().push(rgba.and_then(|rgba| save_png(&path, extent, rgba)).map(|()| path));
        }
        if let (Some((columns, meter)), Some(rgba)) = (meter, buffer.mapped()) {
            let width = extent.width as usize;
            meter.set(Some(super::exposure::correction(rgba, width, columns as usize)));
        }
        ctx.destroy_buffer(buffer);
    })
}

/// Writes the RGBA8 pixels read back from the display image as an RGB PNG, through a
/// temporary file so that a failed write leaves no half-written image.
pub fn save_png(path: &std::path::Path, extent: vk::Extent2D, rgba: &[u8]) -> Result<()> {
    let rgb: Vec<u8> = rgba.chunks_exact(4).flat_map(|p| [p[0], p[1], p[2]]).collect();
    let image = image::RgbImage::from_raw(extent.width, extent.height, rgb).context("screenshot size mismatch")?;
    write_atomically(path, |tmp| {
        image
            .save_with_format(tmp, image::ImageFormat::Png)
            .with_context(|| format!("cannot write screenshot {}", path.display()))
    })
}
