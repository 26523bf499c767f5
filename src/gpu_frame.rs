//! One frame on the GPU for a scene and a model: the G-buffer pass, the network pass, the
//! tonemap pass and the overlay, as a list of passes whose barriers come from what they
//! declare (`rrf_renderer::sync`).
//!
//! Camera, light, exposure and the component shown are per-frame constants: one `GpuFrame`
//! serves every configuration of its size, and `resize` remakes only what depends on the size.

use std::cell::RefCell;

use anyhow::Result;
use rrf_baker::glam::Vec3;
use rrf_baker::model::Model;
use rrf_baker::network::{Component, Network};
use rrf_baker::partition::Region;
use rrf_baker::scene::{PlacedLight, Scene, View};
use rrf_renderer::backend::sync::read_back_passes;
use rrf_renderer::backend::sync::{run_passes, Pass, Resource, ResourceStates};
use rrf_renderer::passes::gbuffer::{GBufferPass, GBufferTargets, GBufferTexel};
use rrf_renderer::passes::mesh::GBufferMesh;
use rrf_renderer::passes::network::{
    DirectLight, LeafBlend, NetworkConstants, NetworkPass, NetworkShaders, NetworkUnit, NetworkWeights, Variant,
};
use rrf_renderer::passes::overlay::{OverlayPass, TextGrid};
use rrf_renderer::passes::tonemap::TonemapPass;
use rrf_renderer::{vk, Context, Destroy, Image};

use crate::gpu_scene::{
    analytic_light, gbuffer_constants, gbuffer_mesh, light_copies, moving_light_object, network_lights,
    network_materials, surface_materials,
};
use crate::shaders;

/// The network units of the scene's objects: per object, pairs of one of its direct networks
/// and one of its indirect networks whose weights sum to one everywhere (one unit for an
/// object that was not split). Objects without networks get none. With analytic direct light
/// only the indirect networks are needed: each is a unit, with itself as a stand-in for the
/// direct network (the pass never evaluates it) over the whole object.
///
/// The bake cuts every node at the midpoint of its box's longest side, so an object's direct
/// and indirect trees are parts of one tree, and two of their leaves are either nested (the
/// cuts of one begin with all of the other's) or apart (on the two sides of one cut). Then the
/// units are the nested pairs, weighing what the deeper leaf weighs: the leaves of the two
/// trees' common refinement, as many as the finer tree has leaves. Trees that are not parts of
/// one tree (a model from elsewhere) get every pair whose supports meet, weighing the product
/// of the two leaves' weights.
pub fn network_units<'a>(scene: &Scene, model: &'a Model, direct: Direct) -> Vec<NetworkUnit<'a>> {
    let weights = |n: &'a Network| NetworkWeights {
        params: &n.params,
        input_min: n.input_min,
        input_max: n.input_max,
        output_scale: n.output_scale,
        blend: LeafBlend { min: n.blend.min, max: n.blend.max, min_band: n.blend.min_band, max_band: n.blend.max_band },
    };
    let whole = |n: &'a Network| NetworkWeights { blend: LeafBlend::WHOLE, ..weights(n) };
    let mut units = Vec::new();
    for (id, o) in scene.objects.iter().enumerate() {
        let indirect = model.networks(&o.name, Component::Indirect);
        if direct == Direct::Analytic {
            let unit = |i: &&'a Network| NetworkUnit { object: id, direct: whole(i), indirect: weights(i) };
            units.extend(indirect.iter().map(unit));
            continue;
        }
        let direct = model.networks(&o.name, Component::Direct);
        let pairs = || direct.iter().flat_map(|d| indirect.iter().map(move |i| (*d, *i)));
        let one_tree = pairs().all(|(d, i)| relation(&d.region, &i.region) != Relation::Unrelated);
        for (d, i) in pairs() {
            let unit = match relation(&d.region, &i.region) {
                Relation::Nested { direct_deeper: true } if one_tree => (weights(d), whole(i)),
                Relation::Nested { direct_deeper: false } if one_tree => (whole(d), weights(i)),
                _ if one_tree => continue,
                _ => {
                    let (d_min, d_max) = d.blend.support();
                    let (i_min, i_max) = i.blend.support();
                    if !(0..3).all(|a| d_min[a].max(i_min[a]) < d_max[a].min(i_max[a])) {
                        continue;
                    }
                    (weights(d), weights(i))
                }
            };
            units.push(NetworkUnit { object: id, direct: unit.0, indirect: unit.1 });
        }
    }
    units
}

