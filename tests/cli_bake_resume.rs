//! A `preview` bake killed during sampling (SIGKILL), again during training (SIGKILL), and
//! stopped once more with Ctrl-C (SIGINT), then run to the end, writes a model file
//! byte-identical to an uninterrupted bake with the same seed. A second bake of the same model
//! while one runs is refused, and a bake never writes its model over a file that is not one.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use common::{rrf, rrf_command};

fn bake_args(output: &Path) -> Vec<String> {
    ["bake", "scenes/cornell-box", "--quality", "preview", "--seed", "5", "--json", "-o"]
        .iter()
        .map(|s| s.to_string())
        .chain([output.to_string_lossy().into_owned()])
        .collect()
}

fn run_bake(output: &Path) -> std::process::Output {
    let args = bake_args(output);
    rrf(&args.iter().map(String::as_str).collect::<Vec<_>>(), &[])
}

fn start_bake(output: &Path) -> Child {
    start_bake_holding(output, None)
}

/// A bake that, given `hold_after`, stops once that many networks are done and waits to be
/// killed or interrupted (`RRF_BAKE_HOLD_AFTER_NETWORKS`): it cannot finish before the test's
/// signal reaches it.
fn start_bake_holding(output: &Path, hold_after: Option<usize>) -> Child {
    let args = bake_args(output);
    let hold = hold_after.map(|n| n.to_string());
    let env: Vec<(&str, &str)> = hold.iter().map(|n| ("RRF_BAKE_HOLD_AFTER_NETWORKS", n.as_str())).collect();
    rrf_command(&args.iter().map(String::as_str).collect::<Vec<_>>(), &env)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start rrf bake")
}

/// Finished cache files whose names start with `prefix`: not the temporary files
/// (`NAME.partial-PID.bin`) that become them when whole.
fn count(cache: &Path, prefix: &str) -> usize {
    std::fs::read_dir(cache).map_or(0, |entries| {
        entries
            .filter(|e| {
                let name = e.as_ref().unwrap().file_name().to_string_lossy().into_owned();
                name.starts_with(prefix) && !name.contains(".partial-")
            })
            .count()
    })
}

/// Waits until `ready` holds, failing if the bake ends first. The limit is only a guard
/// against a hung test, far above the seconds this takes.
fn wait_until(bake: &mut Child, what: &str, ready: impl Fn() -> bool) {
    let start = Instant::now();
    while !ready() {
        assert!(bake.try_wait().unwrap().is_none(), "the bake ended before {what}");
        assert!(start.elapsed() < Duration::from_secs(600), "no {what} after 10 minutes");
        std::thread::sleep(Duration::from_millis(20));
    }
}

fn signal(bake: &Child, signal: i32) {
    // SAFETY: kill(2) on the pid of a child this test started and has not reaped.
    assert_eq!(unsafe { libc::kill(bake.id() as i32, signal) }, 0);
}

