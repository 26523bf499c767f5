//! The glTF metallic-roughness BRDF (glTF 2.0 specification, appendix B, with the
//! `KHR_materials_specular` factor): Lambert diffuse plus GGX specular with the Smith
//! height-correlated masking-shadowing term and Schlick Fresnel.
//!
//! ```text
//! F_d  = specular · Schlick(0.04, v·h)           dielectric Fresnel
//! F_m  = Schlick(baseColor, v·h)                  metal Fresnel
//! f    = (1 − metallic)(1 − F_d) · baseColor / π
//!      + ((1 − metallic) F_d + metallic F_m) · D(h) G₂(v, l) / (4 |n·v| |n·l|)
//! ```
//!
//! with `α = roughness²`. So the diffuse weight is `baseColor × (1 − metallic)` and the
//! specular Fresnel is Schlick with `F0 = mix(0.04, baseColor, metallic)`, as glTF says.
//! Sampling picks the GGX visible-normal lobe (Heitz 2018) or the cosine lobe with
//! probabilities from an estimate of their weights, and returns the pdf of the mixture: the
//! balance heuristic over the two strategies.
//!
//! Everything here works in the local shading frame, where the normal is +z.

use std::f32::consts::{FRAC_1_PI, PI, TAU};

use glam::{Vec2, Vec3};

use super::sampling::cosine_hemisphere;

/// Below this α, GGX becomes numerically a mirror; rrf has no delta lobes.
pub const MIN_ALPHA: f32 = 1e-3;

#[derive(Clone, Copy, Debug)]
pub struct Bsdf {
    pub base_color: Vec3,
    pub metallic: f32,
    pub alpha: f32,
    /// `KHR_materials_specular` factor: 0 makes a dielectric pure Lambert.
    pub specular: f32,
}

#[derive(Clone, Copy, Debug)]
pub struct BsdfSample {
    pub wi: Vec3,
    /// `f · cos θi / pdf`.
    pub weight: Vec3,
    pub pdf: f32,
}

/// Schlick's Fresnel term for reflectance `f0` at normal incidence, at `cos` from the normal.
pub fn schlick(f0: Vec3, cos: f32) -> Vec3 {
    let m = (1.0 - cos).clamp(0.0, 1.0);
    let m5 = (m * m) * (m * m) * m;
    f0 + (Vec3::ONE - f0) * m5
}

fn luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.2126, 0.7152, 0.0722))
}

impl Bsdf {
    pub fn new(base_color: Vec3, metallic: f32, roughness: f32, specular: f32) -> Self {
        Bsdf { base_color, metallic, alpha: (roughness * roughness).max(MIN_ALPHA), specular }
    }

    /// No specular lobe at all: a dielectric with `KHR_materials_specular` factor 0.
    fn is_lambert(&self) -> bool {
        self.specular == 0.0 && self.metallic == 0.0
    }

    /// GGX normal distribution.
    pub fn d(&self, h: Vec3) -> f32 {
        let a2 = self.alpha * self.alpha;
        let t = h.z * h.z * (a2 - 1.0) + 1.0;
        a2 / (PI * t * t)
    }

    /// Smith Λ for GGX.
    fn lambda(&self, w: Vec3) -> f32 {
        let tan2 = (w.x * w.x + w.y * w.y) / (w.z * w.z);
        0.5 * ((1.0 + self.alpha * self.alpha * tan2).sqrt() - 1.0)
    }

    /// The BSDF seen from `wo`, for evaluating and sampling directions from it.
    pub fn seen_from(&self, wo: Vec3) -> SeenFrom {
        let specular_probability = self.specular_probability(wo);
        // A Lambert surface never samples GGX, unless it is black (see `eval_pdf`).
        let lambda_wo = if self.is_lambert() && specular_probability == 0.0 { 0.0 } else { self.lambda(wo) };
        SeenFrom { bsdf: *self, wo, specular_probability, lambda_wo }
    }

