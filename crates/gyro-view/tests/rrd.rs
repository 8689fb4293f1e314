//! The `.rrd` written for a synthetic scene loads back through Rerun's own decoder (the
//! `rerun-sdk==0.36.3` Python package, from the workspace's pinned interop venv under the
//! target directory, `gyro_testkit::interop_python`) and holds the expected entity paths, a
//! transform for every body at every kept sample, and the scalar series with the right lengths
//! and values.

use crate::common;

use std::path::{Path, PathBuf};
use std::process::Command;

use gyro_view::{DampedSinusoid, Output, Sink, ViewOptions, view, view_with_fit};
use serde_json::Value;

fn workdir(name: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
        .join("gyro-view")
        .join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("work dir");
    d
}

/// The workspace's pinned interop venv (rerun-sdk 0.36.3 among its packages), made on first
/// use; None (and a visible SKIPPED) when it cannot be had, a failure under `CI=true`.
fn rerun_python() -> Option<PathBuf> {
    gyro_testkit::interop_python()
}

/// Entity → its JSON summary from tests/rrd_dump.py.
fn dump(py: &Path, rrd: &Path) -> Value {
    let script = gyro_testkit::manifest_dir!()
        .join("tests")
        .join("rrd_dump.py");
    let out = Command::new(py)
        .arg(script)
        .arg(rrd)
        .output()
        .expect("run python");
    assert!(
        out.status.success(),
        "rrd_dump.py failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("json")
}

/// The temporal component of `entity` whose name ends with `component`: (times, values).
fn temporal<'a>(d: &'a Value, entity: &str, component: &str) -> (Vec<i64>, &'a Vec<Value>) {
    let comps = d["entities"][entity]["temporal"]
        .as_object()
        .unwrap_or_else(|| panic!("no temporal data at {entity}"));
    let (_, c) = comps
        .iter()
        .find(|(k, _)| k.ends_with(component))
        .unwrap_or_else(|| panic!("{entity}: no {component} in {:?}", comps.keys()));
    let t = c["time_ns"]
        .as_array()
        .expect("times")
        .iter()
        .map(|v| v.as_i64().expect("i64"))
        .collect();
    (t, c["values"].as_array().expect("values"))
}

fn has_static(d: &Value, entity: &str, component: &str) -> bool {
    d["entities"][entity]["static"].as_array().is_some_and(|a| {
        a.iter()
            .any(|c| c.as_str().is_some_and(|s| s.contains(component)))
    })
}

/// Scalars of one-per-row list values.
fn scalars(values: &[Value]) -> Vec<f64> {
    values
        .iter()
        .map(|v| v[0].as_f64().expect("scalar"))
        .collect()
}

fn f64s(v: &Value) -> Vec<f64> {
    v.as_array()
        .expect("array")
        .iter()
        .map(|x| x.as_f64().expect("f64"))
        .collect()
}

/// The value a series should hold at a time (s).
type Expected = fn(f64) -> f64;

const RATE_HZ: f64 = 2.0;
const SAMPLES: usize = 1200;

fn true_fit() -> DampedSinusoid {
    DampedSinusoid {
        offset: common::ERR_OFFSET,
        drift_per_s: 0.0,
        amplitude: common::ERR_AMP,
        decay_rate_per_s: common::ERR_DECAY,
        period_s: common::ERR_PERIOD,
        phase_rad: 0.0,
        t0_s: 0.0,
        start_s: 100.0,
        end_s: 500.0,
    }
}

