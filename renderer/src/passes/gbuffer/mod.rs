//! The G-buffer raster pass: per pixel, what the network pass needs, packed into 36 bytes plus
//! depth (`shaders-glsl/include/gbuffer_layout.glsl`): the world position, the shading normal
//! (normal-mapped), the object and material, which face is seen, and the material's textured
//! values there (base colour, roughness, metallic, emissive texture). Textures are sampled as
//! the path tracer samples them (`gbuffer_materials.glsl`), and alpha-masked texels discarded.

use ash::vk;
use bytemuck::{Pod, Zeroable};

use crate::backend::context::Context;
use crate::backend::descriptors::{Bind, BoundSet};
use crate::backend::guard::Destroy;
use crate::backend::resources::Image;
use crate::backend::sync::{Access, Pass, ResourceStates, Use};
use crate::error::{Result, VkContext};
use crate::passes::mesh::{Draw, GBufferMesh};
use crate::passes::raster::{self, cleared_depth, Raster, DEPTH_FORMAT};

mod texel;

pub use texel::GBufferTexel;

/// The most objects and materials the packed G-buffer tells apart (16 and 14 bits).
pub const MAX_OBJECTS: usize = 0xffff - 1;
pub const MAX_MATERIALS: usize = 0x3fff;

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
/// Per pixel that shows a mirror's reflection: the mirror's Fresnel weight (rgb) and its index
/// among the frame's mirrors (a); see `mirror_merge.comp`.
pub const MIRROR_WEIGHTS_FORMAT: vk::Format = vk::Format::R16G16B16A16_SFLOAT;

/// The G-buffer's images, in `GENERAL` layout between passes.
pub struct GBufferTargets {
    /// xyz: the world position's bits; w: the shading normal facing the viewer, octahedral.
    pub surface: Image,
    /// Object id + 1 (0 where nothing was drawn), material, front face seen.
    pub id: Image,
    /// The material's textured values: base colour, emissive texture, roughness, metallic.
    pub shading: Image,
    /// Where the pixel shows what a planar mirror reflects (its id says so), the mirror's
    /// weight, written by the mirror's merge step: the image's size in a frame that shows
    /// `mirrors`, else a 1×1 stand-in that the network shaders bind and never read.
    pub mirror_weights: Image,
    pub mirrors: bool,
    depth: Image,
    pub extent: vk::Extent2D,
}

impl GBufferTargets {
    /// The images of a G-buffer of `extent`, with room for mirror weights if it will show
    /// `mirrors`.
    pub fn new(ctx: &Context, extent: vk::Extent2D, mirrors: bool) -> Result<Self> {
        let color =
            vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_SRC;
        let image = |name, format, usage| ctx.create_image(name, extent, format, usage).map(|i| ctx.guard(i));
        let surface = image("gbuffer surface", SURFACE_FORMAT, color)?;
        let id = image("gbuffer id", ID_FORMAT, color)?;
        let shading = image("gbuffer shading", SHADING_FORMAT, color)?;
        let depth = image("gbuffer depth", DEPTH_FORMAT, vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT)?;
        let weights_extent = if mirrors { extent } else { vk::Extent2D { width: 1, height: 1 } };
        let mirror_weights = ctx.guard(ctx.create_image(
            "mirror weights",
            weights_extent,
            MIRROR_WEIGHTS_FORMAT,
            vk::ImageUsageFlags::STORAGE,
        )?);
        ctx.submit_once(|cmd| {
            for image in [&surface, &id, &shading, &mirror_weights] {
                ctx.transition(cmd, image, vk::ImageLayout::UNDEFINED, vk::ImageLayout::GENERAL);
            }
            ctx.transition(cmd, &depth, vk::ImageLayout::UNDEFINED, vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL);
        })?;
        Ok(GBufferTargets {
            surface: surface.keep(),
            id: id.keep(),
            shading: shading.keep(),
            mirror_weights: mirror_weights.keep(),
            mirrors,
            depth: depth.keep(),
            extent,
        })
    }

