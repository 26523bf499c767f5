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
//! with shadow maps from [`crate::shadow`].

use ash::vk;
use bytemuck::{Pod, Zeroable};
use gpu_allocator::MemoryLocation;

use crate::compute::{Bind, ComputePass, Dispatch, Specialization};
use crate::context::Context;
use crate::error::{Error, Result};
use crate::gbuffer::GBufferMesh;
use crate::gbuffer::{self, GBufferTargets};
use crate::guard::Destroy;
use crate::resources::{Buffer, Image};
use crate::shadow::ShadowPass;
use crate::sync::{Access, Pass, ResourceStates, Use};

/// The network layout, shared with the baker and the shaders (one file, see its header).
#[allow(dead_code)] // the renderer uses part of it
mod layout {
    include!("../../baker/src/network_layout.rs");
}
use layout::{B1, FIRST_PARAMETER_ID, HIDDEN1, UNIT_BLEND, W3};
pub use layout::{INPUTS, PARAMETERS, UNIT_STRIDE};
/// The most units `network_classify.comp` tells apart.
const MAX_UNITS: usize = 1024;
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

/// One network as the baker trained it.
#[derive(Clone, Copy)]
pub struct NetworkWeights<'a> {
    pub params: &'a [f32],
    pub input_min: [f32; INPUTS],
    pub input_max: [f32; INPUTS],
    pub output_scale: f32,
    /// Where on its object the network applies, and how it blends with its neighbours.
    pub blend: LeafBlend,
}

/// A kd-tree leaf's weight over space (the baker's `partition::BlendBox` as plain data): 1
/// in its half-open box `min <= p < max` away from its faces, 0 outside the box grown by the
/// bands, and a smoothstep across the band of half-width `min_band` or `max_band` around each
/// face (0: a hard cut). `±f32::MAX` and no band where a side is unbounded.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LeafBlend {
    pub min: [f32; 3],
    pub max: [f32; 3],
    pub min_band: [f32; 3],
    pub max_band: [f32; 3],
}

impl LeafBlend {
    /// A network that covers all of its object.
    pub const WHOLE: LeafBlend =
        LeafBlend { min: [-f32::MAX; 3], max: [f32::MAX; 3], min_band: [0.0; 3], max_band: [0.0; 3] };

    /// Whether the leaf blends with a neighbour somewhere.
    fn has_band(&self) -> bool {
        self.min_band.iter().chain(&self.max_band).any(|&b| b > 0.0)
    }

    /// The leaf's entry in the unit table (`network_units.glsl`).
    fn table(&self) -> impl Iterator<Item = f32> + '_ {
        self.min.iter().chain(&self.max).chain(&self.min_band).chain(&self.max_band).copied()
    }
}

impl NetworkWeights<'_> {
    /// The network with its input normalisation and output scale folded in.
    fn folded(&self) -> Vec<f32> {
        fold(self.params, &self.input_min, &self.input_max, self.output_scale)
    }
}

/// A part of object id `object` with one direct and one indirect network, whose weight at a
/// point is the product of the two networks' [`LeafBlend`] weights there. The weights of an
/// object's units must sum to one everywhere (every pair of a direct and an indirect leaf of
/// two kd-trees whose supports meet), so that a pixel's radiance is their weighted sum.
#[derive(Clone, Copy)]
pub struct NetworkUnit<'a> {
    pub object: usize,
    pub direct: NetworkWeights<'a>,
    pub indirect: NetworkWeights<'a>,
}

impl NetworkUnit<'_> {
    /// Whether the unit blends with another somewhere: then the pass must write radiance
    /// images, not a display image.
    pub fn blends(&self) -> bool {
        self.direct.blend.has_band() || self.indirect.blend.has_band()
    }

    fn check(&self, objects: usize) -> Result<()> {
        if self.direct.params.len() != PARAMETERS || self.indirect.params.len() != PARAMETERS {
            return Err(Error::Invalid(format!("object {}: a network must have {PARAMETERS} parameters", self.object)));
        }
        if self.object >= objects {
            return Err(Error::Invalid(format!("a network unit of object {}, of {objects} objects", self.object)));
        }
        Ok(())
    }
}

/// The units in the order the pass uses (grouped by object, which the unit table needs),
/// checked against `objects` object ids.
fn ordered<'a>(objects: usize, units: &[NetworkUnit<'a>]) -> Result<Vec<NetworkUnit<'a>>> {
    units.iter().try_for_each(|u| u.check(objects))?;
    let mut ordered = units.to_vec();
    ordered.sort_by_key(|u| u.object);
    Ok(ordered)
}

