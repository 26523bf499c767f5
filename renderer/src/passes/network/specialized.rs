//! The specialized variants: one pipeline per unit with its weights as specialization
//! constants (`network_specialized.comp`), after a pass that sorts the image's 8×8 tiles by
//! unit (`network_classify.comp`). The per-object variant dispatches each pipeline over the
//! whole image; the tiled one, indirectly over only its unit's tiles. Both dispatch only the
//! units that can show in the frame, and make a unit's pipeline when a frame first does.

use ash::vk;
use bytemuck::{Pod, Zeroable};
use gpu_allocator::MemoryLocation;

use super::units::{specializations, NetworkUnit};
use super::{network_bindings, DirectLight, FrameUses, NetworkConstants, NetworkShaders, Shared, Written, TILE};
use crate::backend::compute::{Bind, ComputePass, Dispatch, Specialization};
use crate::backend::context::Context;
use crate::backend::guard::Destroy;
use crate::backend::resources::{Buffer, Image};
use crate::backend::sync::{Access, Pass, ResourceStates, Use};
use crate::error::{Error, Result};
use crate::lights::{PointLightShape, Spot};
use crate::passes::gbuffer::{box_in_view, GBufferConstants, GBufferTargets};
use crate::passes::mesh::GBufferMesh;
use crate::passes::shadow::ShadowPass;

/// Where a network unit's weight may be above 0: its object, and a box in world space.
struct UnitSupport {
    object: usize,
    min: [f32; 3],
    max: [f32; 3],
}

impl UnitSupport {
    fn of(unit: &NetworkUnit) -> Self {
        let (d, i) = (unit.direct.blend, unit.indirect.blend);
        UnitSupport {
            object: unit.object,
            min: std::array::from_fn(|a| (d.min[a] - d.min_band[a]).max(i.min[a] - i.min_band[a])),
            max: std::array::from_fn(|a| (d.max[a] + d.max_band[a]).min(i.max[a] + i.max_band[a])),
        }
    }
}

/// The units, in order, whose support may show in one of `views`: where it meets its
/// object's `bounds` (by object id; `None` for no triangles), it is in the view. The moving
/// light's object is drawn moved, so its units always count.
fn units_in_view(
    supports: &[UnitSupport],
    bounds: &[Option<([f32; 3], [f32; 3])>],
    views: &[GBufferConstants],
) -> Vec<usize> {
    let moving = views.first().map_or(0, |v| v.light_object) as usize;
    let in_view = |s: &UnitSupport| {
        if s.object + 1 == moving {
            return true;
        }
        let Some((low, high)) = bounds.get(s.object).copied().flatten() else { return false };
        let min: [f32; 3] = std::array::from_fn(|a| s.min[a].max(low[a]));
        let max: [f32; 3] = std::array::from_fn(|a| s.max[a].min(high[a]));
        (0..3).all(|a| min[a] <= max[a]) && views.iter().any(|v| box_in_view(&v.view_projection, min, max))
    };
    (0..supports.len()).filter(|&unit| in_view(&supports[unit])).collect()
}

/// The most units `network_classify.comp` tells apart.
const MAX_UNITS: usize = 1024;

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

/// The specialized variants' pipelines: the tile classification, then two per unit.
pub(super) struct Specialized {
    classify: ComputePass,
    /// A pipeline per unit for frames of one light, in unit order, then one per unit for
    /// frames of several. Each is made when a frame first shows its unit (on lavapipe each
    /// costs start-up time and about 2 MB), so the several-light set waits for a frame with
    /// two lights, and units out of view wait until they come into it.
    networks: ComputePass,
    /// Each unit's object and the box outside which its weight is 0 (its two leaves' blend
    /// boxes, bands included, intersected).
    supports: Vec<UnitSupport>,
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

/// The bindings of `network_classify_main.glsl`: the dispatch arguments where the others have
/// the lights, and the unit table last.
fn classify_bindings<'a>(
    gbuffer: &'a GBufferTargets,
    shared: Shared<'a>,
    dispatch: &'a Buffer,
    tiles: &'a Buffer,
    written: Written<'a>,
) -> Vec<Bind<'a>> {
    network_bindings(gbuffer, shared, dispatch, tiles, written, [Bind::StorageBuffer(shared.units)])
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

/// The bindings of `network_specialized_main.glsl`: [`network_bindings`] with the shadow maps
/// last, then the unit table.
fn specialized_bindings<'a>(
    gbuffer: &'a GBufferTargets,
    shared: Shared<'a>,
    tiles: &'a Buffer,
    written: Written<'a>,
    direct: &'a Direct,
) -> Vec<Bind<'a>> {
    let rest = [Bind::StorageImage(direct.shadow_maps()), Bind::StorageBuffer(shared.units)];
    network_bindings(gbuffer, shared, shared.lights, tiles, written, rest)
}

/// `words` as bytes, with at least one word: Vulkan buffers cannot be empty.
fn pad(words: &[u32]) -> &[u8] {
    const ZERO: &[u32] = &[0];
    bytemuck::cast_slice(if words.is_empty() { ZERO } else { words })
}

