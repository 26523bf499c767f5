//! The viewer's GPU side: one [`GpuFrame`], frames in flight, and, in a window, the
//! swapchain the frame is blitted to.

use std::cell::RefCell;
use std::path::PathBuf;
use std::rc::Rc;

use anyhow::{Context as _, Result};
use rrf_baker::model::Model;
use rrf_baker::scene::Scene;
use rrf_renderer::backend::frames::FrameLoop;
use rrf_renderer::backend::swapchain::{Surface, Swapchain};
use rrf_renderer::backend::sync::read_back_passes;
use rrf_renderer::backend::sync::{Access, Pass, Resource, Use};
use rrf_renderer::passes::network::Variant;
use rrf_renderer::{vk, Context, Image};

use super::state::ViewerState;
use crate::frame_stats::Stats;
use crate::gpu_frame::{Direct, FrameOutput, GpuFrame, TIMESTAMPS};
use rrf_baker::atomic_file::write_atomically;

/// A window's surface and its swapchain, remade when the window's size changes.
pub struct Presenter {
    surface: Option<Surface>,
    swapchain: Option<Swapchain>,
    present_mode: vk::PresentModeKHR,
    /// Set when presentation says the swapchain no longer fits the surface.
    stale: bool,
}

impl Presenter {
    pub fn new(surface: Surface, present_mode: vk::PresentModeKHR) -> Self {
        Presenter { surface: Some(surface), swapchain: None, present_mode, stale: true }
    }

    /// Destroys the swapchain and the surface; no frame may be pending.
    pub fn destroy(mut self, ctx: &Context) {
        if let Some(s) = self.swapchain.take() {
            s.destroy(ctx);
        }
        if let Some(s) = self.surface.take() {
            s.destroy();
        }
    }
}

pub struct Renderer {
    pub ctx: Context,
    frame: Option<GpuFrame>,
    ring: Option<FrameLoop>,
    /// Nanoseconds per timestamp tick; `None` when the queue cannot write timestamps.
    period_ns: Option<f64>,
    /// Screenshots are written once their frame has finished, from the deletion queue; their
    /// outcome lands here.
    saved: Rc<RefCell<Vec<Result<PathBuf>>>>,
}

impl Renderer {
    /// The frame for `scene` at `extent`, with frames in flight.
    pub fn new(
        ctx: Context,
        scene: &Scene,
        model: &Model,
        (variant, direct): (Variant, Direct),
        extent: vk::Extent2D,
    ) -> Result<Self> {
        let frame = ctx.guard(GpuFrame::new(&ctx, scene, model, variant, extent, FrameOutput::Display, direct)?);
        let ring = FrameLoop::new(&ctx, TIMESTAMPS)?;
        let frame = frame.keep();
        let period_ns = ctx.info.limits.timestamp_period_ns.map(f64::from);
        Ok(Renderer { ctx, frame: Some(frame), ring: Some(ring), period_ns, saved: Rc::default() })
    }

    fn parts(&mut self) -> (&Context, &mut GpuFrame, &mut FrameLoop) {
        (&self.ctx, self.frame.as_mut().expect("live until finish"), self.ring.as_mut().expect("live until finish"))
    }

    pub fn extent(&self) -> vk::Extent2D {
        self.frame.as_ref().expect("live until finish").extent()
    }

    /// Makes the frame `extent` big, after the frames in flight have finished.
    pub fn resize(&mut self, extent: vk::Extent2D) -> Result<()> {
        if extent == self.extent() {
            return Ok(());
        }
        let (ctx, frame, ring) = self.parts();
        ring.wait_all(ctx)?;
        frame.resize(ctx, extent)
    }

    /// Screenshots written since the last call, or the errors that stopped them.
    pub fn take_saved(&self) -> Vec<Result<PathBuf>> {
        std::mem::take(&mut self.saved.borrow_mut())
    }

    /// Fits the presenter's swapchain to the window's `size` (in pixels) and the frame to the
    /// swapchain. Returns `false` when there is nothing to draw to (a minimised window).
    pub fn fit(&mut self, presenter: &mut Presenter, size: (u32, u32)) -> Result<bool> {
        if size.0 == 0 || size.1 == 0 {
            return Ok(false);
        }
        let wanted = vk::Extent2D { width: size.0, height: size.1 };
        let fits = presenter.swapchain.as_ref().is_some_and(|s| s.extent == wanted) && !presenter.stale;
        if !fits {
            // Presentation may still wait on the old swapchain's semaphores.
            self.wait_for_presentation()?;
            let ctx = &self.ctx;
            let surface = presenter.surface.as_ref().expect("live until destroy");
            let old = presenter.swapchain.take();
            let new = Swapchain::new(ctx, surface, wanted, presenter.present_mode, old.as_ref());
            if let Some(old) = old {
                old.destroy(ctx);
            }
            let new = new?;
            if new.extent.width == 0 || new.extent.height == 0 {
                new.destroy(ctx);
                return Ok(false);
            }
            if new.present_mode != presenter.present_mode {
                eprintln!(
                    "warning: the display does not offer present mode {:?}; using {:?}",
                    presenter.present_mode, new.present_mode
                );
                presenter.present_mode = new.present_mode;
            }
            let extent = new.extent;
            presenter.swapchain = Some(new);
            presenter.stale = false;
            self.resize(extent)?;
        }
        Ok(true)
    }