/// A view that fails part-way (here on its second recording, not an MCAP file) leaves no
/// `.rrd` under the final name and no `.partial` beside it; an `.rrd` already there from an
/// earlier view is left as it was. One that succeeds leaves only the final file.
#[test]
fn a_failed_view_leaves_no_rrd_behind() {
    let dir = workdir("failed");
    let good = dir.join("good.mcap");
    common::write_recording(&good, SAMPLES, RATE_HZ);
    let junk = dir.join("junk.mcap");
    std::fs::write(&junk, b"not an MCAP file at all").expect("junk");
    let rrd = dir.join("out.rrd");
    let partial = dir.join("out.rrd.partial");
    let opts = ViewOptions {
        sink: Sink::Save(rrd.clone()),
        ..Default::default()
    };
    let e = view(&[good.clone(), junk.clone()], &opts).expect_err("junk must fail");
    assert!(e.to_string().contains("junk.mcap"), "{e}");
    assert!(!rrd.exists() && !partial.exists(), "left behind after: {e}");
    view(std::slice::from_ref(&good), &opts).expect("view");
    assert!(rrd.is_file() && !partial.exists());
    let before = std::fs::read(&rrd).expect("rrd");
    view(&[good, junk], &opts).expect_err("junk must fail");
    assert_eq!(
        std::fs::read(&rrd).expect("rrd"),
        before,
        "the earlier file changed"
    );
    assert!(!partial.exists());
}

#[test]
fn rrd_holds_bodies_poses_and_series_of_two_runs() {
    let dir = workdir("two-runs");
    let runs = [dir.join("alpha.mcap"), dir.join("beta.mcap")];
    for r in &runs {
        common::write_recording(r, SAMPLES, RATE_HZ);
    }
    let rrd = dir.join("both.rrd");
    let opts = ViewOptions {
        sink: Sink::Save(rrd.clone()),
        max_pose_rate_hz: 1.0,
        ..Default::default()
    };
    // The fit sees the reading error after the last manoeuvre event (320 s) and returns the
    // curve the data were made from.
    let fit = |t: &[f64], y: &[f64]| {
        assert_eq!(t.first(), Some(&320.0));
        assert_eq!(t.len(), y.len());
        Some(true_fit())
    };
    let report = view_with_fit(&runs, &opts, &fit).expect("view");
    let Output::Saved { path, bytes } = &report.output else {
        panic!("not saved: {:?}", report.output)
    };
    assert_eq!(path, &rrd);
    assert!(*bytes > 10_000, "{bytes} bytes");
    assert_eq!(report.runs.len(), 2);
    assert_eq!(report.runs[0].entity, "/runs/alpha");
    assert_eq!(report.runs[1].entity, "/runs/beta");
    assert_eq!(report.runs[0].samples, SAMPLES);
    // 2 Hz decimated to 1 Hz: t = 0, 1, …, 599 s, and the last sample (599.5 s).
    let kept: Vec<i64> = (0..600)
        .map(|s| s * 1_000_000_000)
        .chain([599_500_000_000])
        .collect();
    assert_eq!(report.runs[0].poses_per_frame, kept.len());

    let Some(py) = rerun_python() else { return };
    let d = dump(&py, &rrd);
    assert_eq!(d["recordings"], 1);
    assert_eq!(d["blueprints"], 1, "the layout travels in the file");
    check_time_axes(&d);
    let full_t: Vec<i64> = (0..SAMPLES)
        .map(|i| (i as f64 / RATE_HZ * 1e9).round() as i64)
        .collect();

    for run in ["alpha", "beta"] {
        let root = format!("/runs/{run}");
        check_bodies(&d, &root, &kept);
        check_series(&d, &root, &full_t);
        assert!(has_static(&d, &format!("{root}/about"), "TextDocument"));
    }
}

/// The five time-series views open on the whole run: without a `TimeAxis.view_range`, Rerun
/// shows a plot over more than a minute (this one is 600 s) as the time cursor ± 30 s.
fn check_time_axes(d: &Value) {
    let time_axes: Vec<&String> = d["blueprint_entities"]
        .as_object()
        .expect("blueprint entities")
        .iter()
        .filter(|(path, components)| {
            path.ends_with("/TimeAxis")
                && components
                    .as_array()
                    .expect("components")
                    .iter()
                    .any(|c| c.as_str().is_some_and(|c| c.ends_with("view_range")))
        })
        .map(|(path, _)| path)
        .collect();
    assert_eq!(time_axes.len(), 5, "{time_axes:?}");
}

