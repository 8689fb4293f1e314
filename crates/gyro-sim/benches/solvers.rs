//! Times each integrator on 100 periods of a pendulum (amplitude 1 rad) at rtol 1e-10, sampled
//! at 10 Hz. RK4 runs at a step giving comparable accuracy.

use std::hint::black_box;
use std::ops::ControlFlow;

use criterion::{Criterion, criterion_group, criterion_main};
use gyro_sim::solvers::{Method, OdeSystem, OutputGrid, Tolerances, integrate};

/// θ'' = -(g/l) sin θ with g/l = 1; period ≈ 7.08 s at 1 rad amplitude.
struct Pendulum;

impl OdeSystem for Pendulum {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&mut self, _t: f64, x: &[f64], d: &mut [f64]) {
        d[0] = x[1];
        d[1] = -x[0].sin();
    }
    fn jacobian(&mut self, _t: f64, x: &[f64], jac: &mut [f64]) -> bool {
        jac.copy_from_slice(&[0.0, 1.0, -x[0].cos(), 0.0]);
        true
    }
}

const PERIOD_S: f64 = 7.075_5;

fn bench_solvers(c: &mut Criterion) {
    let tol = Tolerances {
        rtol: 1e-10,
        atol: 1e-12,
        max_step_s: f64::INFINITY,
        initial_step_s: None,
        jacobian_reuse_contraction: gyro_sim::solvers::DEFAULT_JACOBIAN_REUSE_CONTRACTION,
    };
    let grid = OutputGrid {
        t0: 0.0,
        dt: 0.1,
        t_end: 100.0 * PERIOD_S,
    };
    let mut group = c.benchmark_group("pendulum_100_periods_rtol_1e-10");
    group.sample_size(10);
    for method in [
        Method::Dopri5,
        Method::Dop853,
        Method::Vern9,
        Method::Rk4 { step_s: 2e-3 },
        Method::Rodas4,
        Method::Radau5,
    ] {
        // Work counters once per method, so a timing change can be told from a work change.
        let mut x = [1.0, 0.0];
        if let Ok((_, stats)) =
            integrate(&mut Pendulum, method, &tol, &mut x, &grid, &[], |_, _| {
                ControlFlow::Continue(())
            })
        {
            eprintln!(
                "{method}: {} steps, {} rejected, {} rhs, {} jacobians, {} LU",
                stats.steps,
                stats.rejected_steps,
                stats.rhs_evals,
                stats.jacobian_evals,
                stats.lu_decompositions
            );
        }
        group.bench_function(method.to_string(), |b| {
            b.iter(|| {
                let mut x = [1.0, 0.0];
                let mut sum = 0.0;
                let result = integrate(&mut Pendulum, method, &tol, &mut x, &grid, &[], |_, xs| {
                    sum += xs[0];
                    ControlFlow::Continue(())
                });
                black_box((result.is_ok(), sum, x))
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench_solvers);
criterion_main!(benches);
