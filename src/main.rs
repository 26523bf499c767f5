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
    /// Show the Vulkan device, driver, API version and the limits that matter to rrf.
    ///
    /// The first thing to run when something is wrong.
    Info {
        /// Print one line of JSON instead of text.
        #[arg(long)]
        json: bool,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Info { json } => rrf::commands::info::run(json),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
