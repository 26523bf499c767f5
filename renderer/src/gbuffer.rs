//! The G-buffer raster pass: per pixel, what the network pass needs, packed into 36 bytes plus
//! depth (`shaders-glsl/include/gbuffer_layout.glsl`): the world position, the shading normal
//! (normal-mapped), the object and material, which face is seen, and the material's textured
//! values there (base colour, roughness, metallic, emissive texture). Textures are sampled as
//! the path tracer samples them (`gbuffer_materials.glsl`), and alpha-masked texels discarded.

use ash::vk;
use bytemuck::{Pod, Zeroable};
use gpu_allocator::MemoryLocation;

use crate::context::Context;
use crate::descriptors::{Bind, BoundSet};
use crate::error::{Error, Result, VkContext};
use crate::guard::Destroy;
use crate::resources::{Buffer, Image};
use crate::sync::{Access, Pass, ResourceStates, Use};

/// One vertex, in world space; triangles index them (`GBufferMesh`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct GBufferVertex {
    pub position: [f32; 3],
    pub normal: [f32; 3],
    pub uv: [f32; 2],
    /// xyz the tangent, w the bitangent's sign (bitangent = w · normal × tangent).
    pub tangent: [f32; 4],
    pub object: u32,
    pub material: u32,
}

/// How a material uses a texture, as `gbuffer.frag` reads it (`TextureRef` in
/// `gbuffer_materials.glsl`): `uv' = matrix · uv + offset` (row-major 2×2), texels from
/// `first_texel` in the texel buffer, and `shape`: bits 0-14 the width, 15-29 the height, 30
/// set for sRGB texels, 31 set when the texture is used at all.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct TextureRef {
    pub matrix: [f32; 4],
    pub offset: [f32; 2],
    pub first_texel: u32,
    pub shape: u32,
}

impl TextureRef {
    pub const SRGB: u32 = 1 << 30;
    pub const PRESENT: u32 = 1 << 31;
    /// The largest side `shape` holds.
    pub const MAX_SIDE: u32 = (1 << 15) - 1;
}

/// A material as `gbuffer.frag` reads it (`SurfaceMaterial` in `gbuffer_materials.glsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct SurfaceMaterial {
    /// rgb the base colour factor, a its alpha.
    pub base_color: [f32; 4],
    /// Metallic, roughness, the normal map's scale, the alpha cutoff (negative: opaque).
    pub factors: [f32; 4],
    /// Base colour, metallic-roughness, normal and emissive textures.
    pub textures: [TextureRef; 4],
    /// 1 when the material emits from its back face too (glTF `doubleSided`), else 0.
    pub emits_back: u32,
    pub pad: [u32; 3],
}

/// The most objects and materials the packed G-buffer tells apart (16 and 15 bits).
pub const MAX_OBJECTS: usize = 0xffff - 1;
pub const MAX_MATERIALS: usize = 0x7fff;

/// One pixel of the G-buffer, decoded on the CPU (for tests): the twin of
/// `gbuffer_layout.glsl`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GBufferTexel {
    pub position: [f32; 3],
    pub normal: [f32; 3],
    /// Object id + 1; 0 where nothing was drawn.
    pub object: u32,
    pub material: u32,
    pub front: bool,
    pub base_color: [f32; 3],
    pub roughness: f32,
    pub metallic: f32,
    /// The emissive texture's value (1 without one), 0 on a face that does not emit: it
    /// multiplies the material's emission.
    pub emissive_texture: [f32; 3],
}

