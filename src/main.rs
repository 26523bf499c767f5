use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// Real-time global illumination with radiance regression functions, on Vulkan.
///
/// Environment: RRF_DEVICE=<substring> picks the Vulkan device by name;
/// RRF_VALIDATION=0 turns the Khronos validation layer off (it is on when installed).
#[derive(Parser)]
#[command(name = "rrf", version, about, long_about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Show the Vulkan device, driver, API version and limits; or, given a scene, its
    /// objects, lights, views and domains.
    ///
    /// Without SCENE this is the first thing to run when something is wrong.
    Info {
        /// A scene folder (holding scene.gltf or scene.glb, and scene.toml) or a glTF file.
        scene: Option<PathBuf>,
        /// Print one line of JSON instead of text.
        #[arg(long)]
        json: bool,
    },

    /// Write a starter sidecar for a glTF: the light that moves (the scene's light, its
    /// brightest emitter, or a point light the sidecar adds), its box, a camera box and a view.
    ///
    /// Prints what it chose. The sidecar is the glTF's name with .toml; edit it freely.
    Init(rrf::commands::init::InitArgs),
    /// Path-trace ground truth on the CPU, by component (emitted, direct, indirect, or all).
    ///
    /// Uses all cores. The same seed gives the same image. EXR output is linear radiance;
    /// PNG output is tonemapped (exposure, ACES, sRGB) like the renderer's.
    Reference(rrf::commands::reference::ReferenceArgs),
    /// Bake a scene's radiance regression functions: path-traced training samples, then two
    /// networks (direct and indirect light) per object, trained with Levenberg–Marquardt.
    ///
    /// Writes a safetensors model. Samples and trained networks are saved as they are made: a
    /// bake that is interrupted (Ctrl-C, a kill, a crash) resumes where it stopped when the
    /// same command is run again, and writes the same model as an uninterrupted bake.
    Bake(rrf::commands::bake::BakeArgs),
    /// Render one frame from a baked model: each pixel's object networks give its direct and
    /// indirect light; emitters show their emission.
    ///
    /// On the Vulkan device by default (RRF_DEVICE picks one); --cpu for the CPU reference.
    Render(rrf::commands::render::RenderArgs),
    /// Time the GPU passes (G-buffer, network, tonemap) with timestamp queries, median over
    /// frames, and report network evaluations per second. Runs without the validation layer
    /// unless RRF_VALIDATION is set.
    Bench(rrf::commands::bench::BenchArgs),
    /// Measure the networks against the path tracer on configurations they never saw:
    /// relMSE, PSNR and FLIP per component (global, direct, indirect), and one figure per
    /// configuration (predicted direct | indirect | global | reference | FLIP error).
    ///
    /// Writes DIR/metrics.json, DIR/index.html and the figures. References are cached under
    /// the scene's .cache/ folder, so a second eval only renders what changed.
    Eval(rrf::commands::eval::EvalArgs),
    /// Fly through a scene and move its light, with global illumination from the networks at
    /// interactive rates; or play a script of camera and light moves, for tests and demos.
    ///
    /// Opens a window on the Vulkan device (RRF_DEVICE picks one). Without a display it
    /// renders headless and says where the image went.
    View(rrf::commands::view::ViewArgs),
}

fn main() -> ExitCode {
    quiet_on_closed_stdout();
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Info { scene, json } => rrf::commands::info::run(scene.as_deref(), json),
        Command::Init(args) => rrf::commands::init::run(&args),
        Command::Reference(args) => rrf::commands::reference::run(&args),
        Command::Bake(args) => rrf::commands::bake::run(&args),
        Command::Render(args) => rrf::commands::render::run(&args),
        Command::Bench(args) => rrf::commands::bench::run(&args),
        Command::Eval(args) => rrf::commands::eval::run(&args),
        Command::View(args) => rrf::commands::view::run(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

/// A reader that stops early (`rrf info SCENE | head`) ends rrf quietly, as it does other
/// command-line tools, instead of making every later print panic: Rust ignores SIGPIPE by
/// default, and this restores the usual behaviour.
fn quiet_on_closed_stdout() {
    #[cfg(unix)]
    // SAFETY: called first thing in main, before any other thread exists; SIG_DFL is a valid
    // disposition for SIGPIPE.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}
