//! gyro-analysis owns what gyrolab concludes from its recordings: it loads them with polars
//! (one DataFrame per channel, many runs in parallel), fits the settling oscillation (period,
//! logarithmic decrement, damping ratio), the steady reading error and its drift, detects the
//! ballistic deviation after each manoeuvre and the rectified rolling error, and gathers the
//! numbers of each run into a metrics table that compares designs and that a regression check
//! holds against a reviewed baseline. Every estimate carries its 1-σ uncertainty and a quality
//! flag; a fit the data do not allow is refused with a reason, never guessed.
//!
//! It reads recordings only through `gyro-mcap` and the contract of `docs/recordings.md`. From
//! `gyro-model` it takes only physical constants and closed forms (the Schuler period and the
//! speed error a manoeuvre's deviation is judged against, re-exported by [`ballistic`]), never
//! the engines or a compiled model: it knows nothing of how a run was simulated (no dependency
//! on gyro-sim) nor of the command line, which calls the entry points below.
//!
//! # Entry points
//! - [`analyze_runs`] / [`analyze_run`]: recordings → [`MetricsTable`] / [`RunAnalysis`]
//!   (`gyrolab analyze`).
//! - [`compare()`]: runs → [`ComparisonReport`] with terminal and Markdown tables and an overlay
//!   plot in SVG and PNG (`gyrolab compare`).
//! - [`regress()`] and [`update_baseline`]: a table against a TOML baseline with per-metric
//!   tolerances → [`RegressionReport`] (`gyrolab regress [--update]`).
//!
//! # Modules
//! - [`load`]: recordings → DataFrames; [`fit`]: damped sinusoid by Levenberg–Marquardt;
//!   [`steady`]: settled value and drift; [`ballistic`]: deviation after manoeuvres;
//!   [`rolling`]: mean error under rolling; [`metrics`]: per-run analysis and the table;
//!   [`compare`]: runs side by side; [`regress`]: the baseline check; [`plot`]: line plots as
//!   SVG and PNG (also used by `gyrolab accuracy`); [`table`]: the aligned text and Markdown
//!   tables every report and the CLI print; [`error`]: the crate's one error type; [`file`]: every
//!   file written whole (`<name>.partial`, renamed when complete), also for gyro-study and the CLI.
//!
//! Units are SI inside (s, rad); renderers for people show minutes and degrees.

pub mod ballistic;
pub mod compare;
pub mod error;
pub mod file;
pub mod fit;
pub mod load;
pub mod metrics;
pub mod plot;
pub mod regress;
pub mod rolling;
pub mod steady;
pub mod table;

pub use compare::{ComparisonReport, compare};
pub use error::{AnalysisError, Result};
pub use fit::{Estimate, FitOptions, OscillationFit, Quality, fit_damped_sinusoid};
pub use load::{LoadOptions, Run, load_run, load_runs};
pub use metrics::{
    AnalysisOptions, MetricsTable, RunAnalysis, RunMetrics, analyze_run, analyze_runs,
};
pub use regress::{MetricTolerance, MetricTolerances, RegressionReport, regress, update_baseline};
