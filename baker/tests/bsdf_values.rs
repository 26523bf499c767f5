//! The BSDF against values that do not come from its own code: the glTF 2.0 appendix-B
//! formula worked out at fixed angles, and the directional albedo of a white GGX conductor
//! at roughness 1, which has a closed form. `bsdf_sampling.rs` checks sampling, pdf and eval
//! against each other; these tie eval itself to the specification, so a D, G or Fresnel term
//! that is consistently wrong fails here.

use std::f32::consts::PI;

use rrf_baker::glam::Vec3;
use rrf_baker::trace::bsdf::Bsdf;
use rrf_baker::trace::sampling::Rng;

/// The unit vector `theta` degrees from the normal, at azimuth `phi` degrees.
fn direction(theta: f32, phi: f32) -> Vec3 {
    let (t, p) = (theta.to_radians(), phi.to_radians());
    Vec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos())
}

fn assert_close(name: &str, got: Vec3, want: Vec3) {
    let error = ((got - want).abs() / want.abs().max(Vec3::splat(1e-3))).max_element();
    assert!(error < 2e-4, "{name}: eval {got}, appendix B {want} (relative error {error:.1e})");
}

/// f(wo, wi) at fixed angles against values worked out from the specification's own form of
/// the BRDF (α = roughness², D = α²/(π((n·h)²(α²−1)+1)²), the visibility term
/// V = 0.5/(n·l·√((n·v)²(1−α²)+α²) + n·v·√((n·l)²(1−α²)+α²)), Schlick Fresnel with F0 = 0.04
/// scaled by the specular factor for the dielectric and the base colour for the metal, the
/// dielectric's diffuse (1−F)·c/π), in f64, outside this code base.
#[test]
fn eval_matches_appendix_b_at_fixed_angles() {
    // Along the normal both ways, h = n: D = 1/(πα²), V = 1/4 and F = F0 = 1 for a white
    // metal; at roughness 0.5 (α = 1/4) f = 4/π.
    let white_metal = Bsdf::new(Vec3::ONE, 1.0, 0.5, 1.0);
    assert_close("white metal, n to n", white_metal.eval(Vec3::Z, Vec3::Z), Vec3::splat(4.0 / PI));

    let cases = [
        // A mirror pair 60° from the normal, h = n, v·h = 1/2: F = 0.04 + 0.96/32 = 0.07,
        // D = 16/π, V = 0.5/√0.296875; f = 0.93·0.8/π + 0.07·D·V.
        (
            "dielectric r=0.5, mirror pair at 60°",
            Bsdf::new(Vec3::splat(0.8), 0.0, 0.5, 1.0),
            (60.0, 0.0),
            (60.0, 180.0),
            [0.563976; 3],
        ),
        (
            "dielectric r=0.7, 60° to the normal",
            Bsdf::new(Vec3::new(0.6, 0.4, 0.2), 0.0, 0.7, 1.0),
            (60.0, 0.0),
            (0.0, 0.0),
            [0.190496, 0.129383, 0.0682702],
        ),
        (
            "metal r=0.3, off the mirror direction",
            Bsdf::new(Vec3::new(0.95, 0.8, 0.5), 1.0, 0.3, 1.0),
            (30.0, 0.0),
            (50.0, 150.0),
            [0.178755, 0.150545, 0.094125],
        ),
        (
            "half metal r=0.45, grazing",
            Bsdf::new(Vec3::new(0.3, 0.7, 0.5), 0.5, 0.45, 1.0),
            (75.0, 0.0),
            (20.0, 90.0),
            [0.0560039, 0.129048, 0.092526],
        ),
        (
            "dielectric specular 0.5, r=0.2, mirror pair at 40°",
            Bsdf::new(Vec3::splat(0.5), 0.0, 0.2, 0.5),
            (40.0, 0.0),
            (40.0, 180.0),
            [1.87855; 3],
        ),
        // KHR_materials_specular 0: no lobe but Lambert, c/π.
        (
            "lambert",
            Bsdf::new(Vec3::new(0.9, 0.5, 0.1), 0.0, 0.4, 0.0),
            (70.0, 0.0),
            (10.0, 200.0),
            [0.9 / PI, 0.5 / PI, 0.1 / PI],
        ),
    ];
    for (name, bsdf, (theta_o, phi_o), (theta_i, phi_i), want) in cases {
        let (wo, wi) = (direction(theta_o, phi_o), direction(theta_i, phi_i));
        assert_close(name, bsdf.eval(wo, wi), Vec3::from(want));
        assert_eq!(bsdf.eval(wo, -wi), Vec3::ZERO, "{name}: light from below the surface");
    }
}

