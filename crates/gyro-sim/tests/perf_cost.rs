//! CPU cost of one right-hand side and one exact Jacobian, by the body-axes engine the model
//! uses and by the world-axes reference engine it replaced, per scene and fidelity. Measured in
//! this thread's CPU time (from /proc/thread-self/stat), so that a machine shared with other
//! builds gives the same figures as an idle one (criterion's wall-clock figures do not).
//! Ignored by default (it measures, it does not check):
//!
//! `cargo test --release -p gyro-sim --test perf_cost -- --ignored --nocapture --test-threads=1`

use gyro_model::{Fidelity, Jet};
use gyro_sim::{Scene, SceneOverrides, Simulation};
use std::hint::black_box;

/// CPU seconds of this thread (user + system), or None where /proc is not available.
fn thread_cpu_s() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/thread-self/stat").ok()?;
    // Fields after the command name (which is in parentheses and may hold spaces).
    let rest = &s[s.rfind(')')? + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks: f64 = f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0) // USER_HZ is 100 on Linux
}

/// CPU nanoseconds per call of `f`, over at least 1.5 s of CPU.
fn cost_ns(mut f: impl FnMut()) -> Option<f64> {
    for _ in 0..1000 {
        f();
    }
    let start = thread_cpu_s()?;
    let mut calls = 0u64;
    let mut batch = 1000u64;
    loop {
        for _ in 0..batch {
            f();
        }
        calls += batch;
        let used = thread_cpu_s()? - start;
        if used >= 1.5 {
            return Some(used * 1e9 / calls as f64);
        }
        batch *= 2;
    }
}

#[test]
#[ignore = "measures, does not check; run with --ignored --nocapture --test-threads=1"]
fn rhs_and_jacobian_cpu_cost() {
    println!(
        "{:<48} {:>10} {:>10} {:>12} {:>12}",
        "scene/fidelity (dim)", "rhs ns", "ref ns", "jac ns", "ref jac ns"
    );
    for scene in [
        "harbour-50n",
        "rolling-intercardinal",
        "run-north-30kn",
        "foucault-azimuth-45n",
    ] {
        for fidelity in [Fidelity::Full, Fidelity::Gyroscopic, Fidelity::Linear] {
            let ov = SceneOverrides {
                fidelity: Some(fidelity),
                ..Default::default()
            };
            let Ok(sim) = Scene::load(scene, &ov).map(|s| Simulation::new(&s)) else {
                continue;
            };
            let Ok(sim) = sim else { continue };
            let m = &sim.model;
            if m.fidelity != fidelity {
                continue;
            }
            let x = m.x0.clone();
            let dim = x.len();
            let mut dx = vec![0.0; dim];
            let mut jac = vec![0.0; dim * dim];
            let rhs = cost_ns(|| {
                black_box(m.rhs(black_box(1.0), black_box(&x), &mut dx));
            });
            let jac_ns = cost_ns(|| {
                m.jacobian(black_box(1.0), black_box(&x), &mut jac);
                black_box(&jac);
            });
            let (rref, jref) = if fidelity == Fidelity::Linear {
                (None, None)
            } else {
                let mut xj = vec![Jet::<f64, 1>::constant(0.0); dim];
                let mut dxj = vec![Jet::<f64, 1>::constant(0.0); dim];
                (
                    cost_ns(|| {
                        black_box(m.rhs_reference(
                            fidelity,
                            black_box(1.0),
                            black_box(&x),
                            &mut dx,
                        ));
                    }),
                    cost_ns(|| {
                        for col in 0..dim {
                            for i in 0..dim {
                                xj[i] = Jet {
                                    v: x[i],
                                    d: [if i == col { 1.0 } else { 0.0 }],
                                };
                            }
                            m.rhs_reference(fidelity, Jet::constant(1.0), &xj, &mut dxj);
                            for row in 0..dim {
                                jac[row * dim + col] = dxj[row].d[0];
                            }
                        }
                        black_box(&jac);
                    }),
                )
            };
            let show = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.0}"));
            println!(
                "{:<48} {:>10} {:>10} {:>12} {:>12}",
                format!("{scene}/{fidelity} ({dim})"),
                show(rhs),
                show(rref),
                show(jac_ns),
                show(jref)
            );
        }
    }
}
