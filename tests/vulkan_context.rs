//! The Vulkan foundation on lavapipe: device choice, validation counting, leak reports,
//! upload and read-back, and `rrf info`.

mod common;

use common::{finish_clean, gpu, rrf};
use rrf_renderer::{vk, MemoryLocation};

#[test]
fn runs_on_lavapipe_with_validation() {
    let ctx = gpu();
    assert!(ctx.info.validation, "the validation layer must be on in tests");
    if std::env::var("RRF_DEVICE").is_err() {
        assert!(ctx.info.name.contains("llvmpipe"), "tests run on lavapipe, got {}", ctx.info.name);
    }
    eprintln!("test device: {} ({}), validation on", ctx.info.name, ctx.info.driver_info);
    finish_clean(ctx);
}

/// A deliberately invalid call: anisotropic filtering without enabling the feature
/// (VUID-VkSamplerCreateInfo-anisotropyEnable-01070). Harmless to the driver, caught by the layer.
#[test]
fn validation_error_is_counted() {
    let ctx = gpu();
    assert_eq!(ctx.validation_messages(), 0);
    let info = vk::SamplerCreateInfo::default().anisotropy_enable(true).max_anisotropy(4.0);
    // SAFETY: a sampler is a plain object; the call is invalid only by the feature rule.
    let sampler = unsafe { ctx.device.create_sampler(&info, None) }.expect("lavapipe creates the sampler");
    unsafe { ctx.device.destroy_sampler(sampler, None) };
    assert!(ctx.validation_messages() > 0, "the validation layer did not report the invalid sampler");
    assert!(ctx.validation_log().messages().iter().any(|m| m.contains("anisotropy")));
    let report = ctx.finish();
    assert!(!report.is_clean());
}

#[test]
fn leaked_resource_is_reported_by_name() {
    let ctx = gpu();
    let buffer = ctx
        .create_buffer("deliberately leaked", 256, vk::BufferUsageFlags::STORAGE_BUFFER, MemoryLocation::GpuOnly)
        .unwrap();
    std::mem::forget(buffer);
    let report = ctx.finish();
    assert_eq!(report.leaked, vec!["deliberately leaked".to_string()]);
}

#[test]
fn rgba32f_upload_and_read_back_are_exact() {
    let ctx = gpu();
    let extent = vk::Extent2D { width: 19, height: 7 };
    let image = ctx
        .create_image(
            "round trip",
            extent,
            vk::Format::R32G32B32A32_SFLOAT,
            vk::ImageUsageFlags::TRANSFER_DST | vk::ImageUsageFlags::TRANSFER_SRC,
        )
        .unwrap();
    let pixels: Vec<[f32; 4]> =
        (0..19 * 7).map(|i| [i as f32, -(i as f32) * 0.5, 1e-7 * i as f32, 65504.0 + i as f32]).collect();
    ctx.upload_rgba32f(&image, &pixels).unwrap();
    let back = ctx.read_image(&image, vk::ImageLayout::GENERAL).unwrap();
    assert_eq!(back, pixels.concat());
    ctx.destroy_image(image);
    finish_clean(ctx);
}

#[test]
fn bad_image_size_is_an_error_not_a_panic() {
    let ctx = gpu();
    let result = ctx.create_image(
        "empty",
        vk::Extent2D { width: 0, height: 4 },
        vk::Format::R8G8B8A8_UNORM,
        vk::ImageUsageFlags::STORAGE,
    );
    let message = result.err().expect("a 0-pixel image must be refused").to_string();
    assert!(message.contains("\"empty\"") && message.contains("0x4"), "{message}");

    // Within the side limit but beyond what one image may hold (lavapipe: 4 GiB): refused
    // with its size before Vulkan sees it, so no validation message either.
    let result = ctx.create_image(
        "huge",
        vk::Extent2D { width: 16384, height: 16384 },
        vk::Format::R32G32B32A32_SFLOAT,
        vk::ImageUsageFlags::STORAGE,
    );
    let message = result.err().expect("a 4 GiB image must be refused").to_string();
    assert!(message.contains("\"huge\"") && message.contains("4.00 GiB"), "{message}");
    finish_clean(ctx);
}

#[test]
fn info_json_names_the_device() {
    let out = rrf(&["info", "--json"], &[]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let stdout = String::from_utf8(out.stdout).unwrap();
    assert_eq!(stdout.lines().count(), 1, "--json prints one line");
    let info: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    assert!(info["name"].as_str().unwrap().contains("llvmpipe"));
    assert!(info["limits"]["max_storage_buffer_range"].as_u64().unwrap() > 0);
    assert!(!info["driver_info"].as_str().unwrap().is_empty());
}

#[test]
fn unknown_device_name_lists_the_devices() {
    let out = rrf(&["info"], &[("RRF_DEVICE", "no-such-gpu")]);
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("no-such-gpu") && stderr.contains("llvmpipe"), "{stderr}");
}

#[test]
fn no_driver_says_so_and_fails() {
    let missing = "/nonexistent/icd.json";
    let out = rrf(&["info"], &[("VK_DRIVER_FILES", missing), ("VK_ICD_FILENAMES", missing)]);
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("no Vulkan device"), "{stderr}");
    assert!(stderr.contains("mesa-vulkan-drivers"), "{stderr}");
}