/// How a leaf of an object's direct tree and one of its indirect tree lie (see
/// [`network_units`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Relation {
    /// The cuts of one begin with all of the other's; `direct_deeper` when the direct leaf
    /// has more cuts, or as many (the same leaf).
    Nested { direct_deeper: bool },
    /// On the two sides of one cut.
    Apart,
    /// Cut differently: not parts of one tree.
    Unrelated,
}

fn relation(direct: &Region, indirect: &Region) -> Relation {
    let common = direct.0.iter().zip(&indirect.0).take_while(|(a, b)| a == b).count();
    if common == direct.0.len().min(indirect.0.len()) {
        return Relation::Nested { direct_deeper: direct.0.len() >= indirect.0.len() };
    }
    let (a, b) = (direct.0[common], indirect.0[common]);
    if a.axis == b.axis && a.at == b.at {
        Relation::Apart
    } else {
        Relation::Unrelated
    }
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

/// Which light the display image shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shown {
    /// Emission + direct + indirect.
    Gi,
    Direct,
    Indirect,
}

impl Shown {
    /// The shaders' code for it.
    fn code(self) -> u32 {
        match self {
            Shown::Gi => 0,
            Shown::Direct => 1,
            Shown::Indirect => 2,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Shown::Gi => "global",
            Shown::Direct => "direct only",
            Shown::Indirect => "indirect only",
        }
    }
}

/// What a frame writes besides the display image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FrameOutput {
    /// Direct, indirect and global radiance (RGBA32F) for read-back, then the display image
    /// tonemapped from one of them: `rrf render`, `eval`, `bench`.
    Radiance,
    /// Only the display image, written by the network pass itself: the walkthrough. The
    /// storage variant, which cannot, and models whose kd-tree leaves blend (their units add
    /// to each other's radiance) fall back to `Radiance`.
    Display,
}

/// Where a frame's direct light comes from (`--direct`).
#[derive(clap::ValueEnum, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Direct {
    /// `analytic` where the scene's only light is its moving point or spot light (the RRF
    /// paper's own mode, with sharp shadows; not with the storage variant), `learned`
    /// otherwise (area lights, and scenes with other lights).
    #[default]
    Auto,
    /// From each object's direct network: any kind of light, area lights included.
    Learned,
    /// Computed per pixel from the baker's BRDF for a point or spot light, with shadows from
    /// cube shadow maps (the RRF paper's own mode; sharp shadows). Needs the tiled or
    /// per-object variant, and a scene whose only light is its moving point light.
    Analytic,
}

impl Direct {
    /// The mode to render `scene` in with `variant` (`None`: the CPU inference): `Auto`
    /// picks analytic direct light where it can run, learned elsewhere; the others are
    /// themselves.
    pub fn resolve(self, scene: &Scene, variant: Option<Variant>) -> Direct {
        match self {
            Direct::Auto if variant != Some(Variant::Storage) && analytic_light(scene).is_ok() => Direct::Analytic,
            Direct::Auto => Direct::Learned,
            chosen => chosen,
        }
    }

    /// Whether `scene` can be lit this way: analytic direct light needs the scene's only
    /// light to be its moving point or spot light.
    pub fn check_scene(self, scene: &Scene) -> Result<()> {
        match self {
            Direct::Auto | Direct::Learned => Ok(()),
            Direct::Analytic => analytic_light(scene).map(|_| ()),
        }
    }

