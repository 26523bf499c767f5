//! rrf's HDR-FLIP (`src/eval/hdr_flip.rs`) against NVIDIA's reference implementation of
//! FLIP, on a network prediction and a 16-spp path-traced reference of two shipped scenes
//! (64×64, `tests/fixtures/hdr-flip/`, written by `rrf render --cpu` and `rrf reference
//! --spp 16 --footprint centre`). The expected figures were computed by the `flip-evaluator`
//! package (version 1.7, from PyPI) as
//! `flip_evaluator.evaluate(reference, test, "HDR", inputsRGB=False)`.

use std::path::Path;

use rrf::eval::hdr_flip::{hdr_flip, Exposures};
use rrf_baker::glam::Vec3;

fn load(name: &str) -> (Vec<Vec3>, u32, u32) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/hdr-flip").join(name);
    let image = exr::prelude::read_first_rgba_layer_from_file(
        &path,
        |size, _| (vec![Vec3::ZERO; size.width() * size.height()], size.width()),
        |(pixels, width), at, (r, g, b, _a): (f32, f32, f32, f32)| {
            pixels[at.y() * *width + at.x()] = Vec3::new(r, g, b)
        },
    )
    .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let size = image.layer_data.size;
    (image.layer_data.channel_data.pixels.0, size.width() as u32, size.height() as u32)
}

/// `flip-evaluator`'s figures: start and stop exposure, exposure count, mean HDR-FLIP.
const EXPECTED: [(&str, f32, f32, u32, f64); 2] =
    [("cornell-box", -2.560_097, 5.373_796, 8, 0.154_105), ("glossy-room", -1.765_012, 4.784_419, 7, 0.260_734)];

#[test]
fn hdr_flip_agrees_with_nvidias_implementation() {
    for (scene, start, stop, count, expected) in EXPECTED {
        let (reference, width, height) = load(&format!("{scene}-reference.exr"));
        let (test, ..) = load(&format!("{scene}-test.exr"));
        let e = Exposures::of(&reference);
        assert!((e.start - start).abs() < 1e-4 && (e.stop - stop).abs() < 1e-4 && e.count == count, "{scene}: {e:?}");
        let score = hdr_flip(&test, &reference, width, height);
        // The one difference: each exposure reaches LDR-FLIP as 8-bit sRGB.
        assert!((score - expected).abs() < 0.005 * expected, "{scene}: {score} against {expected}");
    }
}
