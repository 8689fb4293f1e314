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
//!
//! **The rolling day at the scene's own tolerance** (cases `…/scene-tol`): `rolling-intercardinal`
//! as its file sets it (rtol 1e-7, atol 1e-5), `gyroscopic` with the scene's DOP853 and `full`
//! with RODAS4 (the full model's 89-Hz nutation holds any explicit method near 96 steps per
//! second; nothing in the reading needs it resolved). Before timing, each prints its work and
//! the achieved error: the largest difference of the reading error (2-Hz samples) from a
//! reference run with DOP853 at rtol 1e-11, atol 1e-13 (that reference takes minutes: about 2
//! for `gyroscopic`, 6–9 for `full`; `GYROLAB_DAY_REFERENCE=off` skips it).
//!
//! `cargo bench -p gyro-sim --bench day -- scene-tol`               (the two rolling days)

use std::hint::black_box;
use std::ops::ControlFlow;
use std::time::Instant;

use criterion::{Criterion, criterion_group, criterion_main};
use gyro_model::Fidelity;
use gyro_sim::solvers::{Method, Tolerances};
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

/// The 24-h rolling day at the scene's own tolerances: `gyroscopic` with the scene's integrator,
/// `full` with RODAS4.
fn bench_rolling_day(c: &mut Criterion) {
    let mut group = c.benchmark_group("day");
    group.sample_size(10);
    let scene = "rolling-intercardinal";
    for (fidelity, method) in [
        (Fidelity::Gyroscopic, None),
        (Fidelity::Full, Some(Method::Rodas4)),
    ] {
        let ov = SceneOverrides {
            fidelity: Some(fidelity),
            duration_s: Some(DAY_S),
            method,
            ..Default::default()
        };
        let sc = match Scene::load(scene, &ov) {
            Ok(s) => s,
            Err(e) => {
                eprintln!("{scene}: {e}");
                continue;
            }
        };
        let sim = match Simulation::new(&sc) {
            Ok(s) => s,
            Err(e) => {
                eprintln!("{scene}/{fidelity}: {e}");
                continue;
            }
        };
        let id = format!("{scene}/{fidelity}/{}/scene-tol", sc.method);
        if !criterion_filter_matches(&id) {
            continue;
        }
        let tol = sc.tolerances;
        let Some((readings, line)) = reading_errors(&sim, sc.method, &tol) else {
            eprintln!("{id}: failed");
            continue;
        };
        eprintln!("{id}: rtol {:e}, atol {:e}; {line}", tol.rtol, tol.atol);
        if std::env::var("GYROLAB_DAY_REFERENCE").is_ok_and(|v| v == "off") {
            eprintln!("{id}: reference skipped (GYROLAB_DAY_REFERENCE=off)");
        } else {
            let reference = Tolerances {
                rtol: 1e-11,
                atol: 1e-13,
                ..tol
            };
            match reading_errors(&sim, Method::Dop853, &reference) {
                Some((exact, line)) => {
                    let worst = readings
                        .iter()
                        .zip(&exact)
                        .map(|(a, b)| (a - b).abs())
                        .fold(0.0, f64::max);
                    eprintln!(
                        "{id}: max |reading error − reference| {worst:.2e} rad over {} samples \
                         (reference dop853 rtol 1e-11 atol 1e-13: {line})",
                        exact.len()
                    );
                }
                None => eprintln!("{id}: reference failed"),
            }
        }
        group.bench_function(id, |b| {
            b.iter(|| {
                let mut last = 0.0;
                let r = sim.run(sc.method, &tol, |_, x| {
                    last = x[0];
                    ControlFlow::Continue(())
                });
                black_box((r.is_ok(), last))
            })
        });
    }
    group.finish();
}

/// The reading error at every output sample of one run, and a line of its work and wall time.
fn reading_errors(
    sim: &Simulation,
    method: Method,
    tol: &Tolerances,
) -> Option<(Vec<f64>, String)> {
    let mut states: Vec<(f64, Vec<f64>)> = Vec::new();
    let t0 = Instant::now();
    let stats = sim
        .run(method, tol, |t, x| {
            states.push((t, x.to_vec()));
            ControlFlow::Continue(())
        })
        .ok()?;
    let wall = t0.elapsed().as_secs_f64();
    let s = &stats.solver;
    let line = format!(
        "{} steps ({} rejected, {:.2} per simulated second), {} rhs, {} jacobians; run {:.2} s",
        s.steps,
        s.rejected_steps,
        s.steps as f64 / sim.grid.t_end.max(1e-300),
        s.rhs_evals,
        s.jacobian_evals,
        wall
    );
    let readings = states
        .iter()
        .map(|(t, x)| sim.model.readout(*t, x).reading_error_rad)
        .collect();
    Some((readings, line))
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

criterion_group!(benches, bench_day, bench_rolling_day);
criterion_main!(benches);
