#![no_main]
//! Fuzz target: see `rrf_baker::fuzzing::model`.

libfuzzer_sys::fuzz_target!(|data: &[u8]| rrf_baker::fuzzing::model(data));