/// A white conductor at roughness 1 (α = 1): D = 1/π everywhere and, with n·v = μ,
/// V = 1/(2(n·l + μ)), so its directional albedo is ∫₀¹ c/(c + μ) dc = 1 − μ ln(1 + 1/μ)
/// (1 − ln 2 along the normal): what single-scattering GGX keeps of the light. Estimated
/// twice: by quadrature of `eval` (which sees D's normalisation) and with the BSDF's own
/// importance sampling, whose weights f·cos/pdf carry G and F (D cancels in them).
#[test]
fn rough_white_conductor_albedo_has_its_closed_form() {
    const N: usize = 400_000;
    const COS_CELLS: usize = 400;
    const PHI_CELLS: usize = 200;
    let bsdf = Bsdf::new(Vec3::ONE, 1.0, 1.0, 1.0);
    for mu in [1.0f64, 0.5, 0.2] {
        let closed_form = 1.0 - mu * (1.0 + 1.0 / mu).ln();
        let wo = Vec3::new((1.0 - mu * mu).sqrt() as f32, 0.0, mu as f32);

        let mut quadrature = 0.0f64;
        for i in 0..COS_CELLS {
            let c = (i as f32 + 0.5) / COS_CELLS as f32;
            let s = (1.0 - c * c).sqrt();
            for j in 0..PHI_CELLS {
                let phi = (j as f32 + 0.5) / PHI_CELLS as f32 * 2.0 * PI;
                let wi = Vec3::new(s * phi.cos(), s * phi.sin(), c);
                quadrature += f64::from(bsdf.eval(wo, wi).x * c);
            }
        }
        quadrature *= 2.0 * std::f64::consts::PI / (COS_CELLS * PHI_CELLS) as f64;
        assert!(
            (quadrature - closed_form).abs() < 1e-3,
            "μ = {mu}: ∫ f cos = {quadrature:.5}, closed form {closed_form:.5}"
        );

        let mut rng = Rng::new(29, 0);
        let (mut sum, mut sum_sq) = (0.0f64, 0.0f64);
        for _ in 0..N {
            let w = bsdf.sample(wo, rng.next_f32(), rng.next_vec2()).map_or(0.0, |s| f64::from(s.weight.x));
            sum += w;
            sum_sq += w * w;
        }
        let mean = sum / N as f64;
        let standard_error = ((sum_sq / N as f64 - mean * mean) / N as f64).sqrt();
        assert!(
            (mean - closed_form).abs() < 4.0 * standard_error + 1e-3,
            "μ = {mu}: sampled albedo {mean:.5} ± {standard_error:.5}, closed form {closed_form:.5}"
        );
    }
}

/// A smooth white conductor reflects all the light that reaches it: at roughness 0.05 its
/// masking is negligible and its Fresnel term is 1, so its albedo is 1 within 1%.
#[test]
fn smooth_white_conductor_reflects_everything() {
    const N: usize = 100_000;
    let bsdf = Bsdf::new(Vec3::ONE, 1.0, 0.05, 1.0);
    for theta in [0.0f32, 45.0, 75.0] {
        let wo = direction(theta, 0.0);
        let mut rng = Rng::new(31, 0);
        let sum: f64 = (0..N)
            .map(|_| bsdf.sample(wo, rng.next_f32(), rng.next_vec2()).map_or(0.0, |s| f64::from(s.weight.x)))
            .sum();
        let albedo = sum / N as f64;
        assert!((albedo - 1.0).abs() < 0.01, "θo = {theta}°: albedo {albedo:.4}");
    }
}