    /// `f(wo, wi)`; zero unless both are above the surface.
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        self.seen_from(wo).eval_pdf(wi).0
    }

    /// Density of [`Bsdf::sample`] producing `wi`, in solid angle.
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        self.seen_from(wo).eval_pdf(wi).1
    }

    /// Samples `wi` from `wo` with `u_lobe` choosing the lobe and `u` the direction.
    pub fn sample(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        self.seen_from(wo).sample(u_lobe, u)
    }

    /// Probability of sampling the specular lobe, from the lobes' weights seen from `wo`.
    fn specular_probability(&self, wo: Vec3) -> f32 {
        let f_d = self.specular * schlick(Vec3::splat(0.04), wo.z).x;
        let w_spec = (1.0 - self.metallic) * f_d + self.metallic * luminance(schlick(self.base_color, wo.z));
        let w_diff = (1.0 - self.metallic) * (1.0 - f_d) * luminance(self.base_color);
        if w_diff <= 0.0 {
            1.0
        } else if w_spec <= 0.0 {
            0.0
        } else {
            // Keep both strategies alive so that neither lobe is starved of samples.
            (w_spec / (w_spec + w_diff)).clamp(0.15, 0.85)
        }
    }

    /// A microfacet normal from the distribution of normals visible from `wo` (Heitz 2018).
    fn sample_visible_normal(&self, wo: Vec3, u: Vec2) -> Vec3 {
        let a = self.alpha;
        let vh = Vec3::new(a * wo.x, a * wo.y, wo.z).normalize();
        let len2 = vh.x * vh.x + vh.y * vh.y;
        let t1 = if len2 > 0.0 { Vec3::new(-vh.y, vh.x, 0.0) / len2.sqrt() } else { Vec3::X };
        let t2 = vh.cross(t1);
        let r = u.x.sqrt();
        let phi = TAU * u.y;
        let p1 = r * phi.cos();
        let s = 0.5 * (1.0 + vh.z);
        let p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * r * phi.sin();
        let nh = p1 * t1 + p2 * t2 + (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt() * vh;
        Vec3::new(a * nh.x, a * nh.y, nh.z.max(1e-7)).normalize()
    }
}

/// A BSDF seen from one direction `wo` (a path vertex's): what depends on `wo` alone, the
/// lobe probability and Smith's Λ(wo), is computed once for every direction the vertex
/// evaluates, and a direction's value and density share its half vector and D.
#[derive(Clone, Copy, Debug)]
pub struct SeenFrom {
    bsdf: Bsdf,
    wo: Vec3,
    specular_probability: f32,
    lambda_wo: f32,
}

impl SeenFrom {
    /// `f(wo, wi)` and the density of [`SeenFrom::sample`] producing `wi` (solid angle); both
    /// zero unless `wo` and `wi` are above the surface.
    pub fn eval_pdf(&self, wi: Vec3) -> (Vec3, f32) {
        let (b, wo) = (&self.bsdf, self.wo);
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return (Vec3::ZERO, 0.0);
        }
        let p = self.specular_probability;
        let (f, specular_pdf) = if b.is_lambert() && p == 0.0 {
            (b.base_color * FRAC_1_PI, 0.0)
        } else {
            let h = (wo + wi).normalize();
            let d = b.d(h);
            let f = if b.is_lambert() {
                b.base_color * FRAC_1_PI
            } else {
                let vh = wo.dot(h).max(0.0);
                let f_d = b.specular * schlick(Vec3::splat(0.04), vh).x;
                let f_m = schlick(b.base_color, vh);
                let diffuse = (1.0 - b.metallic) * (1.0 - f_d) * b.base_color * FRAC_1_PI;
                let fresnel = (1.0 - b.metallic) * Vec3::splat(f_d) + b.metallic * f_m;
                // Height-correlated masking-shadowing G₂.
                let g2 = 1.0 / (1.0 + self.lambda_wo + b.lambda(wi));
                diffuse + fresnel * (d * g2 / (4.0 * wo.z * wi.z))
            };
            // GGX visible-normal sampling's density: G₁(wo) D(h) / (4 cos θo).
            let vndf = 1.0 / (1.0 + self.lambda_wo) * d / (4.0 * wo.z);
            (f, if p > 0.0 { p * vndf } else { 0.0 })
        };
        (f, specular_pdf + (1.0 - p) * wi.z * FRAC_1_PI)
    }

    /// `f(wo, wi)`; zero unless both are above the surface.
    pub fn eval(&self, wi: Vec3) -> Vec3 {
        self.eval_pdf(wi).0
    }

    /// The direction it is seen from, in the shading frame.
    pub fn wo(&self) -> Vec3 {
        self.wo
    }

    /// Samples `wi` with `u_lobe` choosing the lobe and `u` the direction.
    pub fn sample(&self, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        let wo = self.wo;
        if wo.z <= 0.0 {
            return None;
        }
        let wi = if u_lobe < self.specular_probability {
            let h = self.bsdf.sample_visible_normal(wo, u);
            2.0 * wo.dot(h) * h - wo
        } else {
            cosine_hemisphere(u)
        };
        if wi.z <= 0.0 {
            return None;
        }
        let (f, pdf) = self.eval_pdf(wi);
        if pdf <= 0.0 || !pdf.is_finite() {
            return None;
        }
        Some(BsdfSample { wi, weight: f * (wi.z / pdf), pdf })
    }
}
