//! A window's presentation: its surface and a swapchain fitted to the window's size, the
//! swapchain image a frame draws to, and the passes that blit the frame there and hand it to
//! presentation.

use ash::vk;

use crate::backend::context::Context;
use crate::backend::frames::FrameLoop;
use crate::backend::resources::Image;
use crate::backend::swapchain::{Surface, Swapchain};
use crate::backend::sync::{Access, Pass, Resource, Use};
use crate::error::{Result, VkContext};

/// A window's surface and its swapchain, remade when the window's size changes.
pub struct Presenter {
    surface: Option<Surface>,
    swapchain: Option<Swapchain>,
    present_mode: vk::PresentModeKHR,
    /// Set when acquisition or presentation says the swapchain no longer fits the surface.
    stale: bool,
}

/// The swapchain image one frame draws to.
#[derive(Clone, Copy, Debug)]
pub struct PresentTarget {
    index: u32,
    pub image: vk::Image,
    pub extent: vk::Extent2D,
    /// Signalled by the frame's submission, waited on by its presentation.
    pub rendered: vk::Semaphore,
}

impl Presenter {
    pub fn new(surface: Surface, present_mode: vk::PresentModeKHR) -> Self {
        Presenter { surface: Some(surface), swapchain: None, present_mode, stale: true }
    }

    /// Fits the swapchain to the window's `size` (in pixels), after the frames of `ring` and
    /// presentation have finished with the old one. Returns the swapchain's extent, which
    /// may differ from `size`, or `None` when there is nothing to draw to (a minimised
    /// window).
    pub fn fit(&mut self, ctx: &Context, ring: &mut FrameLoop, size: (u32, u32)) -> Result<Option<vk::Extent2D>> {
        if size.0 == 0 || size.1 == 0 {
            return Ok(None);
        }
        let wanted = vk::Extent2D { width: size.0, height: size.1 };
        if let Some(s) = self.swapchain.as_ref().filter(|s| s.extent == wanted && !self.stale) {
            return Ok(Some(s.extent));
        }
        // Presentation may still wait on the old swapchain's semaphores.
        wait_for_presentation(ctx, ring)?;
        let surface = self.surface.as_ref().expect("live until destroy");
        let old = self.swapchain.take();
        let new = Swapchain::new(ctx, surface, wanted, self.present_mode, old.as_ref());
        if let Some(old) = old {
            old.destroy(ctx);
        }
        let new = new?;
        if new.extent.width == 0 || new.extent.height == 0 {
            new.destroy(ctx);
            return Ok(None);
        }
        if new.present_mode != self.present_mode {
            eprintln!(
                "warning: the display does not offer present mode {:?}; using {:?}",
                self.present_mode, new.present_mode
            );
            self.present_mode = new.present_mode;
        }
        let extent = new.extent;
        self.swapchain = Some(new);
        self.stale = false;
        Ok(Some(extent))
    }

    /// The next swapchain image, which may be written once `ready` is signalled; `None` (and
    /// the swapchain marked for [`Presenter::fit`]) when the swapchain no longer fits.
    pub fn acquire(&mut self, ready: vk::Semaphore) -> Result<Option<PresentTarget>> {
        let swapchain = self.swapchain.as_ref().ok_or_else(no_swapchain)?;
        let Some(index) = swapchain.acquire(ready)? else {
            self.stale = true;
            return Ok(None);
        };
        Ok(Some(PresentTarget {
            index,
            image: swapchain.images[index as usize],
            extent: swapchain.extent,
            rendered: swapchain.render_done(index),
        }))
    }

    /// Blits `ldr` to `target` and hands it to presentation.
    pub fn present_passes<'a>(&self, ctx: &'a Context, ldr: &'a Image, target: &PresentTarget) -> [Pass<'a>; 2] {
        let (image, extent) = (target.image, target.extent);
        let resource = Resource::Image { raw: image, aspect: vk::ImageAspectFlags::COLOR, texel_bytes: 4 };
        let uses = vec![Use::image(ldr, Access::TRANSFER_READ), Use { resource, access: Access::TRANSFER_WRITE }];
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
        let present = Pass::new("to presentation", vec![Use { resource, access: Access::PRESENT }], |_| {});
        [blit, present]
    }

    /// Presents `target` once its frame has signalled `rendered`; marks the swapchain for
    /// [`Presenter::fit`] when it no longer fits.
    pub fn present(&mut self, ctx: &Context, target: &PresentTarget) -> Result<()> {
        let swapchain = self.swapchain.as_ref().ok_or_else(no_swapchain)?;
        if !swapchain.present(ctx, target.index)? {
            self.stale = true;
        }
        Ok(())
    }

    /// Waits for every frame of `ring` and for presentation, then destroys the swapchain and
    /// the surface.
    pub fn retire(mut self, ctx: &Context, ring: &mut FrameLoop) -> Result<()> {
        let waited = wait_for_presentation(ctx, ring);
        if let Some(s) = self.swapchain.take() {
            s.destroy(ctx);
        }
        if let Some(s) = self.surface.take() {
            s.destroy();
        }
        waited
    }
}

fn no_swapchain() -> crate::error::Error {
    crate::error::Error::Invalid("no swapchain: call Presenter::fit first".into())
}

/// Waits for every frame in flight and for the queue, presentations included.
fn wait_for_presentation(ctx: &Context, ring: &mut FrameLoop) -> Result<()> {
    ring.wait_all(ctx)?;
    // SAFETY: waiting on the context's own queue, used from this thread only.
    unsafe { ctx.device.queue_wait_idle(ctx.queue) }.vk("vkQueueWaitIdle")
}
