//! rrf's Vulkan renderer, on raw ash and gpu-allocator.
//!
//! It knows nothing of glTF or path tracing: scenes arrive as plain arrays and shaders as
//! SPIR-V words compiled by the root crate's build script.

#![deny(clippy::undocumented_unsafe_blocks)]

pub mod backend;
pub mod error;
pub mod frame;
pub mod lights;
pub mod passes;

pub use ash::vk;
pub use backend::context::{Context, ContextOptions, TeardownReport};
pub use backend::device_info::DeviceInfo;
pub use backend::guard::{Destroy, Guard};
pub use backend::resources::{Buffer, Image};
pub use backend::validation::Validation;
pub use error::{Error, Result};
pub use gpu_allocator::MemoryLocation;