/// The table of `network_units.glsl` for `units` (grouped by object) of `objects` object ids:
/// per object its first unit and unit count, then per unit its two leaves' blend boxes.
fn unit_table(objects: usize, units: &[NetworkUnit]) -> Vec<f32> {
    let mut table = vec![0.0f32; 2 * objects.max(1)];
    for (index, unit) in units.iter().enumerate() {
        let entry = &mut table[2 * unit.object..2 * unit.object + 2];
        if entry[1] == 0.0 {
            entry[0] = index as f32;
        }
        entry[1] += 1.0;
    }
    for unit in units {
        table.extend(unit.direct.blend.table().chain(unit.indirect.blend.table()));
    }
    debug_assert_eq!(table.len(), 2 * objects.max(1) + UNIT_BLEND * units.len());
    table
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

/// A network that takes raw inputs: the input normalisation (the baker's `normalize`, an
/// affine map per input) folded into the first layer and the output scale into the last.
/// Computed in f64, so the result differs from the unfolded network only by f32 rounding.
fn fold(params: &[f32], input_min: &[f32; INPUTS], input_max: &[f32; INPUTS], output_scale: f32) -> Vec<f32> {
    let mut out = params.to_vec();
    for j in 0..HIDDEN1 {
        let mut bias = f64::from(params[B1 + j]);
        for i in 0..INPUTS {
            let (lo, hi) = (f64::from(input_min[i]), f64::from(input_max[i]));
            let range = hi - lo;
            // normalize(x) = a x + b, or 0 for a constant input (range ≤ 1e-6, as in the baker).
            let (a, b) = if range > 1e-6 { (2.0 / range, -2.0 * lo / range - 1.0) } else { (0.0, 0.0) };
            let w = f64::from(params[j * INPUTS + i]);
            out[j * INPUTS + i] = (w * a) as f32;
            bias += w * b;
        }
        out[B1 + j] = bias as f32;
    }
    for p in &mut out[W3..] {
        *p = (f64::from(*p) * f64::from(output_scale)) as f32;
    }
    out
}

/// Specialization constants of the two pipelines of unit `index` of `units` (grouped by
/// object, of `objects` object ids), for frames of one light and of several (see
/// `network_specialized_main.glsl`).
fn specializations(
    objects: usize,
    units: &[NetworkUnit],
    index: usize,
    tiled: bool,
    analytic: bool,
) -> [Specialization; 2] {
    let unit = &units[index];
    let mut words = vec![0u32; FIRST_PARAMETER_ID + 2 * PARAMETERS];
    words[0] = unit.object as u32 + 1;
    words[1] = u32::from(tiled);
    words[2] = u32::from(analytic);
    words[4] = index as u32;
    // OBJECT_FIRST_UNIT, OBJECTS.
    words[5] = units.iter().position(|u| u.object == unit.object).expect("the unit itself") as u32;
    words[6] = objects.max(1) as u32;
    let (direct, indirect) = (unit.direct.folded(), unit.indirect.folded());
    for (word, value) in words[FIRST_PARAMETER_ID..].iter_mut().zip(direct.iter().chain(&indirect)) {
        *word = value.to_bits();
    }
    // SEVERAL_LIGHTS.
    let mut several = words.clone();
    several[3] = 1;
    [words, several]
}

/// The most lights one frame sums (the size of the lights buffer).
pub const MAX_LIGHTS: usize = 16;

/// One light as the network shaders read it (`Light` in `network_inputs.glsl`): a copy of
/// the moving light at `position` (xyz), whose networks' output is scaled by `scale` (rgb).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct NetworkLight {
    pub position: [f32; 4],
    pub scale: [f32; 4],
}

/// The point light the model was trained with, for analytic direct light: its intensity
/// (W/sr, linear RGB; on the axis of a spot light) and a spot light's cone.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointLightShape {
    pub intensity: [f32; 3],
    pub spot: Option<Spot>,
}

/// A spot light's cone: its axis (unit) and the cosines of its inner and outer angles.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spot {
    pub axis: [f32; 3],
    pub cos_inner: f32,
    pub cos_outer: f32,
}

