//! The results table: one row per run (run index, scene, design, every axis value, status and
//! reason, solver statistics, the fitted metrics the study keeps, the recording kept), typed
//! columns with units in their names. Rows reach the disk as Parquet parts
//! (`DIR/parts/part-ATTEMPT-SEQ.parquet`, each written as `.partial` and renamed), so a killed
//! sweep keeps what finished; [`merge`] gathers the parts into `DIR/metrics.parquet`, one row per
//! run in run-index order (a run that succeeded once is that row; else its last failure).

use crate::plan::Plan;
use gyro_analysis::RunMetrics;
use gyro_analysis::error::AnalysisError;
use gyro_analysis::file;
use gyro_analysis::metrics::Cell;
use polars::prelude::*;
use std::fs::File;
use std::path::{Path, PathBuf};

/// A run's status in the table.
pub const OK: &str = "ok";
pub const FAILED: &str = "failed";

/// Columns that measure wall-clock time: the only ones two sweeps of one study may differ in.
pub const TIMING_COLUMNS: [&str; 3] = ["wall_time_s", "rhs_cost_ns", "run_wall_time_s"];

/// Solver statistics kept for every run.
pub const SOLVER_COLUMNS: [&str; 4] = ["steps", "rejected_steps", "rhs_evals", "jacobian_evals"];

/// One run's row.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    pub index: u64,
    pub scene: String,
    pub design: String,
    pub sample: u64,
    pub values: Vec<toml::Value>,
    pub status: String,
    pub reason: String,
    pub metrics: Option<RunMetrics>,
    /// The kept recording, relative to the sweep folder (empty if none was kept).
    pub recording: String,
    /// Wall-clock seconds of the whole run: scene, integration, recording and analysis.
    pub run_wall_time_s: f64,
    /// Size of the run's recording, kept or not (not a column: for the plan's estimate).
    pub recording_bytes: u64,
}

/// The final table of a sweep folder.
pub fn metrics_path(out: &Path) -> PathBuf {
    out.join("metrics.parquet")
}

/// The folder of the parts.
pub fn parts_dir(out: &Path) -> PathBuf {
    out.join("parts")
}

/// Writes `bytes` to `path` through `path.partial` and a rename: never half a file under the
/// final name.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> Result<(), String> {
    file::write_bytes(path, bytes).map_err(|e| format!("cannot write {e}"))
}

/// The table's columns, in order, with their type.
pub fn columns(plan: &Plan) -> Vec<(String, DataType)> {
    let mut c: Vec<(String, DataType)> = vec![
        ("run_index".into(), DataType::UInt64),
        ("scene".into(), DataType::String),
        ("design".into(), DataType::String),
    ];
    if !plan.study.random.is_empty() {
        c.push(("sample".into(), DataType::UInt64));
    }
    for a in &plan.study.grid {
        let t = match a.values.first() {
            Some(toml::Value::String(_)) => DataType::String,
            Some(toml::Value::Boolean(_)) => DataType::Boolean,
            _ => DataType::Float64,
        };
        c.push((a.key.name.clone(), t));
    }
    for a in &plan.study.random {
        c.push((a.key.name.clone(), DataType::Float64));
    }
    c.push(("status".into(), DataType::String));
    c.push(("reason".into(), DataType::String));
    c.push(("output_samples".into(), DataType::UInt64));
    for s in SOLVER_COLUMNS {
        c.push((s.into(), DataType::UInt64));
    }
    let template = RunMetrics::default();
    for m in &plan.study.metrics {
        let t = match template.cell(m) {
            Some(Cell::Str(_)) => DataType::String,
            Some(Cell::U64(_)) => DataType::UInt64,
            _ => DataType::Float64,
        };
        c.push((m.clone(), t));
    }
    c.push(("recording".into(), DataType::String));
    for t in TIMING_COLUMNS {
        c.push((t.into(), DataType::Float64));
    }
    c
}

