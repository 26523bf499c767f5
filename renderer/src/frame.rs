//! One frame: the G-buffer pass, the network pass, the tonemap pass and the overlay, as a list
//! of passes whose barriers the frame's tracker derives from what they declare
//! ([`crate::backend::sync`]). A frame is recorded into a command buffer of its own
//! ([`Frame::draw`], with a [`FrameLoop`] and optionally a window's [`Presenter`]) or into a
//! one-off submission that reads images back ([`Frame::render`]).
//!
//! In a scene with planar mirrors the G-buffer pass runs again for each mirror in view, on the
//! scene seen in it, and a merge step puts what it drew into the frame's G-buffer at the
//! mirror's pixels, which the network pass then shades with the others
//! ([`crate::passes::mirror`]).
//!
//! Camera, lights, exposure and the component shown are per-frame constants: one `Frame`
//! serves every configuration of its size, and `resize` remakes only what depends on the size.

use std::cell::RefCell;

use ash::vk;

use crate::backend::context::Context;
use crate::backend::frames::FrameLoop;
use crate::backend::guard::Destroy;
use crate::backend::present::Presenter;
use crate::backend::resources::{Buffer, Image};
use crate::backend::sync::{read_back_passes, run_passes, Pass, Resource, ResourceStates};
use crate::error::{Error, Result};
use crate::lights::NetworkLight;
use crate::passes::gbuffer::{GBufferConstants, GBufferPass, GBufferTargets, GBufferTexel, LightCopy};
use crate::passes::mesh::{GBufferMesh, GBufferVertex, SurfaceMaterial};
use crate::passes::mirror::{MirrorPass, Reflected};
use crate::passes::network::{DirectLight, NetworkConstants, NetworkPass, NetworkShaders, NetworkUnit, Variant};
use crate::passes::overlay::{OverlayPass, TextGrid};
use crate::passes::tonemap::TonemapPass;

/// Timestamps a frame writes: start, after the G-buffer, after the mirrors' G-buffers and
/// merge steps, after the network pass, after the tonemap pass, after the rest (overlay,
/// presentation blit, read-back).
pub const TIMESTAMPS: u32 = 6;
/// Names of the intervals between consecutive timestamps.
pub const TIMED_PASSES: [&str; 5] = ["gbuffer", "mirrors", "network", "tonemap", "overlay+present"];

/// Which light the display image shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shown {
    /// Emission + direct + indirect.
    Gi,
    Direct,
    Indirect,
}

impl Shown {
    /// The shaders' code for it.
    pub fn code(self) -> u32 {
        match self {
            Shown::Gi => 0,
            Shown::Direct => 1,
            Shown::Indirect => 2,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Shown::Gi => "global",
            Shown::Direct => "direct only",
            Shown::Indirect => "indirect only",
        }
    }
}

/// What a frame writes besides the display image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FrameOutput {
    /// Direct, indirect and global radiance (RGBA32F) for read-back, then the display image
    /// tonemapped from one of them: `rrf render`, `eval`, `bench`.
    Radiance,
    /// Only the display image, written by the network pass itself: the walkthrough. The
    /// storage variant, which cannot, and models whose kd-tree leaves blend (their units add
    /// to each other's radiance) fall back to `Radiance`.
    Display,
}

/// The SPIR-V of every pass, and the overlay's font.
pub struct FrameShaders<'a> {
    pub gbuffer_vertex: &'a [u32],
    pub gbuffer_fragment: &'a [u32],
    pub network: NetworkShaders<'a>,
    pub shadow_vertex: &'a [u32],
    pub shadow_fragment: &'a [u32],
    pub tonemap: &'a [u32],
    pub mirror_merge: &'a [u32],
    pub overlay: &'a [u32],
    /// 8×8 glyphs of ASCII, one byte per row.
    pub font: &'a [[u8; 8]; 128],
}

