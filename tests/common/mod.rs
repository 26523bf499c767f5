//! Shared set-up for GPU tests: lavapipe, validation required, and a teardown that fails the
//! test on any validation message or leaked resource.
#![allow(dead_code)] // each test binary uses its own subset

use rrf_renderer::{Context, ContextOptions, Validation};

/// A context on lavapipe (or on `RRF_DEVICE`) with the validation layer required.
pub fn gpu() -> Context {
    let options = ContextOptions {
        validation: Validation::Required,
        device: Some(std::env::var("RRF_DEVICE").unwrap_or_else(|_| "llvmpipe".into())),
        ..ContextOptions::from_env()
    };
    Context::new(&options).unwrap_or_else(|e| panic!("cannot create the test Vulkan context: {e}"))
}

/// Tears the context down and fails on any validation message or leaked resource.
pub fn finish_clean(ctx: Context) {
    let messages = ctx.validation_log().messages();
    let report = ctx.finish();
    assert!(
        report.is_clean(),
        "{} validation messages, leaked {:?}:\n{}",
        report.validation_messages,
        report.leaked,
        messages.join("\n")
    );
}

/// Runs the `rrf` binary on lavapipe with extra environment variables.
pub fn rrf(args: &[&str], env: &[(&str, &str)]) -> std::process::Output {
    rrf_command(args, env).output().expect("run rrf")
}

/// The command [`rrf`] runs, for a test that starts it and waits later.
pub fn rrf_command(args: &[&str], env: &[(&str, &str)]) -> std::process::Command {
    let mut cmd = std::process::Command::new(env!("CARGO_BIN_EXE_rrf"));
    cmd.args(args).env("RRF_DEVICE", "llvmpipe").current_dir(env!("CARGO_MANIFEST_DIR"));
    for (k, v) in env {
        cmd.env(k, v);
    }
    cmd
}

/// Pixels of two RGB images that differ by more than `levels` in some channel, and the mean
/// of the largest channel difference per pixel.
pub fn difference(a: &image::RgbImage, b: &image::RgbImage, levels: u8) -> (usize, f64) {
    assert_eq!(a.dimensions(), b.dimensions());
    let mut off = 0;
    let mut total = 0u64;
    for (p, q) in a.pixels().zip(b.pixels()) {
        let d = p.0.iter().zip(q.0).map(|(&x, y)| x.abs_diff(y)).max().unwrap_or(0);
        off += usize::from(d > levels);
        total += u64::from(d);
    }
    (off, total as f64 / (a.width() * a.height()) as f64)
}