    /// The images the G-buffer pass draws: surface, id, shading.
    pub fn colors(&self) -> [&Image; 3] {
        [&self.surface, &self.id, &self.shading]
    }

    /// Records where `new` left the images.
    pub fn register(&self, states: &mut ResourceStates) {
        for image in self.colors().into_iter().chain([&self.mirror_weights]) {
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
        for image in [self.surface, self.id, self.shading, self.mirror_weights, self.depth] {
            ctx.destroy_image(image);
        }
    }
}

impl Draw {
    /// Whether any of the run's bounds can be in the view of `c` (see [`box_in_view`]).
    pub(crate) fn visible(&self, c: &GBufferConstants) -> bool {
        let offset = if self.object + 1 == c.light_object { c.light_offset } else { [0.0; 4] };
        let moved = |corner: [f32; 3]| std::array::from_fn(|axis| corner[axis] + offset[axis]);
        box_in_view(&c.view_projection, moved(self.min), moved(self.max))
    }
}

/// Whether any of the box from `min` to `max` can be in the view of the view-projection `m`
/// (column-major), conservatively: a box is out only when all its corners are outside one
/// plane of the clip volume.
pub fn box_in_view(m: &[[f32; 4]; 4], min: [f32; 3], max: [f32; 3]) -> bool {
    let mut outside = [true; 6];
    for [x, y, z, w] in clip_corners(m, min, max) {
        for (plane, beyond) in [x > w, x < -w, y > w, y < -w, z < 0.0, z > w].into_iter().enumerate() {
            outside[plane] &= beyond;
        }
    }
    !outside.contains(&true)
}

/// The pixels of a frame of `extent` where the box from `min` to `max` may show through the
/// view-projection `m`: the rectangle around its corners' projections, a pixel wider each way,
/// or the whole frame when a corner is behind the camera.
pub fn box_on_screen(m: &[[f32; 4]; 4], min: [f32; 3], max: [f32; 3], extent: vk::Extent2D) -> vk::Rect2D {
    let size = [extent.width as f32, extent.height as f32];
    let (mut low, mut high) = ([f32::INFINITY; 2], [f32::NEG_INFINITY; 2]);
    for [x, y, _, w] in clip_corners(m, min, max) {
        if w <= 0.0 {
            return vk::Rect2D { offset: vk::Offset2D::default(), extent };
        }
        for (axis, v) in [x, y].into_iter().enumerate() {
            let pixel = (v / w * 0.5 + 0.5) * size[axis];
            (low[axis], high[axis]) = (low[axis].min(pixel), high[axis].max(pixel));
        }
    }
    let low = std::array::from_fn::<f32, 2, _>(|a| (low[a] - 1.0).floor().clamp(0.0, size[a]));
    let high = std::array::from_fn::<f32, 2, _>(|a| (high[a] + 1.0).ceil().clamp(0.0, size[a]));
    vk::Rect2D {
        offset: vk::Offset2D { x: low[0] as i32, y: low[1] as i32 },
        extent: vk::Extent2D { width: (high[0] - low[0]) as u32, height: (high[1] - low[1]) as u32 },
    }
}

/// The eight corners of the box from `min` to `max` in the clip space of `m` (column-major).
fn clip_corners(m: &[[f32; 4]; 4], min: [f32; 3], max: [f32; 3]) -> [[f32; 4]; 8] {
    std::array::from_fn(|corner| {
        let pick = |axis: usize| if corner & (1 << axis) == 0 { min[axis] } else { max[axis] };
        let p = [pick(0), pick(1), pick(2), 1.0];
        std::array::from_fn(|row| (0..4).map(|col| m[col][row] * p[col]).sum())
    })
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
        let layout_info = vk::PipelineLayoutCreateInfo::default().set_layouts(&set_layouts).push_constant_ranges(&push);
        // SAFETY: a valid create info that outlives the call; the layout is destroyed in `destroy`.
        pass.layout = unsafe { device.create_pipeline_layout(&layout_info, None) }.vk("vkCreatePipelineLayout")?;
        let layout = pass.layout;
        let attributes = [
            vk::VertexInputAttributeDescription::default().location(0).format(vk::Format::R32G32B32_SFLOAT).offset(0),
            vk::VertexInputAttributeDescription::default().location(1).format(vk::Format::R32G32B32_SFLOAT).offset(12),
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
        Ok(pass.keep())
    }

    /// The pass for a frame list: it writes every target and reads the mesh. `mirror`: the
    /// constants view the scene in a mirror (their view-projection reflects it), drawn and
    /// cleared only within this area (the rest of the targets keeps what it held).
    pub fn pass<'a>(
        &'a self,
        ctx: &'a Context,
        targets: &'a GBufferTargets,
        mesh: &'a GBufferMesh,
        constants: GBufferConstants,
        lights: Vec<LightCopy>,
        mirror: Option<vk::Rect2D>,
    ) -> Pass<'a> {
        let mut uses: Vec<Use> =
            targets.colors().iter().map(|i| Use::image(i, Access::COLOR_ATTACHMENT_WRITE)).collect();
        uses.push(Use::image(&targets.depth, Access::DEPTH_ATTACHMENT));
        uses.push(Use::buffer(&mesh.buffer, Access::VERTEX_INDEX_READ));
        uses.push(Use::buffer(&mesh.materials, Access::FRAGMENT_READ));
        uses.push(Use::buffer(&mesh.texels, Access::FRAGMENT_READ));
        let name = if mirror.is_some() { "gbuffer (mirrored)" } else { "gbuffer" };
        Pass::new(name, uses, move |cmd| self.record(ctx, cmd, targets, mesh, (&constants, mirror), &lights))
    }

    /// Records the pass: clears the targets and draws `mesh` seen through `camera` (seen in a
    /// mirror and drawn only within `mirror`'s area, if given), the moving light's geometry
    /// once per copy in `lights`. The color targets are in `GENERAL` layout before and after.
    pub fn record(
        &self,
        ctx: &Context,
        cmd: vk::CommandBuffer,
        targets: &GBufferTargets,
        mesh: &GBufferMesh,
        (camera, mirror): (&GBufferConstants, Option<vk::Rect2D>),
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
        let whole = vk::Rect2D { offset: vk::Offset2D::default(), extent: targets.extent };
        let area = mirror.unwrap_or(whole);
        let info = vk::RenderingInfo::default()
            .render_area(area)
            .layer_count(1)
            .color_attachments(&attachments)
            .depth_attachment(&depth);
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
        let set = self.set.as_ref().map(|s| s.set);
        // A mirror's render area is its rectangle; the view is still the whole frame's.
        raster::render(ctx, cmd, &info, whole, (self.pipelines[0], self.layout, set), mirror.is_some(), || {
            mesh.bind(ctx, cmd);
            let mut textured = false;
            for (constants, moving) in still.chain(copies) {
                let stage = vk::ShaderStageFlags::VERTEX;
                // SAFETY: `cmd` is recording; the layout has a vertex range of this size.
                unsafe { device.cmd_push_constants(cmd, self.layout, stage, 0, bytemuck::bytes_of(&constants)) };
                // Objects whose bounds are outside the view cost no vertex work or triangle
                // set-up.
                let draws = mesh.draws.iter().filter(|d| (d.object + 1 == constants.light_object) == moving);
                for draw in draws.filter(|d| d.visible(&constants)) {
                    if textured != draw.textured {
                        let pipeline = self.pipelines[usize::from(draw.textured)];
                        // SAFETY: `cmd` is recording inside this pass's rendering.
                        unsafe { device.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, pipeline) };
                        textured = draw.textured;
                    }
                    mesh.draw(ctx, cmd, draw);
                }
            }
        });
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

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::passes::mesh::GBufferVertex;

    fn vertex(position: [f32; 3], object: u32) -> GBufferVertex {
        GBufferVertex { position, normal: [0.0, 0.0, 1.0], object, ..Default::default() }
    }

    /// Identity view-projection: the clip volume is x, y in [-1, 1], z in [0, 1].
    pub(crate) fn identity(light_object: u32, light_offset: [f32; 4]) -> GBufferConstants {
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
