use gyro_sim::accuracy::*;

#[test]
#[ignore = "prints the study"]
fn print_study() {
    let cases: Vec<String> = std::env::var("CASES")
        .map(|s| s.split(',').map(str::to_string).collect())
        .unwrap_or_default();
    let r = run_study(&cases, &StudyOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    println!("{}", r.table());
}

#[test]
#[ignore = "scratch"]
fn scratch_costs() {
    use gyro_model::Fidelity;
    use gyro_sim::solvers::{Method, Tolerances};
    use gyro_sim::{Scene, SceneOverrides, Simulation};
    use std::time::Instant;
    let text = |fid: &str| {
        format!(
            "name = \"x\"\nduration_s = 7200\noutput_rate_hz = 0.016666666666666666\n[start]\nlatitude_deg = 50.0\n[compass]\ndesign = \"anschutz-1906\"\nazimuth_offset_deg = 10.0\n[simulation]\nfidelity = \"{fid}\"\n"
        )
    };
    for (fid, m, rtol) in [
        ("gyroscopic", Method::Dop853, 1e-13),
        ("gyroscopic", Method::Dop853, 1e-8),
        ("gyroscopic", Method::Rodas4, 1e-8),
        ("full", Method::Rodas4, 1e-6),
        ("full", Method::Rodas4, 1e-8),
        ("full", Method::Rodas4, 1e-9),
        ("full", Method::Dop853, 1e-6),
    ] {
        let sc = Scene::from_toml("x", &text(fid), None, &SceneOverrides::default()).unwrap();
        let sim = Simulation::new(&sc).unwrap();
        let t = Instant::now();
        let mut last = 0.0;
        let r = sim.run(
            m,
            &Tolerances {
                rtol,
                atol: rtol * 1e-4,
                ..Default::default()
            },
            |t, x| {
                last = sim.model.readout(t, x).reading_error_rad;
                std::ops::ControlFlow::Continue(())
            },
        );
        let n = sim.model.dim();
        let mut j = vec![0.0; n * n];
        sim.model.jacobian(0.0, &sim.model.x0, &mut j);
        let ev = gyro_model::linalg::eigenvalues(&j, n);
        println!(
            "{fid} {m} {rtol:e}: {:.3} s {:?} last {last:.12e} dim {n} rhs cost {:.0} ns eig {:?}",
            t.elapsed().as_secs_f64(),
            r.map(|s| (s.solver.steps, s.solver.rhs_evals)),
            sim.rhs_cost_ns(),
            ev
        );
        let _ = Fidelity::Full;
    }
}

/// gyrolab's side of the Python peer benchmark: `analysis/bench/peer.py` runs this and reads
/// the JSON written to `$PEER_OUT`.
#[test]
#[ignore = "measurement for analysis/bench/peer.py"]
fn peer_side() {
    let opts = StudyOptions {
        tolerances: (4..=12).map(|k| 10f64.powi(-k)).collect(),
        min_timing_s: 0.2,
        max_repeats: 5,
        ..Default::default()
    };
    let r = peer_report(&opts).unwrap_or_else(|e| panic!("{e}"));
    let json = serde_json::to_string_pretty(&r).expect("json");
    match std::env::var("PEER_OUT") {
        Ok(p) => std::fs::write(p, json).expect("write PEER_OUT"),
        Err(_) => println!("{json}"),
    }
}
