//! One frame on the GPU: the G-buffer pass, then the network pass, for a scene and a model.

use anyhow::Result;
use rrf_baker::glam::Vec3;
use rrf_baker::model::Model;
use rrf_baker::network::Component;
use rrf_baker::scene::{Scene, View};
use rrf_renderer::gbuffer::{GBufferMesh, GBufferPass, GBufferTargets};
use rrf_renderer::network_pass::{NetworkConstants, NetworkPass, NetworkShaders, ObjectNetworks, Variant};
use rrf_renderer::tonemap::TonemapPass;
use rrf_renderer::{vk, Context, Image};

use crate::gpu_scene::{camera_constants, gbuffer_vertices};
use crate::shaders;

/// Each object's networks, by object id; `None` for objects the model has none for.
pub fn object_networks<'a>(scene: &Scene, model: &'a Model) -> Vec<Option<ObjectNetworks<'a>>> {
    scene
        .objects
        .iter()
        .map(|o| {
            let direct = model.network(&o.name, Component::Direct)?;
            let indirect = model.network(&o.name, Component::Indirect)?;
            Some(ObjectNetworks {
                direct: &direct.params,
                indirect: &indirect.params,
                input_min: direct.input_min,
                input_max: direct.input_max,
                direct_scale: direct.output_scale,
                indirect_scale: indirect.output_scale,
            })
        })
        .collect()
}

/// The RGB of read-back RGBA pixels.
pub fn rgb(rgba: &[f32]) -> Vec<Vec3> {
    rgba.chunks_exact(4).map(|p| Vec3::new(p[0], p[1], p[2])).collect()
}

/// Images of one frame, read back: RGBA per pixel, rows top to bottom.
pub struct FramePixels {
    pub direct: Vec<f32>,
    pub indirect: Vec<f32>,
    pub gi: Vec<f32>,
}

pub struct GpuFrame {
    targets: GBufferTargets,
    mesh: GBufferMesh,
    gbuffer: GBufferPass,
    network: NetworkPass,
    /// Display-referred output of the tonemap pass (RGBA8, sRGB-encoded).
    ldr: Image,
    tonemap: TonemapPass,
}

/// Timestamps a frame writes: start, after the G-buffer, after the network pass, after the
/// tonemap pass.
pub const TIMESTAMPS: u32 = 4;

impl GpuFrame {
    /// Everything for frames of `scene` at `extent` with network pass `variant`, with the
    /// moving light `light_offset` from where the glTF puts it.
    pub fn new(
        ctx: &Context,
        scene: &Scene,
        model: &Model,
        variant: Variant,
        extent: vk::Extent2D,
        light_offset: Vec3,
    ) -> Result<Self> {
        let targets = GBufferTargets::new(ctx, extent)?;
        let mesh = GBufferMesh::new(ctx, &gbuffer_vertices(scene, light_offset))?;
        let gbuffer = GBufferPass::new(ctx, shaders::GBUFFER_VERT, shaders::GBUFFER_FRAG)?;
        let network_shaders = NetworkShaders {
            storage: shaders::NETWORK_STORAGE_COMP,
            classify: shaders::NETWORK_CLASSIFY_COMP,
            specialized: shaders::NETWORK_SPECIALIZED_COMP,
        };
        let network = NetworkPass::new(ctx, variant, &network_shaders, &targets, &object_networks(scene, model))?;
        let ldr = ctx.create_image(
            "ldr",
            extent,
            vk::Format::R8G8B8A8_UNORM,
            vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_SRC,
        )?;
        ctx.submit_once(|cmd| ctx.transition(cmd, &ldr, vk::ImageLayout::UNDEFINED, vk::ImageLayout::GENERAL))?;
        let tonemap = TonemapPass::new(ctx, shaders::TONEMAP_COMP, &network.outputs.gi, &ldr)?;
        Ok(GpuFrame { targets, mesh, gbuffer, network, ldr, tonemap })
    }

    pub fn extent(&self) -> vk::Extent2D {
        self.targets.extent
    }

    /// Records the frame's passes; with `timestamps`, writes [`TIMESTAMPS`] of them there.
    pub fn record(
        &self,
        ctx: &Context,
        cmd: vk::CommandBuffer,
        view: &View,
        light: Vec3,
        exposure_scale: f32,
        timestamps: Option<vk::QueryPool>,
    ) {
        let extent = self.targets.extent;
        let camera = camera_constants(view, extent.width as f32 / extent.height as f32);
        let constants = NetworkConstants { eye: camera.eye, light: light.extend(1.0).to_array() };
        let stamp = |index: u32, stage: vk::PipelineStageFlags| {
            if let Some(pool) = timestamps {
                // SAFETY: the pool holds TIMESTAMPS queries, reset below before the first.
                unsafe { ctx.device.cmd_write_timestamp(cmd, stage, pool, index) };
            }
        };
        if let Some(pool) = timestamps {
            // SAFETY: recording outside a render pass; the pool belongs to this device.
            unsafe { ctx.device.cmd_reset_query_pool(cmd, pool, 0, TIMESTAMPS) };
        }
        stamp(0, vk::PipelineStageFlags::TOP_OF_PIPE);
        self.gbuffer.record(ctx, cmd, &self.targets, &self.mesh, &camera);
        stamp(1, vk::PipelineStageFlags::BOTTOM_OF_PIPE);
        ctx.memory_barrier(
            cmd,
            (vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT, vk::AccessFlags::COLOR_ATTACHMENT_WRITE),
            (vk::PipelineStageFlags::COMPUTE_SHADER, vk::AccessFlags::SHADER_READ),
        );
        self.network.record(ctx, cmd, &constants);
        stamp(2, vk::PipelineStageFlags::BOTTOM_OF_PIPE);
        ctx.memory_barrier(
            cmd,
            (vk::PipelineStageFlags::COMPUTE_SHADER, vk::AccessFlags::SHADER_WRITE),
            (vk::PipelineStageFlags::COMPUTE_SHADER, vk::AccessFlags::SHADER_READ),
        );
        self.tonemap.record(ctx, cmd, extent, exposure_scale);
        stamp(3, vk::PipelineStageFlags::BOTTOM_OF_PIPE);
    }

    /// Object ids + 1 of the last frame's pixels (0: nothing).
    pub fn read_objects(&self, ctx: &Context) -> Result<Vec<u32>> {
        Ok(ctx.read_image(&self.targets.object, vk::ImageLayout::GENERAL)?.iter().map(|&v| v as u32).collect())
    }

    /// Renders `view` with the light at `light` and reads the HDR images back.
    pub fn render(&self, ctx: &Context, view: &View, light: Vec3) -> Result<FramePixels> {
        ctx.submit_once(|cmd| self.record(ctx, cmd, view, light, 1.0, None))?;
        let read = |image| ctx.read_image(image, vk::ImageLayout::GENERAL);
        let outputs = &self.network.outputs;
        Ok(FramePixels { direct: read(&outputs.direct)?, indirect: read(&outputs.indirect)?, gi: read(&outputs.gi)? })
    }

    pub fn destroy(self, ctx: &Context) {
        self.tonemap.destroy(ctx);
        ctx.destroy_image(self.ldr);
        self.network.destroy(ctx);
        self.gbuffer.destroy(ctx);
        self.mesh.destroy(ctx);
        self.targets.destroy(ctx);
    }
}