    /// Whether `scene` can be rendered this way with `model`: [`Direct::check_scene`], and
    /// learned direct light needs the direct networks, which a bake for analytic direct light
    /// leaves out.
    pub fn check(self, scene: &Scene, model: &Model) -> Result<()> {
        self.check_scene(scene)?;
        let indirect_only = || {
            model
                .networks
                .iter()
                .any(|n| n.component == Component::Indirect && !model.has(&n.object, Component::Direct))
        };
        if self == Direct::Learned && indirect_only() {
            anyhow::bail!(
                "the model of {} has no direct networks (it was baked with --direct analytic): render with \
                 --direct analytic, or bake again without it",
                scene.name
            );
        }
        Ok(())
    }

    /// The CPU inference's mode for `scene`.
    pub fn cpu(self, scene: &Scene) -> rrf_baker::predict::Direct {
        match self.resolve(scene, None) {
            Direct::Analytic => rrf_baker::predict::Direct::Analytic,
            _ => rrf_baker::predict::Direct::Learned,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Direct::Auto => "auto",
            Direct::Learned => "learned",
            Direct::Analytic => "analytic",
        }
    }
}

/// What changes from frame to frame.
#[derive(Clone, Debug)]
pub struct FrameSettings {
    pub view: View,
    /// The lights: copies of the moving light (1 to `rrf_renderer::lights::MAX_LIGHTS`).
    pub lights: Vec<PlacedLight>,
    /// 2^EV.
    pub exposure_scale: f32,
    pub shown: Shown,
}

/// Timestamps a frame writes: start, after the G-buffer, after the network pass, after the
/// tonemap pass, after the rest (overlay, presentation blit, read-back).
pub const TIMESTAMPS: u32 = 5;
/// Names of the intervals between consecutive timestamps.
pub const TIMED_PASSES: [&str; 4] = ["gbuffer", "network", "tonemap", "overlay+present"];

pub struct GpuFrame {
    targets: GBufferTargets,
    mesh: GBufferMesh,
    gbuffer: GBufferPass,
    network: NetworkPass,
    /// Display-referred image (RGBA8, sRGB-encoded): what the tonemap pass writes, the overlay
    /// draws on, the window shows and screenshots save.
    ldr: Image,
    /// Tonemap passes of the global, direct and indirect images (none when the network pass
    /// writes the display image itself).
    tonemaps: Vec<TonemapPass>,
    overlay: OverlayPass,
    /// Where the glTF puts the moving light: each light's copy of its geometry moves from here.
    default_light: Vec3,
    /// The object id of the moving light's own geometry, which follows the light.
    light_object: Option<u32>,
    states: RefCell<ResourceStates>,
}

