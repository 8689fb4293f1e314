//! The local engine: a sweep writes one typed row per run into `metrics.parquet`; a stopped
//! sweep resumes with only the missing runs and ends with the same table; a run that fails is a
//! `failed` row with its reason.

use crate::common::{HARBOUR, study, tmp};
use gyro_study::sweep::run_local;
use gyro_study::table::{self, TIMING_COLUMNS};
use polars::prelude::*;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

fn no_timing(df: &DataFrame) -> DataFrame {
    df.drop_many(TIMING_COLUMNS)
}

#[test]
fn local_sweep_writes_one_typed_row_per_run() {
    let p = study(HARBOUR).expect("loads");
    let out = tmp("local-typed");
    let stop = Arc::new(AtomicBool::new(false));
    let s = run_local(&p, &out, 2, &stop, |_, _| {}).expect("sweep");
    assert_eq!(
        (s.total_runs, s.ran, s.failed, s.already_done),
        (6, 6, 0, 0)
    );
    let df = table::read_parquet(&table::metrics_path(&out)).expect("table");
    assert_eq!(df.height(), 6);
    let idx: Vec<u64> = df["run_index"]
        .u64()
        .expect("u64")
        .into_no_null_iter()
        .collect();
    assert_eq!(idx, [0, 1, 2, 3, 4, 5]);
    assert_eq!(df["start.latitude_deg"].dtype(), &DataType::Float64);
    assert_eq!(df["period_s"].dtype(), &DataType::Float64);
    assert_eq!(df["steps"].dtype(), &DataType::UInt64);
    let status: Vec<&str> = df["status"]
        .str()
        .expect("str")
        .iter()
        .map(|s| s.unwrap_or(""))
        .collect();
    assert!(status.iter().all(|s| *s == "ok"), "{status:?}");
    // The fitted amplitude follows the release offset (2°, 4°, 6°) at each latitude.
    let amp: Vec<f64> = df["amplitude_rad"]
        .f64()
        .expect("f64")
        .into_no_null_iter()
        .collect();
    assert!(
        amp[0].abs() < amp[1].abs() && amp[1].abs() < amp[2].abs(),
        "{amp:?}"
    );
    // Nothing half-written or left over: the parts are merged, the work folder gone.
    assert!(!table::parts_dir(&out).exists());
    assert!(!gyro_study::exec::work_dir(&out).exists());
    // A second run finds everything done and runs nothing.
    let again = run_local(&p, &out, 2, &stop, |_, _| {}).expect("sweep");
    assert_eq!((again.ran, again.already_done), (0, 6));
    let same = table::read_parquet(&table::metrics_path(&out)).expect("table");
    assert!(no_timing(&same).equals_missing(&no_timing(&df)));
}

#[test]
fn a_stopped_sweep_resumes_with_the_missing_runs_only_and_the_same_table() {
    let p = study(HARBOUR).expect("loads");
    let whole = tmp("resume-whole");
    let stop = Arc::new(AtomicBool::new(false));
    run_local(&p, &whole, 2, &stop, |_, _| {}).expect("sweep");
    let reference = table::read_parquet(&table::metrics_path(&whole)).expect("table");

    let out = tmp("resume-stopped");
    let stop = Arc::new(AtomicBool::new(false));
    let first = run_local(&p, &out, 1, &stop, |pr, _| {
        if pr.finished == 2 {
            stop.store(true, Ordering::Relaxed);
        }
    })
    .expect("stopped sweep");
    assert!(first.interrupted);
    assert_eq!(first.ran, 2);
    let status = gyro_study::sweep::status(&out).expect("status");
    assert_eq!((status.ok, status.missing), (2, 4));
    let go = Arc::new(AtomicBool::new(false));
    let second = run_local(&p, &out, 2, &go, |_, _| {}).expect("resumed sweep");
    assert_eq!(
        (second.ran, second.already_done),
        (4, 2),
        "finished runs are not run again"
    );
    let resumed = table::read_parquet(&table::metrics_path(&out)).expect("table");
    assert!(
        no_timing(&resumed).equals_missing(&no_timing(&reference)),
        "resumed:\n{resumed}\nuninterrupted:\n{reference}"
    );
}

