//! The tonemap compute pass against its CPU twin, pixel by pixel: the end-to-end proof that
//! build.rs's SPIR-V, the compute pass helper, storage images and read-back all work.

mod common;

use common::{finish_clean, gpu};
use rrf::shaders;
use rrf_renderer::passes::tonemap::{tonemap, TonemapPass};
use rrf_renderer::vk;

#[test]
fn tonemap_pass_matches_cpu_pixel_by_pixel() {
    let ctx = gpu();
    // Not a multiple of the 8×8 workgroup, so the edge guard is exercised.
    let extent = vk::Extent2D { width: 45, height: 29 };
    let n = (extent.width * extent.height) as usize;
    let hdr = ctx
        .create_image(
            "hdr",
            extent,
            vk::Format::R32G32B32A32_SFLOAT,
            vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_DST,
        )
        .unwrap();
    let ldr = ctx
        .create_image(
            "ldr",
            extent,
            vk::Format::R8G8B8A8_UNORM,
            vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_SRC,
        )
        .unwrap();
    // Radiance from black through the sRGB toe to far above white, plus negatives.
    let radiance: Vec<[f32; 4]> = (0..n)
        .map(|i| {
            let t = i as f32 / n as f32;
            [1e-4 * (i % 7) as f32, 20.0 * t * t, 2.0 - 4.0 * t, 1.0]
        })
        .collect();
    ctx.upload_rgba32f(&hdr, &radiance).unwrap();

    let exposure = 1.5;
    let pass = TonemapPass::new(&ctx, shaders::TONEMAP_COMP, &hdr, &ldr).unwrap();
    ctx.submit_once(|cmd| {
        ctx.transition(cmd, &ldr, vk::ImageLayout::UNDEFINED, vk::ImageLayout::GENERAL);
        pass.record(&ctx, cmd, extent, exposure);
    })
    .unwrap();
    let out = ctx.read_image(&ldr, vk::ImageLayout::GENERAL).unwrap();

    let mut worst = 0.0f32;
    for (i, px) in radiance.iter().enumerate() {
        let want = tonemap([px[0], px[1], px[2]], exposure);
        for c in 0..3 {
            let got = out[4 * i + c];
            worst = worst.max((got - want[c]).abs());
            // 8-bit quantisation: half a step, plus float slack.
            assert!(
                (got - want[c]).abs() <= 0.5 / 255.0 + 1e-4,
                "pixel {i} channel {c}: GPU {got}, CPU {}, radiance {:?}",
                want[c],
                px
            );
        }
        assert_eq!(out[4 * i + 3], 1.0, "alpha of pixel {i}");
    }
    eprintln!("tonemap: worst difference {worst:.2e} over {n} pixels");

    pass.destroy(&ctx);
    ctx.destroy_image(hdr);
    ctx.destroy_image(ldr);
    finish_clean(ctx);
}
