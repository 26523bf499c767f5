//! SPIR-V of every entry point in `shaders-glsl/`, compiled by `build.rs` with glslang.

include!(concat!(env!("OUT_DIR"), "/shaders.rs"));
