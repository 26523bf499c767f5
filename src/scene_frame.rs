//! A frame of a scene: what the renderer's [`Frame`] gets from a scene, a model and the
//! viewer's or a command's settings. The scene's objects become G-buffer meshes and
//! materials ([`crate::gpu_scene`]), its networks become network units, and each frame's view
//! and lights become the passes' constants.

use anyhow::Result;
use rrf_baker::glam::Vec3;
use rrf_baker::model::Model;
use rrf_baker::network::{Component, Network};
use rrf_baker::partition::Region;
use rrf_baker::scene::{Aabb, Mirror, PlacedLight, Scene, View};
use rrf_renderer::frame::{Frame, FrameConstants, FrameOutput, FramePixels, FrameScene, FrameShaders, Shown};
use rrf_renderer::passes::gbuffer::{box_in_view, box_on_screen};
use rrf_renderer::passes::mirror::Reflected;
use rrf_renderer::passes::network::{LeafBlend, NetworkShaders, NetworkUnit, NetworkWeights, Variant, MAX_MIRRORS};
use rrf_renderer::{vk, Context, Destroy};

use crate::direct_mode::DirectMode;
use crate::gpu_scene::{
    analytic_light, gbuffer_constants, gbuffer_mesh, light_copies, moving_light_object, network_lights,
    network_materials, reflected, surface_materials,
};
use crate::shaders;

/// Every shader of a frame, as `build.rs` compiled them.
const FRAME_SHADERS: FrameShaders<'static> = FrameShaders {
    gbuffer_vertex: shaders::GBUFFER_VERT,
    gbuffer_fragment: shaders::GBUFFER_FRAG,
    network: NetworkShaders {
        storage: shaders::NETWORK_STORAGE_COMP,
        classify: shaders::NETWORK_CLASSIFY_COMP,
        specialized: shaders::NETWORK_SPECIALIZED_COMP,
        classify_display: shaders::NETWORK_CLASSIFY_DISPLAY_COMP,
        specialized_display: shaders::NETWORK_DISPLAY_COMP,
    },
    shadow_vertex: shaders::SHADOW_VERT,
    shadow_fragment: shaders::SHADOW_FRAG,
    tonemap: shaders::TONEMAP_COMP,
    mirror_merge: shaders::MIRROR_MERGE_COMP,
    overlay: shaders::OVERLAY_COMP,
    font: &font8x8::legacy::BASIC_LEGACY,
};

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

/// The renderer's frame for a scene, and where the scene's moving light sits, which turns
/// [`FrameSettings`] into the frame's constants.
pub struct SceneFrame {
    pub gpu: Frame,
    /// Where the glTF puts the moving light: each light's copy of its geometry moves from here.
    default_light: Vec3,
    /// The object id of the moving light's own geometry, which follows the light.
    light_object: Option<u32>,
    /// The scene's planar mirrors and their bounds.
    mirrors: Vec<(Mirror, Aabb)>,
}

impl SceneFrame {
    /// Everything for frames of `scene` at `extent` with network pass `variant`, writing
    /// `output`, with direct light from where `direct` (resolved for the scene) says.
    pub fn new(
        ctx: &Context,
        scene: &Scene,
        model: &Model,
        variant: Variant,
        extent: vk::Extent2D,
        output: FrameOutput,
        direct: DirectMode,
    ) -> Result<Self> {
        let direct = direct.resolve(scene, Some(variant));
        let (vertices, indices) = gbuffer_mesh(scene);
        let (surfaces, texels) = surface_materials(scene);
        let units = network_units(scene, model, direct);
        let analytic_light = match direct {
            DirectMode::Auto | DirectMode::Learned => None,
            DirectMode::Analytic => Some(analytic_light(scene)?),
        };
        let mirrors = scene.mirrors();
        let frame_scene = FrameScene {
            vertices: &vertices,
            indices: &indices,
            surfaces: &surfaces,
            texels: &texels,
            objects: scene.objects.len(),
            materials: &network_materials(scene),
            units: &units,
            analytic_light,
            mirrors: !mirrors.is_empty(),
        };
        Ok(SceneFrame {
            gpu: Frame::new(ctx, &FRAME_SHADERS, &frame_scene, variant, extent, output)?,
            default_light: scene.default_light().position,
            light_object: moving_light_object(scene),
            mirrors: mirrors.into_iter().map(|m| (m, scene.objects[m.object as usize].bounds())).collect(),
        })
    }

    /// Whether the scene has planar mirrors, whose reflections frames draw.
    pub fn has_mirrors(&self) -> bool {
        !self.mirrors.is_empty()
    }

    /// The passes' constants for a frame of `settings`: the mirrors among them are those in
    /// view whose reflecting side the camera is on, at most [`MAX_MIRRORS`], the largest on
    /// screen first.
    pub fn constants(&self, settings: &FrameSettings) -> FrameConstants {
        let extent = self.gpu.extent();
        let aspect = extent.width as f32 / extent.height as f32;
        let gbuffer = gbuffer_constants(&settings.view, aspect, self.light_object);
        let m = &gbuffer.view_projection;
        let mirrors = self.mirrors.iter().filter(|(_, b)| box_in_view(m, b.min.to_array(), b.max.to_array()));
        let mut mirrors: Vec<Reflected> = mirrors
            .filter_map(|(mirror, b)| {
                let area = box_on_screen(m, b.min.to_array(), b.max.to_array(), extent);
                reflected(&settings.view, aspect, self.light_object, mirror, area)
            })
            .collect();
        mirrors.sort_by_key(|r| std::cmp::Reverse(u64::from(r.area.extent.width) * u64::from(r.area.extent.height)));
        mirrors.truncate(MAX_MIRRORS as usize);
        FrameConstants {
            gbuffer,
            light_copies: light_copies(self.default_light, &settings.lights),
            lights: network_lights(&settings.lights),
            exposure_scale: settings.exposure_scale,
            shown: settings.shown,
            mirrors,
        }
    }

    /// Renders one frame of `settings` and reads the HDR images back.
    pub fn render(&self, ctx: &Context, settings: &FrameSettings) -> Result<FramePixels> {
        Ok(self.gpu.render(ctx, &self.constants(settings))?)
    }

    /// Renders one frame of `settings` and reads the display image back: RGBA in [0, 1],
    /// sRGB-encoded.
    pub fn render_display(&self, ctx: &Context, settings: &FrameSettings) -> Result<Vec<f32>> {
        Ok(self.gpu.render_display(ctx, &self.constants(settings))?)
    }

    pub fn destroy(self, ctx: &Context) {
        self.gpu.destroy(ctx);
    }
}

impl Destroy for SceneFrame {
    fn destroy(self, ctx: &Context) {
        SceneFrame::destroy(self, ctx);
    }
}

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
pub fn network_units<'a>(scene: &Scene, model: &'a Model, direct: DirectMode) -> Vec<NetworkUnit<'a>> {
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
        // A mirror shows what it reflects, not networks (a model from before it was one may
        // hold some).
        if scene.is_mirror(id as u32) {
            continue;
        }
        let indirect = model.networks(&o.name, Component::Indirect);
        if direct == DirectMode::Analytic {
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