/// Every body of run `root`, nested as its frames, posed at every kept sample with the
/// recorded pose; its shapes, the rotor's marker, the hull and the overlay arrows.
fn check_bodies(d: &Value, root: &str, kept: &[i64]) {
    let mut path = format!("{root}/earth");
    for (frame, _) in common::FRAMES {
        path = format!("{path}/{frame}");
        let (t, tr) = temporal(d, &path, "translation");
        let (tq, q) = temporal(d, &path, "quaternion");
        assert_eq!(t, kept, "{path}: translation times");
        assert_eq!(tq, kept, "{path}: quaternion times");
        for (i, &ns) in kept.iter().enumerate() {
            let (want_t, want_q) = common::pose(frame, ns as f64 * 1e-9);
            let got_t = f64s(&tr[i][0]);
            let got_q = f64s(&q[i][0]);
            for k in 0..3 {
                assert!((got_t[k] - want_t[k]).abs() < 1e-6, "{path} t[{i}]");
            }
            for k in 0..4 {
                assert!(
                    (got_q[k] - want_q[k]).abs() < 1e-6,
                    "{path} q[{i}] {got_q:?} {want_q:?}"
                );
            }
        }
    }
    // Shapes in the bodies' frames, the rotor's turning marker, the schematic hull.
    let ship = format!("{root}/earth/ship");
    assert!(has_static(d, &format!("{ship}/gimbal/shape"), "Mesh3D"));
    assert!(has_static(
        d,
        &format!("{ship}/gimbal/float/shape"),
        "Ellipsoids3D"
    ));
    assert!(has_static(
        d,
        &format!("{ship}/gimbal/float/rotor/shape"),
        "Cylinders3D"
    ));
    assert!(has_static(
        d,
        &format!("{ship}/gimbal/float/rotor/spin_axis"),
        "Arrows3D"
    ));
    assert!(has_static(
        d,
        &format!("{ship}/hull_outline"),
        "LineStrips3D"
    ));
    let (t, _) = temporal(
        d,
        &format!("{ship}/gimbal/float/rotor/spin_marker"),
        "quaternion",
    );
    assert_eq!(t, kept);
    // True North, indicated North and the apparent vertical.
    assert!(has_static(
        d,
        &format!("{root}/overlay/true_north"),
        "Arrows3D"
    ));
    for arrow in ["indicated_north", "apparent_vertical"] {
        let (t, v) = temporal(d, &format!("{root}/overlay/{arrow}"), "vectors");
        assert_eq!(t, kept, "{arrow}");
        assert_eq!(v.len(), kept.len());
    }
    // Under the 0.25 m/s² acceleration (300–320 s) the apparent vertical leans aft.
    let (t, v) = temporal(d, &format!("{root}/overlay/apparent_vertical"), "vectors");
    let i = t
        .iter()
        .position(|&x| x == 310_000_000_000)
        .expect("310 s kept");
    let up = f64s(&v[i][0]);
    let lean = up[0].atan2(up[2]);
    assert!((lean - (0.25_f64).atan2(9.81)).abs() < 1e-5, "lean {lean}");
}

