//! Recordings written with gyro-mcap's writer on the contract of docs/recordings.md, analysed end
//! to end: loading, fits, ballistic deviation, rolling error, the metrics table and its files.
#![allow(clippy::unwrap_used)]

use crate::common;

use std::f64::consts::PI;

use common::{Manoeuvre, Spec, damped, temp_dir, write_run};
use gyro_analysis::ballistic::speed_error_rad;
use gyro_analysis::load::{COMPASS_TOPIC, LoadOptions, stack_channel};
use gyro_analysis::{AnalysisOptions, MetricsTable, Quality, analyze_run, load_run, load_runs};

fn settling_spec() -> Spec {
    Spec {
        error: Box::new(damped(0.002, 0.0, 0.05, 0.2 / 3700.0, 3700.0, 0.0)),
        tilt: Box::new(damped(0.0, 0.0, 0.001, 0.2 / 3700.0, 3700.0, -PI / 2.0)),
        ..Spec::default()
    }
}

#[test]
fn a_channel_becomes_a_frame_with_time_fields_and_run_id() {
    let dir = temp_dir("frame");
    let path = write_run(&dir.join("settle.mcap"), &settling_spec());
    let run = load_run(&path, &LoadOptions::default()).unwrap();
    assert_eq!(run.run_id, "settle");
    let compass = run.frame(COMPASS_TOPIC).unwrap();
    let names: Vec<&str> = compass
        .get_column_names()
        .iter()
        .map(|s| s.as_str())
        .collect();
    assert_eq!(names.first(), Some(&"time_s"));
    assert_eq!(names.last(), Some(&"run_id"));
    assert!(names.contains(&"reading_error_rad") && names.contains(&"theta_rate_rad_per_s"));
    assert_eq!(compass.height(), 6 * 3600 + 1);
    let t = run.f64_field(COMPASS_TOPIC, "time_s").unwrap();
    assert_eq!(t[3600], 3600.0);
    assert_eq!(run.meta("run", "design_name"), Some("synthetic"));
    // Events keep their string and integer columns.
    let events = run.frame("/events").unwrap();
    assert_eq!(events.height(), 0);
    // Asking for one topic decodes only that one.
    let one = load_run(&path, &LoadOptions::topics(&["/ship/state"])).unwrap();
    assert_eq!(one.frames.len(), 1);
    let err = one.frame(COMPASS_TOPIC).unwrap_err().to_string();
    assert!(
        err.contains("settle.mcap") && err.contains("/compass/state"),
        "{err}"
    );
}

#[test]
fn many_runs_load_in_parallel_and_scan_lazily() {
    let dir = temp_dir("many");
    for k in 0..4 {
        let spec = Spec {
            duration_s: 3600.0,
            error: Box::new(move |t| k as f64 + 1e-3 * t),
            ..Spec::default()
        };
        write_run(&dir.join(format!("run{k}.mcap")), &spec);
    }
    let runs = load_runs(std::slice::from_ref(&dir), &LoadOptions::default()).unwrap();
    assert_eq!(runs.len(), 4);
    let glob = dir.join("run[12].mcap");
    assert_eq!(
        load_runs(&[glob], &LoadOptions::default()).unwrap().len(),
        2
    );
    let stacked = stack_channel(&runs, COMPASS_TOPIC).unwrap();
    let ids = stacked.column("run_id").unwrap().str().unwrap();
    let errors = stacked.column("reading_error_rad").unwrap().f64().unwrap();
    let mut sums: std::collections::BTreeMap<&str, (f64, usize)> = Default::default();
    for (id, e) in ids.iter().zip(errors.iter()) {
        let entry = sums.entry(id.unwrap()).or_default();
        entry.0 += e.unwrap();
        entry.1 += 1;
    }
    assert_eq!(sums.len(), 4);
    for (k, (sum, n)) in sums.values().enumerate() {
        let want = k as f64 + 1e-3 * 1800.0;
        let m = sum / *n as f64;
        assert!((m - want).abs() < 1e-9, "run {k}: mean {m}, want {want}");
    }
}