/// How the pass gets direct light.
pub enum DirectLight<'a> {
    /// From each object's direct network.
    Learned,
    /// Computed from the baker's BRDF for copies of point light `light`, with cube shadow maps
    /// drawn by `shadow.vert` and `shadow.frag` (SPIR-V). The specialized variants only.
    Analytic { light: PointLightShape, shadow_vertex: &'a [u32], shadow_fragment: &'a [u32] },
}

/// What the specialized pipelines read for analytic direct light.
enum Direct {
    Learned {
        /// A 1×1 image where the shadow maps would be bound.
        stand_in: Image,
    },
    Analytic {
        light: PointLightShape,
        shadow: ShadowPass,
    },
}

impl Direct {
    fn shadow_maps(&self) -> &Image {
        match self {
            Direct::Learned { stand_in } => stand_in,
            Direct::Analytic { shadow, .. } => shadow.atlas(),
        }
    }
}

impl Destroy for Direct {
    fn destroy(self, ctx: &Context) {
        match self {
            Direct::Learned { stand_in } => ctx.destroy_image(stand_in),
            Direct::Analytic { shadow, .. } => shadow.destroy(ctx),
        }
    }
}

/// Camera and lights, as every variant's shader reads them, and for a pass that writes a
/// display image, how to show it.
#[derive(Clone, Copy, Debug)]
pub struct NetworkConstants {
    eye: [f32; 4],
    lights: [NetworkLight; MAX_LIGHTS],
    light_count: u32,
    /// 2^EV.
    exposure_scale: f32,
    /// The component shown: 0 global, 1 direct, 2 indirect.
    shown: u32,
}

impl NetworkConstants {
    /// The constants of a frame seen from `eye` and lit by `lights` (1 to [`MAX_LIGHTS`]);
    /// `exposure_scale` (2^EV) and `shown` (0 global, 1 direct, 2 indirect) matter only to a
    /// pass that writes a display image.
    pub fn new(eye: [f32; 4], lights: &[NetworkLight], exposure_scale: f32, shown: u32) -> Result<Self> {
        if lights.is_empty() || lights.len() > MAX_LIGHTS {
            return Err(Error::Invalid(format!("{} lights; a frame has 1 to {MAX_LIGHTS}", lights.len())));
        }
        let mut all = [NetworkLight::default(); MAX_LIGHTS];
        all[..lights.len()].copy_from_slice(lights);
        Ok(NetworkConstants { eye, lights: all, light_count: lights.len() as u32, exposure_scale, shown })
    }

