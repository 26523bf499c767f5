//! The BSDF's sampling routine against its own `pdf` (a chi-square goodness-of-fit test, as
//! Mitsuba and PBRT do), `eval`, `pdf` and `sample` against each other, and energy
//! conservation. Deterministic seeds: a failure is a real failure, not bad luck.

use std::f32::consts::{PI, TAU};

use rrf_baker::glam::{Vec2, Vec3};
use rrf_baker::trace::bsdf::Bsdf;
use rrf_baker::trace::sampling::Rng;

/// Materials that cover every lobe combination: pure Lambert, glTF dielectric (Lambert plus
/// a Fresnel-weighted GGX lobe) and metal at several roughness values.
fn materials() -> Vec<(&'static str, Bsdf)> {
    vec![
        ("lambert", Bsdf::new(Vec3::splat(0.8), 0.0, 1.0, 0.0)),
        ("dielectric r=0.5", Bsdf::new(Vec3::new(0.6, 0.4, 0.2), 0.0, 0.5, 1.0)),
        ("dielectric r=0.3", Bsdf::new(Vec3::splat(0.5), 0.0, 0.3, 1.0)),
        ("metal r=0.3", Bsdf::new(Vec3::new(0.95, 0.8, 0.5), 1.0, 0.3, 1.0)),
        ("metal r=0.6", Bsdf::new(Vec3::splat(0.9), 1.0, 0.6, 1.0)),
        ("metal r=1.0", Bsdf::new(Vec3::splat(0.9), 1.0, 1.0, 1.0)),
        ("half metal r=0.45", Bsdf::new(Vec3::new(0.3, 0.7, 0.5), 0.5, 0.45, 1.0)),
    ]
}

/// Directions of incidence from the normal: 0°, 45° and 75°.
fn incident() -> Vec<Vec3> {
    [0.0f32, 45.0, 75.0]
        .iter()
        .map(|deg| {
            let t = deg.to_radians();
            Vec3::new(t.sin(), 0.0, t.cos())
        })
        .collect()
}

const COS_BINS: usize = 24;
const PHI_BINS: usize = 48;
const SUBDIVISIONS: usize = 16;
/// Near the normal a glossy lobe fills a sliver of the top cos θ bins: integrate those finely.
const FINE_COS_SUBDIVISIONS: usize = 512;
const FINE_COS_BINS: usize = 3;

fn bin_of(w: Vec3) -> usize {
    let c = ((w.z * COS_BINS as f32) as usize).min(COS_BINS - 1);
    let phi = w.y.atan2(w.x).rem_euclid(TAU);
    let p = ((phi / TAU * PHI_BINS as f32) as usize).min(PHI_BINS - 1);
    c * PHI_BINS + p
}

fn direction(cos_theta: f32, phi: f32) -> Vec3 {
    let sin = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    Vec3::new(sin * phi.cos(), sin * phi.sin(), cos_theta)
}

/// The probability of each (cos θ, φ) bin under `pdf`, integrated on a fine grid per bin.
fn expected_probabilities(bsdf: &Bsdf, wo: Vec3) -> Vec<f64> {
    let (dc, dp) = (1.0 / COS_BINS as f64, TAU as f64 / PHI_BINS as f64);
    let mut out = vec![0.0; COS_BINS * PHI_BINS];
    for c in 0..COS_BINS {
        let nc = if c >= COS_BINS - FINE_COS_BINS { FINE_COS_SUBDIVISIONS } else { SUBDIVISIONS };
        for p in 0..PHI_BINS {
            let mut sum = 0.0f64;
            for i in 0..nc {
                for j in 0..SUBDIVISIONS {
                    let cos = (c as f64 + (i as f64 + 0.5) / nc as f64) * dc;
                    let phi = (p as f64 + (j as f64 + 0.5) / SUBDIVISIONS as f64) * dp;
                    sum += f64::from(bsdf.pdf(wo, direction(cos as f32, phi as f32)));
                }
            }
            out[c * PHI_BINS + p] = sum * dc * dp / (nc * SUBDIVISIONS) as f64;
        }
    }
    out
}

