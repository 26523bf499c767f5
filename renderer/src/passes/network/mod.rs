//! The network pass: per pixel, the direct and indirect networks of the pixel's
//! [`NetworkUnit`] on inputs built from the G-buffer. A unit is an object with one network of
//! each kind, or, where the baker split an object with its kd-tree, the box of the object
//! where one direct and one indirect leaf meet; an object's boxes partition space.
//! The variants differ in how the weights reach the shader, the pass's main performance
//! question (BENCHMARKS.md has the figures):
//!
//! - [`Variant::Storage`]: one dispatch; every unit's weights in a storage buffer, the unit
//!   found per pixel from its object id and position (`network_storage.comp`).
//! - [`Variant::PerObject`]: one pipeline per unit with its weights as specialization
//!   constants (`network_specialized.comp`), each dispatched over the whole image, skipping
//!   other units' pixels.
//! - [`Variant::Tiled`]: the same pipelines, each dispatched indirectly over only the 8×8
//!   tiles that its unit covers, as `network_classify.comp` sorted them.
//!
//! Every variant sums the networks over the frame's lights ([`NetworkLight`], copies of the
//! moving light), read from a small buffer written at the start of each frame. The specialized
//! variants can also compute direct light instead of learning it ([`DirectLight::Analytic`]),
//! with shadow maps from [`crate::passes::shadow`].

mod interface;
mod specialized;
mod storage;
mod units;
mod weights;

use ash::vk;
use gpu_allocator::MemoryLocation;

use crate::backend::compute::Bind;
use crate::backend::context::Context;
use crate::backend::guard::Destroy;
use crate::backend::resources::{Buffer, Image};
use crate::backend::sync::{Access, Pass, ResourceStates, Use};
use crate::error::{Error, Result};
use crate::lights::{NetworkLight, PointLightShape, MAX_LIGHTS};
use crate::passes::gbuffer::{self, GBufferConstants, GBufferTargets};
use crate::passes::mesh::GBufferMesh;
use specialized::Specialized;
use storage::Storage;
pub use units::NetworkUnit;
use units::{ordered, unit_table};
pub use weights::{LeafBlend, NetworkWeights};

/// The network layout, shared with the baker and the shaders (one file, see its header).
#[allow(dead_code)] // the renderer uses part of it
mod layout {
    include!("../../../../baker/src/network_layout.rs");
}
pub use interface::MAX_MIRRORS;
pub use layout::{INPUTS, PARAMETERS, UNIT_STRIDE};

/// Pixels per side of the tiles the classify pass sorts; the workgroup size of both shaders.
const TILE: u32 = 8;

/// How the networks reach the shader.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Variant {
    Storage,
    PerObject,
    Tiled,
}

impl Variant {
    pub const ALL: [Variant; 3] = [Variant::Tiled, Variant::PerObject, Variant::Storage];

    pub fn name(self) -> &'static str {
        match self {
            Variant::Storage => "storage",
            Variant::PerObject => "per-object",
            Variant::Tiled => "tiled",
        }
    }
}

/// SPIR-V of the network shaders.
pub struct NetworkShaders<'a> {
    pub storage: &'a [u32],
    pub classify: &'a [u32],
    pub specialized: &'a [u32],
    /// The same two steps writing one tonemapped display image.
    pub classify_display: &'a [u32],
    pub specialized_display: &'a [u32],
}

/// How the pass gets direct light.
pub enum DirectLight<'a> {
    /// From each object's direct network.
    Learned,
    /// Computed from the baker's BRDF for copies of point light `light`, with cube shadow maps
    /// drawn by `shadow.vert` and `shadow.frag` (SPIR-V). The specialized variants only.
    Analytic { light: PointLightShape, shadow_vertex: &'a [u32], shadow_fragment: &'a [u32] },
}

/// Camera and lights, as every variant's shader reads them, and for a pass that writes a
/// display image, how to show it.
#[derive(Clone, Copy, Debug)]
pub struct NetworkConstants {
    eye: [f32; 4],
    /// What the shaders' lights buffer holds: the eyes of the camera reflected in the frame's
    /// mirrors, then the lights.
    frame: FrameLights,
    light_count: u32,
    /// 2^EV.
    exposure_scale: f32,
    /// The component shown: 0 global, 1 direct, 2 indirect.
    shown: u32,
}