#[test]
fn interrupted_bakes_resume_to_the_same_model() {
    let dir = std::env::temp_dir().join(format!("rrf-resume-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let reference: PathBuf = dir.join("reference.safetensors");
    let run = run_bake(&reference);
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));

    let model = dir.join("model.safetensors");
    let cache = dir.join("model.bake-cache");
    let lock = dir.join("model.lock");

    // Killed while sampling; a second bake of the same model meanwhile is refused.
    let mut bake = start_bake(&model);
    wait_until(&mut bake, "a sample shard", || count(&cache, "shard-") >= 1);
    let second = run_bake(&model);
    let stderr = String::from_utf8_lossy(&second.stderr);
    assert!(!second.status.success(), "a second bake of the same model must be refused");
    assert!(stderr.contains("another bake") && stderr.contains(&bake.id().to_string()), "{stderr}");
    signal(&bake, libc::SIGKILL);
    bake.wait().unwrap();
    assert!(!model.exists() && lock.exists(), "killed: no model, a stale lock left behind");

    // Killed while training, holding after its first network.
    let mut bake = start_bake_holding(&model, Some(1));
    wait_until(&mut bake, "a trained network", || count(&cache, "network-") >= 1);
    signal(&bake, libc::SIGKILL);
    bake.wait().unwrap();
    assert!(!model.exists());

    // Ctrl-C, holding after one network more than the cache has (so at least one trained
    // here): stops, says how to resume, releases the lock.
    let trained = count(&cache, "network-");
    let mut bake = start_bake_holding(&model, Some(trained + 1));
    wait_until(&mut bake, "another trained network", || count(&cache, "network-") > trained);
    signal(&bake, libc::SIGINT);
    let out = bake.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(130), "{stderr}");
    assert!(stderr.contains("to resume, run the same command again") && stderr.contains("rrf bake"), "{stderr}");
    assert!(!lock.exists() && !model.exists());

    // The last run finishes what is left.
    let out = start_bake(&model).wait_with_output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(report["resumed_shards"].as_u64().unwrap() > 0, "{report}");
    assert!(report["resumed_networks"].as_u64().unwrap() > 1, "{report}");
    assert_eq!(report["non_finite_dropped"], 0, "{report}");
    assert!(
        std::fs::read(&model).unwrap() == std::fs::read(&reference).unwrap(),
        "the resumed model must be byte-identical to the uninterrupted one"
    );
    assert!(!cache.exists() && !lock.exists(), "a finished bake leaves only its model");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_model_is_never_written_over_another_file() {
    let dir = std::env::temp_dir().join(format!("rrf-bake-output-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("scene.gltf");
    std::fs::copy("scenes/cornell-box/scene.gltf", &scene).unwrap();
    let before = std::fs::read(&scene).unwrap();
    for output in [scene.clone(), dir.join("model.bin"), dir.join("missing/model.safetensors")] {
        let run = rrf(&["bake", "scenes/cornell-box", "--quality", "test", "-o", output.to_str().unwrap()], &[]);
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert!(!run.status.success() && stderr.contains(output.to_str().unwrap()), "{stderr}");
        assert!(!stderr.contains("sampling"), "refused before any work: {stderr}");
    }
    assert!(std::fs::read(&scene).unwrap() == before, "the scene file is untouched");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Two bakes of one model started together, ten times: one bakes and the other says which
/// bake holds the model and exits non-zero (or, had the first already finished, bakes
/// again), and the model is whole each time, the same bytes as a bake run alone. With
/// `--wait` both bake, one after the other, to the same model.
#[test]
fn two_bakes_of_one_model_never_meet() {
    let dir = std::env::temp_dir().join(format!("rrf-bake-pairs-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let args = |output: &Path, wait: bool| {
        let mut args = vec!["bake", "scenes/cornell-box", "--quality", "test", "--seed", "3", "-o"];
        args.push(output.to_str().unwrap());
        if wait {
            args.push("--wait");
        }
        args.into_iter().map(String::from).collect::<Vec<_>>()
    };
    let start = |output: &Path, wait: bool| {
        Command::new(env!("CARGO_BIN_EXE_rrf"))
            .args(args(output, wait))
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .expect("start rrf bake")
    };
    let reference = dir.join("reference.safetensors");
    let alone = start(&reference, false).wait_with_output().unwrap();
    assert!(alone.status.success(), "{}", String::from_utf8_lossy(&alone.stderr));
    let expected = std::fs::read(&reference).unwrap();

    for pair in 0..11 {
        let wait = pair == 10;
        let model = dir.join(format!("model-{pair}.safetensors"));
        let bakes = [start(&model, wait), start(&model, wait)];
        let ids: Vec<u32> = bakes.iter().map(Child::id).collect();
        let outputs: Vec<_> = bakes.into_iter().map(|b| b.wait_with_output().unwrap()).collect();
        let refused: Vec<String> = outputs
            .iter()
            .filter(|o| !o.status.success())
            .map(|o| String::from_utf8_lossy(&o.stderr).into_owned())
            .collect();
        if wait {
            assert!(refused.is_empty(), "pair {pair}, --wait: both bake: {refused:?}");
        } else {
            assert!(refused.len() <= 1, "pair {pair}: at least one bake finishes: {refused:?}");
            for stderr in &refused {
                let names_the_other = ids.iter().any(|id| stderr.contains(&format!("process {id}")));
                assert!(stderr.contains("another bake") && names_the_other, "pair {pair}: {stderr}");
            }
        }
        assert!(std::fs::read(&model).unwrap() == expected, "pair {pair}: the model is not the lone bake's");
        assert!(!dir.join(format!("model-{pair}.lock")).exists(), "pair {pair}: the lock file is left");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
