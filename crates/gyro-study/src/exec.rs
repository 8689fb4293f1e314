//! Running runs: one run is its scene recorded to a private file of the attempt
//! (`DIR/work/run-INDEX-ATTEMPT.mcap`, through the recorder's own `.partial`), analysed exactly
//! as `gyrolab analyze` does, then kept under `DIR/recordings/` or deleted as the study says. A
//! run that fails (a bad combination of values, an integration that diverges, a recording the
//! analysis refuses) is a `failed` row with its reason, never a crashed sweep.
//!
//! [`run_indices`] runs a list of indices on a pool of std threads (one per core by default),
//! handing every finished row to the caller, which writes the parts and shows progress.

use crate::plan::Plan;
use crate::table::{FAILED, OK, Row};
use gyro_sim::{RecordOptions, RunError};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::mpsc;
use std::time::Instant;

/// Where runs write their recordings while they run.
pub fn work_dir(out: &Path) -> PathBuf {
    out.join("work")
}

/// Where kept recordings go.
pub fn recordings_dir(out: &Path) -> PathBuf {
    out.join("recordings")
}

/// The name of run `index`'s kept recording, relative to the sweep folder.
pub fn recording_name(index: u64) -> String {
    format!("recordings/run-{index:09}.mcap")
}

/// Runs one run of the plan. `attempt` names this attempt's files (unique per process and
/// retry), so an attempt never writes over another's, dead or alive.
pub fn run_one(
    plan: &Plan,
    index: u64,
    out: &Path,
    attempt: &str,
    interrupt: &Arc<AtomicBool>,
) -> Row {
    let started = Instant::now();
    let spec = plan.run(index);
    let design = plan.design_of(&spec);
    let design_name = toml::from_str::<toml::Value>(&design.text)
        .ok()
        .and_then(|v| Some(v.get("name")?.as_str()?.to_string()))
        .unwrap_or_else(|| design.reference.clone());
    let mut row = Row {
        index,
        scene: plan.scenes[spec.scene].reference.clone(),
        design: design_name,
        sample: spec.sample,
        values: spec.values.clone(),
        status: FAILED.into(),
        reason: String::new(),
        metrics: None,
        recording: String::new(),
        run_wall_time_s: 0.0,
        recording_bytes: 0,
    };
    let finish = |mut row: Row, reason: Option<String>| {
        if let Some(r) = reason {
            row.reason = r;
        }
        row.run_wall_time_s = started.elapsed().as_secs_f64();
        row
    };
    let scene = match plan.scene(&spec) {
        Ok(s) => s,
        Err(e) => return finish(row, Some(format!("bad scene: {e}"))),
    };
    let work = work_dir(out);
    if let Err(e) = std::fs::create_dir_all(&work) {
        return finish(row, Some(format!("cannot create {}: {e}", work.display())));
    }
    let tmp = work.join(format!("run-{index:09}-{attempt}.mcap"));
    let partial = work.join(format!("run-{index:09}-{attempt}.mcap.partial"));
    let recorded = gyro_sim::record(
        &scene,
        &tmp,
        RecordOptions {
            interrupt: Some(interrupt.clone()),
            ..Default::default()
        },
    );
    let keep = |failed: bool| plan.study.recordings.keeps(index, failed);
    let keep_file = |from: &Path, row: &mut Row| {
        let name = recording_name(index);
        let dest = out.join(&name);
        let moved = std::fs::create_dir_all(recordings_dir(out))
            .and_then(|()| std::fs::rename(from, &dest));
        match moved {
            Ok(()) => row.recording = name,
            Err(e) => row.reason.push_str(&format!(" (recording not kept: {e})")),
        }
    };
    let summary = match recorded {
        Ok(s) => s,
        Err(e) => {
            let reason = match &e {
                RunError::Model(m) => format!("the model does not compile: {m}"),
                RunError::Solve(m) => format!("integration failed: {m}"),
                RunError::Record(m) => format!("recording failed: {m}"),
            };
            row.reason = reason;
            if keep(true) && partial.is_file() {
                // What the run wrote up to its failure, as a valid recording.
                let salvaged = work.join(format!("run-{index:09}-{attempt}.salvaged.mcap"));
                if gyro_mcap::recover(&partial, &salvaged).is_ok() {
                    keep_file(&salvaged, &mut row);
                }
            }
            let _ = std::fs::remove_file(&partial);
            return finish(row, None);
        }
    };
    row.recording_bytes = summary.bytes;
    if summary.interrupted_at_s.is_some() {
        let _ = std::fs::remove_file(&summary.path);
        return finish(row, Some("interrupted".into()));
    }
    match gyro_analysis::analyze_run(&summary.path, &Default::default()) {
        Ok(a) => {
            row.metrics = Some(a.metrics);
            row.status = OK.into();
        }
        Err(e) => row.reason = format!("analysis failed: {e}"),
    }
    if keep(row.status != OK) {
        keep_file(&summary.path, &mut row);
    } else {
        let _ = std::fs::remove_file(&summary.path);
    }
    finish(row, None)
}

/// Runs `indices` on `threads` threads; `on_row` sees every row as it finishes (on the calling
/// thread, in finishing order). Setting `interrupt` stops taking new runs and stops the running
/// ones at their next sample (their rows are not reported).
pub fn run_indices(
    plan: &Plan,
    indices: &[u64],
    out: &Path,
    attempt: &str,
    threads: usize,
    interrupt: &Arc<AtomicBool>,
    mut on_row: impl FnMut(Row) -> Result<(), String>,
) -> Result<(), String> {
    let next = AtomicUsize::new(0);
    let (tx, rx) = mpsc::channel::<Row>();
    std::thread::scope(|s| {
        for _ in 0..threads.max(1).min(indices.len().max(1)) {
            let tx = tx.clone();
            let next = &next;
            s.spawn(move || {
                loop {
                    if interrupt.load(Ordering::Relaxed) {
                        break;
                    }
                    let k = next.fetch_add(1, Ordering::Relaxed);
                    let Some(&index) = indices.get(k) else { break };
                    let row = run_one(plan, index, out, attempt, interrupt);
                    if row.reason == "interrupted" {
                        break;
                    }
                    if tx.send(row).is_err() {
                        break;
                    }
                }
            });
        }
        drop(tx);
        let mut result = Ok(());
        for row in rx {
            if result.is_ok()
                && let Err(e) = on_row(row)
            {
                // Stop the others: the rows cannot be kept.
                interrupt.store(true, Ordering::Relaxed);
                result = Err(e);
            }
        }
        result
    })
}

/// Exits the process when its parent dies (it is then adopted: its parent id changes), checked
/// every 200 ms on a thread of its own. A `gyrolab` started by a Ray worker that is killed thus
/// never outlives it, even without Ray's subreaper option.
pub fn exit_with_parent() {
    let parent = std::os::unix::process::parent_id();
    std::thread::spawn(move || {
        loop {
            std::thread::sleep(std::time::Duration::from_millis(200));
            if std::os::unix::process::parent_id() != parent {
                eprintln!("gyrolab: parent process {parent} is gone; exiting");
                std::process::exit(137);
            }
        }
    });
}