/// The network shaders' lights buffer (`network_inputs.glsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct FrameLights {
    mirror_eyes: [[f32; 4]; MAX_MIRRORS as usize],
    lights: [NetworkLight; MAX_LIGHTS],
}

impl NetworkConstants {
    /// The constants of a frame seen from `eye` and lit by `lights` (1 to [`MAX_LIGHTS`]),
    /// whose `mirror_eyes` (at most [`MAX_MIRRORS`]) are the camera reflected in each mirror
    /// it shows, in the order of the mirrors' merge steps; `exposure_scale` (2^EV) and `shown`
    /// (0 global, 1 direct, 2 indirect) matter only to a pass that writes a display image.
    pub fn new(
        eye: [f32; 4],
        lights: &[NetworkLight],
        mirror_eyes: &[[f32; 4]],
        exposure_scale: f32,
        shown: u32,
    ) -> Result<Self> {
        if lights.is_empty() || lights.len() > MAX_LIGHTS {
            return Err(Error::Invalid(format!("{} lights; a frame has 1 to {MAX_LIGHTS}", lights.len())));
        }
        if mirror_eyes.len() > MAX_MIRRORS as usize {
            return Err(Error::Invalid(format!("{} mirrors; a frame shows at most {MAX_MIRRORS}", mirror_eyes.len())));
        }
        let mut frame = FrameLights {
            mirror_eyes: [[0.0; 4]; MAX_MIRRORS as usize],
            lights: [NetworkLight::default(); MAX_LIGHTS],
        };
        frame.mirror_eyes[..mirror_eyes.len()].copy_from_slice(mirror_eyes);
        frame.lights[..lights.len()].copy_from_slice(lights);
        Ok(NetworkConstants { eye, frame, light_count: lights.len() as u32, exposure_scale, shown })
    }

    fn lights(&self) -> &[NetworkLight] {
        &self.frame.lights[..self.light_count as usize]
    }

    /// The lights buffer's bytes: the mirrors' eyes and the frame's lights.
    fn buffer_bytes(&self) -> &[u8] {
        let bytes = bytemuck::bytes_of(&self.frame);
        &bytes[..std::mem::offset_of!(FrameLights, lights) + std::mem::size_of_val(self.lights())]
    }
}

/// HDR outputs of the network pass, in `GENERAL` layout.
pub struct NetworkOutputs {
    pub direct: Image,
    pub indirect: Image,
    /// emission + direct + indirect.
    pub gi: Image,
}

impl NetworkOutputs {
    fn new(ctx: &Context, extent: vk::Extent2D) -> Result<Self> {
        let usage = vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_SRC;
        let format = vk::Format::R32G32B32A32_SFLOAT;
        let image = |name| ctx.create_image(name, extent, format, usage).map(|i| ctx.guard(i));
        let (direct, indirect, gi) = (image("direct")?, image("indirect")?, image("gi")?);
        ctx.submit_once(|cmd| {
            for image in [&direct, &indirect, &gi] {
                ctx.transition(cmd, image, vk::ImageLayout::UNDEFINED, vk::ImageLayout::GENERAL);
            }
        })?;
        Ok(NetworkOutputs { direct: direct.keep(), indirect: indirect.keep(), gi: gi.keep() })
    }

    pub fn all(&self) -> [&Image; 3] {
        [&self.direct, &self.indirect, &self.gi]
    }
}

impl Destroy for NetworkOutputs {
    fn destroy(self, ctx: &Context) {
        for image in [self.direct, self.indirect, self.gi] {
            ctx.destroy_image(image);
        }
    }
}

