//! The metrics of a run: [`analyze_run`] loads a recording and runs every fit and detector on it
//! ([`RunAnalysis`]); its flat summary is one [`RunMetrics`] row, and many rows make a
//! [`MetricsTable`] written as CSV, JSON or Parquet through polars.
//!
//! Windows: the settling oscillation (period, decrement, tilt) is fitted from the start of the
//! recording to the first manoeuvre (the whole run when there is none); the steady error and the
//! rolling error are taken after the last manoeuvre.

use std::fs::File;
use std::path::{Path, PathBuf};

use polars::prelude::*;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::ballistic::{
    BallisticConstants, BallisticDeviation, BallisticOptions, ballistic_deviations, events_of,
    schuler_period_s,
};
use crate::error::{AnalysisError, Result};
use crate::file::write_whole;
use crate::fit::{FitOptions, OscillationFit, Quality, decimate, fit_damped_sinusoid};
use crate::load::{
    COMPASS_TOPIC, LoadOptions, Run, SHIP_TOPIC, SOLVER_TOPIC, expand_inputs, load_run,
};
use crate::rolling::{RollingError, RollingOptions, rolling_error};
use crate::steady::{SteadyError, SteadyOptions, steady_error};
use crate::table::Table;
use gyro_mcap::contract::events as event_fields;
use gyro_mcap::contract::{
    compass_state, design_constants_record, result_record, run_record, ship_state, solver_stats,
};

/// Settings of [`analyze_run`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct AnalysisOptions {
    pub fit: FitOptions,
    pub steady: SteadyOptions,
    pub ballistic: BallisticOptions,
    pub rolling: RollingOptions,
}

/// The reading error as plotted: block means (at most ~2000 points) of the full series.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct PlotSeries {
    pub time_s: Vec<f64>,
    pub error_rad: Vec<f64>,
}

/// Everything the analysis found in one run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunAnalysis {
    pub metrics: RunMetrics,
    /// Damped sinusoid on the reading error (azimuth), start to first manoeuvre.
    pub azimuth: OscillationFit,
    /// The same on the tilt, when recorded.
    pub tilt: Option<OscillationFit>,
    pub steady: SteadyError,
    pub ballistic: Vec<BallisticDeviation>,
    pub rolling: Option<RollingError>,
    /// One line per refusal or oddity, naming the file and channel.
    pub notes: Vec<String>,
    #[serde(skip)]
    pub series: PlotSeries,
}

/// One row of the metrics table. Angles in radians, times in seconds (SI, as everywhere inside
/// gyrolab); `None` where a fit refused (see the quality columns).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct RunMetrics {
    pub run_id: String,
    pub path: String,
    pub scene: String,
    pub design: String,
    pub design_kind: String,
    pub fidelity: String,
    pub integrator: String,
    pub rtol: Option<f64>,
    pub atol: Option<f64>,
    pub effects: String,
    pub status: String,
    pub duration_s: Option<f64>,
    pub samples: u64,
    pub azimuth_quality: String,
    pub period_s: Option<f64>,
    pub period_sigma_s: Option<f64>,
    pub log_decrement: Option<f64>,
    pub log_decrement_sigma: Option<f64>,
    pub damping_ratio: Option<f64>,
    pub damping_ratio_sigma: Option<f64>,
    pub amplitude_rad: Option<f64>,
    pub tilt_quality: String,
    pub tilt_period_s: Option<f64>,
    pub tilt_period_sigma_s: Option<f64>,
    pub tilt_log_decrement: Option<f64>,
    pub tilt_log_decrement_sigma: Option<f64>,
    pub steady_error_rad: Option<f64>,
    pub steady_error_sigma_rad: Option<f64>,
    pub steady_drift_rad_per_s: Option<f64>,
    pub steady_drift_sigma_rad_per_s: Option<f64>,
    /// The reading error at the first sample: where the run starts. A scene without an azimuth
    /// offset starts at the calm equilibrium of its latitude, dial and heading, so a rolling
    /// error net of it is what the sea adds, with no settling left in it.
    pub start_error_rad: Option<f64>,
    pub ballistic_events: u64,
    /// The largest |peak deviation| over the manoeuvres (signed).
    pub ballistic_peak_rad: Option<f64>,
    /// The elementary expectation for that manoeuvre: (T_S²/T² − 1)·Δζ_eq.
    pub ballistic_expected_peak_rad: Option<f64>,
    /// The longest settle time over the manoeuvres (None if one never settles).
    pub ballistic_settle_s: Option<f64>,
    /// Of the manoeuvre with the largest peak: how far the card had swung from its old
    /// equilibrium 1 min after the end, and its rate there (Beghin §70's back-swing, of the
    /// opposite sign when the damper drives the card back; `ballistic::BallisticOptions`).
    pub ballistic_swing_rad: Option<f64>,
    pub ballistic_backswing_rate_rad_per_s: Option<f64>,
    pub rolling_error_rad: Option<f64>,
    pub rolling_error_sigma_rad: Option<f64>,
    pub roll_period_s: Option<f64>,
    pub steps: Option<u64>,
    pub rejected_steps: Option<u64>,
    pub rhs_evals: Option<u64>,
    pub jacobian_evals: Option<u64>,
    pub wall_time_s: Option<f64>,
    pub rhs_cost_ns: Option<f64>,
}

