//! A window's surface and swapchain. The frame is drawn into an image of its own and blitted
//! to the swapchain image, so the swapchain needs only transfer-destination usage, which every
//! driver offers, and the blit converts between RGBA and BGRA.

use std::ffi::CStr;

use ash::vk;
use raw_window_handle::{RawDisplayHandle, RawWindowHandle};

use crate::backend::context::Context;
use crate::error::{Error, Result, VkContext};

/// Instance extensions that a surface for `display` needs.
pub fn required_instance_extensions(display: RawDisplayHandle) -> Result<Vec<&'static CStr>> {
    let names = ash_window::enumerate_required_extensions(display).vk("enumerate_required_extensions")?;
    // SAFETY: ash-window returns pointers to static NUL-terminated extension names.
    Ok(names.iter().map(|&p| unsafe { CStr::from_ptr(p) }).collect())
}

/// The device extensions a swapchain needs.
pub const DEVICE_EXTENSIONS: &[&CStr] = &[ash::khr::swapchain::NAME];

pub struct Surface {
    loader: ash::khr::surface::Instance,
    pub raw: vk::SurfaceKHR,
}

impl Surface {
    /// A surface for the window; fails if the context's queue cannot present to it.
    pub fn new(ctx: &Context, display: RawDisplayHandle, window: RawWindowHandle) -> Result<Self> {
        let loader = ash::khr::surface::Instance::new(ctx.entry(), &ctx.instance);
        // SAFETY: the handles come from a live window that outlives the surface (the caller
        // destroys the surface before the window).
        let raw = unsafe { ash_window::create_surface(ctx.entry(), &ctx.instance, display, window, None) }
            .vk("vkCreate*SurfaceKHR")?;
        let surface = Surface { loader, raw };
        // SAFETY: a query on a live surface and the context's physical device.
        let supported =
            unsafe { surface.loader.get_physical_device_surface_support(ctx.physical_device, ctx.queue_family, raw) };
        match supported {
            Ok(true) => Ok(surface),
            Ok(false) => {
                surface.destroy();
                Err(Error::Invalid(format!("{} cannot present to this window from its queue", ctx.info.name)))
            }
            Err(e) => {
                surface.destroy();
                Err(e).vk("vkGetPhysicalDeviceSurfaceSupportKHR")
            }
        }
    }

    pub fn destroy(self) {
        // SAFETY: the swapchains made from the surface are gone.
        unsafe { self.loader.destroy_surface(self.raw, None) };
    }
}

pub struct Swapchain {
    loader: ash::khr::swapchain::Device,
    raw: vk::SwapchainKHR,
    pub images: Vec<vk::Image>,
    pub format: vk::Format,
    pub extent: vk::Extent2D,
    pub present_mode: vk::PresentModeKHR,
    /// One per image: signalled when the frame drawn into that image is done, waited on by
    /// its presentation. Per image, not per frame in flight, because presentation may hold
    /// it until the image is acquired again.
    render_done: Vec<vk::Semaphore>,
}