/// What the pass writes: the radiance images it owns, or a display image it is given.
#[derive(Clone, Copy)]
enum Written<'a> {
    Radiance(&'a NetworkOutputs),
    Display(&'a Image),
}

impl<'a> Written<'a> {
    /// What a pass with `outputs` (`None` for a display pass) writes, given the display image
    /// the caller passes: a display image goes with, and only with, a display pass.
    fn of(outputs: &'a Option<NetworkOutputs>, display: Option<&'a Image>) -> Result<Self> {
        match (outputs, display) {
            (Some(o), None) => Ok(Written::Radiance(o)),
            (None, Some(image)) => Ok(Written::Display(image)),
            _ => Err(Error::Invalid("a display image goes with, and only with, a display network pass".into())),
        }
    }

    fn images(self) -> Vec<&'a Image> {
        match self {
            Written::Radiance(o) => o.all().to_vec(),
            Written::Display(image) => vec![image],
        }
    }
}

pub struct NetworkPass {
    variant: Variant,
    extent: vk::Extent2D,
    /// Per material: rgb emitted radiance, roughness (what the G-buffer's material ids index).
    materials: Buffer,
    /// The mirrors' eyes and the frame's lights ([`FrameLights`]), written at the start of
    /// each frame.
    lights: Buffer,
    /// The radiance images; `None` when the pass writes a display image instead.
    outputs: Option<NetworkOutputs>,
    /// Object ids the G-buffer may hold.
    objects: u32,
    /// The unit table (`network_units.glsl`).
    units: Buffer,
    kind: Kind,
}

enum Kind {
    Storage(Storage),
    Specialized(Box<Specialized>),
}