/// What a scene gives a frame: its mesh, its materials and its networks.
pub struct FrameScene<'a> {
    pub vertices: &'a [GBufferVertex],
    pub indices: &'a [u32],
    pub surfaces: &'a [SurfaceMaterial],
    /// The texels of the surfaces' textures.
    pub texels: &'a [u32],
    pub objects: usize,
    /// Per object, what the network pass needs of its material (see [`NetworkPass::new`]).
    pub materials: &'a [[f32; 4]],
    pub units: &'a [NetworkUnit<'a>],
    /// Direct light from the networks, or computed for this point light.
    pub analytic_light: Option<crate::lights::PointLightShape>,
    /// Whether the scene has planar mirrors, which frames then draw the reflections of.
    pub mirrors: bool,
}

/// What changes from frame to frame, as the passes read it.
#[derive(Clone, Debug)]
pub struct FrameConstants {
    pub gbuffer: GBufferConstants,
    /// Where the G-buffer draws the moving light's geometry, one copy per light.
    pub light_copies: Vec<LightCopy>,
    /// The lights, as the network pass reads them (1 to [`crate::lights::MAX_LIGHTS`]).
    pub lights: Vec<NetworkLight>,
    /// 2^EV.
    pub exposure_scale: f32,
    pub shown: Shown,
    /// The mirrors whose reflecting side the camera is on (none in a scene without mirrors).
    pub mirrors: Vec<Reflected>,
}

/// Images of one frame, read back: RGBA per pixel, rows top to bottom.
pub struct FramePixels {
    pub direct: Vec<f32>,
    pub indirect: Vec<f32>,
    pub gi: Vec<f32>,
}

/// What [`Frame::draw`] did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Drawn {
    /// Submitted, and handed to presentation in a window.
    Submitted,
    /// Nothing: the window's swapchain no longer fits; [`Presenter::fit`] remakes it.
    Skipped,
}

pub struct Frame {
    targets: GBufferTargets,
    mesh: GBufferMesh,
    gbuffer: GBufferPass,
    network: NetworkPass,
    /// Display-referred image (RGBA8, sRGB-encoded): what the tonemap pass writes, the overlay
    /// draws on, the window shows and screenshots save.
    ldr: Image,
    /// Tonemap passes of the global, direct and indirect images (none when the network pass
    /// writes the display image itself).
    tonemaps: Vec<TonemapPass>,
    overlay: OverlayPass,
    /// The passes that draw what mirrors reflect, in a scene with mirrors.
    reflection: Option<Reflection>,
    /// Where every image of the frame was left, for the barriers of the next pass.
    states: RefCell<ResourceStates>,
}

impl Frame {
    /// Everything for frames of `scene` at `extent` with network pass `variant`, writing
    /// `output`.
    pub fn new(
        ctx: &Context,
        shaders: &FrameShaders,
        scene: &FrameScene,
        variant: Variant,
        extent: vk::Extent2D,
        output: FrameOutput,
    ) -> Result<Self> {
        // Each part is destroyed again if a later one cannot be made.
        let targets = ctx.guard(GBufferTargets::new(ctx, extent, scene.mirrors)?);
        let mesh = ctx.guard(GBufferMesh::new(ctx, scene.vertices, scene.indices, scene.surfaces, scene.texels)?);
        let gbuffer = ctx.guard(GBufferPass::new(ctx, shaders.gbuffer_vertex, shaders.gbuffer_fragment, &mesh)?);
        let ldr = ctx.guard(create_ldr(ctx, extent)?);
        // Units that blend add to each other's radiance images; the frame then tonemaps those.
        let blended = scene.units.iter().any(NetworkUnit::blends);
        let writes_display = output == FrameOutput::Display && variant != Variant::Storage && !blended;
        let display = writes_display.then_some(&*ldr);
        let direct = match scene.analytic_light {
            None => DirectLight::Learned,
            Some(light) => DirectLight::Analytic {
                light,
                shadow_vertex: shaders.shadow_vertex,
                shadow_fragment: shaders.shadow_fragment,
            },
        };
        let (objects, units, materials) = (scene.objects, scene.units, scene.materials);
        let network =
            NetworkPass::new(ctx, variant, &shaders.network, &targets, objects, units, materials, display, direct);
        let network = ctx.guard(network?);
        let reflection = match scene.mirrors {
            true => {
                let seen = ctx.guard(GBufferTargets::new(ctx, extent, false)?);
                let pass = MirrorPass::new(ctx, shaders.mirror_merge, &targets, &seen)?;
                Some(Reflection { targets: seen.keep(), pass })
            }
            false => None,
        };
        let reflection = ctx.guard(reflection);
        let mut tonemaps = ctx.guard(Vec::with_capacity(3));
        for hdr in network.outputs().into_iter().flat_map(|o| [&o.gi, &o.direct, &o.indirect]) {
            tonemaps.push(TonemapPass::new(ctx, shaders.tonemap, hdr, &ldr)?);
        }
        let overlay = OverlayPass::new(ctx, shaders.overlay, shaders.font, &ldr)?;
        let frame = Frame {
            targets: targets.keep(),
            mesh: mesh.keep(),
            gbuffer: gbuffer.keep(),
            network: network.keep(),
            ldr: ldr.keep(),
            tonemaps: tonemaps.keep(),
            overlay,
            reflection: reflection.keep(),
            states: RefCell::default(),
        };
        frame.register(&mut frame.states.borrow_mut());
        Ok(frame)
    }

