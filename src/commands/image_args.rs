//! Options shared by the commands that make an image (`render`, `reference`): which view,
//! where the lights are, how big, and which term of the radiance.

use anyhow::{bail, Context, Result};
use clap::{Args, ValueEnum};
use rrf_baker::glam::Vec3;
use rrf_baker::scene::{PlacedLight, Scene, View};
use rrf_baker::trace::{Footprint, Radiance};

use crate::parse::{parse_exposure, parse_size, parse_vec3};

#[derive(Args, Clone, Debug)]
pub struct ImageArgs {
    /// A named view from the scene (see `rrf info SCENE`); default: the glTF camera.
    #[arg(long, conflicts_with = "camera")]
    pub view: Option<String>,
    /// Camera as EYE:TARGET, each x,y,z in metres, e.g. 0.28,0.27,-0.8:0.28,0.27,0; the
    /// field of view is the default view's.
    #[arg(long, value_name = "EYE:TARGET", allow_hyphen_values = true)]
    pub camera: Option<String>,
    #[arg(long, help = crate::lights::LIGHT_HELP.as_str(), value_name = "POSITION[:color=R,G,B][:intensity=K]", allow_hyphen_values = true)]
    pub light: Vec<String>,
    /// Image size in pixels, each side 1 to 16384.
    #[arg(long, default_value = "256x256", value_name = "WxH")]
    pub size: String,
    /// Exposure in stops for PNG output (EXR is always linear), between -20 and 20.
    #[arg(long, default_value_t = 0.0, value_parser = parse_exposure, allow_hyphen_values = true)]
    pub exposure: f32,
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum RadianceTerm {
    /// Everything: emitted + direct + indirect.
    Gi,
    /// Light that reached the surface straight from a light source.
    Direct,
    /// Light that bounced at least once before reaching the surface.
    Indirect,
    /// The surface's own emission.
    Emitted,
}

impl RadianceTerm {
    pub fn pick(self, r: &Radiance) -> Vec3 {
        match self {
            RadianceTerm::Gi => r.gi(),
            RadianceTerm::Direct => r.direct,
            RadianceTerm::Indirect => r.indirect,
            RadianceTerm::Emitted => r.emitted,
        }
    }
}

/// Where in its pixel each path of a path-traced image starts (`--footprint`).
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum PixelFootprint {
    /// Anywhere in the pixel: an antialiased (box-filtered) image.
    Area,
    /// Through the pixel's centre, as the renderer's G-buffer samples it: the image to score the
    /// networks against pixel for pixel, free of the raster's aliasing at edges and in textures.
    Centre,
}

impl PixelFootprint {
    /// The flag's value, as reports and JSON name it.
    pub fn name(self) -> &'static str {
        match self {
            PixelFootprint::Area => "area",
            PixelFootprint::Centre => "centre",
        }
    }
}

impl From<PixelFootprint> for Footprint {
    fn from(f: PixelFootprint) -> Footprint {
        match f {
            PixelFootprint::Area => Footprint::Area,
            PixelFootprint::Centre => Footprint::Centre,
        }
    }
}

/// The scene's view called `name`, or its default view (the glTF camera) for `None`.
pub fn named_view(scene: &Scene, name: Option<&str>) -> Result<View> {
    let Some(name) = name else {
        return Ok(scene.views[0].clone());
    };
    scene.view(name).cloned().with_context(|| {
        let names = scene.views.iter().map(|v| v.name.as_str()).collect::<Vec<_>>().join(", ");
        format!("--view {name:?}: no such view in {} (views: {names})", scene.name)
    })
}

impl ImageArgs {
    pub fn size(&self) -> Result<(u32, u32)> {
        parse_size(&self.size)
    }

    /// The view to render: `--view`, `--camera`, or the scene's default.
    pub fn resolve_view(&self, scene: &Scene) -> Result<View> {
        let (Some(text), None) = (&self.camera, &self.view) else {
            return named_view(scene, self.view.as_deref());
        };
        // A free camera keeps the default view's field of view.
        let default = named_view(scene, None)?;
        let (eye, target) = text.split_once(':').with_context(|| format!("--camera {text:?}: expected EYE:TARGET"))?;
        let eye = parse_vec3(eye, "--camera eye")?;
        let target = parse_vec3(target, "--camera target")?;
        if eye.distance(target) < 1e-6 {
            bail!("--camera {text:?}: eye and target are the same point");
        }
        Ok(View { name: "camera".into(), eye, target, up: Vec3::Y, fov_y: default.fov_y })
    }

    /// The lights: `--light`s, or the glTF's light.
    pub fn lights(&self, scene: &Scene) -> Result<Vec<PlacedLight>> {
        crate::lights::lights_from_args(scene, &self.light)
    }
}
