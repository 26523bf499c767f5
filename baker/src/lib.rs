//! The offline half of rrf: scene import, the reference path tracer and network training.
//! No Vulkan here.

pub mod atomic_file;
pub mod bake;
pub mod fuzzing;
pub mod hash;
pub mod model;
pub mod network;
pub mod partition;
pub mod predict;
pub mod scene;
pub mod trace;
pub use glam;
