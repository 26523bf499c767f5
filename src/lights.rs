//! Several lights: the `--light` syntax, and what a scene allows.
//!
//! Every light is a copy of the scene's moving light (see [`PlacedLight`]): the networks learned
//! one light, and transport is linear in its emission, so a frame sums the networks once per
//! copy, each scaled by the copy's colour × intensity.

use std::sync::LazyLock;

use anyhow::{bail, Context, Result};
use rrf_baker::glam::Vec3;
use rrf_baker::scene::{PlacedLight, Scene};
pub use rrf_renderer::lights::MAX_LIGHTS;

use crate::parse::parse_vec3;

/// The brightest a light may be made, relative to the glTF's: the G-buffer keeps the scaled
/// emission of the light's own geometry as half floats.
pub const MAX_INTENSITY: f32 = 1000.0;

/// `--help` text of `--light`, shared by the commands that take it.
pub static LIGHT_HELP: LazyLock<String> = LazyLock::new(|| {
    format!(
        "A light: a copy of the scene's moving light. POSITION is x,y,z in metres, or `default` for where the glTF \
         puts it; then optionally `:color=R,G,B` (each 0 to 1) and `:intensity=K` (0 to {MAX_INTENSITY}, relative to \
         the glTF's), e.g. `0.2,0.5,0.3:color=1,0.6,0.3:intensity=2`. Repeat for several lights (at most \
         {MAX_LIGHTS}); the networks are summed over them. Default: one light where the glTF puts it."
    )
});

/// One `--light` value: `POSITION[:color=R,G,B][:intensity=K]`, with POSITION `x,y,z` or
/// `default` (`default_position`).
pub fn parse_light(text: &str, default_position: Vec3) -> Result<PlacedLight> {
    let mut parts = text.split(':');
    let position = parts.next().unwrap_or_default().trim();
    let position = if position == "default" {
        default_position
    } else {
        parse_vec3(position, &format!("--light {text:?}: position"))?
    };
    let (mut color, mut intensity) = (Vec3::ONE, 1.0f32);
    for part in parts {
        let (key, value) = part
            .split_once('=')
            .with_context(|| format!("--light {text:?}: {part:?} is not color=R,G,B or intensity=K"))?;
        match key.trim() {
            "color" | "colour" => {
                color = parse_vec3(value, &format!("--light {text:?}: color"))?;
                if color.min_element() < 0.0 || color.max_element() > 1.0 {
                    bail!("--light {text:?}: each color channel is between 0 and 1 (use intensity to brighten)");
                }
            }
            "intensity" => {
                intensity =
                    value.trim().parse().ok().filter(|k: &f32| (0.0..=MAX_INTENSITY).contains(k)).with_context(
                        || format!("--light {text:?}: intensity {value:?} is not between 0 and {MAX_INTENSITY}"),
                    )?;
            }
            other => bail!("--light {text:?}: unknown setting {other:?}; expected color or intensity"),
        }
    }
    Ok(PlacedLight { position, scale: color * intensity })
}

/// The lights of `texts` (`--light` values) for `scene`, checked by [`check_lights`]; the
/// glTF's light for none.
pub fn lights_from_args(scene: &Scene, texts: &[String]) -> Result<Vec<PlacedLight>> {
    if texts.is_empty() {
        return Ok(vec![scene.default_light()]);
    }
    if scene.moving_light.is_none() {
        bail!("--light: scene {} has no moving light (no [light] in its sidecar)", scene.name);
    }
    let default = scene.default_light().position;
    let lights = texts.iter().map(|t| parse_light(t, default)).collect::<Result<Vec<_>>>()?;
    check_lights(scene, &lights)?;
    for (text, light) in texts.iter().zip(&lights) {
        if let Some(warning) = outside_box(scene, light) {
            eprintln!("warning: --light {text}: {warning}");
        }
    }
    Ok(lights)
}

