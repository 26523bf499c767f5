//! The tonemap pass and its CPU twin (`shaders-glsl/include/tonemap.glsl`).

use ash::vk;

use crate::backend::compute::{Bind, ComputePass};
use crate::backend::context::Context;
use crate::backend::guard::Destroy;
use crate::backend::resources::Image;
use crate::backend::sync::{Access, Pass, Use};
use crate::error::Result;

/// ACES filmic curve, Narkowicz's fit.
pub fn aces_fitted(x: f32) -> f32 {
    ((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14)).clamp(0.0, 1.0)
}

pub fn linear_to_srgb(c: f32) -> f32 {
    if c <= 0.0031308 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

/// Linear HDR radiance to display-referred sRGB in [0, 1]; `exposure_scale` is 2^EV.
pub fn tonemap(radiance: [f32; 3], exposure_scale: f32) -> [f32; 3] {
    radiance.map(|c| linear_to_srgb(aces_fitted(c.max(0.0) * exposure_scale)))
}

/// Reads an `R32G32B32A32_SFLOAT` storage image and writes an `R8G8B8A8_UNORM` one.
pub struct TonemapPass {
    pass: ComputePass,
}

impl TonemapPass {
    /// `spirv` is `tonemap.comp`. Both images must be storage images in `GENERAL` layout
    /// when the pass runs.
    pub fn new(ctx: &Context, spirv: &[u32], hdr: &Image, ldr: &Image) -> Result<Self> {
        let bindings = [Bind::StorageImage(hdr), Bind::StorageImage(ldr)];
        let pass = ComputePass::new(ctx, "tonemap", spirv, &bindings, 4, (8, 8))?;
        Ok(Self { pass })
    }

    /// The pass for a frame list; `hdr` and `ldr` are the images it was made (or last
    /// rebound) with.
    pub fn pass<'a>(&'a self, ctx: &'a Context, hdr: &Image, ldr: &Image, exposure_scale: f32) -> Pass<'a> {
        let uses = vec![Use::image(hdr, Access::COMPUTE_READ), Use::image(ldr, Access::COMPUTE_WRITE)];
        let extent = ldr.extent;
        Pass::new("tonemap", uses, move |cmd| self.record(ctx, cmd, extent, exposure_scale))
    }

    /// Points the pass at other images (after a resize); no frame that uses it may be pending.
    pub fn rebind(&self, ctx: &Context, hdr: &Image, ldr: &Image) {
        self.pass.rebind(ctx, &[Bind::StorageImage(hdr), Bind::StorageImage(ldr)]);
    }

    pub fn record(&self, ctx: &Context, cmd: vk::CommandBuffer, extent: vk::Extent2D, exposure_scale: f32) {
        self.pass.record(ctx, cmd, &exposure_scale.to_le_bytes(), extent.width, extent.height);
    }

    pub fn destroy(self, ctx: &Context) {
        self.pass.destroy(ctx);
    }
}

impl Destroy for TonemapPass {
    fn destroy(self, ctx: &Context) {
        self.pass.destroy(ctx);
    }
}
