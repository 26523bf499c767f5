//! The reference path tracer: the source of training data and the ground truth.

pub mod bsdf;
mod bvh8;
pub mod camera;
pub mod geometry;
pub mod integrator;
pub mod render;
pub mod sampling;
pub mod stratified;
pub mod world;

pub use camera::Camera;
pub use geometry::Geometry;
pub use integrator::{Radiance, TraceSettings};
pub use render::{render, Footprint, RadianceImage, RenderSettings};
pub use world::World;
