//! `rrf bench --json`: one line per variant and frame output with the fields the issues name.
//! It times nothing here; it only checks that the figures are there and sane.

mod common;

use std::path::Path;

use common::rrf;
use rrf_baker::model::Model;

#[test]
fn bench_prints_the_figures() {
    let out = rrf(
        &["bench", "scenes/cornell-box", "--size", "32x32", "--frames", "2", "--json", "--peak-gflops", "250"],
        &[],
    );
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let stdout = String::from_utf8(out.stdout).unwrap();
    let mut runs = Vec::new();
    let mut bytes = std::collections::HashMap::new();
    for line in stdout.lines() {
        let row: serde_json::Value = serde_json::from_str(line).unwrap();
        assert!(row["device"].as_str().unwrap().contains("llvmpipe"));
        let run = format!("{} {}", row["variant"].as_str().unwrap(), row["output"].as_str().unwrap());
        bytes.insert(run.clone(), row["bytes_per_pixel"].as_u64().unwrap());
        runs.push(run);
        assert_eq!(
            (row["width"].as_u64(), row["height"].as_u64(), row["frames"].as_u64()),
            (Some(32), Some(32), Some(2))
        );
        for key in ["gbuffer_ms", "network_ms", "frame_ms", "network_pixels_per_s", "peak_fraction"] {
            let v = row[key].as_f64().unwrap_or_else(|| panic!("{key} missing in {row}"));
            assert!(v.is_finite() && v > 0.0, "{key} = {v}");
        }
        // The display frame has no tonemap pass of its own: its interval may be empty.
        let tonemap = row["tonemap_ms"].as_f64().unwrap();
        assert!(tonemap.is_finite() && tonemap >= 0.0, "tonemap_ms = {tonemap}");
        // Two networks per pixel that shows a trained object: most of the frame.
        let evaluations = row["networks_per_frame"].as_u64().unwrap();
        assert!(evaluations > 1000 && evaluations <= 2 * 32 * 32, "{evaluations}");
    }
    let expected = ["tiled", "per-object", "storage"].map(|v| [format!("{v} radiance"), format!("{v} display")]);
    assert_eq!(runs, expected.concat(), "--variant all and --output both by default");
    assert_eq!(bytes["storage display"], bytes["storage radiance"], "storage falls back to radiance: {bytes:?}");
    // The Cornell box's leaves blend, which only the radiance images can: its display frame
    // falls back to them too.
    assert_eq!(bytes["tiled display"], bytes["tiled radiance"], "blended units fall back to radiance: {bytes:?}");

    // Models with hard cuts (their blend band set to 0): the display frame writes one RGBA8
    // image instead of three RGBA32F ones and a tonemap, in the dining room and in the glossy
    // room, whose mirror's reflection the network pass shades with the rest.
    let display_and_radiance = |scene: &str| {
        let mut hard =
            Model::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join(scene).join("model.safetensors"), None).unwrap();
        hard.metadata.blend_band = 0.0;
        let dir = std::env::temp_dir().join(format!("rrf-bench-hard-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let hard_path = dir.join("hard.safetensors");
        hard.save(&hard_path).unwrap();
        #[rustfmt::skip]
        let out = rrf(
            &["bench", scene, "--model", hard_path.to_str().unwrap(), "--size", "32x32", "--frames", "2", "--json",
              "--variant", "tiled"],
            &[],
        );
        std::fs::remove_dir_all(&dir).unwrap();
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let rows: Vec<serde_json::Value> =
            String::from_utf8(out.stdout).unwrap().lines().map(|l| serde_json::from_str(l).unwrap()).collect();
        let bytes = |output: &str| {
            let row = rows.iter().find(|r| r["output"] == output).unwrap();
            row["bytes_per_pixel"].as_u64().unwrap()
        };
        (bytes("display"), bytes("radiance"))
    };
    let (display, radiance) = display_and_radiance("scenes/many-objects");
    assert!(display < radiance, "many-objects: display {display} bytes, radiance {radiance}");
    let (display, radiance) = display_and_radiance("scenes/glossy-room");
    assert!(display < radiance, "glossy-room: display {display} bytes, radiance {radiance}");
}

#[test]
fn bench_rejects_an_unknown_variant() {
    let out = rrf(&["bench", "scenes/cornell-box", "--variant", "fastest"], &[]);
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("tiled, per-object, storage or all"), "{stderr}");
}
