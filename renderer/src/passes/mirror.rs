//! Planar mirrors: for each mirror the frame sees, the G-buffer and network passes run again
//! on the scene seen in the mirror's plane ([`Reflected`]), into images of their own, and the
//! mirror pass (`mirror.comp`) adds what they saw, weighted by the mirror's Fresnel term, to
//! the mirror's pixels. A mirror seen in a mirror shows only its emission: one reflection.

use ash::vk;

use crate::backend::compute::{Bind, ComputePass};
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
    pad: [u32; 3],
}

/// The mirror pass: reads the frame's G-buffer and the reflection's radiance, adds to the
/// frame's radiance.
pub struct MirrorPass {
    pass: ComputePass,
}

impl MirrorPass {
    /// `spirv` is `mirror.comp`; `gbuffer` and `frame` are the frame's, `seen` the network
    /// outputs of the reflection. All must be storage images in `GENERAL` layout.
    pub fn new(
        ctx: &Context,
        spirv: &[u32],
        gbuffer: &GBufferTargets,
        seen: &NetworkOutputs,
        frame: &NetworkOutputs,
    ) -> Result<Self> {
        let size = std::mem::size_of::<MirrorConstants>() as u32;
        let pass = ComputePass::new(ctx, "mirror", spirv, &bindings(gbuffer, seen, frame), size, (8, 8))?;
        Ok(MirrorPass { pass })
    }

    /// Points the pass at other images (after a resize); no frame that uses it may be pending.
    pub fn rebind(&self, ctx: &Context, gbuffer: &GBufferTargets, seen: &NetworkOutputs, frame: &NetworkOutputs) {
        self.pass.rebind(ctx, &bindings(gbuffer, seen, frame));
    }

    /// The pass for a frame list, for `mirror` seen from `eye`; the images are those the pass
    /// was made (or last rebound) with.
    pub fn pass<'a>(
        &'a self,
        ctx: &'a Context,
        (gbuffer, seen, frame): (&GBufferTargets, &NetworkOutputs, &NetworkOutputs),
        mirror: &Reflected,
        eye: [f32; 4],
    ) -> Pass<'a> {
        let mut uses: Vec<Use> = [&gbuffer.surface, &gbuffer.id, &gbuffer.shading]
            .into_iter()
            .chain(seen.all())
            .map(|image| Use::image(image, Access::COMPUTE_READ))
            .collect();
        uses.extend(frame.all().into_iter().map(|image| Use::image(image, Access::COMPUTE_READ_WRITE)));
        let [x, y, z] = mirror.normal;
        let push = MirrorConstants { eye, normal: [x, y, z, 0.0], object_plus_one: mirror.object + 1, pad: [0; 3] };
        let extent = gbuffer.extent;
        Pass::new("mirror", uses, move |cmd: vk::CommandBuffer| {
            self.pass.record(ctx, cmd, bytemuck::bytes_of(&push), extent.width, extent.height)
        })
    }
}

impl Destroy for MirrorPass {
    fn destroy(self, ctx: &Context) {
        self.pass.destroy(ctx);
    }
}

/// `mirror.comp`'s bindings, in order.
fn bindings<'a>(gbuffer: &'a GBufferTargets, seen: &'a NetworkOutputs, frame: &'a NetworkOutputs) -> Vec<Bind<'a>> {
    let g = [&gbuffer.surface, &gbuffer.id, &gbuffer.shading];
    g.into_iter().chain(seen.all()).chain(frame.all()).map(Bind::StorageImage).collect()
}