impl GpuFrame {
    /// Everything for frames of `scene` at `extent` with network pass `variant`, writing
    /// `output`, with direct light from where `direct` (resolved for the scene) says.
    pub fn new(
        ctx: &Context,
        scene: &Scene,
        model: &Model,
        variant: Variant,
        extent: vk::Extent2D,
        output: FrameOutput,
        direct: Direct,
    ) -> Result<Self> {
        let direct = direct.resolve(scene, Some(variant));
        // Each part is destroyed again if a later one cannot be made.
        let targets = ctx.guard(GBufferTargets::new(ctx, extent)?);
        let (vertices, indices) = gbuffer_mesh(scene);
        let (surfaces, texels) = surface_materials(scene);
        let mesh = ctx.guard(GBufferMesh::new(ctx, &vertices, &indices, &surfaces, &texels)?);
        let gbuffer = ctx.guard(GBufferPass::new(ctx, shaders::GBUFFER_VERT, shaders::GBUFFER_FRAG, &mesh)?);
        let network_shaders = NetworkShaders {
            storage: shaders::NETWORK_STORAGE_COMP,
            classify: shaders::NETWORK_CLASSIFY_COMP,
            specialized: shaders::NETWORK_SPECIALIZED_COMP,
            classify_display: shaders::NETWORK_CLASSIFY_DISPLAY_COMP,
            specialized_display: shaders::NETWORK_DISPLAY_COMP,
        };
        let units = network_units(scene, model, direct);
        let ldr = ctx.guard(create_ldr(ctx, extent)?);
        // Units that blend add to each other's radiance images; the frame then tonemaps those.
        let blended = units.iter().any(NetworkUnit::blends);
        let display = (output == FrameOutput::Display && variant != Variant::Storage && !blended).then_some(&*ldr);
        let materials = network_materials(scene);
        let direct = match direct {
            Direct::Auto | Direct::Learned => DirectLight::Learned,
            Direct::Analytic => DirectLight::Analytic {
                light: analytic_light(scene)?,
                shadow_vertex: shaders::SHADOW_VERT,
                shadow_fragment: shaders::SHADOW_FRAG,
            },
        };
        let network = ctx.guard(NetworkPass::new(
            ctx,
            variant,
            &network_shaders,
            &targets,
            scene.objects.len(),
            &units,
            &materials,
            display,
            direct,
        )?);
        let mut tonemaps = ctx.guard(Vec::with_capacity(3));
        for hdr in network.outputs().into_iter().flat_map(|o| [&o.gi, &o.direct, &o.indirect]) {
            tonemaps.push(TonemapPass::new(ctx, shaders::TONEMAP_COMP, hdr, &ldr)?);
        }
        let overlay = OverlayPass::new(ctx, shaders::OVERLAY_COMP, &font8x8::legacy::BASIC_LEGACY, &ldr)?;
        let frame = GpuFrame {
            targets: targets.keep(),
            mesh: mesh.keep(),
            gbuffer: gbuffer.keep(),
            network: network.keep(),
            ldr: ldr.keep(),
            tonemaps: tonemaps.keep(),
            overlay,
            default_light: scene.default_light().position,
            light_object: moving_light_object(scene),
            states: RefCell::default(),
        };
        frame.register();
        Ok(frame)
    }

    /// Tells the barrier tracker where set-up left every image.
    fn register(&self) {
        let mut states = self.states.borrow_mut();
        self.targets.register(&mut states);
        self.network.register(&mut states);
        states.set_layout(&self.ldr, vk::ImageLayout::GENERAL);
    }

    pub fn extent(&self) -> vk::Extent2D {
        self.targets.extent
    }

    /// The display image (RGBA8, sRGB-encoded).
    pub fn ldr(&self) -> &Image {
        &self.ldr
    }

