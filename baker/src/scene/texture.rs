//! Textures as decoded RGBA8 texels, sampled with wrapping bilinear filtering.

use std::sync::LazyLock;

use glam::{Vec2, Vec4};

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ColorSpace {
    /// Base colour: texels are sRGB-encoded and decoded to linear when sampled.
    Srgb,
    /// Data such as metallic-roughness: texels are used as they are.
    Linear,
}

#[derive(Clone, Debug)]
pub struct Texture {
    pub name: String,
    pub width: u32,
    pub height: u32,
    pub texels: Vec<[u8; 4]>,
    pub color_space: ColorSpace,
}

fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// [`srgb_to_linear`] of every byte value: a `powf` per channel of every texel fetched was a
/// seventh of a textured scene's path tracing.
static SRGB_TO_LINEAR: LazyLock<[f32; 256]> =
    LazyLock::new(|| std::array::from_fn(|b| srgb_to_linear(b as f32 / 255.0)));

impl Texture {
    /// The texel at `x`, `y`, both already wrapped into the texture.
    fn texel(&self, x: usize, y: usize) -> Vec4 {
        let t = self.texels[y * self.width as usize + x];
        match self.color_space {
            ColorSpace::Srgb => {
                let linear = &*SRGB_TO_LINEAR;
                Vec4::new(linear[t[0] as usize], linear[t[1] as usize], linear[t[2] as usize], t[3] as f32 / 255.0)
            }
            ColorSpace::Linear => Vec4::new(t[0] as f32, t[1] as f32, t[2] as f32, t[3] as f32) / 255.0,
        }
    }

    /// Bilinear sample with repeat wrapping, in linear values.
    pub fn sample(&self, uv: Vec2) -> Vec4 {
        let p = uv * Vec2::new(self.width as f32, self.height as f32) - 0.5;
        let (x0, y0) = (p.x.floor(), p.y.floor());
        let (fx, fy) = (p.x - x0, p.y - y0);
        // The four texels' coordinates, wrapped with two divisions rather than eight.
        let wrap = |c: f32, size: u32| {
            let first = (c as i64).rem_euclid(i64::from(size)) as usize;
            (first, if first + 1 == size as usize { 0 } else { first + 1 })
        };
        let ((x0, x1), (y0, y1)) = (wrap(x0, self.width), wrap(y0, self.height));
        let top = self.texel(x0, y0).lerp(self.texel(x1, y0), fx);
        let bottom = self.texel(x0, y1).lerp(self.texel(x1, y1), fx);
        top.lerp(bottom, fy)
    }
}

/// `KHR_texture_transform` of a texture's UVs, as the affine map `uv ↦ M·uv + offset` with
/// `M = R(rotation)·S(scale)`; the identity without the extension. `R` is `[cos sin; −sin cos]`:
/// counter-clockwise in glTF's v-down UV space, as the sample model `TextureTransformTest`,
/// three.js and Babylon have it (the extension's GLSL listing has the sign the other way,
/// KhronosGroup/glTF#1563).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UvTransform {
    /// Row-major 2×2 matrix.
    pub matrix: [f32; 4],
    pub offset: Vec2,
}

impl UvTransform {
    pub const IDENTITY: UvTransform = UvTransform { matrix: [1.0, 0.0, 0.0, 1.0], offset: Vec2::ZERO };

    /// The extension's `offset`, `rotation` (radians) and `scale`, composed as it says:
    /// translation · rotation · scale.
    pub fn new(offset: [f32; 2], rotation: f32, scale: [f32; 2]) -> Self {
        let (s, c) = rotation.sin_cos();
        UvTransform { matrix: [c * scale[0], s * scale[1], -s * scale[0], c * scale[1]], offset: Vec2::from(offset) }
    }

    pub fn apply(&self, uv: Vec2) -> Vec2 {
        let m = &self.matrix;
        Vec2::new(m[0] * uv.x + m[1] * uv.y, m[2] * uv.x + m[3] * uv.y) + self.offset
    }
}

/// A material's use of a texture: which one, and how its UVs are transformed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TextureRef {
    /// Index into [`crate::scene::Scene::textures`].
    pub texture: u32,
    pub transform: UvTransform,
}

impl TextureRef {
    pub fn sample(&self, textures: &[Texture], uv: Vec2) -> Vec4 {
        textures[self.texture as usize].sample(self.transform.apply(uv))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uv_transform_follows_the_extension() {
        // The extension's example: rotate a quarter turn, then scale and offset.
        let t = UvTransform::new([0.5, 0.25], std::f32::consts::FRAC_PI_2, [2.0, 3.0]);
        // (1, 0) scaled to (2, 0), rotated by [c s; -s c] to (0, -2), then offset.
        let p = t.apply(Vec2::new(1.0, 0.0));
        assert!((p - Vec2::new(0.5, -1.75)).length() < 1e-6, "{p}");
        let q = t.apply(Vec2::new(0.0, 1.0));
        assert!((q - Vec2::new(3.5, 0.25)).length() < 1e-6, "{q}");
        assert_eq!(UvTransform::IDENTITY.apply(Vec2::new(0.3, 0.7)), Vec2::new(0.3, 0.7));
    }

    fn texture(color_space: ColorSpace, texels: Vec<[u8; 4]>) -> Texture {
        Texture { name: "t".into(), width: 3, height: 2, texels, color_space }
    }

    #[test]
    fn bilinear_sampling_wraps_at_both_edges() {
        // Texel (x, y) holds 10·(3y + x) + 10 in every channel.
        let texels = (0..6).map(|i| [10 * i + 10; 4]).collect();
        let t = texture(ColorSpace::Linear, texels);
        let value = |x: usize, y: usize| (10 * (3 * y + x) + 10) as f32 / 255.0;
        for (x, y) in [(0, 0), (2, 0), (1, 1)] {
            let centre = Vec2::new((x as f32 + 0.5) / 3.0, (y as f32 + 0.5) / 2.0);
            assert!((t.sample(centre) - Vec4::splat(value(x, y))).abs().max_element() < 1e-6);
        }
        // Both corners of the unit square lie between the same four texels: the first and
        // last column, the first and last row.
        let corners = (value(0, 0) + value(2, 0) + value(0, 1) + value(2, 1)) / 4.0;
        for uv in [Vec2::ZERO, Vec2::ONE] {
            let s = t.sample(uv);
            assert!((s - Vec4::splat(corners)).abs().max_element() < 1e-6, "{uv}: {s}");
        }
    }

    #[test]
    fn srgb_texels_decode_to_linear_and_alpha_stays_linear() {
        let t = texture(ColorSpace::Srgb, vec![[188, 10, 0, 188]; 6]);
        let s = t.sample(Vec2::new(0.3, 0.6));
        // The sRGB curve's values: its power segment, its linear toe and zero.
        let expected = Vec4::new(0.502_886_5, 0.003_035_27, 0.0, 188.0 / 255.0);
        assert!((s - expected).abs().max_element() < 1e-6, "{s}");
    }
}
