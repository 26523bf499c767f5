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