/// Upper tail of the chi-square distribution, by the Wilson–Hilferty normal approximation
/// (accurate to a few per cent at the hundreds of degrees of freedom used here).
fn chi_square_p_value(statistic: f64, dof: f64) -> f64 {
    let z = ((statistic / dof).cbrt() - (1.0 - 2.0 / (9.0 * dof))) / (2.0 / (9.0 * dof)).sqrt();
    0.5 * erfc(z / std::f64::consts::SQRT_2)
}

/// Complementary error function (Numerical Recipes' erfcc, relative error < 1.2e-7).
fn erfc(x: f64) -> f64 {
    let z = x.abs();
    let t = 1.0 / (1.0 + 0.5 * z);
    let poly = -z * z - 1.265_512_23
        + t * (1.000_023_68
            + t * (0.374_091_96
                + t * (0.096_784_18
                    + t * (-0.186_288_06
                        + t * (0.278_868_07
                            + t * (-1.135_203_98 + t * (1.488_515_87 + t * (-0.822_152_23 + t * 0.170_872_77))))))));
    let r = t * poly.exp();
    if x >= 0.0 {
        r
    } else {
        2.0 - r
    }
}

/// Chi-square p-value of `sampler`'s samples against `reference`'s pdf.
fn chi_square(sampler: &Bsdf, reference: &Bsdf, wo: Vec3, seed: u64) -> (f64, f64, usize) {
    const SAMPLES: usize = 1_000_000;
    let mut observed = vec![0.0f64; COS_BINS * PHI_BINS];
    let mut rng = Rng::new(7, seed);
    for _ in 0..SAMPLES {
        if let Some(s) = sampler.sample(wo, rng.next_f32(), rng.next_vec2()) {
            observed[bin_of(s.wi)] += 1.0;
        }
    }
    let expected: Vec<f64> = expected_probabilities(reference, wo).iter().map(|p| p * SAMPLES as f64).collect();
    // Directions the sampler loses (below the horizon) form one more bin.
    let lost_expected = (SAMPLES as f64 - expected.iter().sum::<f64>()).max(0.0);
    let lost_observed = SAMPLES as f64 - observed.iter().sum::<f64>();
    let (mut statistic, mut dof) = (0.0, 0usize);
    let (mut pooled_o, mut pooled_e) = (lost_observed, lost_expected);
    for (o, e) in observed.iter().zip(&expected) {
        if *e < 5.0 {
            pooled_o += o;
            pooled_e += e;
        } else {
            statistic += (o - e) * (o - e) / e;
            dof += 1;
        }
    }
    if pooled_e >= 5.0 {
        statistic += (pooled_o - pooled_e) * (pooled_o - pooled_e) / pooled_e;
        dof += 1;
    } else if pooled_o >= 20.0 {
        return (0.0, statistic, dof); // many samples where the pdf says there are none
    }
    (chi_square_p_value(statistic, (dof - 1) as f64), statistic, dof - 1)
}

#[test]
fn sampling_matches_pdf_chi_square() {
    let cases: Vec<_> = materials().into_iter().flat_map(|m| incident().into_iter().map(move |wo| (m, wo))).collect();
    // Bonferroni: 1% overall across all cases.
    let significance = 0.01 / cases.len() as f64;
    let mut failures = Vec::new();
    for (case, ((name, bsdf), wo)) in cases.iter().enumerate() {
        let (p, statistic, dof) = chi_square(bsdf, bsdf, *wo, case as u64);
        let theta = wo.z.acos().to_degrees();
        eprintln!("{name:<18} θo={theta:>4.1}°  χ²={statistic:>8.1}  dof={dof:>4}  p={p:.3}");
        if p < significance {
            failures.push(format!("{name} at θo={theta:.0}°: p = {p:.2e}"));
        }
    }
    assert!(failures.is_empty(), "sampling does not follow pdf: {failures:?}");
}

