//! The golden image: `rrf render scenes/cornell-box` from the shipped model, through the
//! whole GPU path (G-buffer, network pass, tonemap), against `tests/golden/cornell-box.png`.
//!
//! After a change that is meant to alter the picture, look at the new image and bless it
//! with `RRF_BLESS=1 cargo test --release --test golden_image`.

mod common;

use std::path::Path;

use common::{difference, rrf};

const SIZE: &str = "128x128";
/// Largest difference in 8-bit levels that most pixels may show (rounding, fma, tanh).
const LEVELS: u8 = 2;

fn load(path: &Path) -> image::RgbImage {
    image::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())).to_rgb8()
}

#[test]
fn cornell_box_matches_the_golden_image() {
    let golden = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/golden/cornell-box.png");
    let out = std::env::temp_dir().join(format!("rrf-golden-{}.png", std::process::id()));
    let run = rrf(
        &["render", "scenes/cornell-box", "--size", SIZE, "-o", out.to_str().unwrap()],
        &[("RRF_VALIDATION", "required")],
    );
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    if std::env::var_os("RRF_BLESS").is_some() {
        std::fs::copy(&out, &golden).unwrap();
        eprintln!("blessed {}", golden.display());
    }
    let (new, old) = (load(&out), load(&golden));
    let _ = std::fs::remove_file(&out);
    let (off, mean) = difference(&new, &old, LEVELS);
    let n = (new.width() * new.height()) as usize;
    eprintln!("{off} of {n} pixels differ by more than {LEVELS} levels; mean difference {mean:.3}");
    assert!(off * 1000 <= n, "{off} of {n} pixels differ from the golden image by more than {LEVELS} levels");
    assert!(mean < 0.5, "mean difference {mean:.3} levels");
}
