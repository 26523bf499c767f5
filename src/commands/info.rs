//! `rrf info`: the Vulkan device, its driver and the limits that matter to the renderer.

use anyhow::Result;
use rrf_renderer::{Context, ContextOptions};

pub fn run(json: bool) -> Result<()> {
    let ctx = Context::new(&ContextOptions::from_env())?;
    if json {
        println!("{}", serde_json::to_string(&ctx.info)?);
    } else {
        println!("{}", ctx.info);
    }
    let report = ctx.finish();
    if !report.is_clean() {
        anyhow::bail!(
            "Vulkan teardown was not clean: {} validation messages, leaked {:?}",
            report.validation_messages,
            report.leaked
        );
    }
    Ok(())
}
