//! `gyrolab sweep`: plan, run (local or Ray), status, report, and `exec`, the unit of work a Ray
//! task runs. The study machinery is gyro-study's; this module parses arguments, draws the
//! progress bar, starts the Ray driver and prints.

use crate::commands::{BAD_INPUT, CliError, FAILED, INTERRUPTED};
use clap::{Args, Subcommand};
use gyro_study::sweep::{self, Progress};
use gyro_study::{Plan, Study};
use serde_json::json;
use std::io::BufRead;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

/// The Ray driver shipped with gyrolab (also at `tools/ray_driver.py`); written into the sweep
/// folder when a Ray sweep starts, so the binary needs no checkout.
pub const RAY_DRIVER: &str = include_str!("../../../tools/ray_driver.py");

#[derive(Args)]
pub struct SweepArgs {
    /// Print JSON instead of text.
    #[arg(long, global = true)]
    pub json: bool,
    #[command(subcommand)]
    pub command: SweepCommand,
}

#[derive(Subcommand)]
pub enum SweepCommand {
    /// How many runs a study has, the CPU time and storage it will take (from a few sample runs).
    Plan {
        study: PathBuf,
        /// Sample runs to time (spread over the study).
        #[arg(long, default_value_t = 3)]
        samples: u64,
    },
    /// Run a study into a folder (or finish one: only missing and failed runs are run).
    Run(RunArgs),
    /// What a sweep folder holds: runs done, failed (with reasons) and missing.
    Status { dir: PathBuf },
    /// Tables and plots (SVG) of the metrics against the axes, into DIR/report/.
    Report { dir: PathBuf },
    /// Run some runs of a sweep folder and write their rows as one part (the unit of work of a
    /// Ray task; exits if its parent process dies).
    #[command(hide = true)]
    Exec {
        dir: PathBuf,
        /// Run indices, comma-separated, ranges as A-B.
        #[arg(long)]
        runs: String,
        /// This attempt's name (its files never collide with another attempt's).
        #[arg(long)]
        attempt: String,
        #[arg(long, default_value_t = 1)]
        jobs: usize,
    },
}

