//! Planar mirrors: for each mirror the frame sees, the G-buffer pass runs again on the scene
//! seen in the mirror's plane ([`Reflected`]), into a G-buffer of its own, and the merge step
//! (`mirror_merge.comp`) copies what it drew into the frame's G-buffer at the mirror's pixels,
//! flagged as reflected and with the mirror's Fresnel weight. The frame's one network pass then
//! shades those pixels from the reflected camera with every other pixel. A mirror seen in a
//! mirror shows only its emission: one reflection.
//!
//! A reflection is drawn only where the mirror is: the G-buffer within the mirror's screen
//! rectangle, the merge over the rectangle's tiles.

use ash::vk;

use crate::backend::compute::{tile_block, Bind, ComputePass};
use crate::backend::context::Context;
use crate::backend::guard::Destroy;
use crate::backend::sync::{Access, Pass, Use};
use crate::error::Result;
use crate::passes::gbuffer::{GBufferConstants, GBufferTargets};

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
struct MergeConstants {
    eye: [f32; 4],
    normal: [f32; 4],
    object_plus_one: u32,
    slot: u32,
    /// The first pixel dispatched.
    origin: [u32; 2],
}

/// Pixels per side of the merge step's workgroups.
const TILE: u32 = 8;

/// The merge step of a mirror (`mirror_merge.comp`): puts what the reflection's G-buffer drew
/// into the frame's, at the pixels where the frame sees the mirror.
pub struct MirrorPass {
    merge: ComputePass,
}

impl MirrorPass {
    /// `merge` is the SPIR-V of `mirror_merge.comp`; `frame` the frame's G-buffer (made for
    /// mirrors), `seen` the reflection's.
    pub fn new(ctx: &Context, merge: &[u32], frame: &GBufferTargets, seen: &GBufferTargets) -> Result<Self> {
        let size = std::mem::size_of::<MergeConstants>() as u32;
        let merge = ComputePass::new(ctx, "mirror merge", merge, &bindings(frame, seen), size, (TILE, TILE))?;
        Ok(MirrorPass { merge })
    }

    /// Points the step at other G-buffers (after a resize); no frame that uses them may be
    /// pending.
    pub fn rebind(&self, ctx: &Context, frame: &GBufferTargets, seen: &GBufferTargets) {
        self.merge.rebind(ctx, &bindings(frame, seen));
    }

    /// The merge step for a frame list, for `mirror`, the frame's `slot`-th, seen from `eye`:
    /// after the G-buffer passes of the frame and of the reflection, before the network pass.
    /// The G-buffers are those the step was made (or last rebound) with.
    pub fn pass<'a>(
        &'a self,
        ctx: &'a Context,
        frame: &GBufferTargets,
        seen: &GBufferTargets,
        mirror: &Reflected,
        slot: u32,
        eye: [f32; 4],
    ) -> Pass<'a> {
        let mut uses: Vec<Use> =
            frame.colors().into_iter().map(|image| Use::image(image, Access::COMPUTE_READ_WRITE)).collect();
        uses.extend(seen.colors().into_iter().map(|image| Use::image(image, Access::COMPUTE_READ)));
        uses.push(Use::image(&frame.mirror_weights, Access::COMPUTE_WRITE));
        let [x, y, z] = mirror.normal;
        let (origin, block) = tile_block(mirror.area, TILE);
        let push = MergeConstants { eye, normal: [x, y, z, 0.0], object_plus_one: mirror.object + 1, slot, origin };
        Pass::new("mirror merge", uses, move |cmd: vk::CommandBuffer| {
            self.merge.record(ctx, cmd, bytemuck::bytes_of(&push), block.width, block.height)
        })
    }
}

impl Destroy for MirrorPass {
    fn destroy(self, ctx: &Context) {
        self.merge.destroy(ctx);
    }
}

/// `mirror_merge.comp`'s bindings, in order.
fn bindings<'a>(frame: &'a GBufferTargets, seen: &'a GBufferTargets) -> Vec<Bind<'a>> {
    frame.colors().into_iter().chain(seen.colors()).chain([&frame.mirror_weights]).map(Bind::StorageImage).collect()
}
