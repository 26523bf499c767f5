//! Compute pipelines of one shader with one descriptor set bound at creation
//! ([`crate::backend::descriptors`]). A pass can hold several pipelines of the same shader that differ
//! only in specialization constants.

use std::sync::OnceLock;

use ash::vk;

use crate::backend::context::Context;
pub use crate::backend::descriptors::Bind;
use crate::backend::descriptors::BoundSet;
use crate::backend::guard::Destroy;
use crate::backend::resources::Buffer;
use crate::error::{Result, VkContext};

/// Specialization constant values: word `i` is the 32-bit value of `constant_id = i`.
pub type Specialization = Vec<u32>;

/// How many workgroups a dispatch launches.
pub enum Dispatch<'a> {
    /// Enough to cover `width × height` invocations, rounded up to whole workgroups; the shader
    /// skips invocations outside the image.
    Covering { width: u32, height: u32 },
    /// A `VkDispatchIndirectCommand` at `offset` in `buffer`, written on the device.
    Indirect { buffer: &'a Buffer, offset: u64 },
}

/// The block of whole `tile` × `tile` tiles that covers `area`: its first pixel, which the
/// shader adds to `gl_GlobalInvocationID`, and its size, to dispatch [`Dispatch::Covering`].
/// (`vkCmdDispatchBase` would do the same, but lavapipe of Mesa 22.3 draws the wrong tiles
/// with it.)
pub fn tile_block(area: vk::Rect2D, tile: u32) -> ([u32; 2], vk::Extent2D) {
    let (x, y) = (area.offset.x.max(0) as u32, area.offset.y.max(0) as u32);
    let first = [x / tile * tile, y / tile * tile];
    let extent = vk::Extent2D { width: x + area.extent.width - first[0], height: y + area.extent.height - first[1] };
    (first, extent)
}

pub struct ComputePass {
    pipelines: Vec<vk::Pipeline>,
    /// Pipelines made when a frame first needs them ([`ComputePass::with_deferred`]).
    deferred: Option<Box<Deferred>>,
    pub layout: vk::PipelineLayout,
    set: Option<BoundSet>,
    /// Local workgroup size in x and y, as declared by the shader.
    workgroup: (u32, u32),
}

/// Pipelines of a pass that wait, with their shader, until [`ComputePass::make_deferred`]
/// makes them, each when a frame first needs it. On lavapipe each specialized pipeline costs
/// start-up time and memory (about 2 MB), so a pass with hundreds is better made a few at a
/// time, as frames need them.
struct Deferred {
    name: String,
    spirv: Vec<u32>,
    specializations: Vec<Specialization>,
    made: Vec<OnceLock<vk::Pipeline>>,
}

