//! gyrolab: the command line of the gyrocompass workbench. Thin: it parses arguments (clap),
//! calls the library crates, prints human or JSON output, and maps errors to exit codes:
//! 0 success, 2 bad input (scene, design, recording or arguments), 1 a run that failed,
//! 130 interrupted by Ctrl-C (the recording is still closed and valid).

mod commands;

use clap::{Parser, Subcommand};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "gyrolab",
    version,
    about = "A workbench for the dynamics of gyrocompasses: simulate, record (MCAP), analyse, view"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run a scene and record it as an MCAP file.
    Run(commands::RunArgs),
    /// Record a few shipped scenes into recordings/ and print what they show (the demo).
    Demo {
        /// Output folder.
        #[arg(long, default_value = "recordings")]
        out: PathBuf,
        #[arg(long)]
        json: bool,
    },
    /// Turn a killed run's `.mcap.partial` into a valid recording (up to its last whole chunk).
    Recover {
        partial: PathBuf,
        /// Output path (default: the partial's name without `.partial`).
        #[arg(short, long)]
        output: Option<PathBuf>,
        #[arg(long)]
        json: bool,
    },
    /// List the shipped compass designs.
    Designs {
        #[arg(long)]
        json: bool,
    },
    /// List the shipped scenes.
    Scenes {
        #[arg(long)]
        json: bool,
    },
    /// Channels, counts, time range and metadata of a recording.
    Inspect {
        recording: PathBuf,
        #[arg(long)]
        json: bool,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Run(args) => commands::run(args),
        Command::Demo { out, json } => commands::demo(&out, json),
        Command::Recover {
            partial,
            output,
            json,
        } => commands::recover(&partial, output, json),
        Command::Designs { json } => commands::list(gyro_sim::library::DESIGNS, "designs", json),
        Command::Scenes { json } => commands::list(gyro_sim::library::SCENES, "scenes", json),
        Command::Inspect { recording, json } => commands::inspect(&recording, json),
    };
    match result {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {}", e.message);
            ExitCode::from(e.code)
        }
    }
}
