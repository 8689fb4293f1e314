//! Regression of fitted metrics against a reviewed baseline (a TOML file in `analysis/`):
//! per-metric tolerances |current − baseline| ≤ abs + rel·|baseline|, and the fit quality flags,
//! which must not change. [`regress`] says what moved and by how much; [`update_baseline`]
//! rewrites the file after review.
//!
//! ```toml
//! [tolerances.period_s]
//! abs = 1.0
//! rel = 0.001
//!
//! [runs."anschutz-calm/anschutz-1906/full/dopri5"]
//! azimuth_quality = "ok"
//! period_s = 3801.2
//! ```

use std::collections::BTreeMap;
use std::io::Write as _;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::error::{AnalysisError, Result};
use crate::file::write_whole;
use crate::metrics::{Cell, MetricsTable, RunMetrics, format_number};
use crate::table::{Align, Table};

/// One metric's tolerance: |current − baseline| ≤ abs + rel·|baseline|.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MetricTolerance {
    #[serde(default)]
    pub abs: f64,
    #[serde(default)]
    pub rel: f64,
}

impl MetricTolerance {
    pub fn allowed(&self, baseline: f64) -> f64 {
        self.abs + self.rel * baseline.abs()
    }
}

/// Tolerances by metric (column name of the metrics table); the solver's tolerances are
/// `gyro_sim::solvers::Tolerances`.
pub type MetricTolerances = BTreeMap<String, MetricTolerance>;

/// Quality columns compared for equality.
pub const QUALITY_COLUMNS: [&str; 2] = ["azimuth_quality", "tilt_quality"];

/// The metrics a baseline tracks by default and their tolerances (SI units: s, rad, rad/s).
/// Solver costs that depend on the machine (wall time) are not tracked; step and evaluation
/// counts are (deterministic for a given integrator and tolerance), loosely.
pub fn default_tolerances() -> MetricTolerances {
    let deg = std::f64::consts::PI / 180.0;
    [
        ("period_s", 1.0, 1e-3),
        ("log_decrement", 5e-3, 1e-2),
        ("damping_ratio", 2e-3, 1e-2),
        ("tilt_period_s", 1.0, 1e-3),
        ("tilt_log_decrement", 5e-3, 1e-2),
        ("steady_error_rad", 0.01 * deg, 1e-2),
        ("steady_drift_rad_per_s", 1e-9, 5e-2),
        ("ballistic_peak_rad", 0.02 * deg, 2e-2),
        ("ballistic_settle_s", 60.0, 5e-2),
        ("rolling_error_rad", 0.01 * deg, 2e-2),
        ("steps", 0.0, 0.1),
        ("rhs_evals", 0.0, 0.1),
    ]
    .into_iter()
    .map(|(k, abs, rel)| (k.to_owned(), MetricTolerance { abs, rel }))
    .collect()
}

/// The baseline file.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct Baseline {
    #[serde(default)]
    pub tolerances: MetricTolerances,
    /// Metric values by run key ([`RunMetrics::key`]) and column.
    #[serde(default)]
    pub runs: BTreeMap<String, BTreeMap<String, toml::Value>>,
}

impl Baseline {
    pub fn read(path: &Path) -> Result<Baseline> {
        let text = std::fs::read_to_string(path).map_err(AnalysisError::io(path, "reading"))?;
        toml::from_str(&text).map_err(|e| AnalysisError::Baseline {
            path: path.to_path_buf(),
            what: format!("not a baseline: {e}"),
        })
    }

    /// The baseline of a table: its tracked metrics and quality flags, per run key.
    pub fn of(table: &MetricsTable, tolerances: MetricTolerances) -> Baseline {
        let mut runs = BTreeMap::new();
        for row in &table.rows {
            let mut values = BTreeMap::new();
            for q in QUALITY_COLUMNS {
                if let Some(Cell::Str(s)) = row.cell(q)
                    && !s.is_empty()
                {
                    values.insert(q.to_owned(), toml::Value::String(s));
                }
            }
            for metric in tolerances.keys() {
                match row.cell(metric) {
                    Some(Cell::U64(Some(v))) => {
                        values.insert(
                            metric.clone(),
                            toml::Value::Integer(i64::try_from(v).unwrap_or(i64::MAX)),
                        );
                    }
                    Some(c) => {
                        if let Some(v) = c.as_f64().filter(|v| v.is_finite()) {
                            values.insert(metric.clone(), toml::Value::Float(v));
                        }
                    }
                    None => {}
                }
            }
            runs.insert(row.key(), values);
        }
        Baseline { tolerances, runs }
    }

