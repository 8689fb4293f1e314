//! Regression against a baseline: the unperturbed table passes; a metric moved beyond its
//! tolerance fails and is named; a changed quality flag or a missing run fails too.
#![allow(clippy::unwrap_used)]

use crate::common;

use common::{Spec, damped, temp_dir, write_run};
use gyro_analysis::regress::{Status, default_tolerances};
use gyro_analysis::{MetricsTable, analyze_runs, regress, update_baseline};

fn table(dir: &std::path::Path) -> MetricsTable {
    let a = write_run(
        &dir.join("a.mcap"),
        &Spec {
            design: "alpha".into(),
            error: Box::new(damped(0.002, 0.0, 0.05, 0.2 / 3700.0, 3700.0, 0.0)),
            ..Spec::default()
        },
    );
    let b = write_run(
        &dir.join("b.mcap"),
        &Spec {
            design: "beta".into(),
            error: Box::new(damped(-0.001, 0.0, 0.04, 0.6 / 4100.0, 4100.0, 1.0)),
            ..Spec::default()
        },
    );
    analyze_runs(&[a, b]).unwrap()
}

#[test]
fn baseline_round_trip_and_perturbations() {
    let dir = temp_dir("regress");
    let table = table(&dir);
    let baseline = dir.join("analysis").join("baseline.toml");
    update_baseline(&table, &baseline, None).unwrap();
    let text = std::fs::read_to_string(&baseline).unwrap();
    assert!(
        text.contains("[tolerances.period_s]") && text.contains("calm/alpha/full/dopri5"),
        "{text}"
    );

    // Unperturbed: passes, nothing moved.
    let report = regress(&table, &baseline, None).unwrap();
    assert!(report.passed(), "{}", report.render_terminal());
    assert!(
        report
            .findings
            .iter()
            .all(|f| f.status == Status::Unchanged)
    );

    // Within tolerance: passes, reported as moved.
    let mut moved = table.clone();
    let p = moved.rows[0].period_s.unwrap();
    moved.rows[0].period_s = Some(p + 0.5);
    let report = regress(&moved, &baseline, None).unwrap();
    assert!(report.passed());
    assert!(report.render_terminal().contains("moved"));

    // Beyond tolerance: fails and names the metric and the run.
    let mut bad = table.clone();
    let l = bad.rows[1].log_decrement.unwrap();
    bad.rows[1].log_decrement = Some(l * 1.05);
    let report = regress(&bad, &baseline, None).unwrap();
    assert!(!report.passed());
    let out = report.render_terminal();
    assert!(
        out.contains("REGRESSED") && out.contains("log_decrement"),
        "{out}"
    );
    assert!(
        out.contains("calm/beta/full/dopri5") && out.contains("FAIL"),
        "{out}"
    );
    let names: Vec<&str> = report.regressions().map(|f| f.metric.as_str()).collect();
    assert_eq!(names, ["log_decrement"]);
    assert!(
        report
            .render_markdown()
            .contains("| REGRESSED | calm/beta/full/dopri5 | log_decrement |")
    );

    // A fit that no longer stands: the quality flag and the lost value both fail.
    let mut lost = table.clone();
    lost.rows[0].azimuth_quality = "not_oscillatory".into();
    lost.rows[0].period_s = None;
    let report = regress(&lost, &baseline, None).unwrap();
    let names: Vec<&str> = report.regressions().map(|f| f.metric.as_str()).collect();
    assert!(
        names.contains(&"azimuth_quality") && names.contains(&"period_s"),
        "{names:?}"
    );

    // A run missing from the current set fails.
    let mut missing = table.clone();
    missing.rows.remove(1);
    assert!(!regress(&missing, &baseline, None).unwrap().passed());

    // Tighter tolerances given by the caller win over the file's.
    let mut tight = default_tolerances();
    tight.get_mut("period_s").unwrap().abs = 0.1;
    tight.get_mut("period_s").unwrap().rel = 0.0;
    assert!(!regress(&moved, &baseline, Some(&tight)).unwrap().passed());

    // --update after review: the perturbed values become the baseline, tolerances are kept.
    update_baseline(&bad, &baseline, None).unwrap();
    assert!(regress(&bad, &baseline, None).unwrap().passed());
    assert!(!regress(&table, &baseline, None).unwrap().passed());
}

#[test]
fn a_broken_baseline_names_its_file() {
    let dir = temp_dir("broken");
    let path = dir.join("baseline.toml");
    std::fs::write(&path, "runs = 3\n[[[").unwrap();
    let err = regress(&MetricsTable::default(), &path, None).unwrap_err();
    assert!(err.to_string().contains("baseline.toml"), "{err}");
    let err = regress(&MetricsTable::default(), &dir.join("absent.toml"), None).unwrap_err();
    assert!(err.to_string().contains("absent.toml"), "{err}");
}