    /// Tells `states` where set-up left every image of the frame.
    fn register(&self, states: &mut ResourceStates) {
        self.targets.register(states);
        self.network.register(states);
        if let Some(r) = &self.reflection {
            r.targets.register(states);
        }
        states.set_layout(&self.ldr, vk::ImageLayout::GENERAL);
    }

    /// The frame's own images, as a tracker that knows only them.
    fn own_images(&self) -> ResourceStates {
        let mut own = ResourceStates::default();
        self.register(&mut own);
        own
    }

    /// Takes over what `old`, a frame this one replaces, knew of resources that are not its
    /// own (those of passes drawn with it, such as the user interface's textures), so that
    /// their contents and layouts carry over.
    pub fn carry_states(&self, old: &Frame) {
        let mut states = old.states.take();
        states.forget_all(&old.own_images());
        self.register(&mut states);
        *self.states.borrow_mut() = states;
    }

    /// Tells the barrier tracker that `resource` was just made (see
    /// [`ResourceStates::forget`]), before a pass of [`Frame::draw`] first uses it.
    pub fn forget(&self, resource: Resource) {
        self.states.borrow_mut().forget(resource);
    }

    /// The network pass's variant.
    pub fn variant(&self) -> Variant {
        self.network.variant()
    }

    pub fn extent(&self) -> vk::Extent2D {
        self.targets.extent
    }

    /// The display image (RGBA8, sRGB-encoded).
    pub fn ldr(&self) -> &Image {
        &self.ldr
    }

    /// Remakes the images for `extent`; pipelines and the mesh stay. No frame that uses this
    /// one may be pending. On failure the frame keeps its old size.
    pub fn resize(&mut self, ctx: &Context, extent: vk::Extent2D) -> Result<()> {
        if extent == self.extent() {
            return Ok(());
        }
        let old = self.own_images();
        let targets = ctx.guard(GBufferTargets::new(ctx, extent, self.targets.mirrors)?);
        let ldr = ctx.guard(create_ldr(ctx, extent)?);
        let display = self.network.outputs().is_none().then_some(&*ldr);
        self.network.resize(ctx, &targets, display)?;
        if let Some(r) = &mut self.reflection {
            r.resize(ctx, extent, &targets)?;
        }
        std::mem::replace(&mut self.targets, targets.keep()).destroy(ctx);
        ctx.destroy_image(std::mem::replace(&mut self.ldr, ldr.keep()));
        let hdr = self.network.outputs().into_iter().flat_map(|o| [&o.gi, &o.direct, &o.indirect]);
        for (pass, hdr) in self.tonemaps.iter().zip(hdr) {
            pass.rebind(ctx, hdr, &self.ldr);
        }
        self.overlay.rebind(ctx, &self.ldr);
        // What the tracker knew of the old images goes; what it knows of others stays.
        let mut states = self.states.borrow_mut();
        states.forget_all(&old);
        self.register(&mut states);
        Ok(())
    }

