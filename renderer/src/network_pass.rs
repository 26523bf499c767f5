//! The network compute pass, weights in a storage buffer: per pixel, the object's direct and
//! indirect networks on inputs built from the G-buffer (`shaders-glsl/network_storage.comp`).

use ash::vk;
use bytemuck::{Pod, Zeroable};

use crate::compute::{Bind, ComputePass};
use crate::context::Context;
use crate::error::{Error, Result};
use crate::gbuffer::GBufferTargets;
use crate::resources::{Buffer, Image};

pub const INPUTS: usize = 13;
/// Parameters of one 13 → 20 → 10 → 3 network.
pub const PARAMETERS: usize = 20 * 13 + 20 + 10 * 20 + 10 + 3 * 10 + 3;
/// Floats per object slot: direct and indirect parameters, input ranges, two output scales,
/// and a presence flag.
pub const OBJECT_STRIDE: usize = 2 * PARAMETERS + 2 * INPUTS + 3;

/// One object's two networks, as the shader reads them.
pub struct ObjectNetworks<'a> {
    pub direct: &'a [f32],
    pub indirect: &'a [f32],
    pub input_min: [f32; INPUTS],
    pub input_max: [f32; INPUTS],
    pub direct_scale: f32,
    pub indirect_scale: f32,
}

/// Packs per-object networks by object id; `None` for objects without networks (they get
/// zero direct and indirect light).
pub fn pack_weights(objects: &[Option<ObjectNetworks>]) -> Result<Vec<f32>> {
    let mut out = vec![0.0f32; objects.len().max(1) * OBJECT_STRIDE];
    for (id, object) in objects.iter().enumerate() {
        let Some(n) = object else { continue };
        if n.direct.len() != PARAMETERS || n.indirect.len() != PARAMETERS {
            return Err(Error::Invalid(format!("object {id}: a network must have {PARAMETERS} parameters")));
        }
        let slot = &mut out[id * OBJECT_STRIDE..(id + 1) * OBJECT_STRIDE];
        slot[..PARAMETERS].copy_from_slice(n.direct);
        slot[PARAMETERS..2 * PARAMETERS].copy_from_slice(n.indirect);
        let ranges = &mut slot[2 * PARAMETERS..];
        ranges[..INPUTS].copy_from_slice(&n.input_min);
        ranges[INPUTS..2 * INPUTS].copy_from_slice(&n.input_max);
        ranges[2 * INPUTS] = n.direct_scale;
        ranges[2 * INPUTS + 1] = n.indirect_scale;
        ranges[2 * INPUTS + 2] = 1.0;
    }
    Ok(out)
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct NetworkConstants {
    pub eye: [f32; 4],
    pub light: [f32; 4],
}

/// HDR outputs of the network pass, in `GENERAL` layout.
pub struct NetworkOutputs {
    pub direct: Image,
    pub indirect: Image,
    /// emission + direct + indirect.
    pub gi: Image,
}

pub struct NetworkPass {
    pass: ComputePass,
    weights: Buffer,
    pub outputs: NetworkOutputs,
}

impl NetworkPass {
    /// `spirv` is `network_storage.comp`; `weights` comes from [`pack_weights`].
    pub fn new(ctx: &Context, spirv: &[u32], gbuffer: &GBufferTargets, weights: &[f32]) -> Result<Self> {
        let max = u64::from(ctx.info.limits.max_storage_buffer_range);
        if (weights.len() * 4) as u64 > max {
            return Err(Error::Invalid(format!(
                "{} bytes of weights exceed maxStorageBufferRange {max}",
                weights.len() * 4
            )));
        }
        let weights = ctx.create_buffer_with_data(
            "network weights",
            bytemuck::cast_slice(weights),
            vk::BufferUsageFlags::STORAGE_BUFFER,
        )?;
        let usage = vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_SRC;
        let format = vk::Format::R32G32B32A32_SFLOAT;
        let outputs = NetworkOutputs {
            direct: ctx.create_image("direct", gbuffer.extent, format, usage)?,
            indirect: ctx.create_image("indirect", gbuffer.extent, format, usage)?,
            gi: ctx.create_image("gi", gbuffer.extent, format, usage)?,
        };
        ctx.submit_once(|cmd| {
            for image in [&outputs.direct, &outputs.indirect, &outputs.gi] {
                ctx.transition(cmd, image, vk::ImageLayout::UNDEFINED, vk::ImageLayout::GENERAL);
            }
        })?;
        let bindings = [
            Bind::StorageImage(&gbuffer.position),
            Bind::StorageImage(&gbuffer.normal),
            Bind::StorageImage(&gbuffer.object),
            Bind::StorageImage(&gbuffer.emission),
            Bind::StorageBuffer(&weights),
            Bind::StorageImage(&outputs.direct),
            Bind::StorageImage(&outputs.indirect),
            Bind::StorageImage(&outputs.gi),
        ];
        let pass = ComputePass::new(
            ctx,
            "network (storage buffer)",
            spirv,
            &bindings,
            std::mem::size_of::<NetworkConstants>() as u32,
            (8, 8),
        )?;
        Ok(NetworkPass { pass, weights, outputs })
    }

    pub fn record(&self, ctx: &Context, cmd: vk::CommandBuffer, extent: vk::Extent2D, constants: &NetworkConstants) {
        self.pass.record(ctx, cmd, bytemuck::bytes_of(constants), extent.width, extent.height);
    }

    pub fn destroy(self, ctx: &Context) {
        self.pass.destroy(ctx);
        ctx.destroy_buffer(self.weights);
        for image in [self.outputs.direct, self.outputs.indirect, self.outputs.gi] {
            ctx.destroy_image(image);
        }
    }
}
