//! rrf's Vulkan renderer, on raw ash and gpu-allocator.
//!
//! It knows nothing of glTF or path tracing: scenes arrive as plain arrays and shaders as
//! SPIR-V words compiled by the root crate's build script.

pub mod compute;
pub mod context;
pub mod descriptors;
pub mod device_info;
pub mod error;
pub mod frames;
pub mod gbuffer;
pub mod guard;
pub mod network_pass;
pub mod overlay;
pub mod resources;
pub mod shadow;
pub mod swapchain;
pub mod sync;
pub mod tonemap;
pub mod validation;

pub use ash::vk;
pub use context::{Context, ContextOptions, TeardownReport};
pub use device_info::DeviceInfo;
pub use error::{Error, Result};
pub use gpu_allocator::MemoryLocation;
pub use guard::{Destroy, Guard};
pub use resources::{Buffer, Image};
pub use validation::Validation;