/// Run `root`'s full-rate series (angles in degrees), the fit and its envelope over the fit's
/// window, and the manoeuvre events.
fn check_series(d: &Value, root: &str, full_t: &[i64]) {
    let series: [(&str, Expected); 5] = [
        ("reading_error_deg", |t| {
            common::reading_error(t).to_degrees()
        }),
        ("tilt_deg", |t| common::tilt(t).to_degrees()),
        ("heading_deg/true", |_| 0.3_f64.to_degrees()),
        ("speed_m_per_s", common::speed),
        ("roll_deg", |t| common::roll(t).to_degrees()),
    ];
    for (leaf, f) in series {
        let entity = format!("{root}/series/{leaf}");
        let (t, v) = temporal(d, &entity, "scalars");
        assert_eq!(t, full_t, "{entity}: times");
        let got = scalars(v);
        for (k, &ns) in t.iter().enumerate() {
            let want = f(ns as f64 * 1e-9);
            assert!(
                (got[k] - want).abs() < 1e-9 * (1.0 + want.abs()),
                "{entity}[{k}] {} vs {want}",
                got[k]
            );
        }
    }
    let (t, _) = temporal(d, &format!("{root}/series/heading_deg/compass"), "scalars");
    assert_eq!(t.len(), SAMPLES);
    // The fit and its envelope over the fit's window only.
    let (t, v) = temporal(
        d,
        &format!("{root}/series/reading_error_deg/fit"),
        "scalars",
    );
    assert_eq!(t.len(), 801, "100..=500 s at 2 Hz");
    assert_eq!(t[0], 100_000_000_000);
    for (k, &ns) in t.iter().enumerate() {
        let want = common::reading_error(ns as f64 * 1e-9).to_degrees();
        assert!((scalars(v)[k] - want).abs() < 1e-9);
    }
    let (_, up) = temporal(
        d,
        &format!("{root}/series/reading_error_deg/envelope_upper"),
        "scalars",
    );
    let (_, lo) = temporal(
        d,
        &format!("{root}/series/reading_error_deg/envelope_lower"),
        "scalars",
    );
    let (up, lo) = (scalars(up), scalars(lo));
    let a0 = (common::ERR_AMP * (-common::ERR_DECAY * 100.0).exp()).to_degrees();
    assert!((up[0] - common::ERR_OFFSET.to_degrees() - a0).abs() < 1e-9);
    assert!((lo[0] - common::ERR_OFFSET.to_degrees() + a0).abs() < 1e-9);
    // Manoeuvre events: markers on the reading error and a text log.
    let (t, v) = temporal(
        d,
        &format!("{root}/series/reading_error_deg/events"),
        "scalars",
    );
    assert_eq!(t, vec![300_000_000_000, 320_000_000_000]);
    assert!((scalars(v)[0] - common::reading_error(300.0).to_degrees()).abs() < 1e-9);
    let (t, v) = temporal(d, &format!("{root}/events"), "text");
    assert_eq!(t.len(), 2);
    assert!(
        v[0][0]
            .as_str()
            .is_some_and(|s| s.contains("speed_change start")),
        "{:?}",
        v[0]
    );
}

/// Quaternion product (x, y, z, w).
fn qmul(a: &[f64], b: &[f64]) -> [f64; 4] {
    [
        a[3] * b[0] + a[0] * b[3] + a[1] * b[2] - a[2] * b[1],
        a[3] * b[1] - a[0] * b[2] + a[1] * b[3] + a[2] * b[0],
        a[3] * b[2] + a[0] * b[1] - a[1] * b[0] + a[2] * b[3],
        a[3] * b[3] - a[0] * b[0] - a[1] * b[1] - a[2] * b[2],
    ]
}

