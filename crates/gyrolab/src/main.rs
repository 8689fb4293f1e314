//! gyrolab: the command line of the gyrocompass workbench. Thin: it parses arguments (clap),
//! calls the library crates, prints human or JSON output, and maps errors to exit codes:
//! 0 success, 2 bad input (scene, design, recording or arguments), 1 a run that failed,
//! 130 interrupted by Ctrl-C (the recording is still closed and valid).

mod commands;
mod comparison;
mod sweep;

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
    /// Turn a killed run's `.mcap.partial` into a valid recording (up to its last whole chunk);
    /// the `.partial` file is left as it was.
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
    /// Fitted metrics of recordings (files, folders or globs): period, decrement, steady,
    /// ballistic and rolling errors. Writes the table as CSV, JSON and Parquet with --table.
    Analyze {
        #[arg(required = true)]
        runs: Vec<String>,
        #[arg(long)]
        json: bool,
        /// Write the metrics table to STEM.csv, STEM.json and STEM.parquet.
        #[arg(long)]
        table: Option<PathBuf>,
    },
    /// Side-by-side table of runs and an overlay plot of reading error (SVG and PNG).
    Compare {
        #[arg(required = true)]
        runs: Vec<String>,
        /// Folder for the plots.
        #[arg(long, default_value = "analysis/compare")]
        out: PathBuf,
        /// Print Markdown instead of the terminal table.
        #[arg(long, conflicts_with = "json")]
        markdown: bool,
        /// Print the metrics table and the plots' paths as JSON.
        #[arg(long)]
        json: bool,
    },
    /// Show recordings in Rerun: gimbals posed in 3-D, series of reading error, tilt, heading,
    /// speed and roll, manoeuvre events and the fitted envelope. Spawns the viewer when one is
    /// installed, else saves an .rrd.
    View {
        #[arg(required = true)]
        runs: Vec<PathBuf>,
        /// Save to this .rrd file instead of showing.
        #[arg(long, conflicts_with_all = ["spawn", "connect"])]
        save: Option<PathBuf>,
        /// Start a viewer (the default).
        #[arg(long)]
        spawn: bool,
        /// Stream to a running viewer, e.g. rerun+http://127.0.0.1:9876/proxy.
        #[arg(long, conflicts_with = "spawn")]
        connect: Option<String>,
        /// Exaggerate tilts in the 3-D view by this factor (labelled in the view).
        #[arg(long, default_value_t = 1.0)]
        tilt_exaggeration: f64,
        #[arg(long)]
        json: bool,
    },
    /// Check fitted metrics against the baseline in analysis/: runs the baseline scenes (or
    /// reads the given recordings), prints what moved, exits 1 on a regression.
    Regress {
        /// Recordings to check instead of running the baseline scenes.
        runs: Vec<String>,
        #[arg(long, default_value = "analysis/baseline.toml")]
        baseline: PathBuf,
        /// Rewrite the baseline from this run (after review).
        #[arg(long)]
        update: bool,
        /// Where the baseline scenes are recorded.
        #[arg(long, default_value = "recordings/regress")]
        out: PathBuf,
        #[arg(long)]
        json: bool,
    },
    /// Work-precision study: achieved error against wall time and RHS evaluations for every
    /// integrator, tolerance (1e-3 … 1e-12) and fidelity, on references with exact answers.
    Accuracy {
        /// Cases to run (default: all; see --list).
        cases: Vec<String>,
        /// Print the report as JSON instead of tables.
        #[arg(long)]
        json: bool,
        /// Write the log-log plot, one panel per case (.svg or .png).
        #[arg(long)]
        plot: Option<PathBuf>,
        /// Error the one-line verdicts aim at.
        #[arg(long)]
        target_error: Option<f64>,
        /// Integrators to study, comma-separated (default: dopri5,dop853,vern9,rodas4,rodas5p,radau5,rk4).
        #[arg(long, value_delimiter = ',')]
        methods: Vec<String>,
        /// List the cases and exit.
        #[arg(long)]
        list: bool,
    },
    /// Design studies: grids and Monte Carlo samples of scenes and designs, on every core or
    /// on a Ray cluster, metrics as Parquet (plan, run, status, report).
    Sweep(sweep::SweepArgs),
    /// The compasses compared: every design of the comparison study on its standard scenes,
    /// metrics per design × scene, figures, and the text's comparative claims checked, written
    /// as a Markdown report (docs/comparison.md).
    Comparison(comparison::ComparisonArgs),
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
        Command::Analyze { runs, json, table } => commands::analyze(&runs, json, table.as_deref()),
        Command::Compare {
            runs,
            out,
            markdown,
            json,
        } => commands::compare(&runs, &out, markdown, json),
        Command::View {
            runs,
            save,
            spawn: _,
            connect,
            tilt_exaggeration,
            json,
        } => commands::view(&runs, save, connect, tilt_exaggeration, json),
        Command::Regress {
            runs,
            baseline,
            update,
            out,
            json,
        } => commands::regress(&runs, &baseline, update, &out, json),
        Command::Accuracy {
            cases,
            json,
            plot,
            target_error,
            methods,
            list,
        } => commands::accuracy(commands::AccuracyArgs {
            cases,
            json,
            plot,
            target_error,
            methods,
            list,
        }),
        Command::Sweep(cmd) => sweep::sweep(cmd),
        Command::Comparison(args) => comparison::comparison(args),
    };
    match result {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {}", e.message);
            ExitCode::from(e.code)
        }
    }
}
