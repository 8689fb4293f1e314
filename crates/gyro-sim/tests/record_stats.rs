//! `/solver/stats` carries a progress report about every simulated hour and the final
//! statistics at the end (docs/recordings.md), and the run loop's progress counts are the
//! solver's own counts.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::ops::ControlFlow;

use gyro_mcap::{Column, Recording};
use gyro_sim::record::SOLVER_STATS_EVERY_S;
use gyro_sim::run::Progress;
use gyro_sim::solvers::Method;
use gyro_sim::{RecordOptions, Scene, SceneOverrides, Simulation, record};

fn u64s<'a>(t: &'a gyro_mcap::RecordTable, name: &str) -> &'a [u64] {
    match t.column(name) {
        Some(Column::U64(v)) => v,
        other => panic!("{name}: {other:?}"),
    }
}

fn f64s<'a>(t: &'a gyro_mcap::RecordTable, name: &str) -> &'a [f64] {
    match t.column(name) {
        Some(Column::F64(v)) => v,
        other => panic!("{name}: {other:?}"),
    }
}

/// A 6-hour run at 1 Hz: a report at each of hours 1–5, then the final statistics at 6 h; the
/// counters never decrease and the last message is the run's statistics exactly.
#[test]
fn a_multi_hour_run_reports_every_hour_and_ends_with_the_final_stats() {
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("record-stats");
    std::fs::create_dir_all(&dir).unwrap();
    let ov = SceneOverrides {
        duration_s: Some(6.0 * 3600.0),
        output_rate_hz: Some(1.0),
        ..Default::default()
    };
    let scene = Scene::load("speed-change-20kn", &ov).unwrap();
    let out = dir.join("speed-change.mcap");
    let summary = record(&scene, &out, RecordOptions::default()).unwrap();
    let rec = Recording::open(&out).unwrap();
    let t = rec.read_records("/solver/stats").unwrap();

    let time = f64s(&t, "time_s");
    let hours: Vec<f64> = (1..=6).map(|h| h as f64 * SOLVER_STATS_EVERY_S).collect();
    assert_eq!(time, hours, "one report per simulated hour, then the end");
    let log_s: Vec<f64> = t.log_time_ns.iter().map(|&n| n as f64 * 1e-9).collect();
    assert_eq!(log_s, hours, "logged at their simulated time");

    let s = &summary.stats.solver;
    assert!(s.rhs_evals > 1000 && s.jacobian_evals > 100, "{s:?}");
    let columns: [(&str, u64); 4] = [
        ("steps", s.steps),
        ("rejected_steps", s.rejected_steps),
        ("rhs_evals", s.rhs_evals),
        ("jacobian_evals", s.jacobian_evals),
    ];
    for (name, last) in columns {
        let v = u64s(&t, name);
        assert!(
            v.windows(2).all(|w| w[0] <= w[1]),
            "{name} never decreases: {v:?}"
        );
        assert_eq!(
            *v.last().unwrap(),
            last,
            "{name}: the last message is the final count"
        );
    }
    let wall = f64s(&t, "wall_time_s");
    assert!(wall.windows(2).all(|w| w[0] <= w[1]), "{wall:?}");
    assert_eq!(*wall.last().unwrap(), s.wall_time_s);
    // The progress reports count the work as it is done: the first is well short of the end.
    for name in ["rhs_evals", "steps"] {
        let v = u64s(&t, name);
        assert!(v[0] > 0 && v[0] < *v.last().unwrap(), "{name}: {v:?}");
    }
}

/// At the last sample, the counts the run loop reports are the integrator's own, for every
/// integrator (explicit, fixed-step and Rosenbrock with the model's Jacobian).
#[test]
fn progress_counts_are_the_solvers_counts() {
    let methods = [
        Method::Dopri5,
        Method::Dop853,
        Method::Rk4 { step_s: 0.05 },
        Method::Rodas4,
    ];
    for method in methods {
        let ov = SceneOverrides {
            duration_s: Some(600.0),
            method: Some(method),
            ..Default::default()
        };
        let scene = Scene::load("turn-90", &ov).unwrap();
        let sim = Simulation::new(&scene).unwrap();
        let mut last = Progress::default();
        let mut seen = Vec::new();
        let stats = sim
            .run_with_progress(scene.method, &scene.tolerances, |_, _, probe| {
                last = probe.progress();
                seen.push(last.rhs_evals);
                ControlFlow::Continue(())
            })
            .unwrap();
        let s = stats.solver;
        assert_eq!(last.steps, s.steps, "{method}");
        assert_eq!(last.rejected_steps, s.rejected_steps, "{method}");
        assert_eq!(last.rhs_evals, s.rhs_evals, "{method}");
        assert_eq!(last.jacobian_evals, s.jacobian_evals, "{method}");
        assert!(last.wall_time_s <= s.wall_time_s, "{method}");
        assert!(seen.windows(2).all(|w| w[0] <= w[1]), "{method}");
        assert!(seen[0] < s.rhs_evals, "{method}: counted as the run goes");
    }
}