#[test]
fn a_settling_run_gives_period_decrement_and_steady_error() {
    let dir = temp_dir("settle");
    let path = write_run(&dir.join("settle.mcap"), &settling_spec());
    let a = analyze_run(&path, &AnalysisOptions::default()).unwrap();
    assert_eq!(a.azimuth.quality, Quality::Ok, "{}", a.azimuth.message);
    let m = &a.metrics;
    assert!(
        (m.period_s.unwrap() - 3700.0).abs() < 3.7,
        "{:?}",
        m.period_s
    );
    assert!((m.log_decrement.unwrap() - 0.2).abs() < 2e-3);
    assert!((m.tilt_period_s.unwrap() - 3700.0).abs() < 3.7);
    assert!((m.steady_error_rad.unwrap() - 0.002).abs() < 1e-5);
    assert_eq!(m.steps, Some(2160));
    assert_eq!(m.design, "synthetic");
    assert_eq!(m.key(), "calm/synthetic/full/dopri5");
    assert!(a.notes.is_empty(), "{:?}", a.notes);
    assert!(a.rolling.is_none());
}

#[test]
fn ballistic_deviation_after_a_speed_change() {
    // 10 m/s northward from rest at 50° N, a 60-s manoeuvre at t = 2 h; the compass (T = 3600 s)
    // swings to (T_S²/T² − 1)·Δζ_eq from its new equilibrium, then settles with Λ = 0.5.
    let lat: f64 = 50.0_f64.to_radians();
    let shift = speed_error_rad(10.0, 0.0, lat) - speed_error_rad(0.0, 0.0, lat);
    let ratio = (5064.3f64 / 3600.0).powi(2);
    let d0 = (ratio - 1.0) * shift;
    let (ts, te) = (7200.0, 7260.0);
    let sigma = 0.5 / 3600.0;
    let error = move |t: f64| {
        if t < te {
            0.0
        } else {
            shift + d0 * (-sigma * (t - te)).exp() * (2.0 * PI * (t - te) / 3600.0).cos()
        }
    };
    let spec = Spec {
        duration_s: 12.0 * 3600.0,
        error: Box::new(error),
        undamped_period_s: Some(3600.0),
        manoeuvres: vec![Manoeuvre {
            start_s: ts,
            end_s: te,
            segment: 1,
            speed_before: 0.0,
            speed_after: 10.0,
            heading_before: 0.0,
            heading_after: 0.0,
        }],
        ..Spec::default()
    };
    let dir = temp_dir("ballistic");
    let path = write_run(&dir.join("speed.mcap"), &spec);
    let a = analyze_run(&path, &AnalysisOptions::default()).unwrap();
    assert_eq!(a.ballistic.len(), 1);
    let b = &a.ballistic[0];
    assert_eq!(b.quality, Quality::Ok, "{}", b.message);
    let eq = b.equilibrium_after.unwrap().value;
    assert!((eq - shift).abs() < 1e-4, "equilibrium {eq} vs {shift}");
    let peak = b.peak_deviation_rad.unwrap();
    assert!((peak - d0).abs() < 2e-4, "peak {peak} vs {d0}");
    assert!((b.peak_time_s.unwrap() - te).abs() <= 2.0);
    let expected = b.expected_peak_deviation_rad.unwrap();
    assert!(
        (expected - d0).abs() < 1e-9 * d0.abs().max(1.0),
        "{expected} vs {d0}"
    );
    assert!((b.expected_ballistic_deflection_rad.unwrap() - ratio * shift).abs() < 1e-12);
    assert_eq!(b.expected_schuler_deviation_rad, 0.0);
    // Band: the wider of 0.1° and 10 % of the peak; the envelope enters it at ln(10)/σ.
    let band = b.settle_band_rad;
    assert!((band - 0.1f64.to_radians().max(0.1 * d0.abs())).abs() < 1e-4);
    let envelope_in = (d0.abs() / band).ln() / sigma;
    let settle = b.settle_time_s.unwrap();
    assert!(
        settle <= envelope_in + 1.0 && settle > envelope_in - 1900.0,
        "{settle} vs {envelope_in}"
    );
    assert_eq!(a.metrics.ballistic_events, 1);
    assert!(a.metrics.ballistic_settle_s.is_some());
}

