//! `cargo xtask slurm-bake`: a bake run for real as Slurm array jobs on a one-node cluster
//! started on this machine (Debian's `slurm-wlm` and `munge`), checked against a bake in one
//! process. It exercises `baker/cluster/slurm-bake.sh`, the script users submit with.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Shards per stage, and the scene and quality the check bakes (seconds per stage).
const SHARDS: u32 = 3;
const SCENE: &str = "scenes/cornell-box";
const QUALITY: &str = "test";

pub fn run(root: &Path) -> Result<(), String> {
    let work = root.join("target/slurm");
    let _ = std::fs::remove_dir_all(&work);
    for dir in ["state", "spool", "bake"] {
        std::fs::create_dir_all(work.join(dir)).map_err(|e| format!("{}: {e}", work.display()))?;
    }
    let rrf = root.join("target/release/rrf");
    let conf = write_config(&work)?;
    start_munge()?;
    let cluster = Cluster::start(&conf)?;
    let result = bake_and_compare(root, &work, &rrf, &conf);
    cluster.stop();
    result
}

/// slurm.conf for one node, this machine, with every path under `work`.
fn write_config(work: &Path) -> Result<PathBuf, String> {
    let host = output(Command::new("hostname").arg("-s"))?.trim().to_string();
    let cpus = std::thread::available_parallelism().map_or(1, |n| n.get());
    let w = work.display();
    let text = format!(
        "ClusterName=rrf\nSlurmctldHost={host}\nSlurmUser=root\nSlurmdUser=root\nAuthType=auth/munge\n\
         CredType=cred/munge\nProctrackType=proctrack/linuxproc\nTaskPlugin=task/none\n\
         SelectType=select/cons_tres\nSelectTypeParameters=CR_Core\nSchedulerType=sched/backfill\n\
         StateSaveLocation={w}/state\nSlurmdSpoolDir={w}/spool\nSlurmctldPidFile={w}/slurmctld.pid\n\
         SlurmdPidFile={w}/slurmd.pid\nSlurmctldLogFile={w}/slurmctld.log\nSlurmdLogFile={w}/slurmd.log\n\
         ReturnToService=2\nMpiDefault=none\nJobCompType=jobcomp/none\n\
         AccountingStorageType=accounting_storage/none\n\
         NodeName={host} CPUs={cpus} State=UNKNOWN\n\
         PartitionName=rrf Nodes={host} Default=YES MaxTime=INFINITE State=UP\n"
    );
    let path = work.join("slurm.conf");
    std::fs::write(&path, text).map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(path)
}

/// munged with the key the package made, unless one already answers.
fn start_munge() -> Result<(), String> {
    if Command::new("munge").arg("-n").stdout(Stdio::null()).stderr(Stdio::null()).status().is_ok_and(|s| s.success()) {
        return Ok(());
    }
    std::fs::create_dir_all("/run/munge").map_err(|e| format!("/run/munge: {e}"))?;
    run_ok(Command::new("chown").args(["munge:munge", "/run/munge"]))?;
    run_ok(Command::new("su").args(["-s", "/bin/sh", "munge", "-c", "/usr/sbin/munged"]))?;
    run_ok(Command::new("munge").arg("-n").stdout(Stdio::null()))
}

/// slurmctld and slurmd, stopped again by [`Cluster::stop`].
struct Cluster {
    conf: PathBuf,
}

impl Cluster {
    fn start(conf: &Path) -> Result<Cluster, String> {
        let cluster = Cluster { conf: conf.to_path_buf() };
        for daemon in ["slurmctld", "slurmd"] {
            if let Err(e) = run_ok(Command::new(daemon).env("SLURM_CONF", conf)) {
                cluster.stop();
                return Err(e);
            }
        }
        let start = Instant::now();
        loop {
            let state = output(Command::new("sinfo").args(["-h", "-o", "%t"]).env("SLURM_CONF", conf));
            if state.as_deref().is_ok_and(|s| s.trim() == "idle") {
                return Ok(cluster);
            }
            if start.elapsed() > Duration::from_secs(60) {
                cluster.stop();
                return Err(format!(
                    "the Slurm node is not idle after 60 s (sinfo: {state:?}); logs in {}",
                    conf.display()
                ));
            }
            std::thread::sleep(Duration::from_millis(500));
        }
    }

    fn stop(&self) {
        let _ = Command::new("scancel").arg("--user=root").env("SLURM_CONF", &self.conf).status();
        for daemon in ["slurmd", "slurmctld"] {
            let pid_file = self.conf.with_file_name(format!("{daemon}.pid"));
            if let Ok(pid) = std::fs::read_to_string(&pid_file) {
                let _ = Command::new("kill").arg(pid.trim()).status();
            }
        }
    }
}

/// Bakes the scene in one process and through the cluster, and compares the two models.
fn bake_and_compare(root: &Path, work: &Path, rrf: &Path, conf: &Path) -> Result<(), String> {
    let bake = work.join("bake");
    let scene = root.join(SCENE);
    let (whole, split) = (bake.join("whole.safetensors"), bake.join("split.safetensors"));
    let bake_args =
        |model: &Path| vec!["--quality".to_string(), QUALITY.into(), "-o".into(), model.display().to_string()];
    run_ok(Command::new(rrf).arg("bake").arg(&scene).args(bake_args(&whole)).current_dir(&bake))?;
    let script = root.join("baker/cluster/slurm-bake.sh");
    eprintln!(
        "xtask: {} {} {SHARDS} (sample, aim, train: {SHARDS} tasks each; then merge)",
        script.display(),
        scene.display()
    );
    let merge = output(
        Command::new("sh")
            .arg(&script)
            .arg(&scene)
            .arg(SHARDS.to_string())
            .args(bake_args(&split))
            .env("SLURM_CONF", conf)
            .env("RRF", rrf)
            .current_dir(&bake),
    )?;
    let start = Instant::now();
    while output(Command::new("squeue").args(["-h", "-o", "%i"]).env("SLURM_CONF", conf))?.trim() != "" {
        if start.elapsed() > Duration::from_secs(900) {
            return Err(format!("the Slurm jobs did not finish in 15 minutes; logs in {}", bake.display()));
        }
        std::thread::sleep(Duration::from_secs(1));
    }
    let read =
        |p: &Path| std::fs::read(p).map_err(|e| format!("{}: {e} (job logs in {})", p.display(), bake.display()));
    if read(&whole)? != read(&split)? {
        return Err(format!("{} differs from {}", split.display(), whole.display()));
    }
    eprintln!("xtask: Slurm bake (merge job {}) wrote a model byte-identical to the bake in one process", merge.trim());
    Ok(())
}

fn run_ok(cmd: &mut Command) -> Result<(), String> {
    let status = cmd.status().map_err(|e| format!("cannot run {:?}: {e}", cmd.get_program()))?;
    status.success().then_some(()).ok_or_else(|| format!("{:?} failed: {status}", cmd.get_program()))
}

fn output(cmd: &mut Command) -> Result<String, String> {
    let out = cmd.output().map_err(|e| format!("cannot run {:?}: {e}", cmd.get_program()))?;
    if !out.status.success() {
        return Err(format!("{:?} failed: {}", cmd.get_program(), String::from_utf8_lossy(&out.stderr)));
    }
    Ok(String::from_utf8_lossy(&out.stdout).into_owned())
}
