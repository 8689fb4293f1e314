//! CPU cost of one right-hand side and one exact Jacobian, per shipped scene and fidelity, at
//! the scene's initial state, three ways in one run: the recorded tape the model runs (`rhs`,
//! `jacobian`), the generic body-axes engine it is recorded from (`engine rhs`, `engine
//! jacobian`: what `rhs` cost before the tape), and the world-axes reference engine
//! (`reference rhs`, its Jacobian by column-by-column duals).
//!
//! Measured in this thread's CPU time (`support/thread_cpu.rs`: `/proc/thread-self/schedstat`,
//! nanoseconds), not criterion's wall clock, so that a machine shared with other builds gives
//! the figures of an idle one; where that file is missing (not Linux) it falls back to the wall
//! clock and says so.
//!
//! `cargo bench -p gyro-sim --bench engines`

use criterion::{Criterion, criterion_group, criterion_main};
use gyro_model::{Fidelity, Jet};
use gyro_sim::{Scene, SceneOverrides, Simulation};
use std::hint::black_box;
use thread_cpu::ThreadCpu;

#[path = "support/thread_cpu.rs"]
mod thread_cpu;

fn bench_engines(c: &mut Criterion<ThreadCpu>) {
    let mut group = c.benchmark_group("engines");
    for scene in [
        "harbour-50n",
        "rolling-intercardinal",
        "run-north-30kn",
        "foucault-azimuth-45n",
        "three-gyro-harbour-50n",
    ] {
        for fidelity in [Fidelity::Full, Fidelity::Gyroscopic, Fidelity::Linear] {
            let ov = SceneOverrides {
                fidelity: Some(fidelity),
                ..Default::default()
            };
            let Ok(Ok(sim)) = Scene::load(scene, &ov).map(|s| Simulation::new(&s)) else {
                continue;
            };
            let m = &sim.model;
            if m.fidelity != fidelity {
                continue; // e.g. the one-coordinate gyroscope has no gyroscopic reduction
            }
            let x = m.x0.clone();
            let dim = x.len();
            let label = format!("{scene}/{fidelity} (dim {dim})");
            let mut dx = vec![0.0; dim];
            let mut jac = vec![0.0; dim * dim];
            group.bench_function(format!("{label}/rhs"), |b| {
                b.iter(|| black_box(m.rhs(black_box(1.0), black_box(&x), &mut dx)))
            });
            group.bench_function(format!("{label}/jacobian"), |b| {
                b.iter(|| {
                    m.jacobian(black_box(1.0), black_box(&x), &mut jac);
                    black_box(&jac);
                })
            });
            if fidelity == Fidelity::Linear {
                continue; // the reference engine has no linear form
            }
            group.bench_function(format!("{label}/engine rhs"), |b| {
                b.iter(|| black_box(m.rhs_engine(black_box(1.0), black_box(&x), &mut dx)))
            });
            group.bench_function(format!("{label}/engine jacobian"), |b| {
                b.iter(|| {
                    m.jacobian_engine(black_box(1.0), black_box(&x), &mut jac);
                    black_box(&jac);
                })
            });
            group.bench_function(format!("{label}/reference rhs"), |b| {
                b.iter(|| {
                    black_box(m.rhs_reference(fidelity, black_box(1.0), black_box(&x), &mut dx))
                })
            });
            let mut xj = vec![Jet::<f64, 1>::constant(0.0); dim];
            let mut dxj = vec![Jet::<f64, 1>::constant(0.0); dim];
            group.bench_function(format!("{label}/reference jacobian"), |b| {
                b.iter(|| {
                    for col in 0..dim {
                        for (i, xi) in xj.iter_mut().enumerate() {
                            *xi = Jet {
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
                })
            });
        }
    }
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().with_measurement(ThreadCpu::new());
    targets = bench_engines
}
criterion_main!(benches);
