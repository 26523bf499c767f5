//! A G-buffer pixel decoded on the CPU, for tests: the twin of `gbuffer_layout.glsl`.

/// One pixel of the G-buffer, decoded on the CPU (for tests): the twin of
/// `gbuffer_layout.glsl`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GBufferTexel {
    pub position: [f32; 3],
    pub normal: [f32; 3],
    /// Object id + 1; 0 where nothing was drawn.
    pub object: u32,
    pub material: u32,
    pub front: bool,
    /// Whether the pixel shows what a planar mirror reflects, put there by the mirror's merge
    /// step (`mirror_merge.comp`).
    pub reflected: bool,
    pub base_color: [f32; 3],
    pub roughness: f32,
    pub metallic: f32,
    /// The emissive texture's value (1 without one), 0 on a face that does not emit: it
    /// multiplies the material's emission.
    pub emissive_texture: [f32; 3],
}

impl GBufferTexel {
    /// Decodes the `surface` (four words), `id` (one word) and `shading` (four words) texels.
    pub fn decode(surface: [u32; 4], id: u32, shading: [u32; 4]) -> Self {
        let half = |bits: u32| half_to_f32((bits & 0xffff) as u16);
        let unorm = |bits: u32| (bits & 0xffff) as f32 / 65535.0;
        let snorm = |bits: u32| (f32::from((bits & 0xffff) as u16 as i16) / 32767.0).max(-1.0);
        let (px, py) = (snorm(surface[3]), snorm(surface[3] >> 16));
        let mut n = [px, py, 1.0 - px.abs() - py.abs()];
        if n[2] < 0.0 {
            let sign = |v: f32| if v >= 0.0 { 1.0 } else { -1.0 };
            n = [(1.0 - py.abs()) * sign(px), (1.0 - px.abs()) * sign(py), n[2]];
        }
        let length = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        GBufferTexel {
            position: [f32::from_bits(surface[0]), f32::from_bits(surface[1]), f32::from_bits(surface[2])],
            normal: n.map(|c| c / length),
            object: id & 0xffff,
            material: (id >> 16) & 0x3fff,
            front: id >> 31 == 1,
            reflected: (id >> 30) & 1 == 1,
            base_color: [half(shading[0]), half(shading[0] >> 16), half(shading[1])],
            roughness: unorm(shading[3]),
            metallic: unorm(shading[3] >> 16),
            emissive_texture: [half(shading[1] >> 16), half(shading[2]), half(shading[2] >> 16)],
        }
    }
}

/// IEEE half to f32 (what GLSL's `unpackHalf2x16` does per half).
fn half_to_f32(h: u16) -> f32 {
    let sign = if h >> 15 == 1 { -1.0 } else { 1.0 };
    let exponent = i32::from((h >> 10) & 0x1f);
    let mantissa = f32::from(h & 0x3ff);
    sign * match exponent {
        0 => mantissa * 2f32.powi(-24),
        31 if mantissa == 0.0 => f32::INFINITY,
        31 => f32::NAN,
        e => (1.0 + mantissa / 1024.0) * 2f32.powi(e - 15),
    }
}
