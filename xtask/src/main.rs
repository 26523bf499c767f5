//! `cargo xtask <task>`: the README's two commands, the set-up they share, and the scene
//! generator.
//!
//! On Debian and Ubuntu each task first installs the system packages it needs that are
//! missing, with apt-get (through sudo when not root), and says exactly what it installs.
//! Elsewhere it prints the packages to look for and goes on.

mod scenes;
mod slurm;

use std::path::Path;
use std::process::{Command, ExitCode};

/// What running rrf needs: the Vulkan loader, lavapipe (Mesa's CPU Vulkan driver), and the X
/// client libraries that winit opens at run time for the viewer's window.
const RUN_PACKAGES: &[&str] = &[
    "libvulkan1",
    "mesa-vulkan-drivers",
    "libx11-6",
    "libx11-xcb1",
    "libxcursor1",
    "libxrandr2",
    "libxi6",
    "libxkbcommon-x11-0",
];
/// What the tests need on top: the Khronos validation layer, which every GPU test runs under,
/// a C++ compiler for the vendored glslang, Xvfb (with xauth, which xvfb-run needs) for the
/// viewer's window tests, and xdotool, which clicks in the window.
const TEST_PACKAGES: &[&str] = &["vulkan-validationlayers", "g++", "xvfb", "xauth", "xdotool"];

/// A one-node Slurm cluster for `slurm-bake`.
const SLURM_PACKAGES: &[&str] = &["slurm-wlm", "munge"];

/// The scene the main job runs on.
const DEFAULT_SCENE: &str = "scenes/cornell-box";

const USAGE: &str = "\
usage: cargo xtask <task>

tasks:
  run     install what rrf needs (apt-get), build it, and open the viewer on the default scene
          (without a display: render one frame headless to view.png)
  test    install what the tests need (apt-get), then run every test on lavapipe with the
          Vulkan validation layer on
  setup   only install the system packages that the tests need
  scenes  regenerate the scenes under scenes/ from xtask/src/scenes/
  slurm-bake
          start a one-node Slurm cluster here (installs slurm-wlm and munge), bake the Cornell
          box as array jobs with baker/cluster/slurm-bake.sh, and check the merged model is
          byte-identical to a bake in one process (root; builds rrf first)
  validate-k8s
          check baker/cluster/k8s-bake.yaml against the Kubernetes schemas (installs the
          kubernetes-validate tool from PyPI with pip)
  validate-gltf
          check the scenes' glTF with the Khronos glTF validator (installs it with npm into
          target/gltf-validator/; needs Node.js and npm)";

fn main() -> ExitCode {
    let task = std::env::args().nth(1).unwrap_or_default();
    let result = match task.as_str() {
        "run" => install(RUN_PACKAGES)
            .and_then(|()| cargo(&["run", "--release", "--", "info"]))
            .and_then(|()| cargo(&["run", "--release", "--", "view", DEFAULT_SCENE])),
        "test" => install(&[RUN_PACKAGES, TEST_PACKAGES].concat())
            .and_then(|()| cargo(&["run", "--release", "--", "info"]))
            .and_then(|()| cargo(&["test", "--release", "--workspace"])),
        "setup" => install(&[RUN_PACKAGES, TEST_PACKAGES].concat()),
        "scenes" => scenes::generate(repo_root()),
        "validate-gltf" => validate_gltf(repo_root()),
        "validate-k8s" => validate_k8s(repo_root()),
        "slurm-bake" => install(SLURM_PACKAGES)
            .and_then(|()| cargo(&["build", "--release", "--bin", "rrf"]))
            .and_then(|()| slurm::run(repo_root())),
        "-h" | "--help" | "help" => {
            println!("{USAGE}");
            Ok(())
        }
        _ => Err(format!("unknown task {task:?}\n\n{USAGE}")),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("xtask: {e}");
            ExitCode::FAILURE
        }
    }
}

fn repo_root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR")).parent().unwrap_or(Path::new("."))
}

/// The Khronos glTF validator, pinned.
const GLTF_VALIDATOR: &str = "gltf-validator@2.0.0-dev.3.10";