impl GBufferTexel {
    /// Decodes the `surface` (four words), `id` (one word) and `shading` (four words) texels.
    pub fn decode(surface: [u32; 4], id: u32, shading: [u32; 4]) -> Self {
        let half = |bits: u32| half_to_f32((bits & 0xffff) as u16);
        let unorm = |bits: u32| (bits & 0xffff) as f32 / 65535.0;
        let snorm = |bits: u32| (f32::from((bits & 0xffff) as u16 as i16) / 32767.0).max(-1.0);
        let (px, py) = (snorm(surface[3]), snorm(surface[3] >> 16));
        let mut n = [px, py, 1.0 - px.abs() - py.abs()];
        if n[2] < 0.0 {
            let sign = |v: f32| if v >= 0.0 { 1.0 } else { -1.0 };
            n = [(1.0 - py.abs()) * sign(px), (1.0 - px.abs()) * sign(py), n[2]];
        }
        let length = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        GBufferTexel {
            position: [f32::from_bits(surface[0]), f32::from_bits(surface[1]), f32::from_bits(surface[2])],
            normal: n.map(|c| c / length),
            object: id & 0xffff,
            material: (id >> 16) & 0x7fff,
            front: id >> 31 == 1,
            base_color: [half(shading[0]), half(shading[0] >> 16), half(shading[1])],
            roughness: unorm(shading[3]),
            metallic: unorm(shading[3] >> 16),
            emissive_texture: [half(shading[1] >> 16), half(shading[2]), half(shading[2] >> 16)],
        }
    }
}

/// IEEE half to f32 (what GLSL's `unpackHalf2x16` does per half).
fn half_to_f32(h: u16) -> f32 {
    let sign = if h >> 15 == 1 { -1.0 } else { 1.0 };
    let exponent = i32::from((h >> 10) & 0x1f);
    let mantissa = f32::from(h & 0x3ff);
    sign * match exponent {
        0 => mantissa * 2f32.powi(-24),
        31 if mantissa == 0.0 => f32::INFINITY,
        31 => f32::NAN,
        e => (1.0 + mantissa / 1024.0) * 2f32.powi(e - 15),
    }
}

/// Per-frame constants of the pass: a column-major view-projection matrix (Vulkan clip space:
/// y down, depth 0..1), the eye, and the object id + 1 of the moving light's own geometry
/// (0: no object moves), which is drawn once per [`LightCopy`].
///
/// `light_offset` and `light_scale` are those of the copy being drawn (the pass sets them);
/// 128 bytes in all, the push-constant size every device offers.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GBufferConstants {
    pub view_projection: [[f32; 4]; 4],
    pub eye: [f32; 4],
    pub light_offset: [f32; 4],
    pub light_scale: [f32; 4],
    pub light_object: u32,
    pub pad: [u32; 3],
}

/// One copy of the moving light's geometry: how far it is moved from where the mesh has it,
/// and what its emission is multiplied by (rgb).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightCopy {
    pub offset: [f32; 3],
    pub scale: [f32; 3],
}

pub const SURFACE_FORMAT: vk::Format = vk::Format::R32G32B32A32_UINT;
pub const ID_FORMAT: vk::Format = vk::Format::R32_UINT;
pub const SHADING_FORMAT: vk::Format = vk::Format::R32G32B32A32_UINT;
/// The depth buffer of the passes that rasterise the mesh (G-buffer, shadow maps).
pub(crate) const DEPTH_FORMAT: vk::Format = vk::Format::D32_SFLOAT;

/// The G-buffer's images, in `GENERAL` layout between passes.
pub struct GBufferTargets {
    /// xyz: the world position's bits; w: the shading normal facing the viewer, octahedral.
    pub surface: Image,
    /// Object id + 1 (0 where nothing was drawn), material, front face seen.
    pub id: Image,
    /// The material's textured values: base colour, emissive texture, roughness, metallic.
    pub shading: Image,
    depth: Image,
    pub extent: vk::Extent2D,
}

impl GBufferTargets {
    pub fn new(ctx: &Context, extent: vk::Extent2D) -> Result<Self> {
        let color =
            vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_SRC;
        let image = |name, format, usage| ctx.create_image(name, extent, format, usage).map(|i| ctx.guard(i));
        let surface = image("gbuffer surface", SURFACE_FORMAT, color)?;
        let id = image("gbuffer id", ID_FORMAT, color)?;
        let shading = image("gbuffer shading", SHADING_FORMAT, color)?;
        let depth = image("gbuffer depth", DEPTH_FORMAT, vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT)?;
        ctx.submit_once(|cmd| {
            for image in [&surface, &id, &shading] {
                ctx.transition(cmd, image, vk::ImageLayout::UNDEFINED, vk::ImageLayout::GENERAL);
            }
            ctx.transition(cmd, &depth, vk::ImageLayout::UNDEFINED, vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL);
        })?;
        Ok(GBufferTargets {
            surface: surface.keep(),
            id: id.keep(),
            shading: shading.keep(),
            depth: depth.keep(),
            extent,
        })
    }