fn cell_of(row: &Row, plan: &Plan, name: &str) -> AnyValue<'static> {
    let m = row.metrics.as_ref();
    let metric = |n: &str| m.and_then(|m| m.cell(n));
    let f = |v: Option<f64>| {
        v.filter(|x| x.is_finite())
            .map_or(AnyValue::Null, AnyValue::Float64)
    };
    match name {
        "run_index" => AnyValue::UInt64(row.index),
        "scene" => AnyValue::StringOwned(row.scene.clone().into()),
        "design" => AnyValue::StringOwned(row.design.clone().into()),
        "sample" => AnyValue::UInt64(row.sample),
        "status" => AnyValue::StringOwned(row.status.clone().into()),
        "reason" => AnyValue::StringOwned(row.reason.clone().into()),
        "output_samples" => m.map_or(AnyValue::Null, |m| AnyValue::UInt64(m.samples)),
        "recording" => AnyValue::StringOwned(row.recording.clone().into()),
        "run_wall_time_s" => f(Some(row.run_wall_time_s)),
        _ => {
            if let Some(k) = plan.axis_keys().iter().position(|k| *k == name) {
                return match &row.values[k] {
                    toml::Value::Float(x) => AnyValue::Float64(*x),
                    toml::Value::Integer(i) => AnyValue::Float64(*i as f64),
                    toml::Value::Boolean(b) => AnyValue::Boolean(*b),
                    toml::Value::String(s) => AnyValue::StringOwned(s.clone().into()),
                    other => AnyValue::StringOwned(other.to_string().into()),
                };
            }
            match metric(name) {
                Some(Cell::Str(s)) => AnyValue::StringOwned(s.into()),
                Some(Cell::U64(Some(v))) => AnyValue::UInt64(v),
                Some(Cell::F64(v)) => f(v),
                _ => AnyValue::Null,
            }
        }
    }
}

/// The rows as a DataFrame with the plan's columns.
pub fn to_dataframe(rows: &[Row], plan: &Plan) -> Result<DataFrame, String> {
    let mut cols = Vec::new();
    for (name, dtype) in columns(plan) {
        let values: Vec<AnyValue> = rows.iter().map(|r| cell_of(r, plan, &name)).collect();
        let s = Series::from_any_values_and_dtype(name.as_str().into(), &values, &dtype, false)
            .map_err(|e| format!("column {name}: {e}"))?;
        cols.push(s.into_column());
    }
    DataFrame::new(rows.len(), cols).map_err(|e| format!("building the table: {e}"))
}

/// Writes a DataFrame as Parquet at `path` (through `.partial`).
pub fn write_parquet(df: &mut DataFrame, path: &Path) -> Result<(), String> {
    file::write_whole(path, |w| {
        ParquetWriter::new(w)
            .finish(df)
            .map(|_| ())
            .map_err(AnalysisError::polars(path.display().to_string()))
    })
    .map_err(|e| format!("cannot write {e}"))
}

/// Reads a Parquet file.
pub fn read_parquet(path: &Path) -> Result<DataFrame, String> {
    let file = File::open(path).map_err(|e| format!("{}: {e}", path.display()))?;
    ParquetReader::new(file)
        .finish()
        .map_err(|e| format!("{}: not a readable Parquet table: {e}", path.display()))
}

