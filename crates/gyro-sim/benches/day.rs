//! A 24-hour run per scene and fidelity, without recording (the observer only counts samples):
//! what one simulated day costs in steps, evaluations and wall time. Work counters are printed
//! once per case (so a timing change can be told from a work change), then criterion times the
//! whole run.
//!
//! `cargo bench -p gyro-sim --bench day`                       (harbour-50n and rolling-intercardinal)
//! `cargo bench -p gyro-sim --bench day -- harbour`            (criterion filter)
//! `GYROLAB_DAY_METHOD=dop853 cargo bench -p gyro-sim --bench day` (another integrator than the scene's)
//!
//! Every case runs at rtol 1e-8 (atol 1e-10) with the scene's integrator and output rate; a
//! `linear` harbour is propagated exactly (matrix exponential per sample), so it has no steps.

use std::hint::black_box;
use std::ops::ControlFlow;
use std::time::Instant;

use criterion::{Criterion, criterion_group, criterion_main};
use gyro_model::Fidelity;
use gyro_sim::solvers::Method;
use gyro_sim::{Scene, SceneOverrides, Simulation};

const DAY_S: f64 = 86_400.0;

fn simulation(scene: &str, fidelity: Fidelity) -> Option<(Simulation, Scene)> {
    let method = std::env::var("GYROLAB_DAY_METHOD")
        .ok()
        .and_then(|m| m.parse::<Method>().ok());
    let ov = SceneOverrides {
        fidelity: Some(fidelity),
        rtol: Some(1e-8),
        atol: Some(1e-10),
        duration_s: Some(DAY_S),
        method,
        ..Default::default()
    };
    let sc = match Scene::load(scene, &ov) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("{scene}: {e}");
            return None;
        }
    };
    match Simulation::new(&sc) {
        Ok(sim) => Some((sim, sc)),
        Err(e) => {
            eprintln!("{scene}/{fidelity}: {e}");
            None
        }
    }
}

fn bench_day(c: &mut Criterion) {
    let mut group = c.benchmark_group("day");
    group.sample_size(10);
    for scene in ["harbour-50n", "rolling-intercardinal"] {
        for fidelity in [Fidelity::Gyroscopic, Fidelity::Full, Fidelity::Linear] {
            let Some((sim, sc)) = simulation(scene, fidelity) else {
                continue;
            };
            let id = format!("{scene}/{fidelity}/{}", sc.method);
            if !criterion_filter_matches(&id) {
                continue;
            }
            // One run for the work counters and a first wall time.
            let t0 = Instant::now();
            let mut samples = 0u64;
            match sim.run(sc.method, &sc.tolerances, |_, _| {
                samples += 1;
                ControlFlow::Continue(())
            }) {
                Ok(stats) => {
                    let s = &stats.solver;
                    eprintln!(
                        "{id}: {} steps ({} rejected), {} rhs, {} jacobians, {} LU, {} samples; \
                         rhs {:.0} ns; run {:.1} ms",
                        s.steps,
                        s.rejected_steps,
                        s.rhs_evals,
                        s.jacobian_evals,
                        s.lu_decompositions,
                        samples,
                        sim.rhs_cost_ns(),
                        t0.elapsed().as_secs_f64() * 1e3
                    );
                }
                Err(e) => {
                    eprintln!("{id}: failed: {e}");
                    continue;
                }
            }
            group.bench_function(id, |b| {
                b.iter(|| {
                    let mut last = 0.0;
                    let r = sim.run(sc.method, &sc.tolerances, |_, x| {
                        last = x[0];
                        ControlFlow::Continue(())
                    });
                    black_box((r.is_ok(), last))
                })
            });
        }
    }
    group.finish();
}

/// The counters run is not cheap (a full-fidelity rolling day takes seconds): skip it for cases
/// a command-line filter excludes (criterion's own filter applies to the timed part only).
fn criterion_filter_matches(id: &str) -> bool {
    // Criterion's options that take a value; the first other bare word is the filter.
    const WITH_VALUE: [&str; 12] = [
        "--warm-up-time",
        "--measurement-time",
        "--sample-size",
        "--save-baseline",
        "--baseline",
        "--load-baseline",
        "--profile-time",
        "--nresamples",
        "--noise-threshold",
        "--confidence-level",
        "--significance-level",
        "--color",
    ];
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut skip = false;
    let mut filter = None;
    for a in &args {
        if skip {
            skip = false;
        } else if WITH_VALUE.contains(&a.as_str()) {
            skip = true;
        } else if !a.starts_with('-') {
            filter = Some(a.clone());
            break;
        }
    }
    filter.is_none_or(|f| format!("day/{id}").contains(&f))
}

criterion_group!(benches, bench_day);
criterion_main!(benches);