    fn colors(&self) -> [&Image; 3] {
        [&self.surface, &self.id, &self.shading]
    }

    /// Records where `new` left the images.
    pub fn register(&self, states: &mut ResourceStates) {
        for image in self.colors() {
            states.set_layout(image, vk::ImageLayout::GENERAL);
        }
        states.set_layout(&self.depth, vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL);
    }

    pub fn destroy(self, ctx: &Context) {
        Destroy::destroy(self, ctx);
    }
}

impl Destroy for GBufferTargets {
    fn destroy(self, ctx: &Context) {
        for image in [self.surface, self.id, self.shading, self.depth] {
            ctx.destroy_image(image);
        }
    }
}

/// The scene's triangles, materials and textures on the GPU.
pub struct GBufferMesh {
    /// The vertices, then the triangles' indices from `index_offset`.
    pub(crate) buffer: Buffer,
    index_offset: u64,
    /// One [`SurfaceMaterial`] per material.
    materials: Buffer,
    /// Every texture's RGBA8 texels, one word each.
    texels: Buffer,
    /// One draw per run of an object's triangles, culled against the view each frame.
    pub(crate) draws: Vec<Draw>,
}

/// A run of one object's triangles in the index buffer, with its bounds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Draw {
    pub(crate) object: u32,
    /// Some triangle's material uses a texture: drawn with the pipeline that samples them.
    textured: bool,
    pub(crate) first_index: u32,
    pub(crate) index_count: u32,
    min: [f32; 3],
    max: [f32; 3],
}

impl Draw {
    /// The runs of `indices` (whole triangles) that belong to one object each.
    /// `textured(material)` says whether a material uses a texture.
    fn runs(vertices: &[GBufferVertex], indices: &[u32], textured: impl Fn(u32) -> bool) -> Vec<Draw> {
        let mut draws: Vec<Draw> = Vec::new();
        for (t, triangle) in indices.chunks_exact(3).enumerate() {
            let object = vertices[triangle[0] as usize].object;
            let draw = match draws.last_mut() {
                Some(d) if d.object == object => d,
                _ => {
                    draws.push(Draw {
                        object,
                        textured: false,
                        first_index: 3 * t as u32,
                        index_count: 0,
                        min: [f32::INFINITY; 3],
                        max: [f32::NEG_INFINITY; 3],
                    });
                    draws.last_mut().expect("just pushed")
                }
            };
            draw.index_count += 3;
            draw.textured |= textured(vertices[triangle[0] as usize].material);
            for &v in triangle {
                let p = vertices[v as usize].position;
                draw.min = std::array::from_fn(|axis| draw.min[axis].min(p[axis]));
                draw.max = std::array::from_fn(|axis| draw.max[axis].max(p[axis]));
            }
        }
        draws
    }

    /// Whether any of the run's bounds can be in the view of `c` (conservative: a box is
    /// culled only when all its corners are outside one plane of the clip volume).
    fn visible(&self, c: &GBufferConstants) -> bool {
        let offset = if self.object + 1 == c.light_object { c.light_offset } else { [0.0; 4] };
        let m = &c.view_projection;
        let mut outside = [true; 6];
        for corner in 0..8 {
            let pick = |axis: usize| {
                let v = if corner & (1 << axis) == 0 { self.min[axis] } else { self.max[axis] };
                v + offset[axis]
            };
            let p = [pick(0), pick(1), pick(2), 1.0];
            let clip: [f32; 4] = std::array::from_fn(|row| (0..4).map(|col| m[col][row] * p[col]).sum());
            let (x, y, z, w) = (clip[0], clip[1], clip[2], clip[3]);
            for (plane, beyond) in [x > w, x < -w, y > w, y < -w, z < 0.0, z > w].into_iter().enumerate() {
                outside[plane] &= beyond;
            }
        }
        !outside.contains(&true)
    }
}