/// One cell of the table.
#[derive(Debug, Clone, PartialEq)]
pub enum Cell {
    Str(String),
    F64(Option<f64>),
    U64(Option<u64>),
}

impl Cell {
    pub fn as_f64(&self) -> Option<f64> {
        match self {
            Cell::F64(v) => *v,
            Cell::U64(v) => v.map(|x| x as f64),
            Cell::Str(_) => None,
        }
    }
}

impl RunMetrics {
    /// The row as (column, cell), in table order: the one list every writer and renderer uses.
    pub fn cells(&self) -> Vec<(&'static str, Cell)> {
        use Cell::{F64, Str, U64};
        let s = |v: &String| Str(v.clone());
        vec![
            ("run_id", s(&self.run_id)),
            ("path", s(&self.path)),
            ("scene", s(&self.scene)),
            ("design", s(&self.design)),
            ("design_kind", s(&self.design_kind)),
            ("fidelity", s(&self.fidelity)),
            ("integrator", s(&self.integrator)),
            ("rtol", F64(self.rtol)),
            ("atol", F64(self.atol)),
            ("effects", s(&self.effects)),
            ("status", s(&self.status)),
            ("duration_s", F64(self.duration_s)),
            ("samples", U64(Some(self.samples))),
            ("azimuth_quality", s(&self.azimuth_quality)),
            ("period_s", F64(self.period_s)),
            ("period_sigma_s", F64(self.period_sigma_s)),
            ("log_decrement", F64(self.log_decrement)),
            ("log_decrement_sigma", F64(self.log_decrement_sigma)),
            ("damping_ratio", F64(self.damping_ratio)),
            ("damping_ratio_sigma", F64(self.damping_ratio_sigma)),
            ("amplitude_rad", F64(self.amplitude_rad)),
            ("tilt_quality", s(&self.tilt_quality)),
            ("tilt_period_s", F64(self.tilt_period_s)),
            ("tilt_period_sigma_s", F64(self.tilt_period_sigma_s)),
            ("tilt_log_decrement", F64(self.tilt_log_decrement)),
            (
                "tilt_log_decrement_sigma",
                F64(self.tilt_log_decrement_sigma),
            ),
            ("steady_error_rad", F64(self.steady_error_rad)),
            ("steady_error_sigma_rad", F64(self.steady_error_sigma_rad)),
            ("steady_drift_rad_per_s", F64(self.steady_drift_rad_per_s)),
            (
                "steady_drift_sigma_rad_per_s",
                F64(self.steady_drift_sigma_rad_per_s),
            ),
            ("start_error_rad", F64(self.start_error_rad)),
            ("ballistic_events", U64(Some(self.ballistic_events))),
            ("ballistic_peak_rad", F64(self.ballistic_peak_rad)),
            (
                "ballistic_expected_peak_rad",
                F64(self.ballistic_expected_peak_rad),
            ),
            ("ballistic_settle_s", F64(self.ballistic_settle_s)),
            ("ballistic_swing_rad", F64(self.ballistic_swing_rad)),
            (
                "ballistic_backswing_rate_rad_per_s",
                F64(self.ballistic_backswing_rate_rad_per_s),
            ),
            ("rolling_error_rad", F64(self.rolling_error_rad)),
            ("rolling_error_sigma_rad", F64(self.rolling_error_sigma_rad)),
            ("roll_period_s", F64(self.roll_period_s)),
            ("steps", U64(self.steps)),
            ("rejected_steps", U64(self.rejected_steps)),
            ("rhs_evals", U64(self.rhs_evals)),
            ("jacobian_evals", U64(self.jacobian_evals)),
            ("wall_time_s", F64(self.wall_time_s)),
            ("rhs_cost_ns", F64(self.rhs_cost_ns)),
        ]
    }