impl NetworkPass {
    /// The pass for the network `units` of a scene of `objects` object ids (objects without a
    /// unit get no direct or indirect light), which reads `gbuffer`. With `display` (an RGBA8
    /// storage image of the G-buffer's size), the pass writes only that: the component shown,
    /// tonemapped, as a window shows it; the storage variant cannot. `materials` holds each
    /// material's emitted radiance (rgb, before its emissive texture) and its
    /// `KHR_materials_specular` factor. `direct` says where direct light comes from; the
    /// storage variant learns it.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        ctx: &Context,
        variant: Variant,
        shaders: &NetworkShaders,
        gbuffer: &GBufferTargets,
        objects: usize,
        units: &[NetworkUnit],
        materials: &[[f32; 4]],
        display: Option<&Image>,
        direct: DirectLight,
    ) -> Result<Self> {
        if objects > gbuffer::MAX_OBJECTS || materials.len() > gbuffer::MAX_MATERIALS {
            return Err(Error::Invalid(format!(
                "{objects} objects and {} materials; the G-buffer tells apart at most {} objects and {} materials",
                materials.len(),
                gbuffer::MAX_OBJECTS,
                gbuffer::MAX_MATERIALS
            )));
        }
        let bytes: &[u8] = if materials.is_empty() { &[0; 16] } else { bytemuck::cast_slice(materials) };
        let materials =
            ctx.guard(ctx.create_buffer_with_data("materials", bytes, vk::BufferUsageFlags::STORAGE_BUFFER)?);
        let lights = ctx.guard(ctx.create_buffer(
            "network lights",
            std::mem::size_of::<FrameLights>() as u64,
            vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuOnly,
        )?);
        let units = ordered(objects, units)?;
        let table = ctx.guard(ctx.create_buffer_with_data(
            "network units",
            bytemuck::cast_slice(&unit_table(objects, &units)),
            vk::BufferUsageFlags::STORAGE_BUFFER,
        )?);
        let shared = Shared { materials: &materials, lights: &lights, units: &table };
        let outputs = match display {
            Some(_) => None,
            None => Some(NetworkOutputs::new(ctx, gbuffer.extent)?),
        };
        let outputs = ctx.guard(outputs);
        let written = Written::of(&outputs, display)?;
        let kind = match variant {
            Variant::Storage if matches!(direct, DirectLight::Analytic { .. }) => {
                return Err(Error::Invalid(
                    "analytic direct light needs a specialized network variant (tiled or per-object)".into(),
                ))
            }
            Variant::Storage => match written {
                Written::Radiance(o) => Kind::Storage(Storage::new(ctx, shaders.storage, gbuffer, shared, o, &units)?),
                Written::Display(_) => {
                    return Err(Error::Invalid("the storage network variant cannot write a display image".into()))
                }
            },
            Variant::PerObject | Variant::Tiled => Kind::Specialized(Box::new(Specialized::new(
                ctx,
                shaders,
                gbuffer,
                shared,
                written,
                objects,
                &units,
                variant == Variant::Tiled,
                direct,
            )?)),
        };
        Ok(NetworkPass {
            variant,
            extent: gbuffer.extent,
            materials: materials.keep(),
            lights: lights.keep(),
            outputs: outputs.keep(),
            objects: objects as u32,
            units: table.keep(),
            kind,
        })
    }

    /// The radiance images, unless the pass writes a display image.
    pub fn outputs(&self) -> Option<&NetworkOutputs> {
        self.outputs.as_ref()
    }

    pub fn variant(&self) -> Variant {
        self.variant
    }

    /// Records where `new` and `resize` left the outputs.
    pub fn register(&self, states: &mut ResourceStates) {
        for image in self.outputs.iter().flat_map(|o| o.all()) {
            states.set_layout(image, vk::ImageLayout::GENERAL);
        }
        if let Kind::Specialized(s) = &self.kind {
            s.register(states);
        }
    }

    /// Remakes the size-dependent resources for `gbuffer`'s new size (and `display`, the
    /// display image of that size for a display pass) and points the pipelines at them; the
    /// pipelines stay. No frame that uses the pass may be pending. On failure the pass keeps
    /// its old resources.
    pub fn resize(&mut self, ctx: &Context, gbuffer: &GBufferTargets, display: Option<&Image>) -> Result<()> {
        Written::of(&self.outputs, display)?;
        let extent = gbuffer.extent;
        let outputs = match &self.outputs {
            Some(_) => Some(NetworkOutputs::new(ctx, extent)?),
            None => None,
        };
        let outputs = ctx.guard(outputs);
        let (tiles, capacity) = match &self.kind {
            Kind::Specialized(s) => {
                let (tiles, capacity) = s.tile_buffer(ctx, extent)?;
                (Some(tiles), capacity)
            }
            Kind::Storage(_) => (None, 0),
        };
        let tiles = tiles.map(|t| (t, capacity));
        std::mem::replace(&mut self.outputs, outputs.keep()).destroy(ctx);
        self.extent = extent;
        let written = Written::of(&self.outputs, display)?;
        let shared = Shared { materials: &self.materials, lights: &self.lights, units: &self.units };
        match &mut self.kind {
            Kind::Storage(s) => s.rebind(ctx, gbuffer, shared, written),
            Kind::Specialized(s) => s.rebind(ctx, gbuffer, shared, written, tiles),
        }
        Ok(())
    }

    /// The pass's steps for a frame list. The G-buffer (and for a display pass, `display`)
    /// must be the ones the pass was made or last resized for; `mesh` is the scene the
    /// G-buffer drew, which analytic direct light draws into its shadow maps, and `views`
    /// are the frame's G-buffer passes (its own, then its mirrors'): the specialized
    /// variants shade only the network units that can show in them, and make their
    /// pipelines when a frame first does.
    pub fn passes<'a>(
        &'a self,
        ctx: &'a Context,
        gbuffer: &'a GBufferTargets,
        mesh: &'a GBufferMesh,
        c: NetworkConstants,
        display: Option<&'a Image>,
        views: &[GBufferConstants],
    ) -> Result<Vec<Pass<'a>>> {
        let writes: Vec<Use> = Written::of(&self.outputs, display)?
            .images()
            .into_iter()
            .map(|image| Use::image(image, Access::COMPUTE_WRITE))
            .collect();
        let upload = Pass::new("network lights", vec![Use::buffer(&self.lights, Access::TRANSFER_WRITE)], move |cmd| {
            // SAFETY: recording outside a render pass; at most the buffer's size (under 1 KiB), a
            // multiple of 4 and under vkCmdUpdateBuffer's 64 KiB.
            unsafe { ctx.device.cmd_update_buffer(cmd, self.lights.raw, 0, c.buffer_bytes()) };
        });
        let frame = FrameUses {
            ctx,
            gbuffer,
            extent: self.extent,
            constants: c,
            objects: self.objects,
            materials: Use::buffer(&self.materials, Access::COMPUTE_READ),
            lights: Use::buffer(&self.lights, Access::COMPUTE_READ),
            units: Use::buffer(&self.units, Access::COMPUTE_READ),
            writes,
        };
        let mut passes = vec![upload];
        match &self.kind {
            Kind::Storage(s) => passes.push(s.pass(frame)),
            Kind::Specialized(s) => passes.extend(s.passes(frame, mesh, views)?),
        }
        Ok(passes)
    }

    pub fn destroy(self, ctx: &Context) {
        match self.kind {
            Kind::Storage(s) => s.destroy(ctx),
            Kind::Specialized(s) => Destroy::destroy(*s, ctx),
        }
        ctx.destroy_buffer(self.materials);
        ctx.destroy_buffer(self.units);
        ctx.destroy_buffer(self.lights);
        self.outputs.destroy(ctx);
    }
}

