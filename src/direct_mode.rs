//! `--direct`: where a frame's direct light comes from, and which scenes and models allow
//! each choice.

use anyhow::Result;
use rrf_baker::model::Model;
use rrf_baker::network::Component;
use rrf_baker::scene::Scene;
use rrf_renderer::passes::network::Variant;

use crate::gpu_scene::analytic_light;

/// Where a frame's direct light comes from (`--direct`).
#[derive(clap::ValueEnum, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum DirectMode {
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

impl DirectMode {
    /// The mode to render `scene` in with `variant` (`None`: the CPU inference): `Auto`
    /// picks analytic direct light where it can run, learned elsewhere; the others are
    /// themselves.
    pub fn resolve(self, scene: &Scene, variant: Option<Variant>) -> DirectMode {
        match self {
            DirectMode::Auto if variant != Some(Variant::Storage) && analytic_light(scene).is_ok() => {
                DirectMode::Analytic
            }
            DirectMode::Auto => DirectMode::Learned,
            chosen => chosen,
        }
    }

    /// Whether `scene` can be lit this way: analytic direct light needs the scene's only
    /// light to be its moving point or spot light.
    pub fn check_scene(self, scene: &Scene) -> Result<()> {
        match self {
            DirectMode::Auto | DirectMode::Learned => Ok(()),
            DirectMode::Analytic => analytic_light(scene).map(|_| ()),
        }
    }

    /// Whether `scene` can be rendered this way with `model`: [`DirectMode::check_scene`], and
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
        if self == DirectMode::Learned && indirect_only() {
            anyhow::bail!(
                "the model of {} has no direct networks (it was baked with --direct analytic): render with \
                 --direct analytic, or bake again without it",
                scene.name
            );
        }
        Ok(())
    }

    /// Whether the network pass `variant` can light this way: analytic direct light needs
    /// the tiled or per-object variant.
    pub fn check_variant(self, variant: Variant) -> Result<()> {
        if self == DirectMode::Analytic && variant == Variant::Storage {
            anyhow::bail!("analytic direct light needs the tiled or per-object network pass, not {}", variant.name());
        }
        Ok(())
    }

    /// The CPU inference's mode for `scene`.
    pub fn cpu(self, scene: &Scene) -> rrf_baker::predict::Direct {
        match self.resolve(scene, None) {
            DirectMode::Analytic => rrf_baker::predict::Direct::Analytic,
            _ => rrf_baker::predict::Direct::Learned,
        }
    }

    /// What the mode means, for the viewer's panel.
    pub fn description(self) -> &'static str {
        match self {
            DirectMode::Auto => "chosen per scene",
            DirectMode::Learned => "learned by the networks",
            DirectMode::Analytic => "computed: point light and shadow map",
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            DirectMode::Auto => "auto",
            DirectMode::Learned => "learned",
            DirectMode::Analytic => "analytic",
        }
    }
}
