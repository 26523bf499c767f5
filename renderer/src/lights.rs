//! The lights a frame sums, as the shaders read them, and their limit.

use bytemuck::{Pod, Zeroable};

/// The most lights one frame sums (the size of the lights buffer).
pub const MAX_LIGHTS: usize = 16;

/// One light as the network shaders read it (`Light` in `network_inputs.glsl`): a copy of
/// the moving light at `position` (xyz), whose networks' output is scaled by `scale` (rgb).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct NetworkLight {
    pub position: [f32; 4],
    pub scale: [f32; 4],
}

/// The point light the model was trained with, for analytic direct light: its intensity
/// (W/sr, linear RGB; on the axis of a spot light) and a spot light's cone.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointLightShape {
    pub intensity: [f32; 3],
    pub spot: Option<Spot>,
}

/// A spot light's cone: its axis (unit) and the cosines of its inner and outer angles.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spot {
    pub axis: [f32; 3],
    pub cos_inner: f32,
    pub cos_outer: f32,
}