impl ComputePass {
    /// Builds the pipeline from SPIR-V with entry point `main`, a push-constant block of
    /// `push_bytes`, and `bindings` in binding order. `workgroup` must match the shader's
    /// `local_size_x/y`.
    pub fn new(
        ctx: &Context,
        name: &str,
        spirv: &[u32],
        bindings: &[Bind<'_>],
        push_bytes: u32,
        workgroup: (u32, u32),
    ) -> Result<Self> {
        Self::specialized(ctx, name, spirv, bindings, push_bytes, workgroup, &[Vec::new()])
    }

    /// Like [`ComputePass::new`], with one pipeline per entry of `specializations`, created on
    /// all CPU cores: drivers compile each one separately, and one that folds constants into
    /// the code can take a while.
    pub fn specialized(
        ctx: &Context,
        name: &str,
        spirv: &[u32],
        bindings: &[Bind<'_>],
        push_bytes: u32,
        workgroup: (u32, u32),
        specializations: &[Specialization],
    ) -> Result<Self> {
        let device = &ctx.device;
        // Made step by step; a failed step destroys what was made (null handles are skipped).
        let mut pass = ctx.guard(ComputePass {
            pipelines: Vec::new(),
            deferred: None,
            layout: vk::PipelineLayout::null(),
            set: None,
            workgroup,
        });
        let set = pass.set.insert(BoundSet::new(ctx, name, bindings, vk::ShaderStageFlags::COMPUTE)?);
        let set_layouts = [set.layout];
        let push =
            [vk::PushConstantRange::default().stage_flags(vk::ShaderStageFlags::COMPUTE).offset(0).size(push_bytes)];
        let mut layout_info = vk::PipelineLayoutCreateInfo::default().set_layouts(&set_layouts);
        if push_bytes > 0 {
            layout_info = layout_info.push_constant_ranges(&push);
        }
        // SAFETY: the create info outlives the call; `destroy` destroys the layout.
        pass.layout = unsafe { device.create_pipeline_layout(&layout_info, None) }.vk("vkCreatePipelineLayout")?;

        if !specializations.is_empty() {
            // A lone pipeline is labelled with the pass's name alone.
            let numbers: Vec<usize> =
                if specializations.len() > 1 { (0..specializations.len()).collect() } else { vec![] };
            pass.pipelines = make_pipelines(ctx, name, spirv, pass.layout, specializations, &numbers)?;
        }
        ctx.set_name(pass.layout, name);
        Ok(pass.keep())
    }

    /// The pass with pipelines of `spirv` (its layout's shader), one per entry of
    /// `specializations`, that are not made here: [`ComputePass::make_deferred`] makes each
    /// when a frame first needs it. They follow the pass's own in
    /// [`ComputePass::record_pipeline`]'s numbering.
    pub fn with_deferred(mut self, name: &str, spirv: &[u32], specializations: Vec<Specialization>) -> Self {
        let made = specializations.iter().map(|_| OnceLock::new()).collect();
        self.deferred =
            Some(Box::new(Deferred { name: name.to_string(), spirv: spirv.to_vec(), specializations, made }));
        self
    }

    /// Makes the deferred pipelines of `indices` (in [`ComputePass::record_pipeline`]'s
    /// numbering) that are not made yet, on all CPU cores. Returns how many it made.
    pub fn make_deferred(&self, ctx: &Context, indices: impl IntoIterator<Item = usize>) -> Result<usize> {
        let Some(deferred) = &self.deferred else { return Ok(0) };
        let first = self.pipelines.len();
        let mut missing: Vec<usize> = indices
            .into_iter()
            .map(|index| index.checked_sub(first).expect("a deferred pipeline's index"))
            .filter(|&later| deferred.made[later].get().is_none())
            .collect();
        missing.sort_unstable();
        missing.dedup();
        if missing.is_empty() {
            return Ok(0);
        }
        let specializations: Vec<Specialization> =
            missing.iter().map(|&later| deferred.specializations[later].clone()).collect();
        let numbers: Vec<usize> = missing.iter().map(|later| first + later).collect();
        let made = make_pipelines(ctx, &deferred.name, &deferred.spirv, self.layout, &specializations, &numbers)?;
        for (&later, pipeline) in missing.iter().zip(made) {
            if deferred.made[later].set(pipeline).is_err() {
                // Made on another thread meanwhile: this one was never used.
                // SAFETY: the pipeline belongs to this device and was never used.
                unsafe { ctx.device.destroy_pipeline(pipeline, None) };
            }
        }
        Ok(missing.len())
    }

    /// Points the descriptor set at other resources of the same kinds and order (after a
    /// resize). No submitted command buffer that uses the pass may still be pending.
    pub fn rebind(&self, ctx: &Context, bindings: &[Bind<'_>]) {
        if let Some(set) = &self.set {
            set.rebind(ctx, bindings);
        }
    }

    /// Records a dispatch of the first pipeline that covers `width × height` invocations.
    pub fn record(&self, ctx: &Context, cmd: vk::CommandBuffer, push: &[u8], width: u32, height: u32) {
        self.record_pipeline(ctx, cmd, 0, push, Dispatch::Covering { width, height });
    }

    /// Records a dispatch of pipeline `index` (the order of `specializations`).
    pub fn record_pipeline(
        &self,
        ctx: &Context,
        cmd: vk::CommandBuffer,
        index: usize,
        push: &[u8],
        dispatch: Dispatch,
    ) {
        let device = &ctx.device;
        let pipeline = match index.checked_sub(self.pipelines.len()) {
            None => self.pipelines[index],
            Some(later) => {
                let made = self.deferred.as_ref().and_then(|d| d.made[later].get());
                *made.expect("a deferred pipeline is made before a frame records it")
            }
        };
        // SAFETY: `cmd` is recording, outside a render pass; the pipeline, layout, set and
        // buffers belong to this device and outlive the frame (true of the blocks below too).
        unsafe { device.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::COMPUTE, pipeline) };
        if let Some(set) = self.set.as_ref().filter(|s| s.set != vk::DescriptorSet::null()) {
            let sets = [set.set];
            // SAFETY: as above; the set matches the layout's set 0.
            unsafe { device.cmd_bind_descriptor_sets(cmd, vk::PipelineBindPoint::COMPUTE, self.layout, 0, &sets, &[]) };
        }
        if !push.is_empty() {
            // SAFETY: as above; the layout's push range is the size the pass was made with.
            unsafe { device.cmd_push_constants(cmd, self.layout, vk::ShaderStageFlags::COMPUTE, 0, push) };
        }
        match dispatch {
            Dispatch::Covering { width, height } => {
                let groups = (width.div_ceil(self.workgroup.0), height.div_ceil(self.workgroup.1));
                // SAFETY: as above.
                unsafe { device.cmd_dispatch(cmd, groups.0, groups.1, 1) };
            }
            // SAFETY: as above; the buffer was made with indirect usage and holds the arguments.
            Dispatch::Indirect { buffer, offset } => unsafe { device.cmd_dispatch_indirect(cmd, buffer.raw, offset) },
        }
    }

    pub fn destroy(self, ctx: &Context) {
        Destroy::destroy(self, ctx);
    }
}

impl Destroy for ComputePass {
    fn destroy(self, ctx: &Context) {
        let device = &ctx.device;
        // SAFETY: the caller has finished all GPU work that uses the pass; null handles (of a
        // pass only partly made) are ignored by the destroy calls.
        unsafe {
            let deferred = self.deferred.into_iter().flat_map(|d| d.made).filter_map(OnceLock::into_inner);
            for pipeline in self.pipelines.into_iter().chain(deferred) {
                device.destroy_pipeline(pipeline, None);
            }
            device.destroy_pipeline_layout(self.layout, None);
        }
        self.set.destroy(ctx);
    }
}

/// The pipelines of `spirv` for `specializations`, labelled `name #n` with their `numbers`
/// in the pass, or `name` where `numbers` has none.
fn make_pipelines(
    ctx: &Context,
    name: &str,
    spirv: &[u32],
    layout: vk::PipelineLayout,
    specializations: &[Specialization],
    numbers: &[usize],
) -> Result<Vec<vk::Pipeline>> {
    ctx.step("vkCreateComputePipelines")?;
    let module = ctx.create_shader_module(spirv)?;
    // SAFETY: the module and the layout belong to this device.
    let pipelines = unsafe { create_pipelines(&ctx.device, module, layout, specializations) };
    ctx.destroy_shader_module(module);
    let pipelines = pipelines?;
    for (i, &pipeline) in pipelines.iter().enumerate() {
        let label = numbers.get(i).map_or_else(|| name.to_string(), |n| format!("{name} #{n}"));
        ctx.set_name(pipeline, &label);
    }
    Ok(pipelines)
}

/// One pipeline per specialization, spread over the CPU's cores. On failure, destroys the
/// pipelines it made.
///
/// # Safety
/// `module` and `layout` belong to `device`.
unsafe fn create_pipelines(
    device: &ash::Device,
    module: vk::ShaderModule,
    layout: vk::PipelineLayout,
    specializations: &[Specialization],
) -> Result<Vec<vk::Pipeline>> {
    let create = |spec: &Specialization| -> Result<vk::Pipeline> {
        let entries: Vec<_> = (0..spec.len() as u32)
            .map(|id| vk::SpecializationMapEntry { constant_id: id, offset: 4 * id, size: 4 })
            .collect();
        let info = vk::SpecializationInfo::default().map_entries(&entries).data(bytemuck::cast_slice(spec));
        let mut stage = vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::COMPUTE)
            .module(module)
            .name(c"main");
        if !spec.is_empty() {
            stage = stage.specialization_info(&info);
        }
        let create_info = vk::ComputePipelineCreateInfo::default().stage(stage).layout(layout);
        // SAFETY: the create info and everything it points to live until the call returns;
        // pipeline creation may run on several threads at once without a pipeline cache.
        let created = unsafe { device.create_compute_pipelines(vk::PipelineCache::null(), &[create_info], None) };
        Ok(created.map_err(|(_, e)| e).vk("vkCreateComputePipelines")?[0])
    };
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get()).min(specializations.len()).max(1);
    let chunk = specializations.len().div_ceil(threads).max(1);
    let results: Vec<Result<vk::Pipeline>> = std::thread::scope(|scope| {
        let workers: Vec<_> = specializations
            .chunks(chunk)
            .map(|specs| scope.spawn(move || specs.iter().map(create).collect::<Vec<_>>()))
            .collect();
        workers.into_iter().flat_map(|w| w.join().expect("pipeline creation thread panicked")).collect()
    });
    let mut pipelines = Vec::with_capacity(results.len());
    let mut error = None;
    for result in results {
        match result {
            Ok(pipeline) => pipelines.push(pipeline),
            Err(e) => error = error.or(Some(e)),
        }
    }
    match error {
        None => Ok(pipelines),
        Some(e) => {
            for pipeline in pipelines {
                // SAFETY: the pipelines were never used.
                unsafe { device.destroy_pipeline(pipeline, None) };
            }
            Err(e)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rect(x: i32, y: i32, width: u32, height: u32) -> vk::Rect2D {
        vk::Rect2D { offset: vk::Offset2D { x, y }, extent: vk::Extent2D { width, height } }
    }

    #[test]
    fn a_tile_block_starts_on_a_tile_and_covers_the_area() {
        // Pixels 13..=42 across, 3..=4 down: tiles from 8 and 0, through pixel 42 and 4.
        let (origin, extent) = tile_block(rect(13, 3, 30, 2), 8);
        assert_eq!(origin, [8, 0]);
        assert_eq!((extent.width, extent.height), (35, 5));
        assert_eq!(extent.width.div_ceil(8), 5, "tiles 1 to 5 across");
        // An aligned area is its own block.
        let (origin, extent) = tile_block(rect(16, 8, 16, 8), 8);
        assert_eq!((origin, extent.width, extent.height), ([16, 8], 16, 8));
    }
}
