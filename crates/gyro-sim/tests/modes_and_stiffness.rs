//! Where an explicit integrator's steps go in the Anschütz 1906: the modes (eigenvalues of the
//! exact Jacobian) per fidelity, and how DOP853's step count responds to the tolerance.
//!
//! Findings this file keeps true: the gyroscopic reduction removes exactly the nutation (562
//! rad/s) and nothing else; its fastest mode is the vane's pendulum (≈ 20 rad/s), in harbour
//! and all along a rolling run (there is no 150-rad/s mode); a harbour run with DOP853 is held
//! by that mode's stability bound (the step count does not change with the tolerance), a rolling
//! run by accuracy (the step count grows as the tolerance tightens).

use gyro_model::Fidelity;
use gyro_model::linalg::eigenvalues;
use gyro_sim::solvers::{Method, Tolerances};
use gyro_sim::{Scene, SceneOverrides, Simulation};
use std::ops::ControlFlow;

fn simulation(scene: &str, fidelity: Fidelity, duration_s: Option<f64>) -> Simulation {
    let ov = SceneOverrides {
        fidelity: Some(fidelity),
        duration_s,
        ..Default::default()
    };
    Simulation::new(&Scene::load(scene, &ov).expect("scene")).expect("compiles")
}

/// Eigenvalues of the Jacobian at (t, x), sorted by modulus.
fn modes(sim: &Simulation, t: f64, x: &[f64]) -> Vec<(f64, f64)> {
    let n = x.len();
    let mut a = vec![0.0; n * n];
    sim.model.jacobian(t, x, &mut a);
    let mut ev = eigenvalues(&a, n);
    ev.sort_by(|p, q| p.0.hypot(p.1).total_cmp(&q.0.hypot(q.1)));
    ev
}

#[test]
fn gyroscopic_reduction_removes_the_nutation_and_nothing_else() {
    for scene in ["harbour-50n", "rolling-intercardinal"] {
        let full = simulation(scene, Fidelity::Full, None);
        let gyro = simulation(scene, Fidelity::Gyroscopic, None);
        let ef = modes(&full, 0.0, &full.model.x0);
        let eg = modes(&gyro, 0.0, &gyro.model.x0);
        println!("{scene}: full {ef:?}\n  gyroscopic {eg:?}");
        assert_eq!(ef.len(), eg.len() + 2, "one pair of modes less");
        let nutation = ef[ef.len() - 1].0.hypot(ef[ef.len() - 1].1);
        assert!(
            nutation > 100.0,
            "the full model's fastest pair is the nutation"
        );
        // The Anschütz 1906's float heels about its spin axis, so even at sea its gyroscopic
        // model is the plain reduction (`gyro_model`'s `gyroscopic`), whose frozen-time
        // Jacobian is the full one's less the nutation.
        assert!(
            !gyro.model.carries_gyros(),
            "{scene}: the 1906 is not carried"
        );
        let bound = 1e-3;
        for (f, g) in ef.iter().zip(&eg) {
            let d = (f.0 - g.0).hypot(f.1 - g.1) / f.0.hypot(f.1);
            assert!(d < bound, "{scene}: mode {f:?} became {g:?}");
        }
    }
}

#[test]
fn no_fast_mode_along_a_rolling_run() {
    let sim = simulation("rolling-intercardinal", Fidelity::Gyroscopic, Some(60.0));
    let vane = modes(&sim, 0.0, &sim.model.x0)
        .last()
        .map(|e| e.0.hypot(e.1))
        .expect("modes");
    let mut worst: f64 = 0.0;
    let tol = Tolerances {
        rtol: 1e-8,
        atol: 1e-10,
        max_step_s: f64::INFINITY,
        initial_step_s: None,
        jacobian_reuse_contraction: gyro_sim::solvers::DEFAULT_JACOBIAN_REUSE_CONTRACTION,
    };
    sim.run(Method::Dop853, &tol, |t, x| {
        let m = modes(&sim, t, x).last().map_or(0.0, |e| e.0.hypot(e.1));
        worst = worst.max(m);
        ControlFlow::Continue(())
    })
    .expect("runs");
    println!("fastest mode along 60 s of rolling: {worst:.2} rad/s (vane at rest: {vane:.2})");
    assert!(
        vane > 15.0 && vane < 25.0,
        "the vane pendulum is ≈ 20 rad/s"
    );
    assert!(
        worst < 1.05 * vane,
        "a mode of {worst} rad/s appeared while rolling"
    );
}

fn dop853_steps(scene: &str, rtol: f64) -> u64 {
    let sim = simulation(scene, Fidelity::Gyroscopic, Some(200.0));
    let tol = Tolerances {
        rtol,
        atol: rtol * 1e-2,
        max_step_s: f64::INFINITY,
        initial_step_s: None,
        jacobian_reuse_contraction: gyro_sim::solvers::DEFAULT_JACOBIAN_REUSE_CONTRACTION,
    };
    sim.run(Method::Dop853, &tol, |_, _| ControlFlow::Continue(()))
        .expect("runs")
        .solver
        .steps
}

#[test]
fn harbour_steps_are_held_by_stability_rolling_steps_by_accuracy() {
    let h = [
        dop853_steps("harbour-50n", 1e-6),
        dop853_steps("harbour-50n", 1e-10),
    ];
    let r = [
        dop853_steps("rolling-intercardinal", 1e-6),
        dop853_steps("rolling-intercardinal", 1e-10),
    ];
    println!("200 s, DOP853, rtol 1e-6 → 1e-10: harbour {h:?} steps, rolling {r:?} steps");
    assert!(
        (h[1] as f64) < 1.2 * h[0] as f64,
        "harbour steps follow the tolerance"
    );
    assert!(
        (r[1] as f64) > 2.0 * r[0] as f64,
        "rolling steps ignore the tolerance"
    );
}