/// Runs the Khronos glTF validator over every shipped scene: no errors allowed.
fn validate_gltf(root: &Path) -> Result<(), String> {
    let prefix = root.join("target/gltf-validator");
    if !prefix.join("node_modules/gltf-validator").is_dir() {
        eprintln!("xtask: npm install {GLTF_VALIDATOR} into {}", prefix.display());
        let status = Command::new("npm")
            .args(["install", "--no-save", "--no-audit", "--no-fund", "--prefix"])
            .arg(&prefix)
            .arg(GLTF_VALIDATOR)
            .status()
            .map_err(|e| {
                format!("cannot run npm ({e}); install Node.js and npm (Debian: apt-get install nodejs npm)")
            })?;
        if !status.success() {
            return Err(format!("npm install {GLTF_VALIDATOR} failed: {status}"));
        }
    }
    let mut files: Vec<_> = std::fs::read_dir(root.join("scenes"))
        .map_err(|e| format!("scenes/: {e}"))?
        .filter_map(|e| e.ok().map(|e| e.path().join("scene.gltf")))
        .filter(|p| p.is_file())
        .collect();
    files.sort();
    let status = Command::new("node")
        .arg(root.join("xtask/validate_gltf.js"))
        .args(&files)
        .env("NODE_PATH", prefix.join("node_modules"))
        .status()
        .map_err(|e| format!("cannot run node ({e}); install Node.js"))?;
    if status.success() {
        Ok(())
    } else {
        Err("the glTF validator found errors (above)".into())
    }
}

/// The Kubernetes manifest validator, pinned, and the Kubernetes version it checks against.
const K8S_VALIDATOR: &str = "kubernetes-validate==1.37.0";

/// Validates the Kubernetes manifest of a bake on a cluster, strictly (unknown keys refused).
fn validate_k8s(root: &Path) -> Result<(), String> {
    // Run as a module, so that no console script needs to be on PATH (pyenv shims).
    let validator = || {
        let mut cmd = Command::new("python3");
        cmd.args(["-m", "kubernetes_validate"]);
        cmd
    };
    let have = validator().arg("--version").output().is_ok_and(|o| o.status.success());
    if !have {
        eprintln!("xtask: pip install {K8S_VALIDATOR}");
        let status = Command::new("python3")
            .args(["-m", "pip", "install", "--quiet", "--disable-pip-version-check", K8S_VALIDATOR])
            .status()
            .map_err(|e| format!("cannot run python3 -m pip ({e}); install Python 3 and pip"))?;
        if !status.success() {
            return Err(format!("pip install {K8S_VALIDATOR} failed: {status}"));
        }
    }
    let manifest = root.join("baker/cluster/k8s-bake.yaml");
    let status = validator()
        .arg("--strict")
        .arg(&manifest)
        .status()
        .map_err(|e| format!("cannot run kubernetes-validate: {e}"))?;
    status.success().then_some(()).ok_or_else(|| format!("{} does not validate (above)", manifest.display()))
}

/// Installs the Debian packages of `packages` that are not installed yet.
fn install(packages: &[&str]) -> Result<(), String> {
    if Command::new("dpkg-query").arg("--version").output().is_err() {
        eprintln!(
            "xtask: not a Debian-based system; make sure these (or your distribution's equivalents) \
             are installed: {}",
            packages.join(" ")
        );
        return Ok(());
    }
    let missing: Vec<&str> = packages.iter().copied().filter(|p| !installed(p)).collect();
    if missing.is_empty() {
        return Ok(());
    }
    eprintln!("xtask: installing missing system packages: {}", missing.join(" "));
    let root = Command::new("id").arg("-u").output().is_ok_and(|o| o.stdout.starts_with(b"0"));
    let apt = |args: &[&str]| -> Result<(), String> {
        let mut cmd = if root { Command::new("apt-get") } else { Command::new("sudo") };
        if !root {
            cmd.arg("apt-get");
        }
        cmd.args(args).env("DEBIAN_FRONTEND", "noninteractive");
        let status = cmd.status().map_err(|e| format!("cannot run apt-get: {e}"))?;
        status.success().then_some(()).ok_or_else(|| format!("apt-get {} failed: {status}", args.join(" ")))
    };
    apt(&["update", "-qq"])?;
    apt(&[&["install", "-y", "-qq", "--no-install-recommends"], missing.as_slice()].concat())
}

fn installed(package: &str) -> bool {
    Command::new("dpkg-query")
        .args(["-W", "-f=${Status}", package])
        .output()
        .is_ok_and(|o| String::from_utf8_lossy(&o.stdout).contains("install ok installed"))
}

fn cargo(args: &[&str]) -> Result<(), String> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    eprintln!("xtask: cargo {}", args.join(" "));
    let status = Command::new(cargo).args(args).status().map_err(|e| format!("cannot run cargo: {e}"))?;
    status.success().then_some(()).ok_or_else(|| format!("cargo {} failed: {status}", args.join(" ")))
}
