//! `gyrolab sweep` as a user runs it: plan, run on every core, status, report; bad study files
//! and arguments refused with exit code 2 before any run, naming the file, the line and the key.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use crate::common::{gyrolab, succeed, tmp};
use std::path::Path;

const STUDY: &str = r#"
name = "cli-harbour"
scenes = ["harbour-50n"]

[[axis]]
key = "duration_s"
values = [10800.0]

[[axis]]
key = "start.latitude_deg"
values = [20.0, 40.0, 60.0]

[[axis]]
key = "compass.azimuth_offset_deg"
values = [3.0, 6.0]

[keep]
recordings = "every:2"
"#;

fn write(dir: &Path, name: &str, text: &str) -> String {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p.display().to_string()
}

#[test]
fn plan_run_status_and_report_of_a_small_study() {
    let dir = tmp("sweep", "cli");
    let study = write(&dir, "study.toml", STUDY);
    let out = dir.join("out");
    let plan = succeed(gyrolab().args(["sweep", "plan", &study, "--samples", "2", "--json"]));
    let v: serde_json::Value = serde_json::from_slice(&plan.stdout).unwrap();
    assert_eq!(v["estimate"]["total_runs"], 6);
    assert_eq!(v["estimate"]["kept_recordings"], 3);
    assert!(v["estimate"]["cpu_s_per_run"].as_f64().unwrap() > 0.0);
    assert!(v["estimate"]["recording_bytes_per_run"].as_f64().unwrap() > 1e4);

    let run = succeed(
        gyrolab()
            .args(["sweep", "run", &study, "--out"])
            .arg(&out)
            .args(["--jobs", "2", "--json"]),
    );
    let s: serde_json::Value = serde_json::from_slice(&run.stdout).unwrap();
    assert_eq!(
        (s["ran"].as_u64(), s["failed"].as_u64()),
        (Some(6), Some(0))
    );
    // every:2 keeps the recordings of runs 0, 2 and 4, and they open.
    for i in [0, 2, 4] {
        let rec = out.join(format!("recordings/run-{i:09}.mcap"));
        assert!(
            gyro_mcap::Recording::open(&rec).is_ok(),
            "{}",
            rec.display()
        );
    }
    assert!(!out.join("recordings/run-000000001.mcap").exists());

    let status = succeed(gyrolab().args(["sweep", "status"]).arg(&out).arg("--json"));
    let st: serde_json::Value = serde_json::from_slice(&status.stdout).unwrap();
    assert_eq!(
        (st["ok"].as_u64(), st["missing"].as_u64()),
        (Some(6), Some(0))
    );

    let report = succeed(gyrolab().args(["sweep", "report"]).arg(&out));
    let text = String::from_utf8_lossy(&report.stdout);
    assert!(
        text.contains("start.latitude_deg") && text.contains("period_s"),
        "{text}"
    );
    // One axis plotted as lines, two as a heat map.
    assert!(out.join("report/period_s.svg").is_file());
    assert!(out.join("report/period_s-map.svg").is_file());
    assert!(out.join("report/summary.md").is_file());
    // No half-written file anywhere in the folder.
    let mut stack = vec![out.clone()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap().flatten() {
            let p = e.path();
            assert!(
                !p.to_string_lossy().ends_with(".partial"),
                "{}",
                p.display()
            );
            if p.is_dir() {
                stack.push(p);
            }
        }
    }
}