#[test]
fn a_run_that_diverges_is_a_failed_row_with_its_reason() {
    let p = study(
        r#"
name = "diverging"
scenes = ["harbour-50n"]
[[axis]]
key = "duration_s"
values = [600.0]
[[axis]]
key = "simulation.integrator"
values = ["rodas4", "rk4:30"]
[keep]
recordings = "failed"
"#,
    )
    .expect("loads");
    let out = tmp("diverging");
    let stop = Arc::new(AtomicBool::new(false));
    let s = run_local(&p, &out, 2, &stop, |_, _| {}).expect("the sweep completes");
    assert_eq!((s.ran, s.failed), (2, 1));
    let df = table::read_parquet(&table::metrics_path(&out)).expect("table");
    let status: Vec<&str> = df["status"]
        .str()
        .expect("str")
        .iter()
        .map(|s| s.unwrap_or(""))
        .collect();
    let reason: Vec<&str> = df["reason"]
        .str()
        .expect("str")
        .iter()
        .map(|s| s.unwrap_or(""))
        .collect();
    assert_eq!(status, ["ok", "failed"]);
    assert!(reason[1].contains("non-finite state"), "{reason:?}");
    // recordings = "failed": the failed run's recording is kept (salvaged), the other is not.
    let rec: Vec<&str> = df["recording"]
        .str()
        .expect("str")
        .iter()
        .map(|s| s.unwrap_or(""))
        .collect();
    assert_eq!(rec[0], "");
    assert!(out.join(rec[1]).is_file(), "{rec:?}");
    assert!(gyro_mcap::Recording::open(&out.join(rec[1])).is_ok());
    let st = gyro_study::sweep::status(&out).expect("status");
    assert_eq!(st.failures.len(), 1);
    assert!(st.failures[0].1.contains("non-finite"));
}

#[test]
fn a_monte_carlo_report_gives_spreads_quantiles_and_a_histogram() {
    let p = study(
        r#"
name = "mc-harbour"
scenes = ["harbour-50n"]
[[axis]]
key = "duration_s"
values = [10800.0]
[monte_carlo]
samples = 24
seed = 3
[[random]]
key = "compass.azimuth_offset_deg"
distribution = "normal"
mean = 0.0
std = 4.0
[keep]
metrics = ["amplitude_rad", "period_s"]
"#,
    )
    .expect("loads");
    let out = tmp("mc-report");
    run_local(&p, &out, 2, &Arc::new(AtomicBool::new(false)), |_, _| {}).expect("sweep");
    let r = gyro_study::report::report(&out).expect("report");
    let amp = r
        .spreads
        .iter()
        .find(|s| s.metric == "amplitude_rad")
        .expect("the amplitude's spread");
    assert_eq!(amp.n, 24);
    assert!(amp.quantiles.windows(2).all(|w| w[0] <= w[1]), "{amp:?}");
    // The fitted amplitude is proportional to |release offset| (the linear regime; the table's
    // own axis column): its spread over the samples is the offsets' spread, scaled alike.
    let df = table::read_parquet(&table::metrics_path(&out)).expect("table");
    let off: Vec<f64> = df["compass.azimuth_offset_deg"]
        .f64()
        .expect("f64")
        .iter()
        .map(|v| v.unwrap_or(f64::NAN).to_radians().abs())
        .collect();
    let m = off.iter().sum::<f64>() / off.len() as f64;
    let sd = (off.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (off.len() - 1) as f64).sqrt();
    let k = amp.mean / m;
    assert!(
        (amp.std / (k * sd) - 1.0).abs() < 0.05,
        "{} vs {k} × {sd}",
        amp.std
    );
    // The period does not depend on the offset (linear regime): a narrow spread.
    let per = r
        .spreads
        .iter()
        .find(|s| s.metric == "period_s")
        .expect("period");
    assert!(per.std < 1e-3 * per.mean, "{per:?}");
    assert!(out.join("report/amplitude_rad-histogram.svg").is_file());
    assert!(r.render().contains("Spreads over the Monte Carlo samples"));
}

#[test]
fn a_combination_the_scene_refuses_is_a_failed_row_not_a_crashed_sweep() {
    // Each value loads alone (89.5°N moored; 30 kn at 50°N), but 30 kn North from 89.5°N
    // reaches the pole within the run: that run's scene is refused, the others run.
    let p = study(
        r#"
name = "pole"
scenes = ["harbour-50n"]
[[axis]]
key = "duration_s"
values = [3600.0]
[[axis]]
key = "start.latitude_deg"
values = [10.0, 89.5]
[[axis]]
key = "start.speed_kn"
values = [0.0, 30.0]
"#,
    )
    .expect("every value loads alone");
    let out = tmp("pole");
    let s = run_local(&p, &out, 2, &Arc::new(AtomicBool::new(false)), |_, _| {}).expect("sweep");
    assert_eq!((s.ran, s.failed), (4, 1));
    let df = table::read_parquet(&table::metrics_path(&out)).expect("table");
    let reason: Vec<&str> = df["reason"]
        .str()
        .expect("str")
        .iter()
        .map(|s| s.unwrap_or(""))
        .collect();
    assert!(
        reason[3].starts_with("bad scene:") && reason[3].contains("pole"),
        "{reason:?}"
    );
    assert!(reason[..3].iter().all(|r| r.is_empty()), "{reason:?}");
}