    /// The barrier tracker, for passes that the caller adds to a frame.
    pub fn states(&self) -> std::cell::RefMut<'_, ResourceStates> {
        self.states.borrow_mut()
    }

    /// Remakes the images for `extent`; pipelines and the mesh stay. No frame that uses this
    /// one may be pending. On failure the frame keeps its old size.
    pub fn resize(&mut self, ctx: &Context, extent: vk::Extent2D) -> Result<()> {
        if extent == self.extent() {
            return Ok(());
        }
        let targets = ctx.guard(GBufferTargets::new(ctx, extent)?);
        let ldr = ctx.guard(create_ldr(ctx, extent)?);
        let display = self.network.outputs().is_none().then_some(&*ldr);
        self.network.resize(ctx, &targets, display)?;
        std::mem::replace(&mut self.targets, targets.keep()).destroy(ctx);
        ctx.destroy_image(std::mem::replace(&mut self.ldr, ldr.keep()));
        let hdr = self.network.outputs().into_iter().flat_map(|o| [&o.gi, &o.direct, &o.indirect]);
        for (pass, hdr) in self.tonemaps.iter().zip(hdr) {
            pass.rebind(ctx, hdr, &self.ldr);
        }
        self.overlay.rebind(ctx, &self.ldr);
        *self.states.borrow_mut() = ResourceStates::default();
        self.register();
        Ok(())
    }

    /// Records a frame: the G-buffer, network, tonemap and (with `overlay`, at a scale in
    /// screen pixels per font pixel) overlay passes, then `extra` passes (presentation,
    /// read-back). With `timestamps`, a pool reset for this frame, writes [`TIMESTAMPS`].
    pub fn record<'a>(
        &'a self,
        ctx: &'a Context,
        cmd: vk::CommandBuffer,
        settings: &FrameSettings,
        overlay: Option<(&TextGrid, u32)>,
        timestamps: Option<vk::QueryPool>,
        extra: Vec<Pass<'a>>,
    ) -> Result<()> {
        let passes = self.passes(ctx, settings, overlay, timestamps, extra)?;
        if let Some(pool) = timestamps {
            // SAFETY: the pool holds TIMESTAMPS queries and was reset for this frame.
            unsafe { ctx.device.cmd_write_timestamp2(cmd, vk::PipelineStageFlags2::ALL_COMMANDS, pool, 0) };
        }
        run_passes(ctx, cmd, &mut self.states.borrow_mut(), passes);
        Ok(())
    }

    /// Image bytes a frame moves per pixel, from what its passes declare (without overlay or
    /// read-back): each declared image access counted as one read or write of every pixel, so
    /// an upper bound where a pass touches only some pixels (the classification's background).
    pub fn bytes_per_pixel(&self, ctx: &Context, settings: &FrameSettings) -> Result<u32> {
        let passes = self.passes(ctx, settings, None, None, vec![])?;
        // Blended network units are a pass each, each over its own pixels: together they
        // touch a pixel's images about once, as one pass does.
        let distinct = passes.iter().enumerate().filter(|(i, p)| *i == 0 || passes[i - 1].name != p.name);
        let bytes = distinct.flat_map(|(_, p)| &p.uses).map(|u| match u.resource {
            Resource::Image { texel_bytes, .. } => texel_bytes,
            Resource::Buffer(_) => 0,
        });
        Ok(bytes.sum())
    }

    /// The passes of a frame, for `record`.
    fn passes<'a>(
        &'a self,
        ctx: &'a Context,
        settings: &FrameSettings,
        overlay: Option<(&TextGrid, u32)>,
        timestamps: Option<vk::QueryPool>,
        extra: Vec<Pass<'a>>,
    ) -> Result<Vec<Pass<'a>>> {
        let extent = self.extent();
        let aspect = extent.width as f32 / extent.height as f32;
        let g = gbuffer_constants(&settings.view, aspect, self.light_object);
        let lights = network_lights(&settings.lights);
        let n = NetworkConstants::new(g.eye, &lights, settings.exposure_scale, settings.shown.code())?;
        let copies = light_copies(self.default_light, &settings.lights);
        let mut passes = vec![self.gbuffer.pass(ctx, &self.targets, &self.mesh, g, copies)];
        let stamp = |passes: &mut Vec<Pass>, index: u32| {
            if let (Some(pool), Some(last)) = (timestamps, passes.last_mut()) {
                last.timestamp = Some((pool, index));
            }
        };
        stamp(&mut passes, 1);
        let display = self.network.outputs().is_none().then_some(&self.ldr);
        passes.extend(self.network.passes(ctx, &self.targets, &self.mesh, n, display)?);
        stamp(&mut passes, 2);
        if let Some(outputs) = self.network.outputs() {
            let (tonemap, hdr) = match settings.shown {
                Shown::Gi => (&self.tonemaps[0], &outputs.gi),
                Shown::Direct => (&self.tonemaps[1], &outputs.direct),
                Shown::Indirect => (&self.tonemaps[2], &outputs.indirect),
            };
            passes.push(tonemap.pass(ctx, hdr, &self.ldr, settings.exposure_scale));
        }
        // The tonemap interval ends here even when the network pass did its work.
        passes.push(Pass::new("tonemap done", vec![], |_| {}));
        stamp(&mut passes, 3);
        if let Some((grid, scale)) = overlay {
            passes.extend(self.overlay.passes(ctx, &self.ldr, grid, scale));
        }
        // The last interval always ends with a pass, even an empty one.
        passes.extend(extra);
        passes.push(Pass::new("end of frame", vec![], |_| {}));
        stamp(&mut passes, 4);
        Ok(passes)
    }

    /// Renders one frame and reads the HDR images back.
    pub fn render(&self, ctx: &Context, settings: &FrameSettings) -> Result<FramePixels> {
        let Some(outputs) = self.network.outputs() else {
            anyhow::bail!("this frame writes only its display image (FrameOutput::Display); it has no radiance to read")
        };
        let [direct, indirect, gi] = self
            .read_back(ctx, &[&outputs.direct, &outputs.indirect, &outputs.gi], Some(settings))?
            .try_into()
            .map_err(|_| anyhow::anyhow!("three images read back"))?;
        Ok(FramePixels { direct, indirect, gi })
    }

    /// Renders one frame and reads the display image back: RGBA in [0, 1], sRGB-encoded.
    pub fn render_display(&self, ctx: &Context, settings: &FrameSettings) -> Result<Vec<f32>> {
        Ok(self.read_back(ctx, &[&self.ldr], Some(settings))?.remove(0))
    }

    /// Object ids + 1 of the last frame's pixels (0: nothing).
    pub fn read_objects(&self, ctx: &Context) -> Result<Vec<u32>> {
        let ids = self.read_back(ctx, &[&self.targets.id], None)?.remove(0);
        Ok(ids.iter().map(|&v| GBufferTexel::decode([0; 4], v.to_bits(), [0; 4]).object).collect())
    }

    /// Reads `images` back (as `Context::decode` gives them), after rendering a frame of
    /// `settings` first, or else as the last frame left them; waits for the GPU.
    fn read_back(&self, ctx: &Context, images: &[&Image], settings: Option<&FrameSettings>) -> Result<Vec<Vec<f32>>> {
        let mut buffers = ctx.guard(Vec::with_capacity(images.len()));
        for image in images {
            buffers.push(ctx.create_readback_buffer(image)?);
        }
        ctx.submit_once(|cmd| {
            let passes = images.iter().zip(buffers.iter()).flat_map(|(i, b)| read_back_passes(ctx, i, b)).collect();
            match settings {
                Some(settings) => self.record(ctx, cmd, settings, None, None, passes),
                None => {
                    run_passes(ctx, cmd, &mut self.states.borrow_mut(), passes);
                    Ok(())
                }
            }
        })??;
        images.iter().zip(buffers.iter()).map(|(i, b)| Ok(ctx.decode(i.format, b)?)).collect()
    }

    pub fn destroy(self, ctx: &Context) {
        Destroy::destroy(self, ctx);
    }
}

impl Destroy for GpuFrame {
    fn destroy(self, ctx: &Context) {
        self.overlay.destroy(ctx);
        for pass in self.tonemaps {
            pass.destroy(ctx);
        }
        ctx.destroy_image(self.ldr);
        self.network.destroy(ctx);
        self.gbuffer.destroy(ctx);
        self.mesh.destroy(ctx);
        self.targets.destroy(ctx);
    }
}

fn create_ldr(ctx: &Context, extent: vk::Extent2D) -> Result<Image> {
    let ldr = ctx.guard(ctx.create_image(
        "ldr",
        extent,
        vk::Format::R8G8B8A8_UNORM,
        vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_SRC,
    )?);
    ctx.submit_once(|cmd| ctx.transition(cmd, &ldr, vk::ImageLayout::UNDEFINED, vk::ImageLayout::GENERAL))?;
    Ok(ldr.keep())
}
