//! The sidecar: what glTF cannot say, in a small TOML file beside it.
//!
//! ```toml
//! [light]                    # the light that moves, and the box its position may take
//! node = "CeilingLight"      # a KHR_lights_punctual point-light node or an emissive mesh node
//! min = [0.15, 0.45, 0.15]   # metres, world space
//! max = [0.40, 0.54, 0.40]
//! # intensity = [5, 5, 5]    # instead: a point light that the sidecar adds, named `node`,
//! #                          # at the box's centre, in W/sr (for scenes without a light)
//!
//! [camera]                   # where the camera may be during the walkthrough
//! min = [0.05, 0.05, -0.9]
//! max = [0.50, 0.50, 0.05]
//!
//! [views.front]              # named views for tests, benchmarks and figures
//! eye = [0.278, 0.273, -0.8]
//! target = [0.278, 0.273, 0.0]
//! fov_y = 39.3               # vertical field of view, degrees
//!
//! [bake.final]               # overrides of a bake preset (test, preview, final)
//! configurations = 400
//!
//! [eval]                     # defaults of `rrf eval` for this scene
//! spp = 2048                 # samples per pixel of its references
//!
//! [units]
//! point_lights = "W/sr"      # point-light intensity in W/sr instead of glTF's candela
//! ```

use std::collections::BTreeMap;
use std::path::Path;

use glam::Vec3;
use serde::Deserialize;

use super::error::SceneError;
use super::{MAX_COORDINATE, MAX_EMISSION};

#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Sidecar {
    pub light: Option<LightDomain>,
    pub camera: Option<CameraDomain>,
    #[serde(default)]
    pub views: BTreeMap<String, ViewSpec>,
    #[serde(default)]
    pub bake: BakePresets,
    #[serde(default)]
    pub eval: EvalDefaults,
    #[serde(default)]
    pub units: Units,
}

/// What `rrf eval` uses for this scene where its command line says nothing.
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EvalDefaults {
    /// Samples per pixel of the references, 1 to [`EvalDefaults::MAX_SPP`]: enough that two
    /// references disagree by well under the FLIP that is to be judged (`rrf eval` prints
    /// that floor), which depends on the scene.
    pub spp: Option<u32>,
}

impl EvalDefaults {
    /// The most samples per pixel a reference may take.
    pub const MAX_SPP: u32 = 1 << 20;
}