    pub fn write(&self, path: &Path) -> Result<()> {
        let body = toml::to_string_pretty(self).map_err(|e| AnalysisError::Baseline {
            path: path.to_path_buf(),
            what: format!("cannot serialise: {e}"),
        })?;
        let text = format!(
            "# gyrolab regression baseline: fitted metrics per run (SI: s, rad, rad/s) and the\n\
             # tolerance of each metric, |current - baseline| <= abs + rel*|baseline|.\n\
             # Rewritten by `gyrolab regress --update` after review; edit tolerances by hand.\n\n{body}"
        );
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(AnalysisError::io(dir, "creating"))?;
        }
        write_whole(path, |w| {
            w.write_all(text.as_bytes())
                .map_err(AnalysisError::io(path, "writing"))
        })
    }
}

/// What happened to one metric of one run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Status {
    /// Identical to the baseline.
    Unchanged,
    /// Changed within tolerance.
    Moved,
    /// Changed beyond tolerance, lost, or a quality flag changed: fails the check.
    Regressed,
    /// A baseline run that is not among the current runs: fails the check.
    MissingRun,
    /// Measured now, not in the baseline (a new run or metric): reported, passes.
    New,
}

/// One line of the report.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Finding {
    pub run: String,
    pub metric: String,
    pub status: Status,
    pub baseline: Option<String>,
    pub current: Option<String>,
    pub delta: Option<f64>,
    pub allowed: Option<f64>,
}

/// The comparison of current metrics with a baseline.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RegressionReport {
    pub baseline_path: PathBuf,
    pub findings: Vec<Finding>,
}

impl RegressionReport {
    /// No regression and no missing run.
    pub fn passed(&self) -> bool {
        !self
            .findings
            .iter()
            .any(|f| matches!(f.status, Status::Regressed | Status::MissingRun))
    }

    pub fn regressions(&self) -> impl Iterator<Item = &Finding> {
        self.findings
            .iter()
            .filter(|f| matches!(f.status, Status::Regressed | Status::MissingRun))
    }

    fn lines(&self, all: bool) -> Vec<[String; 6]> {
        self.findings
            .iter()
            .filter(|f| all || f.status != Status::Unchanged)
            .map(|f| {
                [
                    match f.status {
                        Status::Unchanged => "same",
                        Status::Moved => "moved",
                        Status::Regressed => "REGRESSED",
                        Status::MissingRun => "MISSING",
                        Status::New => "new",
                    }
                    .to_owned(),
                    f.run.clone(),
                    f.metric.clone(),
                    f.baseline.clone().unwrap_or_else(|| "–".into()),
                    f.current.clone().unwrap_or_else(|| "–".into()),
                    match (f.delta, f.allowed) {
                        (Some(d), Some(a)) => {
                            format!("{} (allowed ±{})", format_number(d), format_number(a))
                        }
                        (Some(d), None) => format_number(d),
                        _ => String::new(),
                    },
                ]
            })
            .collect()
    }

    fn summary(&self) -> String {
        let count = |s: Status| self.findings.iter().filter(|f| f.status == s).count();
        format!(
            "{}: {} regressed, {} missing, {} moved within tolerance, {} unchanged, {} new (baseline {})",
            if self.passed() { "PASS" } else { "FAIL" },
            count(Status::Regressed),
            count(Status::MissingRun),
            count(Status::Moved),
            count(Status::Unchanged),
            count(Status::New),
            self.baseline_path.display()
        )
    }

    /// What moved, aligned for a terminal, then PASS or FAIL.
    pub fn render_terminal(&self) -> String {
        let t = self.table();
        let mut out = if t.is_empty() {
            String::new()
        } else {
            t.render()
        };
        out.push_str(&self.summary());
        out.push('\n');
        out
    }

    /// The same as a Markdown table.
    pub fn render_markdown(&self) -> String {
        let mut out = format!("**{}**\n\n", self.summary());
        let t = self.table();
        if !t.is_empty() {
            out.push_str(&t.render_markdown());
        }
        out
    }

    fn table(&self) -> Table {
        let mut t = Table::new(&["status", "run", "metric", "baseline", "current", "delta"])
            .align(3, Align::Right)
            .align(4, Align::Right);
        for l in self.lines(false) {
            t.row(l);
        }
        t
    }
}

