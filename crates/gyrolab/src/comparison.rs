//! `gyrolab comparison`: the compasses compared (issue 14). Runs the comparison study (every
//! design × every standard scene, on every core, resumable like any sweep), then writes the
//! report — metrics per design × scene, figures, the text's claims checked — as Markdown and SVG.
//! The machinery is gyro-study's (`sweep`, `comparison`); this module parses, runs and prints.

use crate::commands::{BAD_INPUT, CliError, FAILED, INTERRUPTED};
use clap::Args;
use gyro_study::comparison::{self, Comparison, Timing};
use gyro_study::sweep::{self, Progress};
use gyro_study::{Plan, Study};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

#[derive(Args)]
pub struct ComparisonArgs {
    /// The comparison study: its scenes × its designs.
    #[arg(long, default_value = "sweeps/six-compared.toml")]
    pub study: PathBuf,
    /// The sweep folder (kept: running the command again only re-renders, or finishes a sweep
    /// that was interrupted).
    #[arg(long, default_value = "studies/six-compared")]
    pub out: PathBuf,
    /// The Markdown report; its figures go to a folder of the same stem beside it.
    #[arg(long, default_value = "docs/comparison.md")]
    pub doc: PathBuf,
    /// Start the sweep folder anew (needed after a scene, design or the study's list changed).
    #[arg(long)]
    pub fresh: bool,
    /// Threads (default: every core).
    #[arg(long)]
    pub jobs: Option<usize>,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
    /// Print the comparison (entries, constants, claims, timing) as JSON.
    #[arg(long)]
    pub json: bool,
}

fn bad(m: impl std::fmt::Display) -> CliError {
    CliError {
        code: BAD_INPUT,
        message: m.to_string(),
    }
}
fn failed(m: impl std::fmt::Display) -> CliError {
    CliError {
        code: FAILED,
        message: m.to_string(),
    }
}

/// Removes a sweep folder, refusing anything that does not look like one.
fn remove_sweep_folder(out: &Path) -> Result<(), CliError> {
    if !out.exists() {
        return Ok(());
    }
    if !gyro_study::plan::inputs_dir(out).is_dir() {
        return Err(bad(format!(
            "--fresh: {} is not a sweep folder (no inputs/): not removed",
            out.display()
        )));
    }
    std::fs::remove_dir_all(out).map_err(|e| failed(format!("{}: {e}", out.display())))
}

pub fn comparison(a: ComparisonArgs) -> Result<ExitCode, CliError> {
    if a.jobs == Some(0) {
        return Err(bad("--jobs: 0 (allowed: ≥ 1)"));
    }
    let plan = Plan::new(Study::load(&a.study).map_err(bad)?).map_err(bad)?;
    if a.fresh {
        remove_sweep_folder(&a.out)?;
    }
    let interrupt = Arc::new(AtomicBool::new(false));
    {
        let i = interrupt.clone();
        let _ = ctrlc::set_handler(move || i.store(true, Ordering::Relaxed));
    }
    let threads = a
        .jobs
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    let b = indicatif::ProgressBar::new(0);
    b.set_style(
        indicatif::ProgressStyle::with_template(
            "{bar:40} {pos}/{len} runs, {msg} ({elapsed} elapsed, ETA {eta})",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    if a.quiet || a.json {
        b.set_draw_target(indicatif::ProgressDrawTarget::hidden());
    }
    let load = std::fs::read_to_string("/proc/loadavg")
        .ok()
        .and_then(|l| l.split_whitespace().next()?.parse::<f64>().ok());
    let summary = sweep::run_local(&plan, &a.out, threads, &interrupt, |p: &Progress, row| {
        if b.length() == Some(0) {
            b.set_length(p.to_run);
        }
        b.set_position(p.finished);
        b.set_message(format!("{} failed", p.failed));
        if row.status != gyro_study::table::OK {
            b.println(format!(
                "{} on {} failed: {}",
                row.design, row.scene, row.reason
            ));
        }
    })
    .map_err(|e| {
        failed(format!(
            "{e} (if a scene, a design or the study changed since {} was made, run again with --fresh)",
            a.out.display()
        ))
    })?;
    b.finish_and_clear();
    if summary.interrupted {
        eprintln!("interrupted: run the same command again to finish");
        return Ok(ExitCode::from(INTERRUPTED));
    }
    if summary.already_done == 0 && summary.ran == summary.total_runs {
        let secs = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_secs());
        let t = Timing {
            sweep_wall_s: summary.elapsed_s,
            threads,
            measured_at: format!(
                "{} UTC, day {} of the Unix epoch",
                clock(secs),
                secs / 86400
            ),
            load_average_at_start: load,
        };
        let text = serde_json::to_string_pretty(&t).map_err(failed)?;
        gyro_study::table::write_atomically(&comparison::timing_path(&a.out), text.as_bytes())
            .map_err(failed)?;
    }
    let c = Comparison::load(&a.out).map_err(failed)?;
    let figures = a.doc.with_extension("");
    let plots = comparison::write_plots(&c, &a.out, &figures).map_err(failed)?;
    let rel = figures
        .file_name()
        .map(|f| f.to_string_lossy().to_string())
        .unwrap_or_default();
    let plots: Vec<(String, String)> = plots
        .into_iter()
        .map(|(k, f)| (k, format!("{rel}/{f}")))
        .collect();
    let command = format!(
        "gyrolab comparison --study {} --out {} --doc {} --fresh",
        a.study.display(),
        a.out.display(),
        a.doc.display()
    );
    let md = c.render(&command, &plots);
    if let Some(dir) = a.doc.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| failed(format!("{}: {e}", dir.display())))?;
    }
    gyro_study::table::write_atomically(&a.doc, md.as_bytes()).map_err(failed)?;
    if a.json {
        println!("{}", serde_json::to_string_pretty(&c).map_err(failed)?);
        return Ok(ExitCode::SUCCESS);
    }
    println!(
        "{}: {} runs ({} run now, {} failed, {} already done) in {:.1} s",
        c.study,
        summary.total_runs,
        summary.ran,
        summary.failed,
        summary.already_done,
        summary.elapsed_s
    );
    for cl in &c.claims {
        println!(
            "  {:<16} {}: {}",
            cl.verdict.to_string(),
            cl.id,
            cl.measured
        );
    }
    if let Some(w) = c.slowest() {
        println!(
            "  runs {:.1} s in all; slowest scene {} {:.1} s; slowest run {} on {} {:.1} s",
            w.total_s, w.scene, w.scene_s, w.run_design, w.run_scene, w.run_s
        );
    }
    println!(
        "report {} (figures in {})",
        a.doc.display(),
        figures.display()
    );
    Ok(ExitCode::SUCCESS)
}

/// HH:MM:SS of a Unix time.
fn clock(secs: u64) -> String {
    let s = secs % 86400;
    format!("{:02}:{:02}:{:02}", s / 3600, s / 60 % 60, s % 60)
}
