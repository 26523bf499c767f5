//! rrf: real-time global illumination with radiance regression functions.
//!
//! The binary `rrf` (src/main.rs) is a thin command-line layer over this library, the
//! `rrf-baker` crate (scene import, path tracing, training) and the `rrf-renderer` crate
//! (Vulkan). This crate owns the compiled shaders and hands them to the renderer.

pub mod commands;
pub mod direct_mode;
pub mod eval;
pub mod frame_stats;
pub mod gpu_scene;
pub mod image_out;
pub mod lights;
pub mod parse;
pub mod progress;
pub mod scene_frame;
pub mod shaders;
pub mod viewer;
