//! HDR-FLIP (Andersson, Nilsson, Shirley and Akenine-Möller, "Visualizing Errors in Rendered
//! High Dynamic Range Images", Eurographics 2021), the metric that published neural GI figures
//! use. LDR-FLIP compares two images as one display shows them; HDR-FLIP compares linear
//! radiance at a range of exposures and keeps each pixel's worst error:
//!
//! 1. The exposures run from one that maps the reference's brightest luminance to 0.85 after
//!    tonemapping, to one that maps its median luminance there, in `max(2, ⌈stop − start⌉)`
//!    even steps.
//! 2. At each, both images are scaled by 2^exposure, tonemapped with FLIP's ACES fit and
//!    clamped to [0, 1], then compared by LDR-FLIP.
//! 3. The error map is the per-pixel maximum over exposures; its mean is the score.
//!
//! The `nv-flip` crate offers only LDR-FLIP, so this builds HDR-FLIP on it. Its one departure
//! from NVIDIA's reference implementation is that each tonemapped image reaches LDR-FLIP as
//! 8-bit sRGB; `tests/hdr_flip.rs` checks the exposures and the score against that
//! implementation (the `flip-evaluator` package).

use rrf_baker::glam::Vec3;
use rrf_renderer::passes::tonemap::{aces_fitted, linear_to_srgb};

/// FLIP's tonemapper is the renderer's ACES fit after an exposure of 0.6.
const PRE_EXPOSURE: f32 = 0.6;

/// The tonemapped value that the start and stop exposures give the brightest and the median
/// luminance.
const TARGET: f32 = 0.85;

fn aces(x: f32) -> f32 {
    aces_fitted(PRE_EXPOSURE * x)
}

/// The input that [`aces`] maps to `t`. With `aces_fitted(y) = y (2.51 y + 0.03) / (y (2.43 y
/// + 0.59) + 0.14)`, `y` is the positive root of `(2.51 − 2.43t) y² + (0.03 − 0.59t) y − 0.14t`.
fn aces_inverse(t: f32) -> f32 {
    let (a, b, c) = (2.51 - 2.43 * t, 0.03 - 0.59 * t, -0.14 * t);
    (-b + (b * b - 4.0 * a * c).sqrt()) / (2.0 * a) / PRE_EXPOSURE
}

fn luminance(p: Vec3) -> f32 {
    0.2126 * p.x + 0.7152 * p.y + 0.0722 * p.z
}

/// The exposures (in stops) at which HDR-FLIP compares two images, from `reference`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Exposures {
    pub start: f32,
    pub stop: f32,
    pub count: u32,
}

impl Exposures {
    /// As FLIP computes them: luminances below `f32::EPSILON` count as `f32::EPSILON`, and the
    /// median is the element at index n/2 of the sorted luminances.
    pub fn of(reference: &[Vec3]) -> Exposures {
        let mut y: Vec<f32> = reference.iter().map(|&p| luminance(p).max(f32::EPSILON)).collect();
        if y.is_empty() {
            y.push(f32::EPSILON);
        }
        let middle = y.len() / 2;
        let median = *y.select_nth_unstable_by(middle, f32::total_cmp).1;
        let max = y.iter().copied().fold(f32::EPSILON, f32::max);
        let x = aces_inverse(TARGET);
        let (start, stop) = ((x / max).log2(), (x / median).log2());
        Exposures { start, stop, count: ((stop - start).ceil() as u32).max(2) }
    }

    fn each(self) -> impl Iterator<Item = f32> {
        let step = (self.stop - self.start) / (self.count - 1) as f32;
        (0..self.count).map(move |i| self.start + step * i as f32)
    }
}

/// `pixels` scaled by 2^`exposure`, tonemapped and clamped, as 8-bit sRGB.
fn exposed_srgb8(pixels: &[Vec3], exposure: f32) -> Vec<u8> {
    let scale = exposure.exp2();
    let encode = |c: f32| (linear_to_srgb(aces(c.max(0.0) * scale)) * 255.0 + 0.5) as u8;
    pixels.iter().flat_map(|p| p.to_array().map(encode)).collect()
}

/// The mean HDR-FLIP error of `test` against `reference` (linear RGB, rows top to bottom).
pub fn hdr_flip(test: &[Vec3], reference: &[Vec3], width: u32, height: u32) -> f64 {
    assert_eq!(test.len(), reference.len());
    let mut worst = vec![0.0f32; test.len()];
    for exposure in Exposures::of(reference).each() {
        let error = nv_flip::flip(
            nv_flip::FlipImageRgb8::with_data(width, height, &exposed_srgb8(reference, exposure)),
            nv_flip::FlipImageRgb8::with_data(width, height, &exposed_srgb8(test, exposure)),
            nv_flip::DEFAULT_PIXELS_PER_DEGREE,
        );
        worst.iter_mut().zip(error.to_vec()).for_each(|(w, e)| *w = w.max(e));
    }
    worst.iter().map(|&e| f64::from(e)).sum::<f64>() / worst.len().max(1) as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn aces_inverse_inverts_aces() {
        for t in [0.1, 0.5, TARGET, 0.99] {
            assert!((aces(aces_inverse(t)) - t).abs() < 1e-5, "{t}");
        }
    }

    #[test]
    fn exposures_span_the_brightest_to_the_median_luminance() {
        // Luminance 1 everywhere but one pixel of 20: log2(20) = 4.32 stops apart.
        let mut image = vec![Vec3::ONE; 9];
        image[4] = Vec3::splat(20.0);
        let e = Exposures::of(&image);
        assert!((e.stop - e.start - 20f32.log2()).abs() < 1e-4, "{e:?}");
        assert_eq!(e.count, 5);
        assert!((aces(e.start.exp2() * 20.0) - TARGET).abs() < 1e-5);
        assert!((aces(e.stop.exp2()) - TARGET).abs() < 1e-5);
    }

    #[test]
    fn identical_images_have_no_error_and_darker_ones_do() {
        let truth: Vec<Vec3> =
            (0..1024).map(|i| Vec3::new((i % 32) as f32 / 8.0, 0.3, (i / 32) as f32 / 4.0)).collect();
        assert_eq!(hdr_flip(&truth, &truth, 32, 32), 0.0);
        let dark: Vec<Vec3> = truth.iter().map(|p| *p * 0.5).collect();
        let darker: Vec<Vec3> = truth.iter().map(|p| *p * 0.25).collect();
        let (a, b) = (hdr_flip(&dark, &truth, 32, 32), hdr_flip(&darker, &truth, 32, 32));
        assert!(0.0 < a && a < b && b <= 1.0, "{a} {b}");
    }
}
