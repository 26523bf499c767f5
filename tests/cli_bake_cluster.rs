//! A bake split across processes, as a cluster's array jobs run it: three shards of each stage
//! (sample, aim, train), then the merge, write a model byte-identical to a bake in one process
//! with the same seed, whether the shards run one after another or at the same time. A re-run
//! shard writes the same bytes, and a stage started before the one it needs, or a merge
//! without every train shard, names the missing file and the stage to run.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

use common::rrf_command;

fn bake(output: &Path, extra: &[&str]) -> Output {
    bake_command(output, extra).output().expect("run rrf")
}

fn bake_command(output: &Path, extra: &[&str]) -> Command {
    let output = output.to_str().unwrap();
    let mut args = vec!["bake", "scenes/cornell-box", "--quality", "test", "--seed", "3", "-o", output];
    args.extend(extra);
    rrf_command(&args, &[])
}

/// A fresh folder for test `name`: the tests run in parallel, so each needs its own.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("rrf-bake-cluster-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn succeeds(run: Output) -> String {
    let stderr = String::from_utf8_lossy(&run.stderr).into_owned();
    assert!(run.status.success(), "{stderr}");
    stderr
}

#[test]
fn three_shards_per_stage_then_a_merge_make_the_same_model() {
    let dir = scratch("shards");
    let whole = dir.join("whole.safetensors");
    succeeds(bake(&whole, &[]));

    let split = dir.join("split.safetensors");
    let cache = dir.join("split.bake-cache");
    let early = bake(&split, &["--stage", "train", "--shard", "0/3"]);
    let stderr = String::from_utf8_lossy(&early.stderr);
    assert_eq!(early.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("shard-00000.bin: missing") && stderr.contains("--stage sample"), "{stderr}");

    for stage in ["sample", "aim", "train"] {
        for i in 0..3 {
            let stderr = succeeds(bake(&split, &["--stage", stage, "--shard", &format!("{i}/3")]));
            assert!(stderr.contains(&format!("stage {stage} shard {i}/3")), "{stderr}");
        }
    }
    // The scheduler retries a shard: the same file, byte for byte.
    let shard = cache.join("shard-00001.bin");
    let first = std::fs::read(&shard).unwrap();
    std::fs::remove_file(&shard).unwrap();
    succeeds(bake(&split, &["--stage", "sample", "--shard", "1/3"]));
    assert_eq!(std::fs::read(&shard).unwrap(), first, "a re-run shard writes the same bytes");

    succeeds(bake(&split, &["--merge"]));
    assert!(std::fs::read(&whole).unwrap() == std::fs::read(&split).unwrap(), "merged model differs");
    assert!(!cache.exists(), "the merge removes the bake cache, as a bake does");
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn shard_arguments_are_checked() {
    let dir = scratch("args");
    let model = dir.join("m.safetensors");
    for (extra, expected) in [
        (&["--stage", "sample", "--shard", "3/3"][..], "expected I/N with 0 <= I < N"),
        (&["--stage", "sample"][..], "--shard"),
        (&["--shard", "0/2"][..], "--stage"),
        (&["--merge", "--stage", "aim", "--shard", "0/2"][..], "cannot be used with"),
    ] {
        let run = bake(&model, extra);
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert_eq!(run.status.code(), Some(2), "{extra:?}: {stderr}");
        assert!(stderr.contains(expected), "{extra:?}: {stderr}");
    }
}

/// A cluster runs a stage's shards at the same time on one bake cache: started together, the
/// three shards of each stage and then the merge still write the model of a bake in one
/// process. A merge with one train shard's networks missing names a missing file and the
/// stage to run, exits non-zero, writes no model and leaves the cache for the shard's re-run.
#[test]
fn shards_running_at_the_same_time_make_the_same_model() {
    let dir = scratch("together");
    let whole = dir.join("whole.safetensors");
    succeeds(bake(&whole, &[]));

    let split = dir.join("split.safetensors");
    let cache = dir.join("split.bake-cache");
    for stage in ["sample", "aim", "train"] {
        let shards: Vec<_> = (0..3)
            .map(|i| {
                bake_command(&split, &["--stage", stage, "--shard", &format!("{i}/3")])
                    .stdout(Stdio::null())
                    .stderr(Stdio::piped())
                    .spawn()
                    .unwrap()
            })
            .collect();
        for shard in shards {
            succeeds(shard.wait_with_output().unwrap());
        }
    }

    // One train shard's networks lost: the merge refuses.
    let networks: Vec<PathBuf> = std::fs::read_dir(&cache)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.file_name().unwrap().to_string_lossy().starts_with("network-"))
        .collect();
    assert!(!networks.is_empty(), "the train stage wrote no network files in {}", cache.display());
    let lost = &networks[0];
    let kept = std::fs::read(lost).unwrap();
    std::fs::remove_file(lost).unwrap();
    let merge = bake(&split, &["--merge"]);
    let stderr = String::from_utf8_lossy(&merge.stderr);
    assert_eq!(merge.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("missing") && stderr.contains("--stage train"), "{stderr}");
    assert!(!split.exists(), "a merge that failed wrote a model");
    assert!(cache.exists(), "a merge that failed removed the bake cache");

    std::fs::write(lost, kept).unwrap();
    succeeds(bake(&split, &["--merge"]));
    assert!(std::fs::read(&whole).unwrap() == std::fs::read(&split).unwrap(), "merged model differs");
    let _ = std::fs::remove_dir_all(dir);
}
