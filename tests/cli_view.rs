//! `rrf view`: a scripted run in a real window under Xvfb (camera move, light move, component
//! switch, resize) with core and synchronization validation required, its screenshot against
//! `rrf render` of the same view, light and size; the headless fallback; script errors.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use common::{difference, rrf};

fn temp(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("rrf-view-{}-{name}", std::process::id()))
}

fn load(path: &Path) -> image::RgbImage {
    image::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())).to_rgb8()
}

/// Runs `rrf ARGS` in a window on a fresh Xvfb display.
fn rrf_in_xvfb(args: &[&str]) -> std::process::Output {
    in_xvfb(&[&[env!("CARGO_BIN_EXE_rrf")], args].concat())
}

/// Runs the command `command` (a program and its arguments) on a fresh Xvfb display
/// (`xvfb-run`, which `cargo xtask setup` installs, with xdotool), with rrf on lavapipe and
/// validation required.
fn in_xvfb(command: &[&str]) -> std::process::Output {
    let xvfb = Command::new("xvfb-run")
        .args(["-a", "-s", "-screen 0 1280x1024x24"])
        .args(command)
        .env("RRF_DEVICE", "llvmpipe")
        .env("RRF_VALIDATION", "required")
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output();
    xvfb.unwrap_or_else(|e| panic!("cannot run xvfb-run ({e}); install Xvfb and xdotool with `cargo xtask setup`"))
}

/// Asserts that the viewer's screenshot `shot` shows the frame that `rrf render` makes of the
/// Cornell box with `args` at `(width, height)`: at most 1% of the pixels more than 2 levels
/// off, and a mean difference under half a level.
fn assert_same_as_render(shot: &Path, args: &[&str], (width, height): (u32, u32)) {
    let reference = temp(&format!("render-{}", shot.file_name().unwrap().to_string_lossy()));
    let size = format!("{width}x{height}");
    let common = ["render", "scenes/cornell-box", "--size", &size, "-o", reference.to_str().unwrap()];
    let render = rrf(&[&common[..], args].concat(), &[("RRF_VALIDATION", "required")]);
    assert!(render.status.success(), "{}", String::from_utf8_lossy(&render.stderr));
    let (off, mean) = difference(&load(shot), &load(&reference), 2);
    eprintln!("{off} pixels differ by more than 2 levels; mean {mean:.3}");
    assert!(off * 100 <= (width * height) as usize, "{off} pixels differ from rrf render by more than 2 levels");
    assert!(mean < 0.5, "mean difference {mean:.3} levels");
    let _ = std::fs::remove_file(reference);
}

