//! The storage variant: one dispatch, every unit's weights in a storage buffer, the unit found
//! per pixel from its object id and position (`network_storage.comp`).

use ash::vk;
use bytemuck::{Pod, Zeroable};

use super::interface::SEVERAL_LIGHTS_ID;
use super::layout::UNIT_STRIDE;
use super::units::NetworkUnit;
use super::{network_bindings, FrameUses, NetworkOutputs, Shared, Written, TILE};
use crate::backend::compute::{Bind, ComputePass, Dispatch};
use crate::backend::context::Context;
use crate::backend::guard::Destroy;
use crate::backend::resources::Buffer;
use crate::backend::sync::{Access, Pass, Use};
use crate::error::{Error, Result};
use crate::passes::gbuffer::GBufferTargets;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct StoragePush {
    eye: [f32; 4],
    light_count: u32,
    objects: u32,
    pad: [u32; 2],
}

/// The storage variant's weights: per unit, the folded direct and indirect networks.
fn pack_weights(units: &[NetworkUnit]) -> Vec<f32> {
    let mut out = Vec::with_capacity(units.len().max(1) * UNIT_STRIDE);
    for unit in units {
        out.extend(unit.direct.folded());
        out.extend(unit.indirect.folded());
    }
    if out.is_empty() {
        out.resize(UNIT_STRIDE, 0.0); // Vulkan buffers cannot be empty
    }
    out
}

/// The storage variant's pipelines (one for frames of one light, one for several) and the
/// weights they read.
pub(super) struct Storage {
    pass: ComputePass,
    weights: Buffer,
}

impl Storage {
    pub(super) fn new(
        ctx: &Context,
        spirv: &[u32],
        gbuffer: &GBufferTargets,
        shared: Shared,
        outputs: &NetworkOutputs,
        units: &[NetworkUnit],
    ) -> Result<Self> {
        let weights = pack_weights(units);
        let max = u64::from(ctx.info.limits.max_storage_buffer_range);
        if (weights.len() * 4) as u64 > max {
            return Err(Error::Invalid(format!(
                "{} bytes of weights exceed maxStorageBufferRange {max}",
                weights.len() * 4
            )));
        }
        let weights = ctx.guard(ctx.create_buffer_with_data(
            "network weights",
            bytemuck::cast_slice(&weights),
            vk::BufferUsageFlags::STORAGE_BUFFER,
        )?);
        let written = Written::Radiance(outputs);
        let units = Bind::StorageBuffer(shared.units);
        let bindings = network_bindings(gbuffer, shared, shared.lights, &weights, written, [units]);
        let push = std::mem::size_of::<StoragePush>() as u32;
        // One pipeline for frames of one light, one for several (`SEVERAL_LIGHTS`).
        let lights = [0, 1].map(|several| {
            let mut words = vec![0; SEVERAL_LIGHTS_ID as usize + 1];
            words[SEVERAL_LIGHTS_ID as usize] = several;
            words
        });
        let pass =
            ComputePass::specialized(ctx, "network (storage buffer)", spirv, &bindings, push, (TILE, TILE), &lights)?;
        Ok(Storage { pass, weights: weights.keep() })
    }

    /// Points the pipelines at the resized G-buffer and outputs.
    pub(super) fn rebind(&mut self, ctx: &Context, gbuffer: &GBufferTargets, shared: Shared, written: Written) {
        let units = Bind::StorageBuffer(shared.units);
        self.pass.rebind(ctx, &network_bindings(gbuffer, shared, shared.lights, &self.weights, written, [units]));
    }

    /// The frame's one dispatch.
    pub(super) fn pass<'a>(&'a self, frame: FrameUses<'a>) -> Pass<'a> {
        let mut uses = frame.gbuffer_reads();
        let FrameUses { ctx, extent, constants: c, objects, materials, lights, units, writes, .. } = frame;
        uses.extend([materials, lights, units, Use::buffer(&self.weights, Access::COMPUTE_READ)]);
        uses.extend(writes);
        let push = StoragePush { eye: c.eye, light_count: c.light_count, objects, pad: [0; 2] };
        Pass::new("network (storage buffer)", uses, move |cmd| {
            // Pipeline 1 is for frames of several lights (SEVERAL_LIGHTS).
            let pipeline = usize::from(c.light_count > 1);
            let dispatch = Dispatch::Covering { width: extent.width, height: extent.height };
            self.pass.record_pipeline(ctx, cmd, pipeline, bytemuck::bytes_of(&push), dispatch)
        })
    }
}

impl Destroy for Storage {
    fn destroy(self, ctx: &Context) {
        self.pass.destroy(ctx);
        ctx.destroy_buffer(self.weights);
    }
}