#[test]
fn tilt_exaggeration_multiplies_the_float_tilt_in_the_file() {
    let dir = workdir("exaggerated");
    let run = dir.join("run.mcap");
    common::write_recording(&run, 400, RATE_HZ);
    let rrd = dir.join("run.rrd");
    let opts = ViewOptions {
        sink: Sink::Save(rrd.clone()),
        tilt_exaggeration: 50.0,
        ..Default::default()
    };
    view(&[run], &opts).expect("view");
    let Some(py) = rerun_python() else { return };
    let d = dump(&py, &rrd);
    let mut path = "/runs/run/earth".to_owned();
    let mut chain: Vec<(Vec<i64>, Vec<Value>)> = Vec::new();
    for (frame, _) in &common::FRAMES[..3] {
        path = format!("{path}/{frame}");
        let (t, q) = temporal(&d, &path, "quaternion");
        chain.push((t, q.clone()));
    }
    let (times, _) = &chain[0];
    let mut checked = 0;
    for (i, &ns) in times.iter().enumerate() {
        let t = ns as f64 * 1e-9;
        // earth_from_float = ship · gimbal · float; its z axis tilts about y by 50 × tilt(t)
        // (the recorded roll and counter-roll cancel).
        let q = chain.iter().fold([0.0, 0.0, 0.0, 1.0], |acc, (_, qs)| {
            qmul(&acc, &f64s(&qs[i][0]))
        });
        let z = [
            2.0 * (q[0] * q[2] + q[3] * q[1]),
            2.0 * (q[1] * q[2] - q[3] * q[0]),
            1.0 - 2.0 * (q[0] * q[0] + q[1] * q[1]),
        ];
        let shown = z[0].atan2(z[2]);
        let want = 50.0 * common::tilt(t);
        assert!(
            (shown - want).abs() < 2e-4 * want.abs().max(1e-3),
            "t {t}: {shown} vs {want}"
        );
        checked += 1;
    }
    assert!(checked > 100);
    // The ship's roll (up to 0.05 rad) is exaggerated too, saturating below 80°.
    let roll_shown: Vec<f64> = chain[0]
        .1
        .iter()
        .map(|q| {
            let q = f64s(&q[0]);
            2.0 * q[0].atan2(q[3])
        })
        .collect();
    let max = roll_shown.iter().fold(0.0_f64, |a, &b| a.max(b.abs()));
    assert!(max > 1.0 && max < 80f64.to_radians(), "{max}");
}

/// `Sink::Spawn` with no `rerun` on PATH saves next to the first run and says how to open it.
/// Runs itself in a child process whose PATH holds no viewer.
#[test]
fn spawn_without_viewer_saves_next_to_the_run() {
    if std::env::var_os("GYRO_VIEW_SPAWN_CHILD").is_some() {
        let dir = PathBuf::from(std::env::var_os("GYRO_VIEW_SPAWN_CHILD").expect("dir"));
        let run = dir.join("lonely.mcap");
        common::write_recording(&run, 50, RATE_HZ);
        let opts = ViewOptions {
            sink: Sink::Spawn,
            ..Default::default()
        };
        let report = view(&[run], &opts).expect("view");
        let want = dir.join("lonely.rrd");
        assert!(matches!(&report.output, Output::Saved { path, .. } if path == &want));
        assert!(
            report
                .notes
                .iter()
                .any(|n| n.contains("rerun ") && n.contains("lonely.rrd")),
            "{:?}",
            report.notes
        );
        assert!(want.is_file());
        return;
    }
    let dir = workdir("spawn");
    // libtest names a test by its path inside the binary, without the binary's crate name.
    let this_test = match module_path!().split_once("::") {
        Some((_, module)) => format!("{module}::spawn_without_viewer_saves_next_to_the_run"),
        None => "spawn_without_viewer_saves_next_to_the_run".to_owned(),
    };
    let status = Command::new(std::env::current_exe().expect("exe"))
        .args(["--exact", this_test.as_str(), "--nocapture"])
        .env("GYRO_VIEW_SPAWN_CHILD", &dir)
        .env("PATH", dir.join("no-viewer-here"))
        .status()
        .expect("child");
    assert!(status.success());
    assert!(dir.join("lonely.rrd").is_file());
}

#[test]
fn the_default_fit_is_the_analysis_crates_and_is_drawn_over_the_data() {
    let Some(py) = rerun_python() else {
        return;
    };
    let dir = workdir("analysis-fit");
    let run = dir.join("settle.mcap");
    // 4000 s at 1 Hz: six cycles of the 600-s damped sinusoid after the last event (320 s).
    common::write_recording(&run, 4000, 1.0);
    let rrd = dir.join("settle.rrd");
    let opts = ViewOptions {
        sink: Sink::Save(rrd.clone()),
        max_pose_rate_hz: 0.1,
        ..Default::default()
    };
    view(std::slice::from_ref(&run), &opts).expect("view");
    let d = dump(&py, &rrd);
    let root = "/runs/settle";
    let (t, v) = temporal(
        &d,
        &format!("{root}/series/reading_error_deg/fit"),
        "scalars",
    );
    assert!(
        t.len() > 3000,
        "the fit spans its window: {} samples",
        t.len()
    );
    let v = scalars(v);
    let worst = t
        .iter()
        .zip(&v)
        .map(|(&ns, &y)| (y - common::reading_error(ns as f64 * 1e-9).to_degrees()).abs())
        .fold(0.0, f64::max);
    // gyro-analysis's least-squares fit recovers the noiseless curve it was given.
    assert!(worst < 1e-6, "fit vs data: {worst:e}°");
}

