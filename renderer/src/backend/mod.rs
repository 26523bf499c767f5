//! What every pass stands on: the Vulkan context and its resources, descriptor sets and
//! compute pipelines, the swapchain, frames in flight, the barrier tracker and the guards
//! that destroy what a failed set-up made.

pub mod compute;
pub mod context;
pub mod descriptors;
pub mod device_info;
pub mod frames;
pub mod guard;
pub mod present;
pub mod resources;
pub mod swapchain;
pub mod sync;
pub mod validation;