#[test]
fn rolling_error_is_the_mean_without_the_free_oscillation() {
    // Roll 0.1 rad at 10 s; the error: a rectified mean of 0.004 rad, a roll-frequency wobble,
    // and a free oscillation of 3600 s decaying with Λ = 0.3.
    let spec = Spec {
        rate_hz: 2.0,
        duration_s: 8.0 * 3600.0,
        roll: Box::new(|t| 0.1 * (2.0 * PI * t / 10.0).sin()),
        error: Box::new(|t| {
            0.004
                + 0.002 * (2.0 * PI * t / 10.0 + 0.3).sin()
                + 0.03 * (-0.3 / 3600.0 * t).exp() * (2.0 * PI * t / 3600.0).cos()
        }),
        ..Spec::default()
    };
    let dir = temp_dir("rolling");
    let path = write_run(&dir.join("roll.mcap"), &spec);
    let a = analyze_run(&path, &AnalysisOptions::default()).unwrap();
    let r = a.rolling.unwrap();
    assert_eq!(r.quality, Quality::Ok, "{}", r.message);
    assert!((r.roll_period_s - 10.0).abs() < 1e-3, "{}", r.roll_period_s);
    assert!((r.roll_amplitude_rad - 0.1).abs() < 1e-3);
    let mean = r.mean_error.unwrap().value;
    assert!((mean - 0.004).abs() < 5e-5, "{mean}");
    assert!((a.metrics.rolling_error_rad.unwrap() - 0.004).abs() < 5e-5);
}

#[test]
fn the_table_round_trips_through_csv_json_and_parquet() {
    let dir = temp_dir("table");
    let p1 = write_run(&dir.join("a.mcap"), &settling_spec());
    let spec = Spec {
        design: "other".into(),
        error: Box::new(damped(0.001, 0.0, 0.04, 0.5 / 4100.0, 4100.0, 0.0)),
        ..Spec::default()
    };
    let p2 = write_run(&dir.join("b.mcap"), &spec);
    let table = gyro_analysis::analyze_runs(&[p1, p2]).unwrap();
    assert_eq!(table.rows.len(), 2);
    let df = table.to_dataframe().unwrap();
    assert_eq!(df.height(), 2);
    assert!(df.column("period_s").unwrap().f64().is_ok());
    let files = table.write_all(&dir.join("metrics")).unwrap();
    for f in &files {
        assert!(std::fs::metadata(f).unwrap().len() > 100, "{}", f.display());
    }
    let json = std::fs::read_to_string(&files[1]).unwrap();
    let parsed: serde_json::Value = serde_json::from_str(&json).unwrap();
    assert_eq!(parsed.as_array().map(|a| a.len()), Some(2));
    for f in [&files[0], &files[2]] {
        let back = MetricsTable::read(f).unwrap();
        assert_eq!(back.rows.len(), 2);
        for (x, y) in back.rows.iter().zip(&table.rows) {
            assert_eq!(x.key(), y.key());
            assert_eq!(x.azimuth_quality, y.azimuth_quality);
            let (px, py) = (x.period_s.unwrap(), y.period_s.unwrap());
            assert!(
                (px - py).abs() <= 1e-9 * py,
                "{}: {px} vs {py}",
                f.display()
            );
            assert_eq!(x.steps, y.steps);
        }
    }
    let text = table.render_text();
    assert!(text.contains("period_s") && text.contains("b.mcap"));
}