impl GBufferMesh {
    /// The mesh of `vertices` and the triangles that `indices` (three per triangle) make of
    /// them, with `materials` whose textures index into `texels`. Shared vertices are shaded
    /// once where the driver caches them.
    pub fn new(
        ctx: &Context,
        vertices: &[GBufferVertex],
        indices: &[u32],
        materials: &[SurfaceMaterial],
        texels: &[u32],
    ) -> Result<Self> {
        if let Some(&bad) = indices.iter().find(|&&i| i as usize >= vertices.len()) {
            return Err(Error::Invalid(format!("mesh index {bad} is past its {} vertices", vertices.len())));
        }
        if let Some(bad) = vertices.iter().find(|v| v.material as usize >= materials.len().max(1)) {
            return Err(Error::Invalid(format!(
                "vertex material {} is past the {} materials",
                bad.material,
                materials.len()
            )));
        }
        let textured: Vec<bool> =
            materials.iter().map(|m| m.textures.iter().any(|t| t.shape & TextureRef::PRESENT != 0)).collect();
        let max = u64::from(ctx.info.limits.max_storage_buffer_range);
        if texels.len() as u64 * 4 > max {
            return Err(Error::Invalid(format!(
                "the textures' {} MiB exceed the device's largest storage buffer ({} MiB)",
                (texels.len() * 4) >> 20,
                max >> 20
            )));
        }
        // Storage buffers may not be empty.
        let none = [SurfaceMaterial::default()];
        let material_bytes: &[u8] = bytemuck::cast_slice(if materials.is_empty() { &none } else { materials });
        let texel_bytes: &[u8] = if texels.is_empty() { &[0; 4] } else { bytemuck::cast_slice(texels) };
        let materials = ctx.guard(ctx.create_buffer_with_data(
            "materials",
            material_bytes,
            vk::BufferUsageFlags::STORAGE_BUFFER,
        )?);
        let texels =
            ctx.guard(ctx.create_buffer_with_data("texels", texel_bytes, vk::BufferUsageFlags::STORAGE_BUFFER)?);
        let mut bytes: Vec<u8> = bytemuck::cast_slice(vertices).to_vec();
        let index_offset = bytes.len() as u64;
        bytes.extend_from_slice(bytemuck::cast_slice(indices));
        let staging =
            ctx.guard(ctx.create_buffer_with_data("mesh staging", &bytes, vk::BufferUsageFlags::TRANSFER_SRC)?);
        let buffer = ctx.guard(ctx.create_buffer(
            "scene mesh",
            bytes.len() as u64,
            vk::BufferUsageFlags::VERTEX_BUFFER
                | vk::BufferUsageFlags::INDEX_BUFFER
                | vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuOnly,
        )?);
        ctx.submit_once(|cmd| {
            let region = vk::BufferCopy { src_offset: 0, dst_offset: 0, size: bytes.len() as u64 };
            // SAFETY: both buffers hold at least `bytes.len()` bytes.
            unsafe { ctx.device.cmd_copy_buffer(cmd, staging.raw, buffer.raw, &[region]) };
        })?;
        Ok(GBufferMesh {
            buffer: buffer.keep(),
            index_offset,
            materials: materials.keep(),
            texels: texels.keep(),
            draws: Draw::runs(vertices, indices, |m| textured.get(m as usize).copied().unwrap_or(false)),
        })
    }

    /// Binds the vertex and index buffers for drawing `draws`.
    pub(crate) fn bind(&self, ctx: &Context, cmd: vk::CommandBuffer) {
        // SAFETY: `cmd` is recording; the buffer belongs to this device and outlives the frame.
        unsafe {
            ctx.device.cmd_bind_vertex_buffers(cmd, 0, &[self.buffer.raw], &[0]);
            ctx.device.cmd_bind_index_buffer(cmd, self.buffer.raw, self.index_offset, vk::IndexType::UINT32);
        }
    }

    pub fn destroy(self, ctx: &Context) {
        for buffer in [self.buffer, self.materials, self.texels] {
            ctx.destroy_buffer(buffer);
        }
    }
}

impl Destroy for GBufferMesh {
    fn destroy(self, ctx: &Context) {
        GBufferMesh::destroy(self, ctx);
    }
}