    /// Records and submits one frame of `state`; in a window, presents it. Also saves the frame
    /// as shown to each PNG of `screenshots`, once the GPU has finished it.
    pub fn draw(
        &mut self,
        state: &ViewerState,
        stats: &mut Stats,
        presenter: Option<&mut Presenter>,
        overlay_scale: u32,
        screenshots: Vec<PathBuf>,
    ) -> Result<()> {
        let period_ns = self.period_ns;
        let saved = self.saved.clone();
        let (ctx, frame, ring) = self.parts();
        let (handles, stamps) = ring.begin(ctx)?;
        stats.frame_started();
        if let (Some(stamps), Some(period)) = (stamps, period_ns) {
            stats.add_timestamps(&stamps, period);
        }
        let target = match presenter {
            Some(p) => {
                let swapchain = p.swapchain.as_ref().context("no swapchain: call fit first")?;
                match swapchain.acquire(handles.image_available)? {
                    Some(index) => Some((p, index)),
                    None => {
                        // The frame's commands are left unsubmitted; the slot's next begin
                        // resets them.
                        p.stale = true;
                        return Ok(());
                    }
                }
            }
            None => None,
        };
        let grid = state.overlay.then(|| state.overlay_text(stats, &ctx.info.name));
        let ldr = frame.ldr();
        let readback = match screenshots.is_empty() {
            false => Some(ctx.create_readback_buffer(ldr)?),
            true => None,
        };
        let mut extra: Vec<Pass> = Vec::new();
        if let Some(buffer) = &readback {
            extra.extend(read_back_passes(ctx, ldr, buffer));
        }
        if let Some((p, index)) = &target {
            let swapchain = p.swapchain.as_ref().expect("checked above");
            let image = swapchain.images[*index as usize];
            let resource = Resource::Image { raw: image, aspect: vk::ImageAspectFlags::COLOR, texel_bytes: 4 };
            // The submission waits for the acquire semaphore at the transfer stage.
            frame.states().arrive(resource, vk::PipelineStageFlags2::ALL_TRANSFER);
            extra.extend(present_passes(ctx, ldr, image, swapchain.extent));
        }
        let overlay = grid.as_ref().map(|g| (g, overlay_scale));
        frame.record(ctx, handles.cmd, &state.settings(), overlay, period_ns.map(|_| handles.queries), extra)?;
        let wait = target.as_ref().map(|_| handles.image_available);
        let signal = target.as_ref().map(|(p, i)| p.swapchain.as_ref().expect("checked above").render_done(*i));
        ring.submit(ctx, wait, signal, period_ns.is_some())?;
        if let Some(buffer) = readback {
            let extent = ldr.extent;
            ring.defer(Box::new(move |ctx: &Context| {
                match buffer.mapped() {
                    Some(rgba) => {
                        for path in screenshots {
                            let result = save_png(&path, extent, rgba).map(|()| path);
                            saved.borrow_mut().push(result);
                        }
                    }
                    None => saved.borrow_mut().push(Err(anyhow::anyhow!("the screenshot buffer is not host-visible"))),
                }
                ctx.destroy_buffer(buffer);
            }));
        }
        if let Some((p, index)) = target {
            if !p.swapchain.as_ref().expect("checked above").present(ctx, index)? {
                p.stale = true;
            }
        }
        Ok(())
    }

    /// Waits for every frame and for presentation, then destroys the presenter's swapchain
    /// and surface.
    pub fn retire(&mut self, presenter: Presenter) -> Result<()> {
        let waited = self.wait_for_presentation();
        presenter.destroy(&self.ctx);
        waited
    }

    /// Waits for every frame in flight and for the queue, presentations included.
    fn wait_for_presentation(&mut self) -> Result<()> {
        let (ctx, _, ring) = self.parts();
        ring.wait_all(ctx)?;
        // SAFETY: waiting on the context's own queue, used from this thread only.
        unsafe { ctx.device.queue_wait_idle(ctx.queue) }.context("vkQueueWaitIdle")
    }

    /// Waits for every frame, writes pending screenshots, and tears everything down. Returns
    /// the context's teardown report as an error if it is not clean.
    pub fn finish(mut self) -> Result<()> {
        let ring = self.ring.take().expect("live until finish");
        // Runs the deletion queue: screenshots of the last frames are written here.
        ring.destroy(&self.ctx);
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

/// Blits the display image to a swapchain image and hands it to presentation.
fn present_passes<'a>(ctx: &'a Context, ldr: &'a Image, image: vk::Image, extent: vk::Extent2D) -> [Pass<'a>; 2] {
    let target = Resource::Image { raw: image, aspect: vk::ImageAspectFlags::COLOR, texel_bytes: 4 };
    let uses = vec![Use::image(ldr, Access::TRANSFER_READ), Use { resource: target, access: Access::TRANSFER_WRITE }];
    let blit = Pass::new("blit to swapchain", uses, move |cmd| {
        let layers = vk::ImageSubresourceLayers {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            mip_level: 0,
            base_array_layer: 0,
            layer_count: 1,
        };
        let corner = |e: vk::Extent2D| vk::Offset3D { x: e.width as i32, y: e.height as i32, z: 1 };
        let region = vk::ImageBlit {
            src_subresource: layers,
            src_offsets: [vk::Offset3D::default(), corner(ldr.extent)],
            dst_subresource: layers,
            dst_offsets: [vk::Offset3D::default(), corner(extent)],
        };
        // SAFETY: `cmd` is recording; both images are in the layouts the barrier set.
        unsafe {
            ctx.device.cmd_blit_image(
                cmd,
                ldr.raw,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                image,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &[region],
                vk::Filter::NEAREST,
            )
        };
    });
    let present = Pass::new("to presentation", vec![Use { resource: target, access: Access::PRESENT }], |_| {});
    [blit, present]
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