#[test]
fn scripted_window_run_is_clean_and_matches_render() {
    let shot = temp("window.png");
    let script = temp("script.txt");
    let (eye, target, light) = ("0.40,0.35,-0.45", "0.22,0.2,0.35", "0.2,0.47,0.3");
    std::fs::write(
        &script,
        format!(
            "# every kind of event the test needs\n\
             0    camera 0.278,0.273,-0.8 0.278,0.273,0.2\n\
             0.05 camera {eye} {target} over 0.2\n\
             0.1  light {light} over 0.15\n\
             0.2  component indirect\n\
             0.25 resize 200x150\n\
             0.35 component gi\n\
             0.45 screenshot {}\n\
             0.5  quit\n",
            shot.display()
        ),
    )
    .unwrap();
    let run = rrf_in_xvfb(&[
        "view",
        "scenes/cornell-box",
        "--size",
        "256x192",
        "--no-overlay",
        "--stats",
        "--script",
        script.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "rrf view failed:\n{stderr}");
    assert!(!stderr.contains("headless"), "the run did not open a window:\n{stderr}");
    assert!(stderr.contains(&format!("saved screenshot {}", shot.display())), "{stderr}");
    let stats: serde_json::Value = serde_json::from_slice(&run.stdout).expect("--stats prints one JSON line");
    assert_eq!(stats["frames"], 31, "0.5 s of script time at 60 frames per second, plus the last frame");
    assert!(stats["gpu_ms"]["network_ms"].as_f64().unwrap() > 0.0);
    let startup = &stats["start_s"];
    let phases = ["scene_and_model", "vulkan", "frame_set_up", "first_frame"].map(|k| startup[k].as_f64().unwrap());
    let total = startup["total"].as_f64().unwrap();
    assert!((phases.iter().sum::<f64>() - total).abs() < 1e-6 && phases[2] > 0.0, "start-up {startup}");
    assert!(stderr.contains("start-up ") && stderr.contains("first frame"), "{stderr}");

    let camera = format!("{eye}:{target}");
    assert_eq!(load(&shot).dimensions(), (200, 150), "the screenshot has the size the script asked for");
    assert_same_as_render(&shot, &["--camera", &camera, "--light", light], (200, 150));
    for f in [shot, script] {
        let _ = std::fs::remove_file(f);
    }
}

/// Lights added, moved, recoloured and removed by a script give the frame that `rrf render`
/// gives with the lights that are left.
#[test]
fn scripted_light_edits_match_render_with_the_same_lights() {
    let shot = temp("lights.png");
    let script = temp("lights.txt");
    std::fs::write(
        &script,
        format!(
            "0    add-light 0.2,0.5,0.2:color=1,0.5,0.2\n\
             0.05 light 0.36,0.45,0.38 over 0.1\n\
             0.2  add-light 0.3,0.5,0.3\n\
             0.25 light-color 0.3,0.5,1 intensity 2\n\
             0.3  select-light 1\n\
             0.35 remove-light\n\
             0.45 screenshot {}\n",
            shot.display()
        ),
    )
    .unwrap();
    let run = rrf(
        &[
            "view",
            "scenes/cornell-box",
            "--headless",
            "--size",
            "96x96",
            "--no-overlay",
            "--script",
            script.to_str().unwrap(),
        ],
        &[("RRF_VALIDATION", "required")],
    );
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let lights = ["--light", "0.36,0.45,0.38:color=1,0.5,0.2", "--light", "0.3,0.5,0.3:color=0.3,0.5,1:intensity=2"];
    assert_same_as_render(&shot, &lights, (96, 96));
    for f in [shot, script] {
        let _ = std::fs::remove_file(f);
    }
}

/// A scene whose networks also learned another light refuses a second light, naming it.
#[test]
fn a_scene_with_other_lights_refuses_a_second_one() {
    let script = temp("gallery-lights.txt");
    std::fs::write(&script, "0.1 add-light 0,2.5,0\n").unwrap();
    let run =
        rrf(&["view", "scenes/gallery", "--headless", "--size", "32x32", "--script", script.to_str().unwrap()], &[]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(!run.status.success());
    assert!(stderr.contains("script event at 0.1 s") && stderr.contains("Screen"), "{stderr}");
    let out = temp("gallery.png");
    let render = rrf(&["render", "scenes/gallery", "--light", "default:intensity=2", "-o", out.to_str().unwrap()], &[]);
    let stderr = String::from_utf8_lossy(&render.stderr);
    assert!(!render.status.success() && stderr.contains("also lit by Screen"), "{stderr}");
    assert!(!out.exists());
    let _ = std::fs::remove_file(script);
}

#[test]
fn without_a_display_it_renders_headless_and_says_where() {
    let dir = temp("headless");
    std::fs::create_dir_all(&dir).unwrap();
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_rrf"));
    cmd.args(["view", "scenes/cornell-box", "--size", "64x48", "--no-overlay"])
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .env("RRF_DEVICE", "llvmpipe")
        .env("RRF_VALIDATION", "required")
        .arg("--screenshot")
        .arg(dir.join("view.png"))
        .current_dir(env!("CARGO_MANIFEST_DIR"));
    let run = cmd.output().unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    assert!(stderr.contains("no display") && stderr.contains("rendering headless"), "{stderr}");
    assert!(stderr.contains("saved screenshot"), "{stderr}");
    assert_eq!(load(&dir.join("view.png")).dimensions(), (64, 48));
    // The viewer's first frame: the sidecar's default view and the light where the glTF puts it.
    assert_same_as_render(&dir.join("view.png"), &[], (64, 48));
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn a_bad_script_names_the_file_and_line() {
    let script = temp("bad.txt");
    std::fs::write(&script, "0 camera 0,0,0 1,1,1\n1 fly 2,2,2\n").unwrap();
    let run = rrf(&["view", "scenes/cornell-box", "--headless", "--script", script.to_str().unwrap()], &[]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(!run.status.success());
    assert!(
        stderr.contains(script.to_str().unwrap()) && stderr.contains("line 2") && stderr.contains("unknown command")
    );
    let _ = std::fs::remove_file(script);
}

#[test]
fn shipped_demo_scripts_parse() {
    for scene in ["cornell-box", "glossy-room", "many-objects", "gallery"] {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(scene).join("demo.txt");
        let script = rrf::viewer::script::Script::load(&path).unwrap();
        assert!(script.frames() > 60, "{scene}'s demo is too short");
    }
}

/// The median display-linear luminance of the pixels of `image` in columns `columns` that are
/// not pure black (as the automatic exposure's meter reads them).
fn median_luminance(image: &image::RgbImage, columns: std::ops::Range<u32>) -> f32 {
    let linear = |c: u8| {
        let c = f32::from(c) / 255.0;
        if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    };
    let mut values: Vec<f32> = image
        .enumerate_pixels()
        .filter(|(x, _, p)| columns.contains(x) && p.0 != [0, 0, 0])
        .map(|(_, _, p)| 0.2126 * linear(p.0[0]) + 0.7152 * linear(p.0[1]) + 0.0722 * linear(p.0[2]))
        .collect();
    values.sort_by(f32::total_cmp);
    values[values.len() / 2]
}

#[test]
fn the_settings_panel_draws_in_a_window_and_hides_again() {
    let (with, without) = (temp("panel-on.png"), temp("panel-off.png"));
    let script = temp("panel.txt");
    std::fs::write(
        &script,
        format!(
            "0    panel on\n\
             0    boxes on\n\
             0.1  resize 480x270\n\
             0.3  screenshot {}\n\
             0.35 panel off\n\
             0.35 boxes off\n\
             0.45 screenshot {}\n",
            with.display(),
            without.display()
        ),
    )
    .unwrap();
    let run = rrf_in_xvfb(&[
        "view",
        "scenes/cornell-box",
        "--size",
        "400x240",
        "--no-overlay",
        "--script",
        script.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "rrf view failed:\n{stderr}");
    assert!(!stderr.contains("headless"), "the run did not open a window:\n{stderr}");
    let (with, without) = (load(&with), load(&without));
    assert_eq!(with.dimensions(), (480, 270));
    // The panel is 270 points wide, on the right: there the two frames differ; to its left
    // only the boxes' outlines do.
    let differs = |x0: u32, x1: u32| {
        let mut n = 0;
        for y in 0..270 {
            for x in x0..x1 {
                let (a, b) = (with.get_pixel(x, y).0, without.get_pixel(x, y).0);
                n += usize::from(a.iter().zip(b).any(|(a, b)| a.abs_diff(b) > 2));
            }
        }
        n as f64 / f64::from((x1 - x0) * 270)
    };
    let (panel, scene) = (differs(215, 480), differs(0, 205));
    assert!(panel > 0.5, "only {:.0}% of the panel's pixels differ", panel * 100.0);
    assert!(
        scene > 0.002 && scene < 0.1,
        "{:.1}% of the pixels left of the panel differ (outlines only)",
        scene * 100.0
    );
    // egui's dark panel: mostly dark grey, with lighter text.
    let panel_pixels: Vec<u8> =
        (0..270).flat_map(|y| (215..480).map(move |x| (x, y))).map(|(x, y)| with.get_pixel(x, y).0[1]).collect();
    let dark = panel_pixels.iter().filter(|v| (10..60).contains(*v)).count() as f64 / panel_pixels.len() as f64;
    let light = panel_pixels.iter().filter(|v| **v > 150).count();
    assert!(
        dark > 0.6 && light > 200,
        "the panel is not dark with light text ({:.0}% dark, {light} light)",
        dark * 100.0
    );
    let _ = std::fs::remove_file(script);
}

#[test]
fn automatic_exposure_brings_a_dark_frame_to_mid_grey() {
    let (auto, fixed) = (temp("auto.png"), temp("fixed.png"));
    let shoot = |script: &str, shot: &Path| {
        let path = temp(&format!("{}.txt", shot.file_stem().unwrap().to_string_lossy()));
        std::fs::write(&path, format!("{script}2 screenshot {}\n", shot.display())).unwrap();
        let run = rrf(
            &[
                "view",
                "scenes/cornell-box",
                "--headless",
                "--size",
                "160x90",
                "--no-overlay",
                "--script",
                path.to_str().unwrap(),
            ],
            &[("RRF_VALIDATION", "required")],
        );
        assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
        let _ = std::fs::remove_file(path);
        load(shot)
    };
    let dark = median_luminance(&shoot("0 exposure -6\n", &fixed), 0..160);
    let metered = median_luminance(&shoot("0 exposure -6\n0 exposure auto\n", &auto), 0..160);
    assert!(dark < 0.01, "at -6 EV the median pixel is {dark}");
    assert!(
        (0.09..0.36).contains(&metered),
        "after 2 s of automatic exposure the median pixel is {metered}, not about 0.18"
    );
    for f in [auto, fixed] {
        let _ = std::fs::remove_file(f);
    }
}

/// Switching direct light makes the frame again; the result is the frame that starts that
/// way, and the panel's texts (whose font texture the new frame inherits) still draw.
#[test]
fn switching_direct_light_gives_the_frame_that_starts_that_way() {
    let (switched, fresh) = (temp("switched.png"), temp("fresh.png"));
    let shoot = |direct: &str, events: &str, shot: &Path| {
        let path = temp(&format!("{}.txt", shot.file_stem().unwrap().to_string_lossy()));
        std::fs::write(&path, format!("0 panel on\n{events}0.15 screenshot {}\n", shot.display())).unwrap();
        let args =
            ["view", "scenes/many-objects", "--headless", "--size", "480x270", "--no-overlay", "--direct", direct];
        let run = rrf(&[&args[..], &["--script", path.to_str().unwrap()]].concat(), &[("RRF_VALIDATION", "required")]);
        assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
        let _ = std::fs::remove_file(path);
        load(shot)
    };
    let switched_image = shoot("analytic", "0.05 direct learned\n", &switched);
    let fresh_image = shoot("learned", "", &fresh);
    // The same pixels everywhere but the panel's frame-rate line.
    let differing: Vec<(u32, u32)> = switched_image
        .enumerate_pixels()
        .filter(|(x, y, p)| p.0 != fresh_image.get_pixel(*x, *y).0)
        .map(|(x, y, _)| (x, y))
        .collect();
    assert!(
        differing.iter().all(|&(x, y)| x >= 210 && y < 45),
        "pixels differ outside the frame-rate line: {:?}",
        &differing[..differing.len().min(5)]
    );
    let script = temp("bad-direct.txt");
    std::fs::write(&script, "0.05 direct analytic\n").unwrap();
    let run =
        rrf(&["view", "scenes/gallery", "--headless", "--size", "32x32", "--script", script.to_str().unwrap()], &[]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(
        !run.status.success() && stderr.contains("direct analytic") && stderr.contains("script event at 0.05 s"),
        "{stderr}"
    );
    for f in [switched, fresh, script] {
        let _ = std::fs::remove_file(f);
    }
}

/// Runs the Cornell box at 480×270 with the panel in a window on a fresh Xvfb display, playing
/// `script`; once the panel is laid out, xdotool gives the window the keyboard focus (there is
/// no window manager to) and does `actions` (xdotool commands), if any. Returns stderr.
/// At this size the panel's left edge is at x = 210 and its "add" button at about (251, 95).
fn panel_run(script: &str, actions: &str) -> String {
    let name = format!("xdotool-{}-{}", script.len(), actions.len());
    let (path, log) = (temp(&format!("{name}.txt")), temp(&format!("{name}.log")));
    // Script time runs on while xdotool acts; the run ends by itself.
    std::fs::write(&path, script).unwrap();
    let rrf_bin = env!("CARGO_BIN_EXE_rrf");
    // The actions wait for the first frame (start-up is printed after it) and one more, so
    // that egui has laid the panel out.
    let xdotool = match actions {
        "" => String::new(),
        _ => format!(
            "until grep -q start-up {} || ! kill -0 $pid 2>/dev/null; do sleep 0.2; done; sleep 1; \
             xdotool search --name 'rrf view' windowfocus --sync; xdotool {actions}; ",
            log.display()
        ),
    };
    let run = format!(
        "{rrf_bin} view scenes/cornell-box --size 480x270 --panel --no-overlay --script {} 2>{} & pid=$!; \
         {xdotool}wait $pid",
        path.display(),
        log.display(),
    );
    let xvfb = in_xvfb(&["bash", "-c", &run]);
    let stderr = std::fs::read_to_string(&log).unwrap_or_default();
    assert!(xvfb.status.success(), "rrf view failed:\n{stderr}");
    for f in [path, log] {
        let _ = std::fs::remove_file(f);
    }
    stderr
}

/// A click on the panel's "add" button adds a light: the mouse reaches egui through the
/// window, and the frame then has two lights.
#[test]
fn a_click_on_the_panel_adds_a_light() {
    let stderr = panel_run("4 quit\n", "mousemove 251 95 click 1");
    assert!(stderr.contains("first frame with several lights"), "the click added no light:\n{stderr}");
}

/// The walkthrough's keys reach it while the panel shows, Tab included (egui would take Tab
/// for its own focus): after a click on "add" (light 2 selected), Tab selects light 1 and C
/// makes it warm; the panel then shows what a script that does the same shows.
#[test]
fn keys_reach_the_walkthrough_beside_the_panel() {
    let (keys, scripted) = (temp("keys.png"), temp("scripted.png"));
    panel_run(
        &format!("4 screenshot {}\n", keys.display()),
        "mousemove 251 95 click 1 sleep 0.5 mousemove 100 200 key Tab sleep 0.3 key c",
    );
    let light = "0.278,0.5478,0.2795";
    panel_run(
        &format!(
            "0 add-light {light}\n0 select-light 1\n0 light-color 1,0.75,0.5\n4 screenshot {}\n",
            scripted.display()
        ),
        "",
    );
    let (keys, scripted) = (load(&keys), load(&scripted));
    // The lights' labels (which is selected) and the selected light's colour swatch.
    for (x0, y0, x1, y1) in [(230, 62, 340, 86), (235, 188, 280, 206)] {
        for y in y0..y1 {
            for x in x0..x1 {
                let (a, b) = (keys.get_pixel(x, y).0, scripted.get_pixel(x, y).0);
                assert!(
                    a.iter().zip(b).all(|(a, b)| a.abs_diff(b) <= 2),
                    "({x}, {y}): {a:?} after the keys, {b:?} scripted"
                );
            }
        }
    }
}