    /// One frame of the walkthrough, in the command buffer `ring` has begun: drawn to the
    /// display image with `overlay` (a text grid and its scale in screen pixels per font
    /// pixel) and then the `ui` passes (which draw on [`Frame::ldr`]), copied to `screenshot`
    /// if given, submitted, and with a `presenter` blitted to the window's next image and
    /// presented. Writes [`TIMESTAMPS`] where the device can.
    #[allow(clippy::too_many_arguments)]
    pub fn draw<'a>(
        &'a self,
        ctx: &'a Context,
        ring: &mut FrameLoop,
        presenter: Option<&mut Presenter>,
        constants: &FrameConstants,
        overlay: Option<(&TextGrid, u32)>,
        ui: Vec<Pass<'a>>,
        screenshot: Option<&'a Buffer>,
    ) -> Result<Drawn> {
        let handles = ring.handles();
        let target = match presenter {
            Some(p) => match p.acquire(handles.image_available)? {
                Some(target) => Some((p, target)),
                // The frame's commands are left unsubmitted; the slot's next begin resets them.
                None => return Ok(Drawn::Skipped),
            },
            None => None,
        };
        let mut extra = ui;
        if let Some(buffer) = screenshot {
            extra.extend(read_back_passes(ctx, &self.ldr, buffer));
        }
        if let Some((p, target)) = &target {
            let resource = Resource::Image { raw: target.image, aspect: vk::ImageAspectFlags::COLOR, texel_bytes: 4 };
            // The submission waits for the acquire semaphore at the transfer stage.
            self.states.borrow_mut().arrive(resource, vk::PipelineStageFlags2::ALL_TRANSFER);
            extra.extend(p.present_passes(ctx, &self.ldr, target));
        }
        let timed = ctx.info.limits.timestamp_period_ns.is_some();
        self.record(ctx, handles.cmd, constants, overlay, timed.then_some(handles.queries), extra)?;
        let wait = target.as_ref().map(|_| handles.image_available);
        ring.submit(ctx, wait, target.as_ref().map(|(_, t)| t.rendered), timed)?;
        if let Some((p, target)) = target {
            p.present(ctx, &target)?;
        }
        Ok(Drawn::Submitted)
    }

    /// Records a frame: the G-buffer, network, tonemap and (with `overlay`, at a scale in
    /// screen pixels per font pixel) overlay passes, then `extra` passes (presentation,
    /// read-back). With `timestamps`, a pool reset for this frame, writes [`TIMESTAMPS`].
    pub fn record<'a>(
        &'a self,
        ctx: &'a Context,
        cmd: vk::CommandBuffer,
        constants: &FrameConstants,
        overlay: Option<(&TextGrid, u32)>,
        timestamps: Option<vk::QueryPool>,
        extra: Vec<Pass<'a>>,
    ) -> Result<()> {
        let passes = self.passes(ctx, constants, overlay, timestamps, extra)?;
        if let Some(pool) = timestamps {
            // SAFETY: the pool holds TIMESTAMPS queries and was reset for this frame.
            unsafe { ctx.device.cmd_write_timestamp2(cmd, vk::PipelineStageFlags2::ALL_COMMANDS, pool, 0) };
        }
        run_passes(ctx, cmd, &mut self.states.borrow_mut(), passes);
        Ok(())
    }

    /// Image bytes a frame moves per pixel, from what its passes declare (without overlay or
    /// read-back): each declared image access counted as one read or write of every pixel, so
    /// an upper bound where a pass touches only some pixels (the classification's background).
    pub fn bytes_per_pixel(&self, ctx: &Context, constants: &FrameConstants) -> Result<u32> {
        let passes = self.passes(ctx, constants, None, None, vec![])?;
        // Blended network units are a pass each, each over its own pixels: together they
        // touch a pixel's images about once, as one pass does.
        let distinct = passes.iter().enumerate().filter(|(i, p)| *i == 0 || passes[i - 1].name != p.name);
        let bytes = distinct.flat_map(|(_, p)| &p.uses).map(|u| match u.resource {
            Resource::Image { texel_bytes, .. } => texel_bytes,
            Resource::Buffer(_) => 0,
        });
        Ok(bytes.sum())
    }

    /// The passes of a frame, for `record`.
    fn passes<'a>(
        &'a self,
        ctx: &'a Context,
        constants: &FrameConstants,
        overlay: Option<(&TextGrid, u32)>,
        timestamps: Option<vk::QueryPool>,
        extra: Vec<Pass<'a>>,
    ) -> Result<Vec<Pass<'a>>> {
        let copies = constants.light_copies.clone();
        let mut passes = vec![self.gbuffer.pass(ctx, &self.targets, &self.mesh, constants.gbuffer, copies, None)];
        let stamp = |passes: &mut Vec<Pass>, index: u32| {
            if let (Some(pool), Some(last)) = (timestamps, passes.last_mut()) {
                last.timestamp = Some((pool, index));
            }
        };
        stamp(&mut passes, 1);
        if let Some(r) = &self.reflection {
            for (slot, mirror) in constants.mirrors.iter().enumerate() {
                passes.extend(r.passes(ctx, self, constants, mirror, slot as u32));
            }
        }
        // The mirrors' interval ends here even in a frame without them.
        passes.push(Pass::new("mirrors done", vec![], |_| {}));
        stamp(&mut passes, 2);
        let display = self.network.outputs().is_none().then_some(&self.ldr);
        let c = constants;
        let mirror_eyes: Vec<[f32; 4]> = c.mirrors.iter().map(|m| m.gbuffer.eye).collect();
        let network = NetworkConstants::new(c.gbuffer.eye, &c.lights, &mirror_eyes, c.exposure_scale, c.shown.code())?;
        let views: Vec<GBufferConstants> =
            std::iter::once(c.gbuffer).chain(c.mirrors.iter().map(|m| m.gbuffer)).collect();
        passes.extend(self.network.passes(ctx, &self.targets, &self.mesh, network, display, &views)?);
        stamp(&mut passes, 3);
        if let Some(outputs) = self.network.outputs() {
            let (tonemap, hdr) = match constants.shown {
                Shown::Gi => (&self.tonemaps[0], &outputs.gi),
                Shown::Direct => (&self.tonemaps[1], &outputs.direct),
                Shown::Indirect => (&self.tonemaps[2], &outputs.indirect),
            };
            passes.push(tonemap.pass(ctx, hdr, &self.ldr, constants.exposure_scale));
        }
        // The tonemap interval ends here even when the network pass did its work.
        passes.push(Pass::new("tonemap done", vec![], |_| {}));
        stamp(&mut passes, 4);
        if let Some((grid, scale)) = overlay {
            passes.extend(self.overlay.passes(ctx, &self.ldr, grid, scale));
        }
        // The last interval always ends with a pass, even an empty one.
        passes.extend(extra);
        passes.push(Pass::new("end of frame", vec![], |_| {}));
        stamp(&mut passes, 5);
        Ok(passes)
    }

    /// Renders one frame and reads the HDR images back.
    pub fn render(&self, ctx: &Context, constants: &FrameConstants) -> Result<FramePixels> {
        let Some(outputs) = self.network.outputs() else {
            return Err(Error::Invalid(
                "this frame writes only its display image (FrameOutput::Display); it has no radiance to read".into(),
            ));
        };
        let images = [&outputs.direct, &outputs.indirect, &outputs.gi];
        let [direct, indirect, gi] = self
            .read_back(ctx, &images, Some(constants))?
            .try_into()
            .map_err(|_| Error::Invalid("three images read back".into()))?;
        Ok(FramePixels { direct, indirect, gi })
    }

    /// Renders one frame and reads the display image back: RGBA in [0, 1], sRGB-encoded.
    pub fn render_display(&self, ctx: &Context, constants: &FrameConstants) -> Result<Vec<f32>> {
        Ok(self.read_back(ctx, &[&self.ldr], Some(constants))?.remove(0))
    }

    /// Object ids + 1 of the last frame's pixels (0: nothing) as the network pass shaded them:
    /// where a mirror shows a reflection, the reflected object's.
    pub fn read_objects(&self, ctx: &Context) -> Result<Vec<u32>> {
        let ids = self.read_back(ctx, &[&self.targets.id], None)?.remove(0);
        Ok(ids.iter().map(|&v| GBufferTexel::decode([0; 4], v.to_bits(), [0; 4]).object).collect())
    }

    /// Reads `images` back (as `Context::decode` gives them), after rendering a frame of
    /// `constants` first, or else as the last frame left them; waits for the GPU.
    fn read_back(&self, ctx: &Context, images: &[&Image], constants: Option<&FrameConstants>) -> Result<Vec<Vec<f32>>> {
        let mut buffers = ctx.guard(Vec::with_capacity(images.len()));
        for image in images {
            buffers.push(ctx.create_readback_buffer(image)?);
        }
        ctx.submit_once(|cmd| {
            let passes = images.iter().zip(buffers.iter()).flat_map(|(i, b)| read_back_passes(ctx, i, b)).collect();
            match constants {
                Some(constants) => self.record(ctx, cmd, constants, None, None, passes),
                None => {
                    run_passes(ctx, cmd, &mut self.states.borrow_mut(), passes);
                    Ok(())
                }
            }
        })??;
        images.iter().zip(buffers.iter()).map(|(i, b)| ctx.decode(i.format, b)).collect()
    }

    pub fn destroy(self, ctx: &Context) {
        Destroy::destroy(self, ctx);
    }
}

