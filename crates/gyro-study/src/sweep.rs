//! A sweep folder and what runs in it: the local engine (every core of one machine, one
//! process), one chunk of runs as a Ray task runs it ([`exec_chunk`]), the status of a folder,
//! and the plan's estimate of CPU time and storage from a few sample runs.

use crate::exec::{self, run_indices};
use crate::plan::Plan;
use crate::table::{self, FAILED, OK, Row};
use serde::Serialize;
use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

/// Rows are written as a part at least this often (and every [`PART_ROWS`] rows).
pub const PART_EVERY: Duration = Duration::from_secs(10);
pub const PART_ROWS: usize = 256;

/// Progress of a sweep, as the engine reports it after every run.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Progress {
    /// Runs of this invocation finished (ok or failed), and how many it has to run.
    pub finished: u64,
    pub to_run: u64,
    pub failed: u64,
    /// Runs already done before this invocation (resume).
    pub already_done: u64,
    pub total_runs: u64,
    pub elapsed_s: f64,
}

impl Progress {
    /// Estimated seconds left at the rate so far.
    pub fn eta_s(&self) -> Option<f64> {
        (self.finished > 0)
            .then(|| self.elapsed_s / self.finished as f64 * (self.to_run - self.finished) as f64)
    }
}

/// What a sweep invocation did.
#[derive(Clone, Debug, Serialize)]
pub struct SweepSummary {
    pub total_runs: u64,
    /// Runs this invocation ran, and how many of them failed.
    pub ran: u64,
    pub failed: u64,
    /// Runs found done before it started (not run again).
    pub already_done: u64,
    pub interrupted: bool,
    pub elapsed_s: f64,
    pub table: String,
}

/// The runs of the plan that have no successful row yet (missing or failed), and how many are
/// done.
pub fn pending(plan: &Plan, out: &Path) -> Result<(Vec<u64>, u64), String> {
    let total = plan.total_runs();
    let (ok, _) = table::done(out)?;
    let mut done = vec![false; total as usize];
    for i in &ok {
        if let Some(d) = done.get_mut(*i as usize) {
            *d = true;
        }
    }
    let todo: Vec<u64> = (0..total).filter(|i| !done[*i as usize]).collect();
    let finished = total - todo.len() as u64;
    Ok((todo, finished))
}

/// A name for this process's attempt: unique across processes and time.
pub fn attempt_name(prefix: &str) -> String {
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_nanos())
        .unwrap_or(0);
    format!("{prefix}{}-{nanos:x}", std::process::id())
}

/// Collects rows and writes them as parts.
struct PartSink<'a> {
    plan: &'a Plan,
    out: &'a Path,
    attempt: String,
    seq: u64,
    rows: Vec<Row>,
    last: Instant,
}

impl PartSink<'_> {
    fn push(&mut self, row: Row) -> Result<(), String> {
        self.rows.push(row);
        if self.rows.len() >= PART_ROWS || self.last.elapsed() >= PART_EVERY {
            self.flush()?;
        }
        Ok(())
    }
    fn flush(&mut self) -> Result<(), String> {
        if !self.rows.is_empty() {
            table::write_part(self.out, self.plan, &self.rows, &self.attempt, self.seq)?;
            self.seq += 1;
            self.rows.clear();
        }
        self.last = Instant::now();
        Ok(())
    }
}

/// The local engine: freezes the study into `out` (or checks it is the one there), runs every
/// run that is missing or failed on `threads` threads, writes the rows as parts while it goes,
/// and merges them into `out/metrics.parquet`. `progress` sees every finished run.
pub fn run_local(
    plan: &Plan,
    out: &Path,
    threads: usize,
    interrupt: &Arc<AtomicBool>,
    mut progress: impl FnMut(&Progress, &Row),
) -> Result<SweepSummary, String> {
    let started = Instant::now();
    plan.freeze(out)?;
    let (todo, already_done) = pending(plan, out)?;
    let mut p = Progress {
        to_run: todo.len() as u64,
        already_done,
        total_runs: plan.total_runs(),
        ..Default::default()
    };
    let mut sink = PartSink {
        plan,
        out,
        attempt: attempt_name("local-"),
        seq: 0,
        rows: Vec::new(),
        last: Instant::now(),
    };
    let attempt = sink.attempt.clone();
    let result = run_indices(plan, &todo, out, &attempt, threads, interrupt, |row| {
        p.finished += 1;
        if row.status == FAILED {
            p.failed += 1;
        }
        p.elapsed_s = started.elapsed().as_secs_f64();
        progress(&p, &row);
        sink.push(row)
    });
    let flushed = sink.flush();
    result?;
    flushed?;
    let interrupted = interrupt.load(std::sync::atomic::Ordering::Relaxed);
    table::merge(out)?;
    Ok(SweepSummary {
        total_runs: plan.total_runs(),
        ran: p.finished,
        failed: p.failed,
        already_done,
        interrupted,
        elapsed_s: started.elapsed().as_secs_f64(),
        table: table::metrics_path(out).display().to_string(),
    })
}

/// One chunk of runs as a task runs it (the Ray engine's unit of work): the plan frozen in `out`,
/// the given indices on `threads` threads, the rows written as one part of this attempt (through
/// `.partial`). Returns how many ran and failed.
pub fn exec_chunk(
    out: &Path,
    indices: &[u64],
    attempt: &str,
    threads: usize,
) -> Result<(u64, u64), String> {
    let plan = Plan::load_frozen(out)?;
    let total = plan.total_runs();
    if let Some(bad) = indices.iter().find(|i| **i >= total) {
        return Err(format!(
            "run index {bad} is out of range (the study has {total} runs)"
        ));
    }
    let mut rows = Vec::new();
    let interrupt = Arc::new(AtomicBool::new(false));
    run_indices(&plan, indices, out, attempt, threads, &interrupt, |row| {
        rows.push(row);
        Ok(())
    })?;
    let failed = rows.iter().filter(|r| r.status != OK).count() as u64;
    rows.sort_by_key(|r| r.index);
    if !rows.is_empty() {
        table::write_part(out, &plan, &rows, attempt, 0)?;
    }
    Ok((rows.len() as u64, failed))
}