impl Swapchain {
    /// A swapchain of `extent` (or the surface's own size when it has one) presenting with
    /// `present_mode`, or FIFO if the surface does not offer it. `old` is retired by the new
    /// one; destroy it once no frame uses it.
    pub fn new(
        ctx: &Context,
        surface: &Surface,
        extent: vk::Extent2D,
        present_mode: vk::PresentModeKHR,
        old: Option<&Swapchain>,
    ) -> Result<Self> {
        let (pd, s) = (ctx.physical_device, surface.raw);
        // SAFETY: queries on a live surface and physical device.
        let (caps, formats, modes) = unsafe {
            (
                surface
                    .loader
                    .get_physical_device_surface_capabilities(pd, s)
                    .vk("vkGetPhysicalDeviceSurfaceCapabilitiesKHR")?,
                surface.loader.get_physical_device_surface_formats(pd, s).vk("vkGetPhysicalDeviceSurfaceFormatsKHR")?,
                surface
                    .loader
                    .get_physical_device_surface_present_modes(pd, s)
                    .vk("vkGetPhysicalDeviceSurfacePresentModesKHR")?,
            )
        };
        if !caps.supported_usage_flags.contains(vk::ImageUsageFlags::TRANSFER_DST) {
            return Err(Error::Invalid("the window's swapchain images cannot be blitted to".into()));
        }
        // The frame is sRGB-encoded already: a UNORM swapchain shows it as it is.
        let format = [vk::Format::B8G8R8A8_UNORM, vk::Format::R8G8B8A8_UNORM]
            .into_iter()
            .find_map(|f| formats.iter().find(|sf| sf.format == f).copied())
            .ok_or_else(|| {
                Error::Invalid(format!("the window offers no 8-bit UNORM swapchain format ({formats:?})"))
            })?;
        let present_mode = if modes.contains(&present_mode) { present_mode } else { vk::PresentModeKHR::FIFO };
        let extent = if caps.current_extent.width == u32::MAX {
            vk::Extent2D {
                width: extent.width.clamp(caps.min_image_extent.width, caps.max_image_extent.width),
                height: extent.height.clamp(caps.min_image_extent.height, caps.max_image_extent.height),
            }
        } else {
            caps.current_extent
        };
        let mut count = caps.min_image_count + 1;
        if caps.max_image_count > 0 {
            count = count.min(caps.max_image_count);
        }
        let info = vk::SwapchainCreateInfoKHR::default()
            .surface(s)
            .min_image_count(count)
            .image_format(format.format)
            .image_color_space(format.color_space)
            .image_extent(extent)
            .image_array_layers(1)
            .image_usage(vk::ImageUsageFlags::TRANSFER_DST)
            .image_sharing_mode(vk::SharingMode::EXCLUSIVE)
            .pre_transform(caps.current_transform)
            .composite_alpha(vk::CompositeAlphaFlagsKHR::OPAQUE)
            .present_mode(present_mode)
            .clipped(true)
            .old_swapchain(old.map_or(vk::SwapchainKHR::null(), |o| o.raw));
        let loader = ash::khr::swapchain::Device::new(&ctx.instance, &ctx.device);
        // SAFETY: valid create info on a live surface; the old swapchain (if any) is retired.
        let raw = unsafe { loader.create_swapchain(&info, None) }.vk("vkCreateSwapchainKHR")?;
        let mut swapchain = Swapchain {
            loader,
            raw,
            images: Vec::new(),
            format: format.format,
            extent,
            present_mode,
            render_done: Vec::new(),
        };
        // SAFETY: queries and creations on the live swapchain; `destroy` undoes them on failure.
        let made = unsafe {
            swapchain.loader.get_swapchain_images(raw).vk("vkGetSwapchainImagesKHR").and_then(|images| {
                swapchain.images = images;
                for i in 0..swapchain.images.len() {
                    let semaphore = ctx
                        .device
                        .create_semaphore(&vk::SemaphoreCreateInfo::default(), None)
                        .vk("vkCreateSemaphore")?;
                    ctx.set_name(semaphore, &format!("swapchain image {i} rendered"));
                    swapchain.render_done.push(semaphore);
                }
                Ok(())
            })
        };
        match made {
            Ok(()) => Ok(swapchain),
            Err(e) => {
                swapchain.destroy(ctx);
                Err(e)
            }
        }
    }

    /// Acquires the next image, signalling `ready` when it may be written. `None` when the
    /// swapchain no longer matches the surface and must be recreated.
    pub fn acquire(&self, ready: vk::Semaphore) -> Result<Option<u32>> {
        // SAFETY: the semaphore is unsignalled and not waited on elsewhere.
        match unsafe { self.loader.acquire_next_image(self.raw, u64::MAX, ready, vk::Fence::null()) } {
            Ok((index, _suboptimal)) => Ok(Some(index)),
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => Ok(None),
            Err(e) => Err(e).vk("vkAcquireNextImageKHR"),
        }
    }

    /// The semaphore the frame drawn into image `index` signals and its presentation waits on.
    pub fn render_done(&self, index: u32) -> vk::Semaphore {
        self.render_done[index as usize]
    }

    /// Presents image `index`. Returns `false` when the swapchain should be recreated.
    pub fn present(&self, ctx: &Context, index: u32) -> Result<bool> {
        let waits = [self.render_done(index)];
        let swapchains = [self.raw];
        let indices = [index];
        let info =
            vk::PresentInfoKHR::default().wait_semaphores(&waits).swapchains(&swapchains).image_indices(&indices);
        // SAFETY: the image was acquired and a submitted frame signals `render_done`.
        match unsafe { self.loader.queue_present(ctx.queue, &info) } {
            Ok(suboptimal) => Ok(!suboptimal),
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => Ok(false),
            Err(e) => Err(e).vk("vkQueuePresentKHR"),
        }
    }

    /// Destroys the swapchain; no frame that uses it may be pending.
    pub fn destroy(self, ctx: &Context) {
        // SAFETY: as the caller guarantees, nothing uses the swapchain or its semaphores.
        unsafe {
            for semaphore in self.render_done {
                ctx.device.destroy_semaphore(semaphore, None);
            }
            self.loader.destroy_swapchain(self.raw, None);
        }
    }
}