/// Writes rows as a new part of the sweep folder `out`; returns its path.
pub fn write_part(
    out: &Path,
    plan: &Plan,
    rows: &[Row],
    attempt: &str,
    seq: u64,
) -> Result<PathBuf, String> {
    let dir = parts_dir(out);
    std::fs::create_dir_all(&dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    let path = dir.join(format!("part-{attempt}-{seq:06}.parquet"));
    let mut df = to_dataframe(rows, plan)?;
    write_parquet(&mut df, &path)?;
    Ok(path)
}

/// The finished parts of a sweep folder (`.partial` files are not parts).
pub fn part_files(out: &Path) -> Result<Vec<PathBuf>, String> {
    let dir = parts_dir(out);
    let mut v = Vec::new();
    if dir.is_dir() {
        for e in std::fs::read_dir(&dir).map_err(|e| format!("{}: {e}", dir.display()))? {
            let p = e.map_err(|e| e.to_string())?.path();
            if p.extension().is_some_and(|x| x == "parquet") {
                v.push(p);
            }
        }
    }
    v.sort();
    Ok(v)
}

/// Everything recorded so far: the merged table and every part after it, stacked.
fn all_rows(out: &Path) -> Result<Option<DataFrame>, String> {
    let mut frames = Vec::new();
    let m = metrics_path(out);
    if m.is_file() {
        frames.push(read_parquet(&m)?);
    }
    for p in part_files(out)? {
        frames.push(read_parquet(&p)?);
    }
    let mut it = frames.into_iter();
    let Some(mut df) = it.next() else {
        return Ok(None);
    };
    for f in it {
        df.vstack_mut(&f)
            .map_err(|e| format!("{}: parts of different columns: {e}", out.display()))?;
    }
    Ok(Some(df))
}

/// Per run index: whether some row succeeded, and the position of the row chosen for it.
fn choose(df: &DataFrame) -> Result<Vec<(u64, bool, usize)>, String> {
    let idx = df
        .column("run_index")
        .and_then(|c| c.u64().cloned())
        .map_err(|e| format!("run_index: {e}"))?;
    let status = df
        .column("status")
        .and_then(|c| c.str().cloned())
        .map_err(|e| format!("status: {e}"))?;
    let mut best: std::collections::BTreeMap<u64, (bool, usize)> = Default::default();
    for (pos, (i, s)) in idx.iter().zip(status.iter()).enumerate() {
        let Some(i) = i else { continue };
        let ok = s == Some(OK);
        match best.get(&i) {
            Some((true, _)) => {}
            _ => {
                best.insert(i, (ok, pos));
            }
        }
    }
    Ok(best
        .into_iter()
        .map(|(i, (ok, pos))| (i, ok, pos))
        .collect())
}

/// The runs that succeeded and those that failed so far (from the table and the parts).
pub fn done(out: &Path) -> Result<(Vec<u64>, Vec<u64>), String> {
    let Some(df) = all_rows(out)? else {
        return Ok((vec![], vec![]));
    };
    let mut ok = Vec::new();
    let mut failed = Vec::new();
    for (i, good, _) in choose(&df)? {
        if good {
            ok.push(i);
        } else {
            failed.push(i);
        }
    }
    Ok((ok, failed))
}

/// Gathers the parts into `DIR/metrics.parquet` (one row per run, in run-index order; written
/// as `.partial` and renamed), then removes the parts it took in and any `.partial` file left by
/// a killed attempt. Returns the table.
pub fn merge(out: &Path) -> Result<DataFrame, String> {
    let parts = part_files(out)?;
    let Some(df) = all_rows(out)? else {
        return Err(format!("{}: no run has finished yet", out.display()));
    };
    let chosen = choose(&df)?;
    let positions: Vec<IdxSize> = chosen.iter().map(|(_, _, p)| *p as IdxSize).collect();
    let mut table = df
        .take(&IdxCa::from_vec("idx".into(), positions))
        .map_err(|e| format!("merging the parts: {e}"))?;
    table.rechunk_mut();
    write_parquet(&mut table, &metrics_path(out))?;
    for p in parts {
        let _ = std::fs::remove_file(p);
    }
    remove_partials(out);
    Ok(table)
}

/// Removes `.partial` files (of attempts that died) from the parts and work folders.
pub fn remove_partials(out: &Path) {
    for dir in [parts_dir(out), crate::exec::work_dir(out)] {
        let Ok(entries) = std::fs::read_dir(&dir) else {
            continue;
        };
        for e in entries.flatten() {
            let p = e.path();
            if p.to_string_lossy().ends_with(".partial") || dir.ends_with("work") {
                let _ = std::fs::remove_file(&p);
            }
        }
        let _ = std::fs::remove_dir(&dir);
    }
}