/// The state of a sweep folder.
#[derive(Clone, Debug, Serialize)]
pub struct Status {
    pub study: String,
    pub study_file: String,
    pub total_runs: u64,
    pub ok: u64,
    pub failed: u64,
    pub missing: u64,
    /// Parts not yet merged into `metrics.parquet`.
    pub unmerged_parts: usize,
    pub table: Option<String>,
    /// The first failures: (run index, reason).
    pub failures: Vec<(u64, String)>,
}

/// Reads a sweep folder's state (without changing it).
pub fn status(out: &Path) -> Result<Status, String> {
    let plan = Plan::load_frozen(out)?;
    let (ok, failed) = table::done(out)?;
    let total = plan.total_runs();
    let mut failures = Vec::new();
    if !failed.is_empty() {
        for f in std::iter::once(table::metrics_path(out))
            .filter(|p| p.is_file())
            .chain(table::part_files(out)?)
        {
            let df = table::read_parquet(&f)?;
            let (Ok(i), Ok(s), Ok(r)) = (
                df.column("run_index"),
                df.column("status"),
                df.column("reason"),
            ) else {
                continue;
            };
            let (Ok(i), Ok(s), Ok(r)) = (i.u64(), s.str(), r.str()) else {
                continue;
            };
            for ((i, s), r) in i.iter().zip(s.iter()).zip(r.iter()) {
                if let (Some(i), Some(FAILED), Some(r)) = (i, s, r)
                    && failed.contains(&i)
                    && !failures.iter().any(|(j, _)| *j == i)
                {
                    failures.push((i, r.to_string()));
                }
            }
        }
        failures.sort();
        failures.truncate(20);
    }
    let m = table::metrics_path(out);
    Ok(Status {
        study: plan.study.name.clone(),
        study_file: plan.study.file.clone(),
        total_runs: total,
        ok: ok.len() as u64,
        failed: failed.len() as u64,
        missing: total - ok.len() as u64 - failed.len() as u64,
        unmerged_parts: table::part_files(out)?.len(),
        table: m.is_file().then(|| m.display().to_string()),
        failures,
    })
}

/// What a study will cost, from a few sample runs.
#[derive(Clone, Debug, Serialize)]
pub struct Estimate {
    pub total_runs: u64,
    pub sample_runs: Vec<u64>,
    /// Mean wall time of a sample run on one core (simulate, record, analyse), s.
    pub cpu_s_per_run: f64,
    pub cpu_hours: f64,
    /// Mean size of a sample run's recording, bytes.
    pub recording_bytes_per_run: f64,
    /// Recordings the study keeps, expected (failed runs: unknown before running, counted 0).
    pub kept_recordings: u64,
    pub storage_bytes: f64,
    pub storage_limit_bytes: f64,
    /// Parquet bytes per row of the table, measured on the sample rows (an upper bound).
    pub table_bytes_per_row: f64,
    pub failed_samples: u64,
}

/// Runs `n` sample runs (spread over the index range) in a scratch folder and scales up.
pub fn estimate(plan: &Plan, n: u64, scratch: &Path) -> Result<Estimate, String> {
    let total = plan.total_runs();
    let n = n.clamp(1, total);
    let samples: Vec<u64> = (0..n).map(|k| k * total / n).collect();
    std::fs::create_dir_all(scratch).map_err(|e| format!("{}: {e}", scratch.display()))?;
    let interrupt = Arc::new(AtomicBool::new(false));
    let mut rows = Vec::new();
    for &i in &samples {
        rows.push(exec::run_one(plan, i, scratch, "estimate", &interrupt));
    }
    let wall: f64 = rows.iter().map(|r| r.run_wall_time_s).sum();
    let bytes: f64 = rows.iter().map(|r| r.recording_bytes as f64).sum();
    let failed_samples = rows.iter().filter(|r| r.status != OK).count() as u64;
    let table_path = scratch.join("sample.parquet");
    let mut df = table::to_dataframe(&rows, plan)?;
    table::write_parquet(&mut df, &table_path)?;
    let table_bytes = std::fs::metadata(&table_path).map(|m| m.len()).unwrap_or(0) as f64;
    let _ = std::fs::remove_dir_all(scratch);
    let per_run = wall / n as f64;
    let rec = bytes / n as f64;
    let kept = match plan.study.recordings {
        crate::study::KeepRecordings::All => total,
        crate::study::KeepRecordings::None | crate::study::KeepRecordings::Failed => 0,
        crate::study::KeepRecordings::Every(k) => total.div_ceil(k),
    };
    let per_row = table_bytes / n as f64;
    Ok(Estimate {
        total_runs: total,
        sample_runs: samples,
        cpu_s_per_run: per_run,
        cpu_hours: per_run * total as f64 / 3600.0,
        recording_bytes_per_run: rec,
        kept_recordings: kept,
        storage_bytes: rec * kept as f64 + per_row * total as f64,
        storage_limit_bytes: plan.study.max_storage_mb * 1e6,
        table_bytes_per_row: per_row,
        failed_samples,
    })
}
