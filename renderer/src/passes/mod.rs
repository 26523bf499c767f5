//! The passes of a frame, in the order they run: the shadow maps and the G-buffer (both
//! rasterised), the network pass, the tonemap, the text overlay and the user interface.

pub mod gbuffer;
pub mod mesh;
pub mod mirror;
pub mod network;
pub mod overlay;
pub mod raster;
pub mod shadow;
pub mod tonemap;
pub mod ui;
