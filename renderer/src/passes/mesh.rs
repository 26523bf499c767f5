//! The scene's triangles, materials and textures as the G-buffer and shadow passes draw them,
//! in runs of one object's triangles (culled against the view by the G-buffer pass).

use ash::vk;
use bytemuck::{Pod, Zeroable};
use gpu_allocator::MemoryLocation;

use crate::backend::context::Context;
use crate::backend::guard::Destroy;
use crate::backend::resources::Buffer;
use crate::error::{Error, Result};

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

/// The scene's triangles, materials and textures on the GPU.
pub struct GBufferMesh {
    /// The vertices, then the triangles' indices from `index_offset`.
    pub(crate) buffer: Buffer,
    index_offset: u64,
    /// One [`SurfaceMaterial`] per material.
    pub(crate) materials: Buffer,
    /// Every texture's RGBA8 texels, one word each.
    pub(crate) texels: Buffer,
    /// One draw per run of an object's triangles, culled against the view each frame.
    pub(crate) draws: Vec<Draw>,
}

/// A run of one object's triangles in the index buffer, with its bounds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Draw {
    pub(crate) object: u32,
    /// Some triangle's material uses a texture: drawn with the pipeline that samples them.
    pub(crate) textured: bool,
    pub(crate) first_index: u32,
    pub(crate) index_count: u32,
    pub(crate) min: [f32; 3],
    pub(crate) max: [f32; 3],
}

impl Draw {
    /// The runs of `indices` (whole triangles) that belong to one object each.
    /// `textured(material)` says whether a material uses a texture.
    pub(crate) fn runs(vertices: &[GBufferVertex], indices: &[u32], textured: impl Fn(u32) -> bool) -> Vec<Draw> {
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
}

impl GBufferMesh {
    /// Each object's bounds, by object id: `None` for an object without triangles.
    pub(crate) fn object_bounds(&self) -> Vec<Option<([f32; 3], [f32; 3])>> {
        let mut bounds: Vec<Option<([f32; 3], [f32; 3])>> = Vec::new();
        for draw in &self.draws {
            let object = draw.object as usize;
            if bounds.len() <= object {
                bounds.resize(object + 1, None);
            }
            let (min, max) = bounds[object].get_or_insert((draw.min, draw.max));
            for axis in 0..3 {
                min[axis] = min[axis].min(draw.min[axis]);
                max[axis] = max[axis].max(draw.max[axis]);
            }
        }
        bounds
    }

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

    /// Records `draw`, one of this mesh's index runs, into `cmd`, inside a rendering with a
    /// pipeline, this mesh's buffers ([`GBufferMesh::bind`]) and the constants bound.
    pub(crate) fn draw(&self, ctx: &Context, cmd: vk::CommandBuffer, draw: &Draw) {
        // SAFETY: as the caller guarantees, `cmd` is ready to draw; the run's indices lie
        // inside the index buffer, and `new` checked each against the vertex count.
        unsafe { ctx.device.cmd_draw_indexed(cmd, draw.index_count, 1, draw.first_index, 0, 0) };
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