    fn lights(&self) -> &[NetworkLight] {
        &self.lights[..self.light_count as usize]
    }
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct StoragePush {
    eye: [f32; 4],
    light_count: u32,
    objects: u32,
    pad: [u32; 2],
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct SpecializedPush {
    eye: [f32; 4],
    light_count: u32,
    tile_capacity: u32,
    exposure_scale: f32,
    shown: u32,
    light_intensity: [f32; 4],
    spot_axis: [f32; 4],
    spot_cos_outer: f32,
    pad: [u32; 3],
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct ClassifyPush {
    objects: u32,
    units: u32,
    tile_capacity: u32,
    exposure_scale: f32,
    shown: u32,
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
    /// The frame's lights ([`NetworkLight`]), written at the start of each frame.
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
    Storage { pass: ComputePass, weights: Buffer },
    Specialized(Box<Specialized>),
}

struct Specialized {
    classify: ComputePass,
    /// Two pipelines per unit, in unit order: for frames of one light, then of several.
    networks: ComputePass,
    unit_count: u32,
    tiled: bool,
    /// A `VkDispatchIndirectCommand` per unit.
    dispatch: Buffer,
    /// What `dispatch` is reset to before each frame: no tiles, y = z = 1.
    dispatch_reset: Vec<u32>,
    /// Tile lists: `tile_capacity` entries per unit; sized with the image.
    tiles: Buffer,
    tile_capacity: u32,
    direct: Direct,
    /// Whether units blend: each unit's dispatch then adds to what the ones before it wrote,
    /// as a pass of its own, after a barrier.
    blended: bool,
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
            (MAX_LIGHTS * std::mem::size_of::<NetworkLight>()) as u64,
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
                Written::Radiance(o) => storage(ctx, shaders.storage, gbuffer, shared, o, &units)?,
                Written::Display(_) => {
                    return Err(Error::Invalid("the storage network variant cannot write a display image".into()))
                }
            },
            Variant::PerObject | Variant::Tiled => Kind::Specialized(Box::new(specialized(
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
            match &s.direct {
                Direct::Learned { stand_in } => states.set_layout(stand_in, vk::ImageLayout::GENERAL),
                Direct::Analytic { shadow, .. } => shadow.register(states),
            }
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
                let (tiles, capacity) = tile_buffer(ctx, s.unit_count as usize, extent)?;
                (Some(tiles), capacity)
            }
            Kind::Storage { .. } => (None, 0),
        };
        let tiles = tiles.map(|t| (t, capacity));
        std::mem::replace(&mut self.outputs, outputs.keep()).destroy(ctx);
        self.extent = extent;
        let written = Written::of(&self.outputs, display)?;
        let shared = Shared { materials: &self.materials, lights: &self.lights, units: &self.units };
        match &mut self.kind {
            Kind::Storage { pass, weights } => pass
                .rebind(ctx, &network_bindings(gbuffer, shared, weights, written, Bind::StorageBuffer(shared.units))),
            Kind::Specialized(s) => {
                if let Some((tiles, capacity)) = tiles {
                    ctx.destroy_buffer(std::mem::replace(&mut s.tiles, tiles));
                    s.tile_capacity = capacity;
                }
                let bindings = classify_bindings(gbuffer, shared, &s.dispatch, &s.tiles, written);
                s.classify.rebind(ctx, &bindings);
                s.networks.rebind(ctx, &s.bindings(gbuffer, shared, written));
            }
        }
        Ok(())
    }

    /// The pass's steps for a frame list. The G-buffer (and for a display pass, `display`)
    /// must be the ones the pass was made or last resized for; `mesh` is the scene the
    /// G-buffer drew, which analytic direct light draws into its shadow maps.
    pub fn passes<'a>(
        &'a self,
        ctx: &'a Context,
        gbuffer: &'a GBufferTargets,
        mesh: &'a GBufferMesh,
        c: NetworkConstants,
        display: Option<&'a Image>,
    ) -> Result<Vec<Pass<'a>>> {
        let extent = self.extent;
        let read = |image| Use::image(image, Access::COMPUTE_READ);
        let g = [&gbuffer.surface, &gbuffer.id, &gbuffer.shading];
        let materials = Use::buffer(&self.materials, Access::COMPUTE_READ);
        let lights = Use::buffer(&self.lights, Access::COMPUTE_READ);
        let units = Use::buffer(&self.units, Access::COMPUTE_READ);
        let writes: Vec<Use> = Written::of(&self.outputs, display)?
            .images()
            .into_iter()
            .map(|image| Use::image(image, Access::COMPUTE_WRITE))
            .collect();
        let upload = Pass::new("network lights", vec![Use::buffer(&self.lights, Access::TRANSFER_WRITE)], move |cmd| {
            // SAFETY: recording outside a render pass; at most MAX_LIGHTS × 32 bytes, a multiple
            // of 4 and under vkCmdUpdateBuffer's 64 KiB.
            unsafe { ctx.device.cmd_update_buffer(cmd, self.lights.raw, 0, bytemuck::cast_slice(c.lights())) };
        });
        let mut passes = vec![upload];
        match &self.kind {
            Kind::Storage { pass, weights } => {
                let mut uses: Vec<Use> = g.iter().map(|i| read(i)).collect();
                uses.extend([materials, lights, units, Use::buffer(weights, Access::COMPUTE_READ)]);
                uses.extend(writes);
                let push = StoragePush { eye: c.eye, light_count: c.light_count, objects: self.objects, pad: [0; 2] };
                passes.push(Pass::new("network (storage buffer)", uses, move |cmd| {
                    // Pipeline 1 is for frames of several lights (SEVERAL_LIGHTS).
                    let pipeline = usize::from(c.light_count > 1);
                    let dispatch = Dispatch::Covering { width: extent.width, height: extent.height };
                    pass.record_pipeline(ctx, cmd, pipeline, bytemuck::bytes_of(&push), dispatch)
                }));
            }
            Kind::Specialized(s) => {
                let reset = Pass::new(
                    "network dispatch reset",
                    vec![Use::buffer(&s.dispatch, Access::TRANSFER_WRITE)],
                    |cmd| {
                        // SAFETY: recording outside a render pass; at most 12 KiB (MAX_UNITS),
                        // under vkCmdUpdateBuffer's 64 KiB.
                        unsafe {
                            ctx.device.cmd_update_buffer(
                                cmd,
                                s.dispatch.raw,
                                0,
                                bytemuck::cast_slice(&s.dispatch_reset),
                            )
                        };
                    },
                );
                let mut uses = vec![
                    read(&gbuffer.id),
                    read(&gbuffer.shading),
                    read(&gbuffer.surface),
                    materials,
                    units,
                    Use::buffer(&s.dispatch, Access::COMPUTE_READ_WRITE),
                    Use::buffer(&s.tiles, Access::COMPUTE_WRITE),
                ];
                uses.extend(writes.iter().copied());
                let push = ClassifyPush {
                    objects: self.objects,
                    units: s.unit_count,
                    tile_capacity: s.tile_capacity,
                    exposure_scale: c.exposure_scale,
                    shown: c.shown,
                };
                let classify = Pass::new("network tile classification", uses, move |cmd| {
                    s.classify.record(ctx, cmd, bytemuck::bytes_of(&push), extent.width, extent.height)
                });
                let mut uses: Vec<Use> = g.iter().map(|i| read(i)).collect();
                uses.extend([materials, lights, units, Use::buffer(&s.tiles, Access::COMPUTE_READ)]);
                uses.push(read(s.direct.shadow_maps()));
                if s.tiled {
                    uses.push(Use::buffer(&s.dispatch, Access::INDIRECT_READ));
                }
                // Blending units read what the units before them wrote.
                let written = if s.blended { Access::COMPUTE_READ_WRITE } else { Access::COMPUTE_WRITE };
                uses.extend(writes.iter().map(|w| Use { access: written, ..*w }));
                if !s.dispatch_reset.is_empty() {
                    passes.push(reset);
                }
                if let Direct::Analytic { shadow, .. } = &s.direct {
                    let positions = c.lights().iter().map(|l| [l.position[0], l.position[1], l.position[2]]).collect();
                    passes.push(shadow.pass(ctx, mesh, positions));
                }
                passes.push(classify);
                let push = s.push(&c);
                if s.blended {
                    for unit in 0..s.unit_count as usize {
                        passes.push(Pass::new("network unit (blended)", uses.clone(), move |cmd| {
                            s.record_unit(ctx, cmd, extent, &c, &push, unit)
                        }));
                    }
                } else {
                    passes.push(Pass::new("network (specialization constants)", uses, move |cmd| {
                        (0..s.unit_count as usize).for_each(|unit| s.record_unit(ctx, cmd, extent, &c, &push, unit))
                    }));
                }
            }
        }
        Ok(passes)
    }