impl Specialized {
    #[allow(clippy::too_many_arguments)] // NetworkPass::new's, passed on
    pub(super) fn new(
        ctx: &Context,
        shaders: &NetworkShaders,
        gbuffer: &GBufferTargets,
        shared: Shared,
        written: Written,
        objects: usize,
        units: &[NetworkUnit],
        tiled: bool,
        direct: DirectLight,
    ) -> Result<Self> {
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
        let (one_light, several_lights): (Vec<Specialization>, Vec<Specialization>) =
            (0..units.len()).map(|index| specializations(objects, units, index, tiled, analytic).into()).unzip();
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
        let name = "network (specialization constants)";
        let push_bytes = std::mem::size_of::<SpecializedPush>() as u32;
        let networks =
            ComputePass::specialized(ctx, name, specialized_spirv, &bindings, push_bytes, (TILE, TILE), &[])?
                .with_deferred(name, specialized_spirv, one_light.into_iter().chain(several_lights).collect());
        Ok(Specialized {
            classify: classify.keep(),
            networks,
            supports: units.iter().map(UnitSupport::of).collect(),
            tiled,
            dispatch: dispatch.keep(),
            dispatch_reset,
            tiles: tiles.keep(),
            tile_capacity,
            direct: direct.keep(),
            blended,
        })
    }