    /// A cell by column name.
    pub fn cell(&self, column: &str) -> Option<Cell> {
        self.cells()
            .into_iter()
            .find(|(c, _)| *c == column)
            .map(|(_, v)| v)
    }

    /// The key that identifies the run across baselines: scene/design/fidelity/integrator when
    /// the recording names them, else the run id.
    pub fn key(&self) -> String {
        if self.scene.is_empty() && self.design.is_empty() {
            return self.run_id.clone();
        }
        let mut parts = vec![self.scene.as_str(), self.design.as_str()];
        if !self.fidelity.is_empty() {
            parts.push(&self.fidelity);
        }
        if !self.integrator.is_empty() {
            parts.push(&self.integrator);
        }
        parts.join("/")
    }
}

/// One row per run.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct MetricsTable {
    pub rows: Vec<RunMetrics>,
}

impl MetricsTable {
    /// The table as a DataFrame (column order of [`RunMetrics::cells`]).
    pub fn to_dataframe(&self) -> Result<DataFrame> {
        let template = RunMetrics::default().cells();
        let n = self.rows.len();
        let rows: Vec<Vec<(&'static str, Cell)>> = self.rows.iter().map(|r| r.cells()).collect();
        let mut columns = Vec::with_capacity(template.len());
        for (k, (name, kind)) in template.iter().enumerate() {
            let column = match kind {
                Cell::Str(_) => Column::new(
                    (*name).into(),
                    rows.iter()
                        .map(|r| match &r[k].1 {
                            Cell::Str(s) => s.clone(),
                            _ => String::new(),
                        })
                        .collect::<Vec<String>>(),
                ),
                Cell::F64(_) => Column::new(
                    (*name).into(),
                    rows.iter()
                        .map(|r| r[k].1.as_f64().filter(|v| v.is_finite()))
                        .collect::<Vec<Option<f64>>>(),
                ),
                Cell::U64(_) => Column::new(
                    (*name).into(),
                    rows.iter()
                        .map(|r| match &r[k].1 {
                            Cell::U64(v) => *v,
                            _ => None,
                        })
                        .collect::<Vec<Option<u64>>>(),
                ),
            };
            columns.push(column);
        }
        DataFrame::new(n, columns).map_err(AnalysisError::polars("building the metrics table"))
    }

    /// Writes CSV.
    pub fn write_csv(&self, path: &Path) -> Result<()> {
        let mut df = self.to_dataframe()?;
        write_whole(path, |file| {
            CsvWriter::new(file)
                .finish(&mut df)
                .map_err(AnalysisError::polars(format!(
                    "{}: writing CSV",
                    path.display()
                )))
        })
    }

    /// Writes JSON (an array of row objects).
    pub fn write_json(&self, path: &Path) -> Result<()> {
        let mut df = self.to_dataframe()?;
        write_whole(path, |file| {
            JsonWriter::new(file)
                .with_json_format(JsonFormat::Json)
                .finish(&mut df)
                .map_err(AnalysisError::polars(format!(
                    "{}: writing JSON",
                    path.display()
                )))
        })
    }

    /// Writes Parquet.
    pub fn write_parquet(&self, path: &Path) -> Result<()> {
        let mut df = self.to_dataframe()?;
        write_whole(path, |file| {
            ParquetWriter::new(file)
                .finish(&mut df)
                .map(|_| ())
                .map_err(AnalysisError::polars(format!(
                    "{}: writing Parquet",
                    path.display()
                )))
        })
    }

    /// Writes `<stem>.csv`, `<stem>.json` and `<stem>.parquet`; returns the paths.
    pub fn write_all(&self, stem: &Path) -> Result<Vec<PathBuf>> {
        let paths: Vec<PathBuf> = ["csv", "json", "parquet"]
            .iter()
            .map(|ext| stem.with_extension(ext))
            .collect();
        self.write_csv(&paths[0])?;
        self.write_json(&paths[1])?;
        self.write_parquet(&paths[2])?;
        Ok(paths)
    }

    /// Reads a table written by [`write_csv`](Self::write_csv) or
    /// [`write_parquet`](Self::write_parquet) back (by extension).
    pub fn read(path: &Path) -> Result<MetricsTable> {
        let ctx = format!("{}: reading a metrics table", path.display());
        let df = if path.extension().is_some_and(|e| e == "parquet") {
            let file = File::open(path).map_err(AnalysisError::io(path, "opening"))?;
            ParquetReader::new(file)
                .finish()
                .map_err(AnalysisError::polars(ctx.clone()))?
        } else {
            CsvReadOptions::default()
                .with_has_header(true)
                .try_into_reader_with_file_path(Some(path.to_path_buf()))
                .and_then(|r| r.finish())
                .map_err(AnalysisError::polars(ctx.clone()))?
        };
        from_dataframe(&df).map_err(|what| AnalysisError::Input {
            input: path.display().to_string(),
            what,
        })
    }

    /// Each run as an indented block of its metrics (what `gyrolab analyze` prints).
    pub fn render_text(&self) -> String {
        let mut out = String::new();
        for r in &self.rows {
            out.push_str(&format!("{}  ({})\n", r.run_id, r.path));
            let mut t = Table::headless(2).indent("  ");
            for (name, cell) in r.cells().iter().skip(2) {
                let text = match cell {
                    Cell::Str(s) if s.is_empty() => continue,
                    Cell::Str(s) => s.clone(),
                    Cell::F64(None) | Cell::U64(None) => continue,
                    Cell::F64(Some(v)) => format_number(*v),
                    Cell::U64(Some(v)) => v.to_string(),
                };
                t.row([name.to_string(), text]);
            }
            out.push_str(&t.render());
        }
        out
    }
}

/// A number with 6 significant digits, plain or scientific as fits.
pub fn format_number(v: f64) -> String {
    if v == 0.0 || (1e-3..1e6).contains(&v.abs()) {
        let digits = (5 - v.abs().log10().floor().max(-3.0) as i32).clamp(0, 9) as usize;
        format!("{v:.digits$}")
    } else {
        format!("{v:.5e}")
    }
}

fn from_dataframe(df: &DataFrame) -> std::result::Result<MetricsTable, String> {
    let n = df.height();
    let mut rows = vec![RunMetrics::default(); n];
    for (name, kind) in RunMetrics::default().cells() {
        let Ok(col) = df.column(name) else {
            continue;
        };
        let series = col.as_materialized_series();
        for (i, row) in rows.iter_mut().enumerate() {
            let value = series.get(i).map_err(|e| format!("column {name}: {e}"))?;
            let cell = match kind {
                Cell::Str(_) => Cell::Str(match value {
                    AnyValue::String(s) => s.to_owned(),
                    AnyValue::StringOwned(s) => s.to_string(),
                    AnyValue::Null => String::new(),
                    other => other.to_string(),
                }),
                Cell::F64(_) => Cell::F64(value.extract::<f64>()),
                Cell::U64(_) => Cell::U64(value.extract::<u64>()),
            };
            set_cell(row, name, cell);
        }
    }
    Ok(MetricsTable { rows })
}

/// Sets a field by column name (the inverse of [`RunMetrics::cells`]).
pub(crate) fn set_cell(r: &mut RunMetrics, name: &str, cell: Cell) {
    let f = || cell.as_f64();
    let u = || match &cell {
        Cell::U64(v) => *v,
        Cell::F64(v) => v.filter(|x| *x >= 0.0).map(|x| x as u64),
        Cell::Str(_) => None,
    };
    let s = || match &cell {
        Cell::Str(s) => s.clone(),
        _ => String::new(),
    };
    match name {
        "run_id" => r.run_id = s(),
        "path" => r.path = s(),
        "scene" => r.scene = s(),
        "design" => r.design = s(),
        "design_kind" => r.design_kind = s(),
        "fidelity" => r.fidelity = s(),
        "integrator" => r.integrator = s(),
        "rtol" => r.rtol = f(),
        "atol" => r.atol = f(),
        "effects" => r.effects = s(),
        "status" => r.status = s(),
        "duration_s" => r.duration_s = f(),
        "samples" => r.samples = u().unwrap_or(0),
        "azimuth_quality" => r.azimuth_quality = s(),
        "period_s" => r.period_s = f(),
        "period_sigma_s" => r.period_sigma_s = f(),
        "log_decrement" => r.log_decrement = f(),
        "log_decrement_sigma" => r.log_decrement_sigma = f(),
        "damping_ratio" => r.damping_ratio = f(),
        "damping_ratio_sigma" => r.damping_ratio_sigma = f(),
        "amplitude_rad" => r.amplitude_rad = f(),
        "tilt_quality" => r.tilt_quality = s(),
        "tilt_period_s" => r.tilt_period_s = f(),
        "tilt_period_sigma_s" => r.tilt_period_sigma_s = f(),
        "tilt_log_decrement" => r.tilt_log_decrement = f(),
        "tilt_log_decrement_sigma" => r.tilt_log_decrement_sigma = f(),
        "steady_error_rad" => r.steady_error_rad = f(),
        "steady_error_sigma_rad" => r.steady_error_sigma_rad = f(),
        "steady_drift_rad_per_s" => r.steady_drift_rad_per_s = f(),
        "steady_drift_sigma_rad_per_s" => r.steady_drift_sigma_rad_per_s = f(),
        "start_error_rad" => r.start_error_rad = f(),
        "ballistic_events" => r.ballistic_events = u().unwrap_or(0),
        "ballistic_peak_rad" => r.ballistic_peak_rad = f(),
        "ballistic_expected_peak_rad" => r.ballistic_expected_peak_rad = f(),
        "ballistic_settle_s" => r.ballistic_settle_s = f(),
        "ballistic_swing_rad" => r.ballistic_swing_rad = f(),
        "ballistic_backswing_rate_rad_per_s" => r.ballistic_backswing_rate_rad_per_s = f(),
        "rolling_error_rad" => r.rolling_error_rad = f(),
        "rolling_error_sigma_rad" => r.rolling_error_sigma_rad = f(),
        "roll_period_s" => r.roll_period_s = f(),
        "steps" => r.steps = u(),
        "rejected_steps" => r.rejected_steps = u(),
        "rhs_evals" => r.rhs_evals = u(),
        "jacobian_evals" => r.jacobian_evals = u(),
        "wall_time_s" => r.wall_time_s = f(),
        "rhs_cost_ns" => r.rhs_cost_ns = f(),
        _ => {}
    }
}

/// Analyses every recording the arguments name (files, folders, globs), in parallel; the first
/// failure (in argument order) is returned, naming its file.
pub fn analyze_runs<P: AsRef<Path> + Sync>(inputs: &[P]) -> Result<MetricsTable> {
    Ok(MetricsTable {
        rows: analyze_all(inputs, &AnalysisOptions::default())?
            .into_iter()
            .map(|a| a.metrics)
            .collect(),
    })
}

/// As [`analyze_runs`], keeping each run's whole analysis.
pub fn analyze_all<P: AsRef<Path> + Sync>(
    inputs: &[P],
    opts: &AnalysisOptions,
) -> Result<Vec<RunAnalysis>> {
    let paths = expand_inputs(inputs)?;
    paths.par_iter().map(|p| analyze_run(p, opts)).collect()
}

/// Loads one recording and analyses it. Errors (a file that is not a recording, a missing
/// channel or field, an empty channel) name the file and channel; refusals of a fit (too short,
/// not oscillatory, …) are not errors: they show as quality flags and as `notes`.
pub fn analyze_run(path: &Path, opts: &AnalysisOptions) -> Result<RunAnalysis> {
    let run = load_run(path, &LoadOptions::default())?;
    analyze_loaded(&run, opts)
}

fn u64_last(run: &Run, topic: &str, field: &str) -> Option<u64> {
    let frame = run.frame(topic).ok()?;
    let col = frame.column(field).ok()?;
    let ca = col.u64().ok()?;
    ca.iter().flatten().last()
}

fn f64_last(run: &Run, topic: &str, field: &str) -> Option<f64> {
    run.f64_field(topic, field)
        .ok()?
        .iter()
        .rev()
        .copied()
        .find(|v| v.is_finite())
}

/// The first manoeuvre's start and the last one's end (s), if any.
fn manoeuvre_span(events: &[crate::ballistic::ManoeuvreEvent]) -> (Option<f64>, Option<f64>) {
    let mut manoeuvre_times: Vec<(f64, &str)> = events
        .iter()
        .filter(|e| e.manoeuvre != event_fields::STEADY && e.time_s.is_finite())
        .map(|e| (e.time_s, e.phase.as_str()))
        .collect();
    manoeuvre_times.sort_by(|a, b| a.0.total_cmp(&b.0));
    let first_start = manoeuvre_times
        .iter()
        .find(|(_, p)| *p == event_fields::START)
        .map(|m| m.0);
    let last_end = manoeuvre_times
        .iter()
        .rev()
        .find(|(_, p)| *p == event_fields::END)
        .map(|m| m.0);
    (first_start, last_end)
}

/// The ballistic deviation after each manoeuvre, with the run's recorded design constants.
fn ballistic_of(
    run: &Run,
    t: &[f64],
    err: &[f64],
    events: &[crate::ballistic::ManoeuvreEvent],
    design_period: Option<f64>,
    period_hint: Option<f64>,
    opts: &AnalysisOptions,
) -> Vec<BallisticDeviation> {
    let ship_lat = run
        .f64_field(SHIP_TOPIC, "time_s")
        .ok()
        .zip(run.f64_field(SHIP_TOPIC, ship_state::LATITUDE_RAD).ok());
    let constants = BallisticConstants {
        undamped_period_s: design_period,
        schuler_period_s: run
            .meta_f64(
                design_constants_record::NAME,
                design_constants_record::SCHULER_PERIOD_S,
            )
            .unwrap_or_else(schuler_period_s),
        latitude_rad: run
            .meta_f64(run_record::NAME, run_record::LATITUDE_DEG)
            .map(f64::to_radians),
    };
    ballistic_deviations(
        t,
        err,
        events,
        ship_lat,
        &constants,
        period_hint,
        &opts.ballistic,
    )
}

/// The rolling error from `last_end` on (the whole run without manoeuvres); `None` when the
/// run recorded no roll.
fn rolling_of(
    run: &Run,
    t: &[f64],
    err: &[f64],
    last_end: Option<f64>,
    period_hint: Option<f64>,
    opts: &AnalysisOptions,
) -> Option<RollingError> {
    let st = run.f64_field(SHIP_TOPIC, ship_state::TIME_S).ok()?;
    let roll = run.f64_field(SHIP_TOPIC, ship_state::ROLL_RAD).ok()?;
    let mut ro = opts.rolling;
    if let Some(te) = last_end {
        ro.from_s = ro.from_s.max(te);
    }
    rolling_error(t, err, st, roll, period_hint, &ro)
}

/// Analyses a loaded run (see [`analyze_run`]).
pub fn analyze_loaded(run: &Run, opts: &AnalysisOptions) -> Result<RunAnalysis> {
    let compass = run.frame(COMPASS_TOPIC)?;
    if compass.height() == 0 {
        return Err(AnalysisError::EmptyChannel {
            path: run.path.clone(),
            topic: COMPASS_TOPIC.to_owned(),
        });
    }
    let t = run.f64_field(COMPASS_TOPIC, compass_state::TIME_S)?;
    let err = run.f64_field(COMPASS_TOPIC, compass_state::READING_ERROR_RAD)?;
    let tilt = run.f64_field(COMPASS_TOPIC, compass_state::TILT_RAD).ok();
    let file = run.path.display().to_string();
    let mut notes = Vec::new();

    let events = events_of(run)?;
    let (first_start, last_end) = manoeuvre_span(&events);
    let upto = t.partition_point(|v| first_start.is_none_or(|s| *v < s));

    // Settling oscillation: start to first manoeuvre.
    let azimuth = fit_damped_sinusoid(&t[..upto], &err[..upto], &opts.fit);
    if !azimuth.quality.is_ok() {
        notes.push(format!(
            "{file}: {COMPASS_TOPIC} reading_error_rad: period and decrement refused ({}): {}",
            azimuth.quality, azimuth.message
        ));
    }
    let tilt_fit = tilt.map(|x| fit_damped_sinusoid(&t[..upto], &x[..upto], &opts.fit));
    if let Some(f) = tilt_fit.as_ref().filter(|f| !f.quality.is_ok()) {
        notes.push(format!(
            "{file}: {COMPASS_TOPIC} tilt_rad: period and decrement refused ({}): {}",
            f.quality, f.message
        ));
    }
    let design_period = run.meta_f64(
        design_constants_record::NAME,
        design_constants_record::UNDAMPED_PERIOD_S,
    );
    let period_hint = azimuth
        .period_s
        .map(|p| p.value)
        .or_else(|| {
            run.meta_f64(
                design_constants_record::NAME,
                design_constants_record::MODE_PERIOD_S,
            )
        })
        .or(design_period);

    // Steady error: after the last manoeuvre (or the whole run).
    let steady = match last_end {
        None => steady_error(t, err, Some(&azimuth), period_hint, &opts.steady),
        Some(te) => {
            let from = t.partition_point(|v| *v < te);
            let f = fit_damped_sinusoid(&t[from..], &err[from..], &opts.fit);
            steady_error(
                &t[from..],
                &err[from..],
                Some(&f),
                period_hint,
                &opts.steady,
            )
        }
    };
    if steady.value.is_none() {
        notes.push(format!(
            "{file}: {COMPASS_TOPIC} reading_error_rad: steady error refused: {}",
            steady.message
        ));
    }

    // Ballistic deviations.
    let ballistic = ballistic_of(run, t, err, &events, design_period, period_hint, opts);
    for b in ballistic.iter().filter(|b| !b.quality.is_ok()) {
        notes.push(format!(
            "{file}: {COMPASS_TOPIC} reading_error_rad: ballistic deviation of segment {}: {}",
            b.segment, b.message
        ));
    }

    // Rolling error, after the last manoeuvre.
    let rolling = rolling_of(run, t, err, last_end, period_hint, opts);
    if let Some(r) = rolling.as_ref().filter(|r| !r.quality.is_ok()) {
        notes.push(format!(
            "{file}: {SHIP_TOPIC} roll_rad: rolling error refused: {}",
            r.message
        ));
    }

    let (pt, px) = decimate(t, err, 2000);
    let mut metrics = summarise(
        run,
        t,
        &azimuth,
        tilt_fit.as_ref(),
        &steady,
        &ballistic,
        rolling.as_ref(),
    );
    metrics.start_error_rad = err.first().copied().filter(|e| e.is_finite());
    Ok(RunAnalysis {
        metrics,
        azimuth,
        tilt: tilt_fit,
        steady,
        ballistic,
        rolling,
        notes,
        series: PlotSeries {
            time_s: pt,
            error_rad: px,
        },
    })
}

fn summarise(
    run: &Run,
    t: &[f64],
    azimuth: &OscillationFit,
    tilt: Option<&OscillationFit>,
    steady: &SteadyError,
    ballistic: &[BallisticDeviation],
    rolling: Option<&RollingError>,
) -> RunMetrics {
    let meta = |k: &str| run.meta(run_record::NAME, k).unwrap_or_default().to_owned();
    let result_f64 = |k: &str| run.result(k).and_then(|s| s.trim().parse::<f64>().ok());
    let v = |e: Option<crate::fit::Estimate>| e.map(|e| e.value);
    let sd = |e: Option<crate::fit::Estimate>| e.map(|e| e.sigma);
    let worst = ballistic
        .iter()
        .filter(|b| b.peak_deviation_rad.is_some())
        .max_by(|a, b| {
            let pa = a.peak_deviation_rad.unwrap_or(0.0).abs();
            let pb = b.peak_deviation_rad.unwrap_or(0.0).abs();
            pa.total_cmp(&pb)
        });
    let settle = if ballistic.is_empty() || ballistic.iter().any(|b| b.settle_time_s.is_none()) {
        None
    } else {
        ballistic
            .iter()
            .filter_map(|b| b.settle_time_s)
            .fold(None, |m: Option<f64>, s| Some(m.map_or(s, |m| m.max(s))))
    };
    let duration = match (t.first(), t.last()) {
        (Some(a), Some(b)) => Some(b - a),
        _ => None,
    };
    RunMetrics {
        run_id: run.run_id.clone(),
        path: run.path.display().to_string(),
        scene: meta(run_record::SCENE_NAME),
        design: meta(run_record::DESIGN_NAME),
        design_kind: meta(run_record::DESIGN_KIND),
        fidelity: meta(run_record::FIDELITY),
        integrator: meta(run_record::INTEGRATOR),
        rtol: run.meta_f64(run_record::NAME, run_record::RTOL),
        atol: run.meta_f64(run_record::NAME, run_record::ATOL),
        effects: meta(run_record::EFFECTS),
        status: run.status().to_owned(),
        duration_s: duration,
        samples: t.len() as u64,
        azimuth_quality: azimuth.quality.to_string(),
        period_s: v(azimuth.period_s),
        period_sigma_s: sd(azimuth.period_s),
        log_decrement: v(azimuth.log_decrement),
        log_decrement_sigma: sd(azimuth.log_decrement),
        damping_ratio: v(azimuth.damping_ratio),
        damping_ratio_sigma: sd(azimuth.damping_ratio),
        amplitude_rad: v(azimuth.amplitude),
        tilt_quality: tilt.map(|f| f.quality.to_string()).unwrap_or_default(),
        tilt_period_s: tilt.and_then(|f| v(f.period_s)),
        tilt_period_sigma_s: tilt.and_then(|f| sd(f.period_s)),
        tilt_log_decrement: tilt.and_then(|f| v(f.log_decrement)),
        tilt_log_decrement_sigma: tilt.and_then(|f| sd(f.log_decrement)),
        steady_error_rad: v(steady.value),
        steady_error_sigma_rad: sd(steady.value),
        steady_drift_rad_per_s: v(steady.drift_per_s),
        steady_drift_sigma_rad_per_s: sd(steady.drift_per_s),
        start_error_rad: None,
        ballistic_events: ballistic.len() as u64,
        ballistic_peak_rad: worst.and_then(|b| b.peak_deviation_rad),
        ballistic_expected_peak_rad: worst.and_then(|b| b.expected_peak_deviation_rad),
        ballistic_settle_s: settle,
        ballistic_swing_rad: worst.and_then(|b| b.swing_rad),
        ballistic_backswing_rate_rad_per_s: worst.and_then(|b| b.backswing_rate_rad_per_s),
        rolling_error_rad: rolling.and_then(|r| v(r.mean_error)),
        rolling_error_sigma_rad: rolling.and_then(|r| sd(r.mean_error)),
        roll_period_s: rolling.map(|r| r.roll_period_s).filter(|p| p.is_finite()),
        steps: u64_last(run, SOLVER_TOPIC, solver_stats::STEPS)
            .or_else(|| result_f64(result_record::STEPS).map(|v| v as u64)),
        rejected_steps: u64_last(run, SOLVER_TOPIC, solver_stats::REJECTED_STEPS),
        rhs_evals: u64_last(run, SOLVER_TOPIC, solver_stats::RHS_EVALS)
            .or_else(|| result_f64(result_record::RHS_EVALS).map(|v| v as u64)),
        jacobian_evals: u64_last(run, SOLVER_TOPIC, solver_stats::JACOBIAN_EVALS),
        wall_time_s: f64_last(run, SOLVER_TOPIC, solver_stats::WALL_TIME_S)
            .or_else(|| result_f64(result_record::WALL_TIME_S)),
        rhs_cost_ns: run.meta_f64(run_record::NAME, run_record::RHS_COST_NS),
    }
}

/// The quality string of a fit as a [`Quality`] (unknown or empty: `None`).
pub fn parse_quality(s: &str) -> Option<Quality> {
    s.parse().ok()
}
