//! Parsers of the values that the command line and the viewer's scripts share: sizes,
//! exposures and points.

use anyhow::{bail, Context, Result};
use rrf_baker::glam::Vec3;

/// The most exposure, in stops either way, that rrf accepts.
pub const MAX_EXPOSURE: f32 = 20.0;

/// Stops of exposure: a finite number within ±[`MAX_EXPOSURE`].
pub fn parse_exposure(text: &str) -> Result<f32, String> {
    match text.trim().parse::<f32>() {
        Ok(v) if v.is_finite() && v.abs() <= MAX_EXPOSURE => Ok(v),
        _ => Err(format!("{text:?} is not a number of stops between -{MAX_EXPOSURE} and {MAX_EXPOSURE}")),
    }
}

/// `WxH`, each between 1 and 16384.
pub fn parse_size(text: &str) -> Result<(u32, u32)> {
    let parse = || -> Option<(u32, u32)> {
        let (w, h) = text.split_once(['x', 'X'])?;
        Some((w.trim().parse().ok()?, h.trim().parse().ok()?))
    };
    match parse() {
        Some((w, h)) if (1..=16384).contains(&w) && (1..=16384).contains(&h) => Ok((w, h)),
        _ => bail!("--size {text:?}: expected WxH with each between 1 and 16384, e.g. 512x512"),
    }
}

/// `x,y,z`, three finite numbers; `what` names the value in the error.
pub fn parse_vec3(text: &str, what: &str) -> Result<Vec3> {
    let parts: Vec<&str> = text.split(',').collect();
    if parts.len() != 3 {
        bail!("{what} {text:?}: expected x,y,z");
    }
    let mut v = [0.0f32; 3];
    for (slot, part) in v.iter_mut().zip(&parts) {
        *slot = part.trim().parse().with_context(|| format!("{what} {text:?}: {part:?} is not a number"))?;
        if !slot.is_finite() {
            bail!("{what} {text:?}: {part:?} is not finite");
        }
    }
    Ok(Vec3::from(v))
}
