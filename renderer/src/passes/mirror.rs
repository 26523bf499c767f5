//! Planar mirrors: for each mirror the frame sees, the G-buffer and network passes run again
//! on the scene seen in the mirror's plane ([`Reflected`]), into images of their own, and the
//! mirror pass (`mirror.comp`) adds what they saw, weighted by the mirror's Fresnel term, to
//! the mirror's pixels. A mirror seen in a mirror shows only its emission: one reflection.
//!
//! Every step of a reflection runs only where the mirror is: the G-buffer within the mirror's
//! screen rectangle, the network pass only at the pixels where the frame sees the mirror (the
//! mask step clears the others), the compute steps over the rectangle's tiles.

use ash::vk;

use crate::backend::compute::{tile_block, Bind, ComputePass};
use crate::backend::context::Context;
use crate::backend::guard::Destroy;
use crate::backend::sync::{Access, Pass, Use};
use crate::error::Result;
use crate::passes::gbuffer::{GBufferConstants, GBufferTargets};
use crate::passes::network::NetworkOutputs;

/// One mirror as a frame sees it.
#[derive(Clone, Copy, Debug)]
pub struct Reflected {
    /// The mirror's object id.
    pub object: u32,
    /// Its plane's unit normal on the camera's side.
    pub normal: [f32; 3],
    /// The G-buffer's constants for the scene seen in the mirror: the view-projection
    /// reflected in its plane, with its near plane on the mirror, and the camera's reflection
    /// as the eye.
    pub gbuffer: GBufferConstants,
    /// The pixels the mirror may cover: the reflection is drawn only there.
    pub area: vk::Rect2D,
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct MirrorConstants {
    eye: [f32; 4],
    normal: [f32; 4],
    object_plus_one: u32,
    pad: u32,
    /// The first pixel dispatched.
    origin: [u32; 2],
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct MaskConstants {
    object_plus_one: u32,
    pad: u32,
    /// The first pixel dispatched.
    origin: [u32; 2],
}

/// Pixels per side of the workgroups of both steps.
const TILE: u32 = 8;

/// The images of a frame and of the reflection drawn for it that the mirror passes read and
/// write, in `GENERAL` layout as storage images.
#[derive(Clone, Copy)]
pub struct MirrorImages<'a> {
    /// The frame's G-buffer and radiance.
    pub gbuffer: &'a GBufferTargets,
    pub frame: &'a NetworkOutputs,
    /// The reflection's G-buffer and the radiance its network pass found there.
    pub seen_gbuffer: &'a GBufferTargets,
    pub seen: &'a NetworkOutputs,
}

/// The two compute steps of a mirror: the mask (`mirror_mask.comp`), between the reflection's
/// G-buffer and network passes, drops from the reflection what the mirror does not show; the
/// pass proper (`mirror.comp`) adds the reflection to the mirror's pixels. Both run only over
/// the mirror's screen rectangle.
pub struct MirrorPass {
    mask: ComputePass,
    add: ComputePass,
}

impl MirrorPass {
    /// `add` and `mask` are the SPIR-V of `mirror.comp` and `mirror_mask.comp`.
    pub fn new(ctx: &Context, add: &[u32], mask: &[u32], images: MirrorImages) -> Result<Self> {
        let (size, tile) = (std::mem::size_of::<MirrorConstants>() as u32, (TILE, TILE));
        let add = ctx.guard(ComputePass::new(ctx, "mirror", add, &add_bindings(images), size, tile)?);
        let size = std::mem::size_of::<MaskConstants>() as u32;
        let mask = ComputePass::new(ctx, "mirror mask", mask, &mask_bindings(images), size, tile)?;
        Ok(MirrorPass { mask, add: add.keep() })
    }

    /// Points the passes at other images (after a resize); no frame that uses them may be
    /// pending.
    pub fn rebind(&self, ctx: &Context, images: MirrorImages) {
        self.add.rebind(ctx, &add_bindings(images));
        self.mask.rebind(ctx, &mask_bindings(images));
    }

    /// The mask step for a frame list, for `mirror`: run after the reflection's G-buffer pass
    /// and before its network pass. The images are those the pass was made (or last rebound)
    /// with.
    pub fn mask_pass<'a>(&'a self, ctx: &'a Context, images: MirrorImages, mirror: &Reflected) -> Pass<'a> {
        let uses = vec![
            Use::image(&images.gbuffer.id, Access::COMPUTE_READ),
            Use::image(&images.seen_gbuffer.id, Access::COMPUTE_READ_WRITE),
        ];
        let (origin, block) = tile_block(mirror.area, TILE);
        let push = MaskConstants { object_plus_one: mirror.object + 1, pad: 0, origin };
        Pass::new("mirror mask", uses, move |cmd: vk::CommandBuffer| {
            self.mask.record(ctx, cmd, bytemuck::bytes_of(&push), block.width, block.height)
        })
    }

    /// The step that adds what `mirror`, seen from `eye`, reflects, for a frame list.
    pub fn pass<'a>(&'a self, ctx: &'a Context, images: MirrorImages, mirror: &Reflected, eye: [f32; 4]) -> Pass<'a> {
        let gbuffer = images.gbuffer;
        let mut uses: Vec<Use> = [&gbuffer.surface, &gbuffer.id, &gbuffer.shading]
            .into_iter()
            .chain(images.seen.all())
            .map(|image| Use::image(image, Access::COMPUTE_READ))
            .collect();
        uses.extend(images.frame.all().into_iter().map(|image| Use::image(image, Access::COMPUTE_READ_WRITE)));
        let [x, y, z] = mirror.normal;
        let (origin, block) = tile_block(mirror.area, TILE);
        let push = MirrorConstants { eye, normal: [x, y, z, 0.0], object_plus_one: mirror.object + 1, pad: 0, origin };
        Pass::new("mirror", uses, move |cmd: vk::CommandBuffer| {
            self.add.record(ctx, cmd, bytemuck::bytes_of(&push), block.width, block.height)
        })
    }
}

impl Destroy for MirrorPass {
    fn destroy(self, ctx: &Context) {
        self.mask.destroy(ctx);
        self.add.destroy(ctx);
    }
}

/// `mirror.comp`'s bindings, in order.
fn add_bindings(images: MirrorImages) -> Vec<Bind> {
    let g = images.gbuffer;
    [&g.surface, &g.id, &g.shading]
        .into_iter()
        .chain(images.seen.all())
        .chain(images.frame.all())
        .map(Bind::StorageImage)
        .collect()
}

/// `mirror_mask.comp`'s bindings, in order.
fn mask_bindings(images: MirrorImages) -> Vec<Bind> {
    vec![Bind::StorageImage(&images.gbuffer.id), Bind::StorageImage(&images.seen_gbuffer.id)]
}