pub struct GBufferPass {
    /// For draws without textures, and with (`gbuffer.frag`'s TEXTURED constant): lavapipe
    /// runs the code of a branch no fragment takes, and the texture code made untextured
    /// scenes' G-buffer ten times slower.
    pipelines: [vk::Pipeline; 2],
    layout: vk::PipelineLayout,
    /// The materials and texels of the mesh the pass was made for.
    set: Option<BoundSet>,
}

impl GBufferPass {
    /// `vertex` and `fragment` are the SPIR-V of `gbuffer.vert` and `gbuffer.frag`; the pass
    /// reads the materials and textures of `mesh`, and draws only that mesh.
    pub fn new(ctx: &Context, vertex: &[u32], fragment: &[u32], mesh: &GBufferMesh) -> Result<Self> {
        let device = &ctx.device;
        let push = [vk::PushConstantRange::default()
            .stage_flags(vk::ShaderStageFlags::VERTEX)
            .size(std::mem::size_of::<GBufferConstants>() as u32)];
        // Destroyed by the guard if a step fails; null handles are skipped.
        let mut pass = ctx.guard(GBufferPass {
            pipelines: [vk::Pipeline::null(); 2],
            layout: vk::PipelineLayout::null(),
            set: None,
        });
        let bindings = [Bind::StorageBuffer(&mesh.materials), Bind::StorageBuffer(&mesh.texels)];
        let set = pass.set.insert(BoundSet::new(ctx, "gbuffer", &bindings, vk::ShaderStageFlags::FRAGMENT)?);
        let set_layouts = [set.layout];
        // SAFETY: valid create infos that outlive the calls; objects destroyed in `destroy`.
        unsafe {
            pass.layout = device
                .create_pipeline_layout(
                    &vk::PipelineLayoutCreateInfo::default().set_layouts(&set_layouts).push_constant_ranges(&push),
                    None,
                )
                .vk("vkCreatePipelineLayout")?;
            let layout = pass.layout;
            let attributes = [
                vk::VertexInputAttributeDescription::default()
                    .location(0)
                    .format(vk::Format::R32G32B32_SFLOAT)
                    .offset(0),
                vk::VertexInputAttributeDescription::default()
                    .location(1)
                    .format(vk::Format::R32G32B32_SFLOAT)
                    .offset(12),
                vk::VertexInputAttributeDescription::default().location(2).format(vk::Format::R32_UINT).offset(48),
                vk::VertexInputAttributeDescription::default().location(3).format(vk::Format::R32_UINT).offset(52),
                vk::VertexInputAttributeDescription::default().location(4).format(vk::Format::R32G32_SFLOAT).offset(24),
                vk::VertexInputAttributeDescription::default()
                    .location(5)
                    .format(vk::Format::R32G32B32A32_SFLOAT)
                    .offset(32),
            ];
            let raster = Raster {
                vertex,
                fragment,
                attributes: &attributes,
                color_formats: &[SURFACE_FORMAT, ID_FORMAT, SHADING_FORMAT],
                depth_format: DEPTH_FORMAT,
            };
            // Specialization constant 0 (TEXTURED) off, then on.
            let pipelines = raster.pipelines(ctx, layout, &[0, 1])?;
            pass.pipelines.copy_from_slice(&pipelines);
            ctx.set_name(pass.pipelines[0], "gbuffer");
            ctx.set_name(pass.pipelines[1], "gbuffer (textured)");
            ctx.set_name(layout, "gbuffer");
        }
        Ok(pass.keep())
    }