impl Destroy for Frame {
    fn destroy(self, ctx: &Context) {
        self.reflection.destroy(ctx);
        self.overlay.destroy(ctx);
        for pass in self.tonemaps {
            pass.destroy(ctx);
        }
        ctx.destroy_image(self.ldr);
        self.network.destroy(ctx);
        self.gbuffer.destroy(ctx);
        self.mesh.destroy(ctx);
        self.targets.destroy(ctx);
    }
}

/// What draws the scene seen in a mirror: its own G-buffer, and the step that merges what it
/// drew into the frame's.
struct Reflection {
    targets: GBufferTargets,
    pass: MirrorPass,
}

impl Reflection {
    /// Remakes the G-buffer for `extent` and points the merge step at it and at the frame's
    /// new `gbuffer`.
    fn resize(&mut self, ctx: &Context, extent: vk::Extent2D, gbuffer: &GBufferTargets) -> Result<()> {
        let targets = GBufferTargets::new(ctx, extent, false)?;
        std::mem::replace(&mut self.targets, targets).destroy(ctx);
        self.pass.rebind(ctx, gbuffer, &self.targets);
        Ok(())
    }

    /// The passes that put what `mirror`, the `slot`-th of the frame's, reflects into the
    /// G-buffer of the frame `owner` draws with `constants`.
    fn passes<'a>(
        &'a self,
        ctx: &'a Context,
        owner: &'a Frame,
        constants: &FrameConstants,
        mirror: &Reflected,
        slot: u32,
    ) -> [Pass<'a>; 2] {
        let copies = constants.light_copies.clone();
        [
            owner.gbuffer.pass(ctx, &self.targets, &owner.mesh, mirror.gbuffer, copies, Some(mirror.area)),
            self.pass.pass(ctx, &owner.targets, &self.targets, mirror, slot, constants.gbuffer.eye),
        ]
    }
}

impl Destroy for Reflection {
    fn destroy(self, ctx: &Context) {
        self.pass.destroy(ctx);
        self.targets.destroy(ctx);
    }
}

fn create_ldr(ctx: &Context, extent: vk::Extent2D) -> Result<Image> {
    let ldr = ctx.guard(ctx.create_image(
        "ldr",
        extent,
        vk::Format::R8G8B8A8_UNORM,
        // A color attachment too, for the user interface's draws.
        vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_SRC | vk::ImageUsageFlags::COLOR_ATTACHMENT,
    )?);
    ctx.submit_once(|cmd| ctx.transition(cmd, &ldr, vk::ImageLayout::UNDEFINED, vk::ImageLayout::GENERAL))?;
    Ok(ldr.keep())
}