#[test]
fn bad_studies_and_arguments_exit_2_before_any_run() {
    let dir = tmp("sweep", "bad");
    let out = dir.join("out");
    let cases = [
        (
            "unknown-key",
            "key = \"start.headng_deg\"\nvalues = [0.0]",
            "start.headng_deg",
            6,
        ),
        (
            "empty-range",
            "key = \"start.latitude_deg\"\nfrom = 10.0\nto = 20.0\ncount = 0",
            "start.latitude_deg",
            9,
        ),
        (
            "wrong-type",
            "key = \"sea.roll_period_s\"\nvalues = [true]",
            "sea.roll_period_s",
            6,
        ),
        (
            "out-of-range",
            "key = \"start.latitude_deg\"\nvalues = [30.0, 91.0]",
            "start.latitude_deg",
            6,
        ),
    ];
    for (name, axis, key, line) in cases {
        let text = format!("name = \"bad\"\nscenes = [\"harbour-50n\"]\n\n[[axis]]\n\n{axis}\n");
        let study = write(&dir, &format!("{name}.toml"), &text);
        let o = gyrolab()
            .args(["sweep", "run", &study, "--out"])
            .arg(&out)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{name}: {err}");
        assert!(err.contains(&format!("{study}:{line}:")), "{name}: {err}");
        assert!(err.contains(key), "{name}: {err}");
        assert!(!out.exists(), "{name}: nothing is written before the runs");
    }
    // More storage than the study allows: refused without --yes, naming the limit's line.
    let big = write(
        &dir,
        "big.toml",
        &STUDY.replace(
            "recordings = \"every:2\"",
            "recordings = \"all\"\nmax_storage_mb = 1.0",
        ),
    );
    let o = gyrolab()
        .args(["sweep", "run", &big, "--out"])
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    let line = STUDY
        .lines()
        .position(|l| l.contains("recordings = "))
        .unwrap()
        + 2;
    assert!(
        err.contains(&format!("big.toml:{line}: `keep.max_storage_mb`")),
        "{err}"
    );
    assert!(err.contains("--yes"), "{err}");
    assert!(!out.exists());
    // Bad arguments.
    let study = write(&dir, "ok.toml", STUDY);
    for args in [
        vec!["--engine", "spark"],
        vec!["--engine", "ray"],
        vec!["--jobs", "0"],
    ] {
        let o = gyrolab()
            .args(["sweep", "run", &study, "--out"])
            .arg(&out)
            .args(&args)
            .output()
            .unwrap();
        assert_eq!(
            o.status.code(),
            Some(2),
            "{args:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
    }
    let o = gyrolab()
        .args(["sweep", "status"])
        .arg(dir.join("nowhere"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
}

#[test]
fn ctrl_c_stops_a_local_sweep_with_130_keeping_what_finished_and_a_rerun_finishes_it() {
    let dir = tmp("sweep", "ctrl-c");
    let study = write(
        &dir,
        "rolling.toml",
        r#"
name = "ctrl-c"
scenes = ["rolling-intercardinal"]
[[axis]]
key = "duration_s"
values = [3600.0]
[[axis]]
key = "start.heading_deg"
values = [0.0, 30.0, 60.0, 90.0, 120.0, 150.0]
# Runs of a few tenths of a second each (the shipped scene's atol 1e-6 is 3x faster): the
# interrupt waits for the second run to start, so five runs are still to go when it comes.
[[axis]]
key = "simulation.atol"
values = [1e-10]
"#,
    );
    let out = dir.join("out");
    let child = gyrolab()
        .args(["sweep", "run", &study, "--out"])
        .arg(&out)
        .args(["--jobs", "1", "--quiet"])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // Interrupt as soon as the second run has started (its recording appears in `work/`): the
    // first has then finished and five are left, whatever this machine's speed. A sleep timed
    // for one engine speed broke twice as the engine got faster.
    let work = out.join("work");
    let started = std::time::Instant::now();
    let second_started = || {
        std::fs::read_dir(&work).is_ok_and(|d| {
            d.flatten().any(|e| {
                e.file_name()
                    .to_string_lossy()
                    .starts_with("run-000000001-")
            })
        })
    };
    while !second_started() {
        assert!(
            started.elapsed() < std::time::Duration::from_secs(120),
            "the second run never started in {}",
            work.display()
        );
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    let _ = std::process::Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status();
    let o = child.wait_with_output().unwrap();
    assert_eq!(
        o.status.code(),
        Some(130),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let st = succeed(gyrolab().args(["sweep", "status"]).arg(&out).arg("--json"));
    let st: serde_json::Value = serde_json::from_slice(&st.stdout).unwrap();
    let done = st["ok"].as_u64().unwrap();
    assert!((1..6).contains(&done), "{st}");
    assert_eq!(done + st["missing"].as_u64().unwrap(), 6, "{st}");
    let again = succeed(
        gyrolab()
            .args(["sweep", "run", &study, "--out"])
            .arg(&out)
            .args(["--json", "--quiet"]),
    );
    let s: serde_json::Value = serde_json::from_slice(&again.stdout).unwrap();
    assert_eq!(s["already_done"].as_u64(), Some(done), "{s}");
    assert_eq!(s["ran"].as_u64(), Some(6 - done), "{s}");
}