    /// The pass for a frame list: it writes every target and reads the mesh.
    pub fn pass<'a>(
        &'a self,
        ctx: &'a Context,
        targets: &'a GBufferTargets,
        mesh: &'a GBufferMesh,
        constants: GBufferConstants,
        lights: Vec<LightCopy>,
    ) -> Pass<'a> {
        let mut uses: Vec<Use> =
            targets.colors().iter().map(|i| Use::image(i, Access::COLOR_ATTACHMENT_WRITE)).collect();
        uses.push(Use::image(&targets.depth, Access::DEPTH_ATTACHMENT));
        uses.push(Use::buffer(&mesh.buffer, Access::VERTEX_INDEX_READ));
        uses.push(Use::buffer(&mesh.materials, Access::FRAGMENT_READ));
        uses.push(Use::buffer(&mesh.texels, Access::FRAGMENT_READ));
        Pass::new("gbuffer", uses, move |cmd| self.record(ctx, cmd, targets, mesh, &constants, &lights))
    }

    /// Records the pass: clears the targets and draws `mesh` seen through `camera`, the moving
    /// light's geometry once per copy in `lights`. The color targets are in `GENERAL` layout
    /// before and after.
    pub fn record(
        &self,
        ctx: &Context,
        cmd: vk::CommandBuffer,
        targets: &GBufferTargets,
        mesh: &GBufferMesh,
        camera: &GBufferConstants,
        lights: &[LightCopy],
    ) {
        let device = &ctx.device;
        let zero = vk::ClearValue { color: vk::ClearColorValue { uint32: [0; 4] } };
        let attachments: Vec<vk::RenderingAttachmentInfo> = targets
            .colors()
            .iter()
            .map(|image| {
                vk::RenderingAttachmentInfo::default()
                    .image_view(image.view)
                    .image_layout(vk::ImageLayout::GENERAL)
                    .load_op(vk::AttachmentLoadOp::CLEAR)
                    .store_op(vk::AttachmentStoreOp::STORE)
                    .clear_value(zero)
            })
            .collect();
        let depth = cleared_depth(&targets.depth);
        let area = vk::Rect2D { offset: vk::Offset2D::default(), extent: targets.extent };
        let info = vk::RenderingInfo::default()
            .render_area(area)
            .layer_count(1)
            .color_attachments(&attachments)
            .depth_attachment(&depth);
        let viewport = vk::Viewport {
            x: 0.0,
            y: 0.0,
            width: targets.extent.width as f32,
            height: targets.extent.height as f32,
            min_depth: 0.0,
            max_depth: 1.0,
        };
        // SAFETY: `cmd` is recording outside a render pass; all objects belong to this device.
        unsafe {
            device.cmd_begin_rendering(cmd, &info);

            device.cmd_set_viewport(cmd, 0, &[viewport]);
            device.cmd_set_scissor(cmd, 0, &[area]);
            if let Some(set) = &self.set {
                device.cmd_bind_descriptor_sets(cmd, vk::PipelineBindPoint::GRAPHICS, self.layout, 0, &[set.set], &[]);
            }
            mesh.bind(ctx, cmd);
            // The scene, then each copy of the moving light with its own offset and scale.
            let still = std::iter::once((*camera, false));
            let copies = lights.iter().map(|l| {
                let placed = GBufferConstants {
                    light_offset: [l.offset[0], l.offset[1], l.offset[2], 0.0],
                    light_scale: [l.scale[0], l.scale[1], l.scale[2], 0.0],
                    ..*camera
                };
                (placed, true)
            });
            let mut bound = None;
            for (constants, moving) in still.chain(copies) {
                let stage = vk::ShaderStageFlags::VERTEX;
                device.cmd_push_constants(cmd, self.layout, stage, 0, bytemuck::bytes_of(&constants));
                // Objects whose bounds are outside the view cost no vertex work or triangle
                // set-up.
                let draws = mesh.draws.iter().filter(|d| (d.object + 1 == constants.light_object) == moving);
                for draw in draws.filter(|d| d.visible(&constants)) {
                    if bound != Some(draw.textured) {
                        let pipeline = self.pipelines[usize::from(draw.textured)];
                        device.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, pipeline);
                        bound = Some(draw.textured);
                    }
                    device.cmd_draw_indexed(cmd, draw.index_count, 1, draw.first_index, 0, 0);
                }
            }
            device.cmd_end_rendering(cmd);
        }
    }

    pub fn destroy(self, ctx: &Context) {
        Destroy::destroy(self, ctx);
    }
}

impl Destroy for GBufferPass {
    fn destroy(self, ctx: &Context) {
        // SAFETY: no GPU work that uses the pipeline is pending; null handles are ignored.
        unsafe {
            for pipeline in self.pipelines {
                ctx.device.destroy_pipeline(pipeline, None);
            }
            ctx.device.destroy_pipeline_layout(self.layout, None);
        }
        self.set.destroy(ctx);
    }
}

