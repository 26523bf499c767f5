//! Image metrics of a prediction against its reference: relMSE and HDR-FLIP on linear
//! radiance, and PSNR and FLIP on the tonemapped 8-bit images a person would look at.

use rrf_baker::glam::Vec3;
use serde::Serialize;

use super::hdr_flip::hdr_flip;
use crate::image_out::tonemap_rgb8;

#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct Metrics {
    /// mean((x − y)² / (y² + 0.01)) over pixels and channels, on linear radiance.
    pub relmse: f64,
    /// Of the tonemapped sRGB images, in dB; capped at 100 for identical images.
    pub psnr: f64,
    /// Mean FLIP error (NVIDIA's LDR-FLIP, 67 pixels per degree) of the tonemapped images.
    pub flip: f64,
    /// Mean HDR-FLIP error of the linear images ([`hdr_flip`]), the published methods' metric.
    pub hdr_flip: f64,
}

impl Metrics {
    /// The mean of each metric over `all`.
    pub fn mean<'a>(all: impl Iterator<Item = &'a Metrics>) -> Metrics {
        let (mut sum, mut n) = (Metrics::default(), 0.0);
        for m in all {
            sum.relmse += m.relmse;
            sum.psnr += m.psnr;
            sum.flip += m.flip;
            sum.hdr_flip += m.hdr_flip;
            n += 1.0;
        }
        if n > 0.0 {
            sum.relmse /= n;
            sum.psnr /= n;
            sum.flip /= n;
            sum.hdr_flip /= n;
        }
        sum
    }
}

/// The metrics of two trivial predictions of a reference: all black, and every pixel the
/// reference's mean colour. A model's numbers mean something only well below these.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct Baselines {
    pub black: Metrics,
    pub mean_colour: Metrics,
}

impl Baselines {
    pub fn of(reference: &[Vec3], width: u32, height: u32) -> Baselines {
        let mean = reference.iter().copied().sum::<Vec3>() / reference.len().max(1) as f32;
        Baselines {
            black: compare(&vec![Vec3::ZERO; reference.len()], reference, width, height).metrics,
            mean_colour: compare(&vec![mean; reference.len()], reference, width, height).metrics,
        }
    }

    /// The mean of each baseline over `all`.
    pub fn mean<'a>(all: impl Iterator<Item = &'a Baselines> + Clone) -> Baselines {
        Baselines {
            black: Metrics::mean(all.clone().map(|b| &b.black)),
            mean_colour: Metrics::mean(all.map(|b| &b.mean_colour)),
        }
    }
}

/// A comparison: the metrics and FLIP's per-pixel error map (0 to 1, rows top to bottom).
pub struct Comparison {
    pub metrics: Metrics,
    pub flip_map: Vec<f32>,
}

pub fn compare(predicted: &[Vec3], reference: &[Vec3], width: u32, height: u32) -> Comparison {
    assert_eq!(predicted.len(), reference.len());
    let relmse = predicted
        .iter()
        .zip(reference)
        .flat_map(|(x, y)| (0..3).map(move |c| (f64::from(x[c]), f64::from(y[c]))))
        .map(|(x, y)| (x - y).powi(2) / (y * y + 0.01))
        .sum::<f64>()
        / (3 * predicted.len().max(1)) as f64;

    let (test, truth) = (tonemap_rgb8(predicted, 0.0), tonemap_rgb8(reference, 0.0));
    let mse = test.iter().zip(&truth).map(|(&a, &b)| ((f64::from(a) - f64::from(b)) / 255.0).powi(2)).sum::<f64>()
        / test.len().max(1) as f64;
    let psnr = if mse > 0.0 { (10.0 * (1.0 / mse).log10()).min(100.0) } else { 100.0 };

    let error = nv_flip::flip(
        nv_flip::FlipImageRgb8::with_data(width, height, &truth),
        nv_flip::FlipImageRgb8::with_data(width, height, &test),
        nv_flip::DEFAULT_PIXELS_PER_DEGREE,
    );
    let flip = f64::from(nv_flip::FlipPool::from_image(&error).mean());
    let hdr_flip = hdr_flip(predicted, reference, width, height);
    Comparison { metrics: Metrics { relmse, psnr, flip, hdr_flip }, flip_map: error.to_vec() }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identical_images_score_perfectly() {
        let image: Vec<Vec3> = (0..64).map(|i| Vec3::splat(i as f32 / 64.0)).collect();
        let m = compare(&image, &image, 8, 8).metrics;
        assert_eq!((m.relmse, m.psnr, m.flip, m.hdr_flip), (0.0, 100.0, 0.0, 0.0));
    }

    #[test]
    fn relmse_follows_its_definition() {
        // x = 0.2 against y = 0.1 in every channel: 0.01 / (0.01 + 0.01) = 0.5.
        let m = compare(&[Vec3::splat(0.2); 4], &[Vec3::splat(0.1); 4], 2, 2).metrics;
        assert!((m.relmse - 0.5).abs() < 1e-6, "{}", m.relmse);
    }

    /// An 8×8 checkerboard of 2×2 black and white squares against a copy whose right half
    /// keeps only the red of the white squares. The radiance saturates the display (sRGB 1.0),
    /// so the 8-bit images are known exactly: 16 pixels differ by 255 in two channels of three,
    /// MSE 32 / 192 = 1/6, PSNR 10 log10(6) dB; relMSE the same share, each such channel
    /// (1e4)² / ((1e4)² + 0.01). FLIP: NVIDIA's implementation (`flip-evaluator` 1.7 from PyPI,
    /// `evaluate(reference, test, "LDR")` on the same images as sRGB in [0, 1], 67.02 pixels
    /// per degree) gives 0.6237234.
    #[test]
    fn a_checkerboard_scores_what_the_definitions_say() {
        let white = Vec3::splat(1e4);
        let reference: Vec<Vec3> =
            (0..64).map(|i| if (i % 8 / 2 + i / 8 / 2) % 2 == 0 { white } else { Vec3::ZERO }).collect();
        let predicted: Vec<Vec3> =
            reference.iter().enumerate().map(|(i, &v)| if i % 8 < 4 { v } else { v * Vec3::X }).collect();
        let m = compare(&predicted, &reference, 8, 8).metrics;
        assert!((m.psnr - 10.0 * 6f64.log10()).abs() < 1e-9, "PSNR {}", m.psnr);
        assert!((m.relmse - 1.0 / 6.0).abs() < 1e-6, "relMSE {}", m.relmse);
        assert!((m.flip - 0.6237234).abs() < 1e-4, "FLIP {}", m.flip);
    }

    #[test]
    fn a_worse_prediction_scores_worse() {
        let truth: Vec<Vec3> =
            (0..256).map(|i| Vec3::new((i % 16) as f32 / 16.0, 0.3, (i / 16) as f32 / 16.0)).collect();
        let near: Vec<Vec3> = truth.iter().map(|v| *v * 1.02).collect();
        let far: Vec<Vec3> = truth.iter().map(|v| *v * 1.5).collect();
        let (a, b) = (compare(&near, &truth, 16, 16).metrics, compare(&far, &truth, 16, 16).metrics);
        assert!(a.relmse < b.relmse && a.psnr > b.psnr && a.flip < b.flip && a.hdr_flip < b.hdr_flip, "{a:?} {b:?}");
    }
}
