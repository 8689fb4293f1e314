//! gyro-study: design studies at scale. A study file (TOML, `sweeps/`) names base scenes and
//! designs, grid axes and seeded random axes over any scene or design key, and what to keep of
//! each run; a pure function maps a run index to its scene ([`Plan::run`], [`Plan::scene`]), so
//! any worker runs any index and a retry or a resume reproduces it exactly. A run is recorded
//! and analysed as `gyrolab run` and `gyrolab analyze` would; its metrics are one row of
//! `DIR/metrics.parquet`, written in parts while the sweep goes and merged at its end.
//!
//! It knows nothing of the command line (gyrolab draws the progress bar and starts the Ray
//! driver); it owns the study format, the mapping, the engines' shared machinery and the table.
//!
//! # Modules
//! - [`study`]: the study file and its checks; [`draw`]: seeded draws as pure functions;
//! - [`plan`]: a study resolved against its scenes and designs, the run-index map, the frozen
//!   inputs of a sweep folder;
//! - [`exec`]: one run, and a list of runs on a pool of threads;
//! - [`table`]: rows, Parquet parts, the merge into `metrics.parquet`;
//! - [`sweep`]: the local engine, a Ray task's chunk, a folder's status, the plan's estimate;
//! - [`report`]: tables and plots of the metrics against the axes;
//! - [`comparison`]: every design on one standard scene set, and the text's comparative claims
//!   checked against the metrics (`gyrolab comparison`, docs/comparison.md).

pub mod comparison;
pub mod draw;
pub mod exec;
pub mod plan;
pub mod report;
pub mod study;
pub mod sweep;
pub mod table;

pub use plan::{Plan, RunSpec};
pub use study::Study;