/// The depth attachment of a pass that rasterises the mesh: `depth` ([`DEPTH_FORMAT`]),
/// cleared to the far plane, not stored.
pub(crate) fn cleared_depth(depth: &Image) -> vk::RenderingAttachmentInfo<'static> {
    vk::RenderingAttachmentInfo::default()
        .image_view(depth.view)
        .image_layout(vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL)
        .load_op(vk::AttachmentLoadOp::CLEAR)
        .store_op(vk::AttachmentStoreOp::DONT_CARE)
        .clear_value(vk::ClearValue { depth_stencil: vk::ClearDepthStencilValue { depth: 1.0, stencil: 0 } })
}

/// A graphics pipeline that rasterises the scene mesh ([`GBufferVertex`]) with depth testing,
/// for the G-buffer and shadow passes.
pub(crate) struct Raster<'a> {
    pub vertex: &'a [u32],
    pub fragment: &'a [u32],
    /// The vertex attributes the shaders read, from one binding of `GBufferVertex`s.
    pub attributes: &'a [vk::VertexInputAttributeDescription],
    pub color_formats: &'a [vk::Format],
    pub depth_format: vk::Format,
}

impl Raster<'_> {
    /// One pipeline per value of specialization constant 0, with `layout`. No face culling;
    /// viewport and scissor are dynamic. The caller destroys the pipelines.
    pub(crate) fn pipelines(
        &self,
        ctx: &Context,
        layout: vk::PipelineLayout,
        values: &[u32],
    ) -> Result<Vec<vk::Pipeline>> {
        let device = &ctx.device;
        ctx.step("vkCreateGraphicsPipelines")?;
        // SAFETY: valid create infos that outlive the calls; the modules are destroyed here.
        unsafe {
            let module = |code| device.create_shader_module(&vk::ShaderModuleCreateInfo::default().code(code), None);
            let vs = module(self.vertex).vk("vkCreateShaderModule")?;
            let fs = match module(self.fragment) {
                Ok(fs) => fs,
                Err(e) => {
                    device.destroy_shader_module(vs, None);
                    return Err(e).vk("vkCreateShaderModule");
                }
            };
            let stages = [
                vk::PipelineShaderStageCreateInfo::default()
                    .stage(vk::ShaderStageFlags::VERTEX)
                    .module(vs)
                    .name(c"main"),
                vk::PipelineShaderStageCreateInfo::default()
                    .stage(vk::ShaderStageFlags::FRAGMENT)
                    .module(fs)
                    .name(c"main"),
            ];
            let bindings = [vk::VertexInputBindingDescription::default()
                .binding(0)
                .stride(std::mem::size_of::<GBufferVertex>() as u32)
                .input_rate(vk::VertexInputRate::VERTEX)];
            let vertex_input = vk::PipelineVertexInputStateCreateInfo::default()
                .vertex_binding_descriptions(&bindings)
                .vertex_attribute_descriptions(self.attributes);
            let assembly =
                vk::PipelineInputAssemblyStateCreateInfo::default().topology(vk::PrimitiveTopology::TRIANGLE_LIST);
            let viewport = vk::PipelineViewportStateCreateInfo::default().viewport_count(1).scissor_count(1);
            // The projection's y flip and Vulkan's y-down framebuffer cancel: front faces are
            // counter-clockwise on screen, as in the scene.
            let raster = vk::PipelineRasterizationStateCreateInfo::default()
                .polygon_mode(vk::PolygonMode::FILL)
                .cull_mode(vk::CullModeFlags::NONE)
                .front_face(vk::FrontFace::COUNTER_CLOCKWISE)
                .line_width(1.0);
            let multisample =
                vk::PipelineMultisampleStateCreateInfo::default().rasterization_samples(vk::SampleCountFlags::TYPE_1);
            let depth = vk::PipelineDepthStencilStateCreateInfo::default()
                .depth_test_enable(true)
                .depth_write_enable(true)
                .depth_compare_op(vk::CompareOp::LESS);
            let blend = vec![
                vk::PipelineColorBlendAttachmentState::default()
                    .color_write_mask(vk::ColorComponentFlags::RGBA);
                self.color_formats.len()
            ];
            let blending = vk::PipelineColorBlendStateCreateInfo::default().attachments(&blend);
            let dynamic_states = [vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR];
            let dynamic = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dynamic_states);
            let mut rendering = vk::PipelineRenderingCreateInfo::default()
                .color_attachment_formats(self.color_formats)
                .depth_attachment_format(self.depth_format);
            let info = vk::GraphicsPipelineCreateInfo::default()
                .vertex_input_state(&vertex_input)
                .input_assembly_state(&assembly)
                .viewport_state(&viewport)
                .rasterization_state(&raster)
                .multisample_state(&multisample)
                .depth_stencil_state(&depth)
                .color_blend_state(&blending)
                .dynamic_state(&dynamic)
                .layout(layout)
                .push_next(&mut rendering);
            let mut pipelines = Vec::with_capacity(values.len());
            let mut created = Ok(());
            for &value in values {
                let value = [value];
                let entries = [vk::SpecializationMapEntry { constant_id: 0, offset: 0, size: 4 }];
                let specialization =
                    vk::SpecializationInfo::default().map_entries(&entries).data(bytemuck::cast_slice(&value));
                let mut stages = stages;
                stages[1] = stages[1].specialization_info(&specialization);
                match device.create_graphics_pipelines(vk::PipelineCache::null(), &[info.stages(&stages)], None) {
                    Ok(p) => pipelines.push(p[0]),
                    Err((_, e)) => {
                        created = Err(e);
                        break;
                    }
                }
            }
            device.destroy_shader_module(vs, None);
            device.destroy_shader_module(fs, None);
            if let Err(e) = created {
                for p in pipelines {
                    device.destroy_pipeline(p, None);
                }
                return Err(e).vk("vkCreateGraphicsPipelines");
            }
            Ok(pipelines)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn vertex(position: [f32; 3], object: u32) -> GBufferVertex {
        GBufferVertex { position, normal: [0.0, 0.0, 1.0], object, ..Default::default() }
    }

    /// Identity view-projection: the clip volume is x, y in [-1, 1], z in [0, 1].
    fn identity(light_object: u32, light_offset: [f32; 4]) -> GBufferConstants {
        let mut view_projection = [[0.0; 4]; 4];
        for (i, column) in view_projection.iter_mut().enumerate() {
            column[i] = 1.0;
        }
        GBufferConstants {
            view_projection,
            eye: [0.0; 4],
            light_offset,
            light_scale: [1.0; 4],
            light_object,
            pad: [0; 3],
        }
    }

    #[test]
    fn runs_split_by_object_and_cull_outside_the_view() {
        let vertices = [
            vertex([0.0, 0.0, 0.5], 0),
            vertex([0.1, 0.0, 0.5], 0),
            vertex([0.0, 0.1, 0.5], 0),
            vertex([5.0, 5.0, 0.5], 1),
            vertex([5.1, 5.0, 0.5], 1),
            vertex([5.0, 5.1, 0.5], 1),
        ];
        let draws = Draw::runs(&vertices, &[0, 1, 2, 3, 4, 5, 2, 1, 0], |_| false);
        assert_eq!(draws.len(), 3, "object 0, object 1, object 0 again");
        assert_eq!((draws[1].first_index, draws[1].index_count), (3, 3));
        assert_eq!(draws[1].min, [5.0, 5.0, 0.5]);
        let view = identity(0, [0.0; 4]);
        assert!(draws[0].visible(&view) && !draws[1].visible(&view));
        // The moving light's object follows its offset, into the view here.
        let moved = identity(2, [-5.0, -5.0, 0.0, 0.0]);
        assert!(draws[1].visible(&moved));
        // Behind the near plane.
        let behind = Draw::runs(&[vertex([0.0, 0.0, -1.0], 0); 3], &[0, 1, 2], |_| false);
        assert!(!behind[0].visible(&view));
        // A box around the whole view is visible though no corner is inside.
        let around = [vertex([-9.0, -9.0, -9.0], 0), vertex([9.0, 9.0, 9.0], 0), vertex([9.0, -9.0, 0.5], 0)];
        assert!(Draw::runs(&around, &[0, 1, 2], |_| false)[0].visible(&view));
    }
}
