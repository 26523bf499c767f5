//! Output paths and display flags are checked before any work starts, and images are written
//! whole or not at all.

mod common;

use common::rrf;

#[test]
fn bad_outputs_fail_before_any_work_and_name_the_problem() {
    let dir = std::env::temp_dir().join(format!("rrf-outputs-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let jpg = dir.join("frame.jpg");
    let missing = dir.join("no-such-folder").join("frame.png");
    for command in ["render", "reference"] {
        for (output, needle) in [(&jpg, ".exr (linear HDR) or .png"), (&missing, "does not exist")] {
            let run = rrf(&[command, "scenes/cornell-box", "-o", output.to_str().unwrap()], &[]);
            let stderr = String::from_utf8_lossy(&run.stderr);
            assert!(!run.status.success(), "{command} -o {}", output.display());
            assert!(stderr.contains(needle) && stderr.contains(output.to_str().unwrap()), "{command}: {stderr}");
            // Nothing was rendered: no progress, no Vulkan device chosen.
            assert!(!stderr.contains("wrote"), "{stderr}");
        }
    }
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn exposure_must_be_a_finite_number_of_stops() {
    for bad in ["nan", "inf", "-1e9", "bright"] {
        let run = rrf(&["render", "scenes/cornell-box", "--exposure", bad, "-o", "x.png"], &[]);
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert!(!run.status.success() && stderr.contains("between -20 and 20"), "--exposure {bad}: {stderr}");
    }
}

/// A render over an existing image replaces it whole, with no temporary file left: the image
/// is then, pixel for pixel, the second render's, as written to a fresh file.
#[test]
fn images_are_replaced_whole() {
    let dir = std::env::temp_dir().join(format!("rrf-atomic-{}", std::process::id()));
    let fresh = std::env::temp_dir().join(format!("rrf-atomic-fresh-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::create_dir_all(&fresh).unwrap();
    let out = dir.join("frame.png");
    let render = |exposure: &str, to: &std::path::Path| {
        let args = ["render", "scenes/cornell-box", "--cpu", "--size", "16x16", "--exposure", exposure];
        let run = rrf(&[&args[..], &["-o", to.to_str().unwrap()]].concat(), &[]);
        assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
        image::open(to).unwrap().to_rgb8()
    };
    let first = render("0", &out);
    let replaced = render("-1.5", &out);
    let names: Vec<String> =
        std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    assert_eq!(names, ["frame.png"], "no temporary file is left beside the image");
    let expected = render("-1.5", &fresh.join("frame.png"));
    assert_eq!(replaced.dimensions(), (16, 16));
    assert!(replaced == expected, "the replaced image is not the second render's");
    assert!(replaced != first, "the two exposures render the same image: nothing was replaced");
    std::fs::remove_dir_all(dir).unwrap();
    std::fs::remove_dir_all(fresh).unwrap();
}

/// An EXR lists its chunks in increasing order, so the same pixels always make the same bytes
/// (chunks compressed in parallel with no order asked for land as they finish): two writes of
/// the same reference are byte-identical, and the header says the order.
#[test]
fn exr_files_are_the_same_bytes_for_the_same_pixels() {
    let dir = std::env::temp_dir().join(format!("rrf-exr-order-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let write = |name: &str| {
        let out = dir.join(name);
        let args = ["reference", "scenes/cornell-box", "--size", "300x200", "--spp", "1", "-o"];
        let run = rrf(&[&args[..], &[out.to_str().unwrap()]].concat(), &[]);
        assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
        out
    };
    let (a, b) = (write("a.exr"), write("b.exr"));
    let meta = exr::meta::MetaData::read_from_file(&a, false).unwrap();
    assert_eq!(meta.headers[0].line_order, exr::meta::attribute::LineOrder::Increasing);
    assert!(std::fs::read(&a).unwrap() == std::fs::read(&b).unwrap(), "two writes of the same image differ");
    std::fs::remove_dir_all(dir).unwrap();
}

/// `rrf info SCENE | head -1`: a reader that stops early ends rrf quietly, not with a panic.
#[test]
fn a_closed_standard_output_ends_quietly() {
    use std::io::Read;
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_rrf"))
        .args(["info", "scenes/many-objects"])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // Closed before rrf prints anything, so that every print meets the closed pipe.
    drop(child.stdout.take());
    let mut stderr = String::new();
    child.stderr.take().unwrap().read_to_string(&mut stderr).unwrap();
    child.wait().unwrap();
    assert!(!stderr.contains("panicked"), "{stderr}");
}

#[test]
fn counts_outside_their_documented_range_are_refused() {
    for (args, flag) in [
        (&["eval", "scenes/cornell-box", "--configs", "1000000000000", "-o", "x"][..], "--configs"),
        (&["eval", "scenes/cornell-box", "--configs", "18446744073709551615", "-o", "x"][..], "--configs"),
        (&["eval", "scenes/cornell-box", "--spp", "0", "-o", "x"][..], "--spp"),
        (&["reference", "scenes/cornell-box", "--spp", "4294967295", "-o", "x.png"][..], "--spp"),
        (&["reference", "scenes/cornell-box", "--max-depth", "0", "-o", "x.png"][..], "--max-depth"),
        (&["bench", "scenes/cornell-box", "--frames", "0"][..], "--frames"),
    ] {
        let run = rrf(args, &[]);
        let stderr = String::from_utf8_lossy(&run.stderr);
        // clap's usage error: exit 2, the flag and its range named; never an abort (134).
        assert_eq!(run.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(flag) && stderr.contains("in "), "{args:?}: {stderr}");
    }
}