/// A spring between two bodies: a line from its point on the gimbal to its point on the float,
/// in the earth frame, at every pose shown, each end carried through its body's recorded poses;
/// a linkage's rod (from the float to the gimbal) likewise, under `linkages/`.
#[test]
fn springs_and_linkages_are_drawn_between_their_bodies() {
    let dir = workdir("spring");
    let run = dir.join("spring.mcap");
    common::write_recording_with_pots(&run, SAMPLES, RATE_HZ);
    let rrd = dir.join("spring.rrd");
    let opts = ViewOptions {
        sink: Sink::Save(rrd.clone()),
        max_pose_rate_hz: 1.0,
        ..Default::default()
    };
    view(std::slice::from_ref(&run), &opts).expect("view");
    let Some(py) = rerun_python() else { return };
    let d = dump(&py, &rrd);
    // p in a frame, carried up the synthetic chain to the earth frame.
    let rotate = |q: [f64; 4], v: [f64; 3]| {
        let (x, y, z, w) = (q[0], q[1], q[2], q[3]);
        let u = [
            y * v[2] - z * v[1],
            z * v[0] - x * v[2],
            x * v[1] - y * v[0],
        ];
        let uu = [
            y * u[2] - z * u[1],
            z * u[0] - x * u[2],
            x * u[1] - y * u[0],
        ];
        [0, 1, 2].map(|i| v[i] + 2.0 * (w * u[i] + uu[i]))
    };
    let in_earth = |frame: &str, p: [f64; 3], time: f64| {
        let mut x = p;
        let mut f = frame;
        while let Some((_, parent)) = common::FRAMES.iter().find(|(c, _)| *c == f) {
            let (tr, q) = common::pose(f, time);
            let r = rotate(q, x);
            x = [0, 1, 2].map(|i| r[i] + tr[i]);
            f = parent;
        }
        x
    };
    for (entity, body, s) in [
        ("/runs/spring/earth/springs/hh", "gimbal", common::spring()),
        (
            "/runs/spring/earth/linkages/rod",
            "float",
            common::linkage(),
        ),
    ] {
        let (t, strips) = temporal(&d, entity, "strips");
        assert!(t.len() > 100, "{entity}: {} times", t.len());
        for (k, &ns) in t.iter().enumerate() {
            let time = ns as f64 * 1e-9;
            let ends = [
                in_earth(body, s.point_m, time),
                in_earth(&s.other_body, s.other_point_m, time),
            ];
            let strip: Vec<Vec<f64>> = strips[k][0]
                .as_array()
                .expect("a strip")
                .iter()
                .map(f64s)
                .collect();
            assert_eq!(strip.len(), 2, "{entity}[{k}]");
            for (got, want) in strip.iter().zip(&ends) {
                for i in 0..3 {
                    assert!(
                        (got[i] - want[i]).abs() < 1e-5,
                        "{entity}[{k}]: {got:?} vs {want:?}"
                    );
                }
            }
        }
    }
}