/// Whether `scene` can be lit by `lights`: 1 to [`MAX_LIGHTS`] of them, and other than one
/// light as bright as the glTF's only where the moving light is the scene's only light.
pub fn check_lights(scene: &Scene, lights: &[PlacedLight]) -> Result<()> {
    if lights.is_empty() || lights.len() > MAX_LIGHTS {
        bail!("{} lights; rrf renders 1 to {MAX_LIGHTS}", lights.len());
    }
    let trained = lights.len() == 1 && lights[0].scale == Vec3::ONE;
    let others = scene.static_lights();
    if !trained && !others.is_empty() {
        bail!(
            "scene {} is also lit by {}, whose light the networks learned together with the moving light's: \
             several lights, colours and intensities need the moving light to be the scene's only light",
            scene.name,
            others.join(", ")
        );
    }
    Ok(())
}

/// Why `scene`'s light cannot be copied, recoloured or dimmed, if it cannot, in a few words
/// (for the viewer's overlay): it has no moving light, or other lights besides it.
pub fn fixed_lights(scene: &Scene) -> Option<String> {
    if scene.moving_light.is_none() {
        return Some(format!("{} has no moving light", scene.name));
    }
    let others = scene.static_lights();
    (!others.is_empty()).then(|| format!("{} also has {}, learned with it", scene.name, others.join(", ")))
}

/// Why `light` is not where the networks were trained, if it is not: outside the light's box.
pub fn outside_box(scene: &Scene, light: &PlacedLight) -> Option<String> {
    let bounds = scene.moving_light.as_ref()?.bounds;
    (!bounds.contains(light.position)).then(|| {
        format!(
            "{} is outside the light's box {:?} .. {:?}; the networks were not trained there",
            fmt_vec3(light.position),
            bounds.min.to_array(),
            bounds.max.to_array()
        )
    })
}

fn fmt_vec3(v: Vec3) -> String {
    format!("{},{},{}", v.x, v.y, v.z)
}

/// `count` lights spread through the moving light's box (its centre first, then points of
/// a 3-D Halton sequence), together as bright as the glTF's one: what `rrf bench --lights`
/// times.
pub fn spread_lights(scene: &Scene, count: usize) -> Result<Vec<PlacedLight>> {
    if count == 1 {
        return Ok(vec![scene.default_light()]);
    }
    let Some(light) = &scene.moving_light else {
        bail!("--lights {count}: scene {} has no moving light to copy", scene.name);
    };
    let scale = Vec3::splat(1.0 / count as f32);
    let lights: Vec<PlacedLight> = (0..count)
        .map(|k| {
            let u = if k == 0 { Vec3::splat(0.5) } else { Vec3::new(halton(k, 2), halton(k, 3), halton(k, 5)) };
            PlacedLight { position: light.bounds.lerp(u), scale }
        })
        .collect();
    check_lights(scene, &lights)?;
    Ok(lights)
}

/// Element `index` of the van der Corput sequence in `base`.
fn halton(mut index: usize, base: usize) -> f32 {
    let (mut result, mut f) = (0.0, 1.0);
    while index > 0 {
        f /= base as f32;
        result += f * (index % base) as f32;
        index /= base;
    }
    result
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_position_colour_and_intensity() {
        let d = Vec3::new(1.0, 2.0, 3.0);
        let l = parse_light("0.5,-1,2:color=1,0.5,0:intensity=2", d).unwrap();
        assert_eq!(l, PlacedLight { position: Vec3::new(0.5, -1.0, 2.0), scale: Vec3::new(2.0, 1.0, 0.0) });
        assert_eq!(parse_light("default", d).unwrap(), PlacedLight { position: d, scale: Vec3::ONE });
        let dim = parse_light("default:intensity=0.25", d).unwrap();
        assert_eq!(dim.scale, Vec3::splat(0.25));
        for (bad, says) in [
            ("1,2", "x,y,z"),
            ("1,2,3:color=2,0,0", "between 0 and 1"),
            ("1,2,3:intensity=-1", "intensity"),
            ("1,2,3:intensity=1e9", "intensity"),
            ("1,2,3:brightness=2", "unknown setting"),
            ("1,2,3:color", "color=R,G,B"),
        ] {
            let error = format!("{:#}", parse_light(bad, d).unwrap_err());
            assert!(error.contains(says), "{bad}: {error}");
        }
    }

    #[test]
    fn halton_points_are_spread_in_the_unit_cube() {
        let points: Vec<f32> = (1..9).map(|k| halton(k, 2)).collect();
        assert_eq!(points, [0.5, 0.25, 0.75, 0.125, 0.625, 0.375, 0.875, 0.0625]);
    }
}
