//! The offline half of rrf: scene import, the reference path tracer and network training.
//! No Vulkan here.

pub mod scene;
pub mod trace;
pub use glam;