/// A liquid tank on a body: the compartments' outlines are static in the carrier's frame, and
/// each compartment's oil is a unit cylinder scaled to c + Σ aᵢ·levelᵢ and centred half way up
/// over its floor, at every kept sample, from the recorded levels.
#[test]
fn tank_is_drawn_with_its_recorded_levels() {
    let dir = workdir("tank");
    let run = dir.join("tank.mcap");
    common::write_recording_with_pots(&run, SAMPLES, RATE_HZ);
    let rrd = dir.join("tank.rrd");
    let opts = ViewOptions {
        sink: Sink::Save(rrd.clone()),
        max_pose_rate_hz: 1.0,
        ..Default::default()
    };
    view(std::slice::from_ref(&run), &opts).expect("view");
    let Some(py) = rerun_python() else { return };
    let d = dump(&py, &rrd);
    let tank = "/runs/tank/earth/ship/gimbal/float/tank/oil";
    assert!(has_static(&d, &format!("{tank}/outline"), "Cylinders3D"));
    let drawing = common::tank();
    for (i, comp) in drawing.compartments.iter().enumerate() {
        let column = format!("{tank}/compartment_{}", i + 1);
        assert!(has_static(&d, &format!("{column}/oil"), "Cylinders3D"));
        let (t, scale) = temporal(&d, &column, "scale");
        let (tt, translation) = temporal(&d, &column, "translation");
        assert_eq!(t.len(), 601, "{column}: one column a kept sample");
        assert_eq!(t, tt);
        for (k, &ns) in t.iter().enumerate() {
            let h = drawing.rest_depth_m
                + comp.level_coefficients[0] * common::mercury_level(ns as f64 * 1e-9);
            let s = f64s(&scale[k][0]);
            let x = f64s(&translation[k][0]);
            assert!(
                (s[2] - h).abs() < 1e-6,
                "{column}[{k}]: height {} vs {h}",
                s[2]
            );
            assert!(
                (x[2] - (drawing.floor_height_m + 0.5 * h)).abs() < 1e-6,
                "{column}[{k}]: centre"
            );
            assert!((x[0] - comp.centroid_m[0]).abs() < 1e-6);
        }
    }
}

/// Communicating pots on a body: the tube and the pots' outlines are static in the carrier's
/// frame, and each pot's liquid column is a unit cylinder scaled to c ± u and centred half way
/// up, at every kept sample, from the recorded level.
#[test]
fn pots_are_drawn_with_their_recorded_levels() {
    let dir = workdir("pots");
    let run = dir.join("pots.mcap");
    common::write_recording_with_pots(&run, SAMPLES, RATE_HZ);
    let rrd = dir.join("pots.rrd");
    let opts = ViewOptions {
        sink: Sink::Save(rrd.clone()),
        max_pose_rate_hz: 1.0,
        ..Default::default()
    };
    view(std::slice::from_ref(&run), &opts).expect("view");
    let Some(py) = rerun_python() else { return };
    let d = dump(&py, &rrd);
    let pots = "/runs/pots/earth/ship/gimbal/float/pots/mercury";
    assert!(has_static(&d, &format!("{pots}/tube"), "LineStrips3D"));
    assert!(has_static(&d, &format!("{pots}/outline"), "Cylinders3D"));
    let p = common::pots();
    let c = p.rest_level_m;
    for (pot, base, sign) in [
        ("first", p.first_base_m, 1.0),
        ("second", p.second_base_m, -1.0),
    ] {
        let column = format!("{pots}/{pot}");
        assert!(has_static(&d, &format!("{column}/liquid"), "Cylinders3D"));
        let (t, scale) = temporal(&d, &column, "scale");
        let (tt, translation) = temporal(&d, &column, "translation");
        assert_eq!(t.len(), 601, "{column}: one column a kept sample");
        assert_eq!(t, tt);
        for (i, &ns) in t.iter().enumerate() {
            let h = c + sign * common::mercury_level(ns as f64 * 1e-9);
            let s = f64s(&scale[i][0]);
            let x = f64s(&translation[i][0]);
            assert!(
                (s[2] - h).abs() < 1e-6,
                "{column}[{i}]: height {} vs {h}",
                s[2]
            );
            assert!(
                (x[2] - (base[2] + 0.5 * h)).abs() < 1e-6,
                "{column}[{i}]: centre"
            );
            assert!((x[0] - base[0]).abs() < 1e-6);
        }
    }
}