fn value_text(v: &toml::Value) -> String {
    match v {
        toml::Value::Float(f) => format_number(*f),
        toml::Value::Integer(i) => i.to_string(),
        toml::Value::String(s) => s.clone(),
        other => other.to_string(),
    }
}

fn value_f64(v: &toml::Value) -> Option<f64> {
    match v {
        toml::Value::Float(f) => Some(*f),
        toml::Value::Integer(i) => Some(*i as f64),
        _ => None,
    }
}

/// Compares `table` with the baseline at `baseline_path`. Tolerances: `tolerances` when given,
/// else the baseline file's, else [`default_tolerances`] (per metric, the first that has it).
pub fn regress(
    table: &MetricsTable,
    baseline_path: &Path,
    tolerances: Option<&MetricTolerances>,
) -> Result<RegressionReport> {
    let baseline = Baseline::read(baseline_path)?;
    let mut tol = default_tolerances();
    tol.extend(baseline.tolerances.clone());
    if let Some(t) = tolerances {
        tol.extend(t.clone());
    }
    let by_key: BTreeMap<String, &RunMetrics> = table.rows.iter().map(|r| (r.key(), r)).collect();
    let mut findings = Vec::new();
    for (key, values) in &baseline.runs {
        let Some(row) = by_key.get(key) else {
            findings.push(Finding {
                run: key.clone(),
                metric: String::new(),
                status: Status::MissingRun,
                baseline: None,
                current: None,
                delta: None,
                allowed: None,
            });
            continue;
        };
        for q in QUALITY_COLUMNS {
            let base = values.get(q).map(value_text);
            let cur = match row.cell(q) {
                Some(Cell::Str(s)) if !s.is_empty() => Some(s),
                _ => None,
            };
            if base.is_none() && cur.is_none() {
                continue;
            }
            let status = match (&base, &cur) {
                (Some(b), Some(c)) if b == c => Status::Unchanged,
                (None, Some(_)) => Status::New,
                _ => Status::Regressed,
            };
            findings.push(Finding {
                run: key.clone(),
                metric: q.to_owned(),
                status,
                baseline: base,
                current: cur,
                delta: None,
                allowed: None,
            });
        }
        for (metric, t) in &tol {
            let base = values.get(metric).and_then(value_f64);
            let cur = row
                .cell(metric)
                .and_then(|c| c.as_f64())
                .filter(|v| v.is_finite());
            let (status, delta, allowed) = match (base, cur) {
                (None, None) => continue,
                (None, Some(_)) => (Status::New, None, None),
                (Some(b), None) => (Status::Regressed, None, Some(t.allowed(b))),
                (Some(b), Some(c)) => {
                    let d = c - b;
                    let a = t.allowed(b);
                    let s = if d == 0.0 {
                        Status::Unchanged
                    } else if d.abs() <= a {
                        Status::Moved
                    } else {
                        Status::Regressed
                    };
                    (s, Some(d), Some(a))
                }
            };
            findings.push(Finding {
                run: key.clone(),
                metric: metric.clone(),
                status,
                baseline: values.get(metric).map(value_text),
                current: cur.map(format_number),
                delta,
                allowed,
            });
        }
    }
    for (key, _) in by_key
        .iter()
        .filter(|(k, _)| !baseline.runs.contains_key(*k))
    {
        findings.push(Finding {
            run: key.clone(),
            metric: String::new(),
            status: Status::New,
            baseline: None,
            current: None,
            delta: None,
            allowed: None,
        });
    }
    Ok(RegressionReport {
        baseline_path: baseline_path.to_path_buf(),
        findings,
    })
}

/// Rewrites the baseline at `path` from `table`, keeping the file's tolerances (or `tolerances`
/// when given, or the defaults when the file does not exist yet).
pub fn update_baseline(
    table: &MetricsTable,
    path: &Path,
    tolerances: Option<&MetricTolerances>,
) -> Result<Baseline> {
    let tol = match tolerances {
        Some(t) => t.clone(),
        None if path.exists() => {
            let b = Baseline::read(path)?;
            if b.tolerances.is_empty() {
                default_tolerances()
            } else {
                b.tolerances
            }
        }
        None => default_tolerances(),
    };
    let baseline = Baseline::of(table, tol);
    baseline.write(path)?;
    Ok(baseline)
}