#[derive(Args)]
pub struct RunArgs {
    pub study: PathBuf,
    /// The sweep folder (a path every node sees, for the Ray engine).
    #[arg(long)]
    pub out: PathBuf,
    /// local (every core of this machine) or ray (a running Ray cluster).
    #[arg(long, default_value = "local")]
    pub engine: String,
    /// The Ray cluster's address (HOST:PORT of its GCS), for --engine ray.
    #[arg(long)]
    pub address: Option<String>,
    /// Threads of the local engine (default: every core).
    #[arg(long)]
    pub jobs: Option<usize>,
    /// Runs per Ray task.
    #[arg(long, default_value_t = 4)]
    pub chunk: usize,
    /// Retries of a Ray task whose worker died or whose gyrolab failed.
    #[arg(long, default_value_t = 3)]
    pub max_retries: u32,
    /// The Python with Ray installed (default: $GYROLAB_PYTHON, else python3).
    #[arg(long)]
    pub python: Option<PathBuf>,
    /// Go ahead even if the study would write more than its `keep.max_storage_mb`.
    #[arg(long)]
    pub yes: bool,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
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

fn load(study: &Path) -> Result<Plan, CliError> {
    let s = Study::load(study).map_err(bad)?;
    Plan::new(s).map_err(bad)
}

pub fn sweep(args: SweepArgs) -> Result<ExitCode, CliError> {
    let json = args.json;
    match args.command {
        SweepCommand::Plan { study, samples } => plan(&study, samples, json),
        SweepCommand::Run(a) => run(a, json),
        SweepCommand::Status { dir } => status(&dir, json),
        SweepCommand::Report { dir } => report(&dir, json),
        SweepCommand::Exec {
            dir,
            runs,
            attempt,
            jobs,
        } => exec(&dir, &runs, &attempt, jobs),
    }
}

fn scratch() -> PathBuf {
    std::env::temp_dir().join(format!("gyrolab-sweep-plan-{}", std::process::id()))
}

fn mb(b: f64) -> String {
    format!("{:.1} MB", b / 1e6)
}

fn plan(study: &Path, samples: u64, json: bool) -> Result<ExitCode, CliError> {
    let p = load(study)?;
    if samples == 0 {
        return Err(bad("--samples: 0 (allowed: ≥ 1)"));
    }
    let e = sweep::estimate(&p, samples, &scratch()).map_err(failed)?;
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    if json {
        println!(
            "{}",
            json!({"study": p.study.name, "axes": p.axis_keys(), "dimensions": p.study.dimensions(), "recordings": p.study.recordings.to_string(), "estimate": e, "cores": cores})
        );
        return Ok(ExitCode::SUCCESS);
    }
    let s = &p.study;
    println!("{} ({}): {} runs", s.name, s.file, e.total_runs);
    println!(
        "  scenes: {}",
        p.scenes
            .iter()
            .map(|x| x.reference.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    );
    if !p.designs.is_empty() {
        println!(
            "  designs: {}",
            p.designs
                .iter()
                .map(|x| x.reference.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    for a in &s.grid {
        println!("  axis {}: {} values", a.key.name, a.values.len());
    }
    for a in &s.random {
        println!("  random {}: {:?}", a.key.name, a.distribution);
    }
    if !s.random.is_empty() {
        println!(
            "  Monte Carlo: {} samples per grid point, seed {}",
            s.samples, s.seed
        );
    }
    println!(
        "  CPU: {:.3} s per run ({} sample runs{}) → {:.2} CPU hours; {:.2} h on this machine's {cores} cores",
        e.cpu_s_per_run,
        e.sample_runs.len(),
        if e.failed_samples > 0 {
            format!(", {} failed", e.failed_samples)
        } else {
            String::new()
        },
        e.cpu_hours,
        e.cpu_hours / cores as f64
    );
    println!(
        "  storage: recordings = \"{}\": {} kept × {} + table {} per row → {} (limit {})",
        s.recordings,
        e.kept_recordings,
        mb(e.recording_bytes_per_run),
        format_args!("{:.0} B", e.table_bytes_per_row),
        mb(e.storage_bytes),
        mb(e.storage_limit_bytes)
    );
    println!(
        "  every recording: {} ({} per run)",
        mb(e.recording_bytes_per_run * e.total_runs as f64),
        mb(e.recording_bytes_per_run)
    );
    Ok(ExitCode::SUCCESS)
}

/// Refuses a study that would write more than its storage limit, before any run.
fn check_storage(p: &Plan, yes: bool) -> Result<(), CliError> {
    let s = &p.study;
    let kept = s.recordings != gyro_study::study::KeepRecordings::None
        && s.recordings != gyro_study::study::KeepRecordings::Failed;
    let estimate = if kept {
        sweep::estimate(p, 1, &scratch())
            .map_err(failed)?
            .storage_bytes
    } else {
        // The table only: well under 2 kB per row.
        2e3 * p.total_runs() as f64
    };
    let limit = s.max_storage_mb * 1e6;
    if estimate > limit && !yes {
        let key = if s.text.contains("max_storage_mb") {
            "max_storage_mb"
        } else {
            "recordings"
        };
        let line = gyro_model::error::locate(&s.text, Some("[keep]"), key)
            .map(|l| format!(":{l}"))
            .unwrap_or_default();
        return Err(bad(format!(
            "{}{line}: `keep.{key}`: the sweep would write about {} ({} runs, recordings = \"{}\"), more than keep.max_storage_mb = {} MB (allowed: pass --yes, raise the limit, or keep fewer recordings)",
            s.file,
            mb(estimate),
            p.total_runs(),
            s.recordings,
            s.max_storage_mb
        )));
    }
    Ok(())
}

fn bar(total: u64, hidden: bool) -> indicatif::ProgressBar {
    let b = indicatif::ProgressBar::new(total);
    b.set_style(
        indicatif::ProgressStyle::with_template(
            "{bar:40} {pos}/{len} runs, {msg} ({elapsed} elapsed, ETA {eta})",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    if hidden {
        b.set_draw_target(indicatif::ProgressDrawTarget::hidden());
    }
    b
}

fn run(a: RunArgs, json: bool) -> Result<ExitCode, CliError> {
    let p = load(&a.study)?;
    match a.engine.as_str() {
        "local" | "ray" => {}
        other => return Err(bad(format!("--engine: `{other}` (allowed: local, ray)"))),
    }
    if a.engine == "ray" && a.address.is_none() {
        return Err(bad(
            "--engine ray needs --address HOST:PORT (the cluster's GCS address, as `ray start --head` printed it)",
        ));
    }
    if a.jobs == Some(0) || a.chunk == 0 {
        return Err(bad("--jobs and --chunk: 0 (allowed: ≥ 1)"));
    }
    check_storage(&p, a.yes)?;
    let interrupt = Arc::new(AtomicBool::new(false));
    {
        let i = interrupt.clone();
        let _ = ctrlc::set_handler(move || i.store(true, Ordering::Relaxed));
    }
    let summary = if a.engine == "local" {
        let threads = a
            .jobs
            .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
        let b = bar(0, a.quiet || json);
        let s = sweep::run_local(&p, &a.out, threads, &interrupt, |pr: &Progress, row| {
            if b.length() == Some(0) {
                b.set_length(pr.to_run);
            }
            b.set_position(pr.finished);
            b.set_message(format!("{} failed", pr.failed));
            if row.status != gyro_study::table::OK {
                b.println(format!("run {} failed: {}", row.index, row.reason));
            }
        })
        .map_err(failed)?;
        b.finish_and_clear();
        s
    } else {
        run_ray(&p, &a, json, &interrupt)?
    };
    if json {
        println!("{}", serde_json::to_string(&summary).map_err(failed)?);
    } else {
        println!(
            "{}: {} runs: {} run now ({} failed), {} already done; {:.1} s; table {}",
            p.study.name,
            summary.total_runs,
            summary.ran,
            summary.failed,
            summary.already_done,
            summary.elapsed_s,
            summary.table
        );
        if summary.interrupted {
            println!("interrupted: run the same command again to finish");
        }
    }
    Ok(if summary.interrupted {
        ExitCode::from(INTERRUPTED)
    } else {
        ExitCode::SUCCESS
    })
}

/// The Ray engine: chunks of the pending runs handed to the Python driver, which submits them
/// as tasks (with retries) to the cluster at `--address` and reports each as it finishes.
fn run_ray(
    p: &Plan,
    a: &RunArgs,
    json: bool,
    interrupt: &Arc<AtomicBool>,
) -> Result<sweep::SweepSummary, CliError> {
    let started = std::time::Instant::now();
    let out = std::path::absolute(&a.out).map_err(|e| bad(format!("--out: {e}")))?;
    p.freeze(&out).map_err(failed)?;
    let (todo, already_done) = sweep::pending(p, &out).map_err(failed)?;
    let ray_dir = out.join("ray");
    std::fs::create_dir_all(&ray_dir)
        .map_err(|e| failed(format!("cannot create {}: {e}", ray_dir.display())))?;
    let chunks: Vec<&[u64]> = todo.chunks(a.chunk).collect();
    let tasks = ray_dir.join("tasks.json");
    gyro_study::table::write_atomically(
        &tasks,
        serde_json::to_string(&chunks).map_err(failed)?.as_bytes(),
    )
    .map_err(failed)?;
    let driver = ray_dir.join("driver.py");
    gyro_study::table::write_atomically(&driver, RAY_DRIVER.as_bytes()).map_err(failed)?;
    let exe = std::env::current_exe().map_err(|e| failed(format!("where is gyrolab: {e}")))?;
    let python = a
        .python
        .clone()
        .or_else(|| std::env::var_os("GYROLAB_PYTHON").map(PathBuf::from))
        .unwrap_or_else(|| PathBuf::from("python3"));
    let mut ran = 0u64;
    let mut failed_runs = 0u64;
    if !chunks.is_empty() {
        let mut child = std::process::Command::new(&python)
            .arg(&driver)
            .arg("--address")
            .arg(a.address.as_deref().unwrap_or_default())
            .arg("--out")
            .arg(&out)
            .arg("--gyrolab")
            .arg(&exe)
            .arg("--tasks")
            .arg(&tasks)
            .arg("--max-retries")
            .arg(a.max_retries.to_string())
            .stdout(std::process::Stdio::piped())
            .spawn()
            .map_err(|e| {
                bad(format!(
                    "cannot start the Ray driver with {}: {e} (install Ray as the README says and pass --python or set GYROLAB_PYTHON)",
                    python.display()
                ))
            })?;
        let b = bar(todo.len() as u64, a.quiet || json);
        b.set_message("0 failed");
        let mut finished = false;
        let mut task_errors = Vec::new();
        if let Some(stdout) = child.stdout.take() {
            for line in std::io::BufReader::new(stdout).lines() {
                let Ok(line) = line else { break };
                let Ok(v) = serde_json::from_str::<serde_json::Value>(&line) else {
                    continue;
                };
                match v["event"].as_str() {
                    Some("done") => {
                        ran += v["ran"].as_u64().unwrap_or(0);
                        failed_runs += v["failed"].as_u64().unwrap_or(0);
                        b.set_position(ran);
                        b.set_message(format!("{failed_runs} failed"));
                    }
                    Some("task_failed") => {
                        let m = format!(
                            "task {} failed after its retries: {}",
                            v["task"],
                            v["error"].as_str().unwrap_or("")
                        );
                        b.println(&m);
                        task_errors.push(m);
                    }
                    Some("finished") => finished = true,
                    _ => {}
                }
                if interrupt.load(Ordering::Relaxed) {
                    let _ = child.kill();
                    break;
                }
            }
        }
        let status = child
            .wait()
            .map_err(|e| failed(format!("the Ray driver: {e}")))?;
        b.finish_and_clear();
        if interrupt.load(Ordering::Relaxed) {
            return Ok(sweep::SweepSummary {
                total_runs: p.total_runs(),
                ran,
                failed: failed_runs,
                already_done,
                interrupted: true,
                elapsed_s: started.elapsed().as_secs_f64(),
                table: String::new(),
            });
        }
        if !status.success() || !finished {
            return Err(failed(format!(
                "the Ray driver stopped ({status}) after {ran} of {} runs; what finished is kept in {}: run the same command again to finish",
                todo.len(),
                gyro_study::table::parts_dir(&out).display()
            )));
        }
        if !task_errors.is_empty() {
            return Err(failed(format!(
                "{} task(s) failed after their retries (first: {}); run the same command again to retry them",
                task_errors.len(),
                task_errors[0]
            )));
        }
    }
    gyro_study::table::merge(&out).map_err(failed)?;
    let _ = std::fs::remove_dir_all(&ray_dir);
    Ok(sweep::SweepSummary {
        total_runs: p.total_runs(),
        ran,
        failed: failed_runs,
        already_done,
        interrupted: false,
        elapsed_s: started.elapsed().as_secs_f64(),
        table: gyro_study::table::metrics_path(&out).display().to_string(),
    })
}

fn status(dir: &Path, json: bool) -> Result<ExitCode, CliError> {
    let s = sweep::status(dir).map_err(bad)?;
    if json {
        println!("{}", serde_json::to_string_pretty(&s).map_err(failed)?);
        return Ok(ExitCode::SUCCESS);
    }
    println!(
        "{} ({}): {} runs: {} ok, {} failed, {} missing",
        s.study, s.study_file, s.total_runs, s.ok, s.failed, s.missing
    );
    match &s.table {
        Some(t) => println!("  table: {t}"),
        None => println!("  table: not merged yet"),
    }
    if s.unmerged_parts > 0 {
        println!(
            "  {} part(s) not yet merged (a sweep is running or was stopped: `sweep run` again finishes and merges)",
            s.unmerged_parts
        );
    }
    for (i, r) in &s.failures {
        println!("  run {i} failed: {r}");
    }
    Ok(ExitCode::SUCCESS)
}

fn report(dir: &Path, json: bool) -> Result<ExitCode, CliError> {
    let r = gyro_study::report::report(dir).map_err(bad)?;
    if json {
        println!("{}", serde_json::to_string_pretty(&r).map_err(failed)?);
    } else {
        print!("{}", r.render());
    }
    Ok(ExitCode::SUCCESS)
}

/// Parses `1,2,5-9`.
fn parse_runs(s: &str) -> Result<Vec<u64>, String> {
    let mut v = Vec::new();
    for part in s.split(',').filter(|p| !p.trim().is_empty()) {
        let part = part.trim();
        let parse = |x: &str| {
            x.trim().parse::<u64>().map_err(|_| {
                format!("--runs: `{part}` (allowed: indices and ranges A-B, comma-separated)")
            })
        };
        match part.split_once('-') {
            Some((a, b)) => {
                let (a, b) = (parse(a)?, parse(b)?);
                if b < a {
                    return Err(format!("--runs: `{part}`: an empty range"));
                }
                v.extend(a..=b);
            }
            None => v.push(parse(part)?),
        }
    }
    if v.is_empty() {
        return Err("--runs: no run".into());
    }
    Ok(v)
}

fn exec(dir: &Path, runs: &str, attempt: &str, jobs: usize) -> Result<ExitCode, CliError> {
    gyro_study::exec::exit_with_parent();
    if attempt.is_empty()
        || !attempt
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_')
    {
        return Err(bad(format!(
            "--attempt: `{attempt}` (allowed: letters, digits, `-`, `_`)"
        )));
    }
    let indices = parse_runs(runs).map_err(bad)?;
    let (ran, failed_runs) =
        sweep::exec_chunk(dir, &indices, attempt, jobs.max(1)).map_err(failed)?;
    println!(
        "{}",
        json!({"ran": ran, "failed": failed_runs, "attempt": attempt})
    );
    Ok(ExitCode::SUCCESS)
}