    /// The frame's steps: reset the indirect dispatches, draw the shadow maps (analytic
    /// direct light), sort the tiles by unit, then each unit's pipeline; blending units each
    /// in a pass of their own, as they add to what the units before them wrote.
    ///
    /// Only the units that may show in one of `views` (the frame's G-buffer passes) are
    /// dispatched, after their pipelines are made if this is the first frame to show them:
    /// the others have no pixels, so the tile classification lists none for them.
    pub(super) fn passes<'a>(
        &'a self,
        frame: FrameUses<'a>,
        mesh: &'a GBufferMesh,
        views: &[GBufferConstants],
    ) -> Result<Vec<Pass<'a>>> {
        let g = frame.gbuffer_reads();
        let FrameUses { ctx, extent, constants: c, objects, materials, lights, units, writes, .. } = frame;
        let shown = units_in_view(&self.supports, &mesh.object_bounds(), views);
        self.networks.make_deferred(ctx, shown.iter().map(|&unit| self.pipeline(&c, unit)))?;
        let read = |image| Use::image(image, Access::COMPUTE_READ);
        let mut passes = Vec::new();
        if !self.dispatch_reset.is_empty() {
            passes.push(Pass::new(
                "network dispatch reset",
                vec![Use::buffer(&self.dispatch, Access::TRANSFER_WRITE)],
                |cmd| {
                    // SAFETY: recording outside a render pass; at most 12 KiB (MAX_UNITS), under
                    // vkCmdUpdateBuffer's 64 KiB.
                    unsafe {
                        ctx.device.cmd_update_buffer(
                            cmd,
                            self.dispatch.raw,
                            0,
                            bytemuck::cast_slice(&self.dispatch_reset),
                        )
                    };
                },
            ));
        }
        if let Direct::Analytic { shadow, .. } = &self.direct {
            let positions = c.lights().iter().map(|l| [l.position[0], l.position[1], l.position[2]]).collect();
            passes.push(shadow.pass(ctx, mesh, positions));
        }
        let mut uses = g.clone();
        uses.extend([
            materials,
            units,
            Use::buffer(&self.dispatch, Access::COMPUTE_READ_WRITE),
            Use::buffer(&self.tiles, Access::COMPUTE_WRITE),
        ]);
        uses.extend(writes.iter().copied());
        let push = ClassifyPush {
            objects,
            units: self.supports.len() as u32,
            tile_capacity: self.tile_capacity,
            exposure_scale: c.exposure_scale,
            shown: c.shown,
        };
        passes.push(Pass::new("network tile classification", uses, move |cmd| {
            self.classify.record(ctx, cmd, bytemuck::bytes_of(&push), extent.width, extent.height)
        }));
        let mut uses = g;
        uses.extend([materials, lights, units, Use::buffer(&self.tiles, Access::COMPUTE_READ)]);
        uses.push(read(self.direct.shadow_maps()));
        if self.tiled {
            uses.push(Use::buffer(&self.dispatch, Access::INDIRECT_READ));
        }
        // Blending units read what the units before them wrote.
        let written = if self.blended { Access::COMPUTE_READ_WRITE } else { Access::COMPUTE_WRITE };
        uses.extend(writes.iter().map(|w| Use { access: written, ..*w }));
        let push = self.push(&c);
        if self.blended {
            for unit in shown {
                passes.push(Pass::new("network unit (blended)", uses.clone(), move |cmd| {
                    self.record_unit(ctx, cmd, extent, &c, &push, unit)
                }));
            }
        } else {
            passes.push(Pass::new("network (specialization constants)", uses, move |cmd| {
                shown.iter().for_each(|&unit| self.record_unit(ctx, cmd, extent, &c, &push, unit))
            }));
        }
        Ok(passes)
    }

    /// Tile lists for the pass's units at `extent`, and their capacity.
    pub(super) fn tile_buffer(&self, ctx: &Context, extent: vk::Extent2D) -> Result<(Buffer, u32)> {
        tile_buffer(ctx, self.supports.len(), extent)
    }

    /// Records where `new` left the shadow maps or their stand-in.
    pub(super) fn register(&self, states: &mut ResourceStates) {
        match &self.direct {
            Direct::Learned { stand_in } => states.set_layout(stand_in, vk::ImageLayout::GENERAL),
            Direct::Analytic { shadow, .. } => shadow.register(states),
        }
    }

    /// Points the pipelines at the resized G-buffer and outputs, with `tiles`, the tile lists
    /// made for the new size, and their capacity.
    pub(super) fn rebind(
        &mut self,
        ctx: &Context,
        gbuffer: &GBufferTargets,
        shared: Shared,
        written: Written,
        tiles: Option<(Buffer, u32)>,
    ) {
        if let Some((tiles, capacity)) = tiles {
            ctx.destroy_buffer(std::mem::replace(&mut self.tiles, tiles));
            self.tile_capacity = capacity;
        }
        let bindings = classify_bindings(gbuffer, shared, &self.dispatch, &self.tiles, written);
        self.classify.rebind(ctx, &bindings);
        self.networks.rebind(ctx, &self.bindings(gbuffer, shared, written));
    }

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
        let dispatch = if self.tiled {
            Dispatch::Indirect { buffer: &self.dispatch, offset: 12 * index as u64 }
        } else {
            Dispatch::Covering { width: extent.width, height: extent.height }
        };
        self.networks.record_pipeline(ctx, cmd, self.pipeline(c, index), bytemuck::bytes_of(push), dispatch);
    }

    /// Unit `unit`'s pipeline in `networks` for a frame of `c`: the one-light set, then the
    /// several-light set.
    fn pipeline(&self, c: &NetworkConstants, unit: usize) -> usize {
        if c.light_count > 1 {
            self.supports.len() + unit
        } else {
            unit
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::passes::gbuffer::tests::identity;
    use crate::passes::network::{LeafBlend, NetworkWeights};

    /// The view of the clip volume itself moved by `x` along x, with object id + 1
    /// `light_object` the moving light's.
    fn view(x: f32, light_object: u32) -> GBufferConstants {
        let mut view = identity(light_object, [0.0; 4]);
        view.view_projection[3][0] = -x;
        view
    }

    fn support(object: usize, from_x: f32, to_x: f32) -> UnitSupport {
        UnitSupport { object, min: [from_x, -f32::MAX, -f32::MAX], max: [to_x, f32::MAX, f32::MAX] }
    }

    #[test]
    fn a_units_support_is_its_leaves_boxes_with_their_bands() {
        let weights = |blend| NetworkWeights {
            params: &[],
            input_min: [0.0; 13],
            input_max: [1.0; 13],
            output_scale: 1.0,
            blend,
        };
        let below = LeafBlend { max: [1.0, f32::MAX, f32::MAX], max_band: [0.1, 0.0, 0.0], ..LeafBlend::WHOLE };
        let above = LeafBlend { min: [0.5, -f32::MAX, -f32::MAX], min_band: [0.05, 0.0, 0.0], ..LeafBlend::WHOLE };
        let s = UnitSupport::of(&NetworkUnit { object: 3, direct: weights(below), indirect: weights(above) });
        assert_eq!(s.object, 3);
        assert_eq!((s.min[0], s.max[0]), (0.45, 1.1));
        assert_eq!((s.min[1], s.max[1]), (-f32::MAX, f32::MAX));
    }

    #[test]
    fn only_units_that_can_show_are_shaded() {
        // Object 0 spans x from -3 to 3; its units split it at 1 and 2 (bands of 0.1).
        // Object 1 has no triangles; object 2 is out of view but is the moving light.
        let slab = ([-3.0, -0.5, 0.2], [3.0, 0.5, 0.8]);
        let bounds = [Some(slab), None, Some(([7.0, 0.0, 0.5], [8.0, 0.1, 0.6]))];
        let supports = [
            support(0, -f32::MAX, 1.1),
            support(0, 0.9, 2.1),
            support(0, 1.9, f32::MAX),
            support(1, -f32::MAX, f32::MAX),
            support(2, -f32::MAX, f32::MAX),
        ];
        let camera = view(0.0, 0);
        assert_eq!(units_in_view(&supports, &bounds, &[camera]), [0, 1], "x from -1 to 1 sees the first two");
        // A mirror's view of x from 1.5 to 3.5 adds the third.
        assert_eq!(units_in_view(&supports, &bounds, &[camera, view(2.5, 0)]), [0, 1, 2]);
        assert_eq!(units_in_view(&supports, &bounds, &[view(-5.0, 0)]), [] as [usize; 0], "nothing in view");
        assert_eq!(units_in_view(&supports, &bounds, &[view(-5.0, 3)]), [4], "the moving light is drawn moved");
    }
}