    pub fn destroy(self, ctx: &Context) {
        match self.kind {
            Kind::Storage { pass, weights } => {
                pass.destroy(ctx);
                ctx.destroy_buffer(weights);
            }
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

impl Destroy for Specialized {
    fn destroy(self, ctx: &Context) {
        self.classify.destroy(ctx);
        self.networks.destroy(ctx);
        self.direct.destroy(ctx);
        for buffer in [self.dispatch, self.tiles] {
            ctx.destroy_buffer(buffer);
        }
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

/// The bindings `network_storage.comp` and `network_specialized_main.glsl` share: the
/// G-buffer, the materials and the lights (`network_inputs.glsl`), the variant's buffer
/// (weights or tile lists), what the pass writes, then `last` (the storage variant's unit
/// table, the specialized variants' shadow maps).
fn network_bindings<'a>(
    gbuffer: &'a GBufferTargets,
    shared: Shared<'a>,
    buffer: &'a Buffer,
    written: Written<'a>,
    last: Bind<'a>,
) -> Vec<Bind<'a>> {
    let mut binds = vec![
        Bind::StorageImage(&gbuffer.surface),
        Bind::StorageImage(&gbuffer.id),
        Bind::StorageBuffer(shared.materials),
        Bind::StorageImage(&gbuffer.shading),
        Bind::StorageBuffer(shared.lights),
        Bind::StorageBuffer(buffer),
    ];
    binds.extend(written.images().into_iter().map(Bind::StorageImage));
    binds.push(last);
    binds
}

/// The bindings of `network_classify_main.glsl`.
fn classify_bindings<'a>(
    gbuffer: &'a GBufferTargets,
    shared: Shared<'a>,
    dispatch: &'a Buffer,
    tiles: &'a Buffer,
    written: Written<'a>,
) -> Vec<Bind<'a>> {
    let mut binds = vec![
        Bind::StorageImage(&gbuffer.id),
        Bind::StorageBuffer(shared.materials),
        Bind::StorageImage(&gbuffer.shading),
        Bind::StorageBuffer(shared.units),
        Bind::StorageBuffer(dispatch),
        Bind::StorageBuffer(tiles),
        Bind::StorageImage(&gbuffer.surface),
    ];
    binds.extend(written.images().into_iter().map(Bind::StorageImage));
    binds
}

fn storage(
    ctx: &Context,
    spirv: &[u32],
    gbuffer: &GBufferTargets,
    shared: Shared,
    outputs: &NetworkOutputs,
    units: &[NetworkUnit],
) -> Result<Kind> {
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
    let bindings =
        network_bindings(gbuffer, shared, &weights, Written::Radiance(outputs), Bind::StorageBuffer(shared.units));
    let push = std::mem::size_of::<StoragePush>() as u32;
    // One pipeline for frames of one light, one for several (`SEVERAL_LIGHTS`).
    let lights = [vec![0], vec![1]];
    let pass =
        ComputePass::specialized(ctx, "network (storage buffer)", spirv, &bindings, push, (TILE, TILE), &lights)?;
    Ok(Kind::Storage { pass, weights: weights.keep() })
}

/// The tile lists of `units` network units at `extent`, and the tiles per unit.
fn tile_buffer(ctx: &Context, units: usize, extent: vk::Extent2D) -> Result<(Buffer, u32)> {
    let tile_capacity = extent.width.div_ceil(TILE) * extent.height.div_ceil(TILE);
    let tiles_bytes = units.max(1) as u64 * u64::from(tile_capacity) * 4;
    let max = u64::from(ctx.info.limits.max_storage_buffer_range);
    if tiles_bytes > max {
        return Err(Error::Invalid(format!(
            "tile lists of {units} network units at {}x{} need {tiles_bytes} bytes, over maxStorageBufferRange {max}; \
             render smaller or use --variant storage",
            extent.width, extent.height
        )));
    }
    let tiles =
        ctx.create_buffer("network tiles", tiles_bytes, vk::BufferUsageFlags::STORAGE_BUFFER, MemoryLocation::GpuOnly)?;
    Ok((tiles, tile_capacity))
}

#[allow(clippy::too_many_arguments)] // NetworkPass::new's, passed on
fn specialized(
    ctx: &Context,
    shaders: &NetworkShaders,
    gbuffer: &GBufferTargets,
    shared: Shared,
    written: Written,
    objects: usize,
    units: &[NetworkUnit],
    tiled: bool,
    direct: DirectLight,
) -> Result<Specialized> {
    let (classify_spirv, specialized_spirv) = match written {
        Written::Radiance(_) => (shaders.classify, shaders.specialized),
        Written::Display(_) => (shaders.classify_display, shaders.specialized_display),
    };
    if units.len() > MAX_UNITS {
        return Err(Error::Invalid(format!(
            "{} network units; the specialized network variants handle at most {MAX_UNITS} (use --variant storage)",
            units.len()
        )));
    }
    let analytic = matches!(direct, DirectLight::Analytic { .. });
    let specializations: Vec<Specialization> =
        (0..units.len()).flat_map(|index| specializations(objects, units, index, tiled, analytic)).collect();
    let blended = units.iter().any(NetworkUnit::blends);
    if blended && matches!(written, Written::Display(_)) {
        return Err(Error::Invalid("blending network units write radiance images, not a display image".into()));
    }
    let dispatch_reset: Vec<u32> = units.iter().flat_map(|_| [0, 1, 1]).collect();

    let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
    let (tiles, tile_capacity) = tile_buffer(ctx, units.len(), gbuffer.extent)?;
    let tiles = ctx.guard(tiles);
    let dispatch = ctx.guard(ctx.create_buffer(
        "network dispatch",
        pad(&dispatch_reset).len() as u64,
        storage | vk::BufferUsageFlags::INDIRECT_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
        MemoryLocation::GpuOnly,
    )?);
    let classify = ctx.guard(ComputePass::new(
        ctx,
        "network tile classification",
        classify_spirv,
        &classify_bindings(gbuffer, shared, &dispatch, &tiles, written),
        std::mem::size_of::<ClassifyPush>() as u32,
        (TILE, TILE),
    )?);
    let direct = ctx.guard(match direct {
        DirectLight::Learned => {
            let one = vk::Extent2D { width: 1, height: 1 };
            let usage = vk::ImageUsageFlags::STORAGE;
            let stand_in = ctx.guard(ctx.create_image("no shadow maps", one, vk::Format::R32_SFLOAT, usage)?);
            ctx.submit_once(|cmd| {
                ctx.transition(cmd, &stand_in, vk::ImageLayout::UNDEFINED, vk::ImageLayout::GENERAL)
            })?;
            Direct::Learned { stand_in: stand_in.keep() }
        }
        DirectLight::Analytic { light, shadow_vertex, shadow_fragment } => {
            Direct::Analytic { light, shadow: ShadowPass::new(ctx, shadow_vertex, shadow_fragment)? }
        }
    });
    let bindings = specialized_bindings(gbuffer, shared, &tiles, written, &direct);
    let networks = ComputePass::specialized(
        ctx,
        "network (specialization constants)",
        specialized_spirv,
        &bindings,
        std::mem::size_of::<SpecializedPush>() as u32,
        (TILE, TILE),
        &specializations,
    )?;
    Ok(Specialized {
        classify: classify.keep(),
        networks,
        unit_count: units.len() as u32,
        tiled,
        dispatch: dispatch.keep(),
        dispatch_reset,
        tiles: tiles.keep(),
        tile_capacity,
        direct: direct.keep(),
        blended,
    })
}

/// The bindings of `network_specialized_main.glsl`: [`network_bindings`] with the shadow maps
/// last, then the unit table.
fn specialized_bindings<'a>(
    gbuffer: &'a GBufferTargets,
    shared: Shared<'a>,
    tiles: &'a Buffer,
    written: Written<'a>,
    direct: &'a Direct,
) -> Vec<Bind<'a>> {
    let mut binds = network_bindings(gbuffer, shared, tiles, written, Bind::StorageImage(direct.shadow_maps()));
    binds.push(Bind::StorageBuffer(shared.units));
    binds
}