impl Destroy for NetworkPass {
    fn destroy(self, ctx: &Context) {
        NetworkPass::destroy(self, ctx);
    }
}

/// The buffers every variant's network shader reads besides the G-buffer.
#[derive(Clone, Copy)]
struct Shared<'a> {
    materials: &'a Buffer,
    lights: &'a Buffer,
    /// The unit table (`network_units.glsl`).
    units: &'a Buffer,
}

/// What a frame's network pass reads and writes besides a variant's own buffers.
struct FrameUses<'a> {
    ctx: &'a Context,
    gbuffer: &'a GBufferTargets,
    extent: vk::Extent2D,
    constants: NetworkConstants,
    objects: u32,
    materials: Use,
    lights: Use,
    units: Use,
    /// The images the pass writes.
    writes: Vec<Use>,
}

impl<'a> FrameUses<'a> {
    /// The G-buffer's images, which every network shader reads, with the mirror weights in a
    /// frame that shows mirrors (elsewhere a stand-in nothing writes).
    fn gbuffer_reads(&self) -> Vec<Use> {
        let g = self.gbuffer;
        let weights = g.mirrors.then_some(&g.mirror_weights);
        let images = g.colors().into_iter().chain(weights);
        images.map(|image| Use::image(image, Access::COMPUTE_READ)).collect()
    }
}

/// The bindings of a network shader, in the order of [`interface`]: the G-buffer and the
/// materials, `fourth` (the lights, or the classification's dispatch arguments), the
/// variant's `buffer` (weights or tile lists), the mirror weights, what the pass writes, then
/// `rest`.
fn network_bindings<'a>(
    gbuffer: &'a GBufferTargets,
    shared: Shared<'a>,
    fourth: &'a Buffer,
    buffer: &'a Buffer,
    written: Written<'a>,
    rest: impl IntoIterator<Item = Bind<'a>>,
) -> Vec<Bind<'a>> {
    use interface::*;
    let numbered = [
        (SURFACE_BINDING, Bind::StorageImage(&gbuffer.surface)),
        (ID_BINDING, Bind::StorageImage(&gbuffer.id)),
        (MATERIALS_BINDING, Bind::StorageBuffer(shared.materials)),
        (SHADING_BINDING, Bind::StorageImage(&gbuffer.shading)),
        (LIGHTS_BINDING, Bind::StorageBuffer(fourth)),
        (WEIGHTS_BINDING, Bind::StorageBuffer(buffer)),
        (MIRROR_BINDING, Bind::StorageImage(&gbuffer.mirror_weights)),
    ];
    const _: () = assert!(LIGHTS_BINDING == DISPATCH_BINDING && WEIGHTS_BINDING == TILES_BINDING);
    // A set binds each resource at its position in the list.
    let mut binds = Vec::new();
    for (binding, bind) in numbered {
        debug_assert_eq!(binding as usize, binds.len());
        binds.push(bind);
    }
    debug_assert_eq!(FIRST_OUTPUT_BINDING as usize, binds.len());
    binds.extend(written.images().into_iter().map(Bind::StorageImage));
    binds.extend(rest);
    binds
}