/// How to read the glTF's numbers where exporters differ.
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Units {
    /// `KHR_lights_punctual` point-light intensity: candela, as glTF says (the default), or
    /// W/sr for files written with rrf's radiometric units.
    #[serde(default)]
    pub point_lights: PointLightUnits,
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
pub enum PointLightUnits {
    #[default]
    #[serde(rename = "candela")]
    Candela,
    #[serde(rename = "W/sr")]
    WattsPerSteradian,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LightDomain {
    pub node: String,
    pub min: [f32; 3],
    pub max: [f32; 3],
    /// With it, the sidecar adds a point light of this radiant intensity (W/sr) named `node`
    /// at the box's centre, instead of naming one of the glTF.
    pub intensity: Option<[f32; 3]>,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraDomain {
    pub min: [f32; 3],
    pub max: [f32; 3],
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ViewSpec {
    pub eye: [f32; 3],
    pub target: [f32; 3],
    /// Vertical field of view in degrees.
    pub fov_y: f32,
}

#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BakePresets {
    pub test: Option<BakeOverrides>,
    pub preview: Option<BakeOverrides>,
    #[serde(rename = "final")]
    pub final_: Option<BakeOverrides>,
}

/// Settings of a bake preset that a scene may override; unset fields keep the preset's value.
/// Each must lie in its [`BakeOverrides::RANGES`] range.
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BakeOverrides {
    /// Latin-hypercube configurations (light position × viewpoint).
    pub configurations: Option<u32>,
    /// Rays cast over the sphere from each configuration's viewpoint; each hit is a sample.
    pub rays_per_configuration: Option<u32>,
    /// Paths traced per sample to estimate its direct and indirect radiance.
    pub paths_per_sample: Option<u32>,
    /// Longest path, in bounces.
    pub max_depth: Option<u32>,
    /// Levenberg–Marquardt iterations per network at most.
    pub max_iterations: Option<u32>,
    /// The deepest an object's kd-tree may grow (0: one network per object and component).
    pub split_depth: Option<u32>,
    /// The most samples one network trains on (a random subset of its leaf's).
    pub max_samples_per_network: Option<u32>,
}

/// An axis-aligned box in world space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub min: Vec3,
    pub max: Vec3,
}

impl BakeOverrides {
    /// The accepted range of each setting: at least 1, and at most what a bake can hold
    /// (the samples of a bake are about configurations × rays × 80 bytes).
    pub const RANGES: [(&'static str, u32, u32); 7] = [
        ("configurations", 1, 65_536),
        ("rays_per_configuration", 1, 1_000_000),
        ("paths_per_sample", 1, 65_536),
        ("max_depth", 1, 64),
        ("max_iterations", 1, 100_000),
        ("split_depth", 0, 8),
        ("max_samples_per_network", 1, 1_000_000),
    ];

    pub(super) fn values(&self) -> [Option<u32>; 7] {
        [
            self.configurations,
            self.rays_per_configuration,
            self.paths_per_sample,
            self.max_depth,
            self.max_iterations,
            self.split_depth,
            self.max_samples_per_network,
        ]
    }
}

impl Aabb {
    pub fn contains(&self, p: Vec3) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }

    /// The point at `t` in [0, 1]³ (0 is `min`, 1 is `max`).
    pub fn lerp(&self, t: Vec3) -> Vec3 {
        self.min + (self.max - self.min) * t
    }
}

impl Sidecar {
    /// Reads and parses the sidecar at `file`.
    pub fn read(file: &Path) -> Result<Self, SceneError> {
        let text = std::fs::read_to_string(file).map_err(|e| SceneError::new(file, "", format!("cannot read: {e}")))?;
        Sidecar::parse(file, &text)
    }

    pub fn parse(file: &Path, text: &str) -> Result<Self, SceneError> {
        let sidecar: Sidecar = toml::from_str(text).map_err(|e| {
            let element = match e.span() {
                Some(span) => format!("line {}", text[..span.start.min(text.len())].matches('\n').count() + 1),
                None => String::new(),
            };
            SceneError::new(file, element, e.message().trim().to_string())
        })?;
        sidecar.check(file)?;
        Ok(sidecar)
    }

    /// Checks what serde cannot: finite numbers, boxes with min ≤ max, sensible views.
    fn check(&self, file: &Path) -> Result<(), SceneError> {
        if let Some(light) = &self.light {
            check_box(file, "light", light.min, light.max)?;
            // A light of zero intensity is refused where the moving light is resolved, as a
            // glTF light of zero intensity is.
            if light.intensity.is_some_and(|i| !i.iter().all(|v| (0.0..=MAX_EMISSION).contains(v))) {
                return Err(SceneError::new(
                    file,
                    "light.intensity",
                    format!("must lie between 0 and {MAX_EMISSION:e} W/sr per channel"),
                ));
            }
        }
        if let Some(camera) = &self.camera {
            check_box(file, "camera", camera.min, camera.max)?;
        }
        for (name, view) in &self.views {
            let element = format!("views.{name}");
            if !view.eye.iter().chain(&view.target).all(|v| v.abs() <= MAX_COORDINATE) {
                return Err(SceneError::new(
                    file,
                    element,
                    format!("eye and target must be finite and within {MAX_COORDINATE:e} m from the origin"),
                ));
            }
            if Vec3::from(view.eye).distance(Vec3::from(view.target)) < 1e-6 {
                return Err(SceneError::new(file, element, "eye and target are the same point"));
            }
            if !(view.fov_y > 0.0 && view.fov_y < 180.0) {
                return Err(SceneError::new(file, element + ".fov_y", "must be between 0 and 180 degrees"));
            }
        }
        let presets = [("test", &self.bake.test), ("preview", &self.bake.preview), ("final", &self.bake.final_)];
        for (preset, overrides) in presets {
            let Some(overrides) = overrides else { continue };
            for ((key, min, max), value) in BakeOverrides::RANGES.iter().zip(overrides.values()) {
                if value.is_some_and(|v| !(*min..=*max).contains(&v)) {
                    return Err(SceneError::new(
                        file,
                        format!("bake.{preset}.{key}"),
                        format!("{} is outside the accepted range {min} to {max}", value.unwrap_or(0)),
                    ));
                }
            }
        }
        if self.eval.spp.is_some_and(|spp| !(1..=EvalDefaults::MAX_SPP).contains(&spp)) {
            return Err(SceneError::new(
                file,
                "eval.spp",
                format!("{} is outside the accepted range 1 to {}", self.eval.spp.unwrap_or(0), EvalDefaults::MAX_SPP),
            ));
        }
        Ok(())
    }
}

fn check_box(file: &Path, key: &str, min: [f32; 3], max: [f32; 3]) -> Result<(), SceneError> {
    if !min.iter().chain(&max).all(|v| v.abs() <= MAX_COORDINATE) {
        return Err(SceneError::new(
            file,
            key,
            format!("min and max must be finite and within {MAX_COORDINATE:e} m from the origin"),
        ));
    }
    for (axis, name) in ["x", "y", "z"].iter().enumerate() {
        if min[axis] > max[axis] {
            return Err(SceneError::new(
                file,
                key,
                format!("min > max on axis {name} ({} > {})", min[axis], max[axis]),
            ));
        }
    }
    Ok(())
}
