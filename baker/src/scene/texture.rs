//! Textures as decoded RGBA8 texels, sampled with wrapping bilinear filtering.

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

impl Texture {
    fn texel(&self, x: i64, y: i64) -> Vec4 {
        let x = x.rem_euclid(self.width as i64) as usize;
        let y = y.rem_euclid(self.height as i64) as usize;
        let t = self.texels[y * self.width as usize + x];
        let v = Vec4::new(t[0] as f32, t[1] as f32, t[2] as f32, t[3] as f32) / 255.0;
        match self.color_space {
            ColorSpace::Srgb => Vec4::new(srgb_to_linear(v.x), srgb_to_linear(v.y), srgb_to_linear(v.z), v.w),
            ColorSpace::Linear => v,
        }
    }

    /// Bilinear sample with repeat wrapping, in linear values.
    pub fn sample(&self, uv: Vec2) -> Vec4 {
        let p = uv * Vec2::new(self.width as f32, self.height as f32) - 0.5;
        let (x0, y0) = (p.x.floor(), p.y.floor());
        let (fx, fy) = (p.x - x0, p.y - y0);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let top = self.texel(x0, y0).lerp(self.texel(x0 + 1, y0), fx);
        let bottom = self.texel(x0, y0 + 1).lerp(self.texel(x0 + 1, y0 + 1), fx);
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
}