/// The test has teeth: sampling one roughness against the pdf of a 10% rougher lobe fails.
#[test]
fn chi_square_rejects_a_slightly_wrong_pdf() {
    let sampler = Bsdf::new(Vec3::splat(0.9), 1.0, 0.6, 1.0);
    let wrong = Bsdf::new(Vec3::splat(0.9), 1.0, 0.66, 1.0);
    let (p, _, _) = chi_square(&sampler, &wrong, incident()[1], 99);
    assert!(p < 1e-6, "p = {p}");
}

#[test]
fn eval_pdf_and_sample_agree() {
    for (name, bsdf) in materials() {
        for wo in incident() {
            let mut rng = Rng::new(11, 0);
            for _ in 0..20_000 {
                let Some(s) = bsdf.sample(wo, rng.next_f32(), rng.next_vec2()) else { continue };
                let pdf = bsdf.pdf(wo, s.wi);
                assert!((s.pdf - pdf).abs() <= 1e-4 * pdf, "{name}: sample pdf {} vs pdf() {pdf}", s.pdf);
                let weight = bsdf.eval(wo, s.wi) * s.wi.z / pdf;
                assert!((s.weight - weight).abs().max_element() <= 1e-4 * weight.max_element().max(1e-3), "{name}");
                assert!(s.wi.z > 0.0 && (s.wi.length() - 1.0).abs() < 1e-4, "{name}: wi = {}", s.wi);
            }
            // Reciprocity of eval.
            for _ in 0..1000 {
                let wi = direction(rng.next_f32(), TAU * rng.next_f32());
                let (a, b) = (bsdf.eval(wo, wi), bsdf.eval(wi, wo));
                assert!((a - b).abs().max_element() <= 1e-4 * a.max_element().max(1e-3), "{name}: {a} vs {b}");
            }
        }
    }
}

/// Directional albedo ∫ f cos dω by importance sampling and, independently, by uniform
/// hemisphere sampling: the two must agree, and neither may exceed 1.
#[test]
fn albedo_is_at_most_one_and_both_estimators_agree() {
    const N: usize = 400_000;
    for (name, bsdf) in materials() {
        for wo in incident() {
            let mut rng = Rng::new(13, 1);
            let (mut is_sum, mut is_sq) = (Vec3::ZERO, Vec3::ZERO);
            let (mut u_sum, mut u_sq) = (Vec3::ZERO, Vec3::ZERO);
            for _ in 0..N {
                let w = bsdf.sample(wo, rng.next_f32(), rng.next_vec2()).map_or(Vec3::ZERO, |s| s.weight);
                is_sum += w;
                is_sq += w * w;
                let u: Vec2 = rng.next_vec2();
                let wi = direction(u.x, TAU * u.y);
                let v = bsdf.eval(wo, wi) * wi.z * (2.0 * PI);
                u_sum += v;
                u_sq += v * v;
            }
            let n = N as f32;
            let (is_mean, u_mean) = (is_sum / n, u_sum / n);
            let is_err = ((is_sq / n - is_mean * is_mean) / n).max(Vec3::ZERO).sqrt();
            let u_err = ((u_sq / n - u_mean * u_mean) / n).max(Vec3::ZERO).sqrt();
            let tolerance = 4.0 * (is_err * is_err + u_err * u_err).sqrt() + Vec3::splat(1e-3);
            assert!(
                (is_mean - u_mean).abs().cmple(tolerance).all(),
                "{name}, θo={:.0}°: importance {is_mean} vs uniform {u_mean}",
                wo.z.acos().to_degrees()
            );
            assert!(
                is_mean.cmple(Vec3::ONE + 4.0 * is_err + Vec3::splat(1e-3)).all(),
                "{name}, θo={:.0}°: albedo {is_mean} exceeds 1",
                wo.z.acos().to_degrees()
            );
        }
    }
    // A white Lambert surface reflects everything.
    let white = Bsdf::new(Vec3::ONE, 0.0, 1.0, 0.0);
    let mut rng = Rng::new(3, 3);
    let wo = Vec3::Z;
    for _ in 0..1000 {
        let s = white.sample(wo, rng.next_f32(), rng.next_vec2()).unwrap();
        assert!((s.weight - Vec3::ONE).abs().max_element() < 1e-5);
    }
}