/// `words` as bytes, with at least one word: Vulkan buffers cannot be empty.
fn pad(words: &[u32]) -> &[u8] {
    const ZERO: &[u32] = &[0];
    bytemuck::cast_slice(if words.is_empty() { ZERO } else { words })
}

impl Specialized {
    /// The networks' bindings at the current size.
    fn bindings<'a>(&'a self, gbuffer: &'a GBufferTargets, shared: Shared<'a>, written: Written<'a>) -> Vec<Bind<'a>> {
        specialized_bindings(gbuffer, shared, &self.tiles, written, &self.direct)
    }

    /// The networks' push constants for a frame with constants `c`.
    fn push(&self, c: &NetworkConstants) -> SpecializedPush {
        let (intensity, spot) = match &self.direct {
            Direct::Analytic { light, .. } => (light.intensity, light.spot),
            Direct::Learned { .. } => ([0.0; 3], None),
        };
        let spot = spot.unwrap_or(Spot { axis: [0.0; 3], cos_inner: 1.0, cos_outer: 0.0 });
        SpecializedPush {
            eye: c.eye,
            light_count: c.light_count,
            tile_capacity: self.tile_capacity,
            exposure_scale: c.exposure_scale,
            shown: c.shown,
            light_intensity: [intensity[0], intensity[1], intensity[2], 0.0],
            spot_axis: [spot.axis[0], spot.axis[1], spot.axis[2], spot.cos_inner],
            spot_cos_outer: spot.cos_outer,
            pad: [0; 3],
        }
    }

    /// Unit `index`'s dispatch: over its tiles (tiled) or the whole image. Without blending it
    /// writes only its own unit's pixels; with blending, it adds to the units before it.
    fn record_unit(
        &self,
        ctx: &Context,
        cmd: vk::CommandBuffer,
        extent: vk::Extent2D,
        c: &NetworkConstants,
        push: &SpecializedPush,
        index: usize,
    ) {
        let several = usize::from(c.light_count > 1);
        let dispatch = if self.tiled {
            Dispatch::Indirect { buffer: &self.dispatch, offset: 12 * index as u64 }
        } else {
            Dispatch::Covering { width: extent.width, height: extent.height }
        };
        self.networks.record_pipeline(ctx, cmd, 2 * index + several, bytemuck::bytes_of(push), dispatch);
    }
}
