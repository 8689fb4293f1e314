//! The work-precision study as a library: its errors are physics (each case's exact answer),
//! so they are asserted here; its times are never asserted (run `gyrolab accuracy` or the
//! ignored `print_study` to see them).

use gyro_sim::accuracy::*;
use gyro_sim::solvers::Method;

fn opts(methods: Vec<Method>, tolerances: Vec<f64>) -> StudyOptions {
    StudyOptions {
        methods,
        tolerances,
        min_timing_s: 0.0,
        max_repeats: 1,
        ..Default::default()
    }
}

fn names(v: &[&str]) -> Vec<String> {
    v.iter().map(|s| s.to_string()).collect()
}

#[test]
fn villarceau_errors_follow_the_tolerance() {
    let r = run_study(
        &names(&[
            "villarceau-small",
            "villarceau-large",
            "villarceau-separatrix",
        ]),
        &opts(
            vec![Method::Dop853, Method::Dopri5],
            vec![1e-4, 1e-7, 1e-10, 1e-12],
        ),
    )
    .unwrap_or_else(|e| panic!("{e}"));
    for c in &r.cases {
        for p in &c.points {
            let e = p.error.unwrap_or_else(|| panic!("{}: {p:?}", c.name));
            // Global error over N periods stays within a few hundred tolerances (the
            // separatrix case amplifies phase errors by dT/dE).
            let k = if c.name == "villarceau-separatrix" {
                3000.0
            } else {
                300.0
            };
            assert!(
                e < k * p.rtol,
                "{} {} rtol {:e}: error {e:e}",
                c.name,
                p.method,
                p.rtol
            );
        }
        let at = |m: &str, t: f64| {
            c.points
                .iter()
                .find(|p| p.method == m && p.rtol == t)
                .and_then(|p| p.error)
                .unwrap_or(f64::NAN)
        };
        assert!(
            at("dop853", 1e-12) < 1e-9,
            "{}: {}",
            c.name,
            at("dop853", 1e-12)
        );
        assert!(at("dop853", 1e-12) < at("dop853", 1e-7) * 1e-3);
        assert!(c.verdict.starts_with("for 1e-6 on"), "{}", c.verdict);
    }
}

#[test]
fn jacobi_integral_and_exact_linear_solutions() {
    let r = run_study(
        &names(&["jacobi-latitude", "anschutz-4state", "anschutz-linear"]),
        &opts(vec![Method::Rodas4, Method::Dop853], vec![1e-4, 1e-6]),
    )
    .unwrap_or_else(|e| panic!("{e}"));
    for c in &r.cases {
        for p in &c.points {
            if let Some(e) = p.error {
                assert!(
                    e < 50.0 * p.rtol,
                    "{} {} rtol {:e}: error {e:e}",
                    c.name,
                    p.method,
                    p.rtol
                );
            } else {
                // Only budget skips are allowed (explicit methods on the stiff cases).
                let note = p.note.clone().unwrap_or_default();
                assert!(
                    note.starts_with("skipped") || note.starts_with("stopped"),
                    "{note}"
                );
            }
        }
    }
}

#[test]
fn fidelity_axis_shows_the_model_error() {
    let r = run_study(
        &names(&["fidelity"]),
        &opts(vec![Method::Rodas4], vec![1e-4, 1e-6]),
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let c = &r.cases[0];
    let err = |fid: &str, rtol: f64| {
        c.points
            .iter()
            .find(|p| p.fidelity == fid && (p.rtol == rtol || p.method == "expm"))
            .and_then(|p| p.error)
            .unwrap_or(f64::NAN)
    };
    // Against the full reference: the full model converges, the gyroscopic one stops at its
    // model error (precessional inertia dropped, ~1e-4 of ω²), the linear one at the
    // pendulum's amplitude dependence (second order in the 10° release).
    let (full, gyro, lin) = (
        err("full", 1e-6),
        err("gyroscopic", 1e-6),
        err("linear", 0.0),
    );
    println!("full {full:.2e}, gyroscopic {gyro:.2e}, linear {lin:.2e}");
    assert!(full < 1e-5, "full at 1e-6: {full:e}");
    assert!(
        (1e-6..1e-3).contains(&gyro),
        "gyroscopic model error {gyro:e}"
    );
    assert!((1e-4..5e-2).contains(&lin), "linear model error {lin:e}");
    assert!(full < gyro && gyro < lin);
    assert!(err("gyroscopic", 1e-4) > gyro * 0.5);
}

#[test]
fn outputs_are_well_formed() {
    let r = run_study(
        &names(&["villarceau-small"]),
        &opts(
            vec![Method::Dop853, Method::Rk4 { step_s: 0.1 }],
            vec![1e-4, 1e-8],
        ),
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let json: serde_json::Value = serde_json::from_str(&r.to_json()).expect("valid JSON");
    assert_eq!(json["cases"][0]["name"], "villarceau-small");
    assert_eq!(json["cases"][0]["points"].as_array().map(Vec::len), Some(4));
    let table = r.table();
    assert!(table.contains("villarceau-small") && table.contains("Verdicts"));
    let e = run_study(&names(&["nope"]), &StudyOptions::default()).expect_err("unknown");
    assert!(e.to_string().contains("villarceau-small"), "{e}");
}

/// The whole default study with its table (≈ 1 min): `cargo test --release -p gyro-sim --test
/// accuracy print_study -- --ignored --nocapture` (CASES=a,b to choose; JSON=file.json
/// to write it; `gyrolab accuracy --plot file.svg` draws the plot).
#[test]
#[ignore = "prints the study"]
fn print_study() {
    let cases: Vec<String> = std::env::var("CASES")
        .map(|s| s.split(',').map(str::to_string).collect())
        .unwrap_or_default();
    let r = run_study(&cases, &StudyOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    println!("{}", r.table());
    if let Ok(p) = std::env::var("JSON") {
        std::fs::write(p, r.to_json()).expect("write JSON");
    }
}

/// gyrolab's side of the Python peer benchmark: `analysis/bench/peer.py` runs this and reads
/// the JSON written to `$PEER_OUT`.
#[test]
#[ignore = "measurement for analysis/bench/peer.py"]
fn peer_side() {
    let opts = StudyOptions {
        // Three a decade, as peer.py's TOLS: 1, 5, 2 × 10^-k from 1e-3 down to 1e-12.
        tolerances: (3..=12)
            .flat_map(|k| [1.0, 0.5, 0.2].map(|m| m * 10f64.powi(-k)))
            .take(28)
            .collect(),
        // As peer.py's best_time: repeat a point until 0.2 s went into it (at most 1000
        // runs), as Python's timeit does. With five runs at most, a 12-µs point kept its
        // cold-cache first runs (12.7 µs best of 5 against 11.8 µs best of 10⁵) and SciPy's
        // 1.1-ms LSODA points spread 1.27–1.98 ms over three measurements of five runs, against
        // 1.13–1.16 ms as the best of 300.
        min_timing_s: 0.2,
        max_repeats: 1000,
        ..Default::default()
    };
    let r = peer_report(&opts).unwrap_or_else(|e| panic!("{e}"));
    let json = serde_json::to_string_pretty(&r).expect("json");
    match std::env::var("PEER_OUT") {
        Ok(p) => std::fs::write(p, json).expect("write PEER_OUT"),
        Err(_) => println!("{json}"),
    }
}
