#![no_main]
//! Fuzz target: see `rrf_baker::fuzzing::gltf`.

libfuzzer_sys::fuzz_target!(|data: &[u8]| rrf_baker::fuzzing::gltf(data));
