//! Cost of one right-hand side (and of one exact Jacobian) per shipped design and fidelity, at
//! the scene's initial state: the unit every integrator pays for. Also the hand-written
//! equations the accuracy study and the Python peer use (Villarceau eq. 44 bis, Beghin's 4-state
//! linear Anschütz), to show what the engine's generality costs per evaluation.
//!
//! `cargo bench -p gyro-sim --bench rhs`

use criterion::{Criterion, criterion_group, criterion_main};
use gyro_model::Fidelity;
use gyro_sim::accuracy::{Anschutz4, LinearSystem, foucault_release};
use gyro_sim::solvers::OdeSystem;
use gyro_sim::{Scene, SceneOverrides, Simulation};
use std::hint::black_box;

fn scene(name: &str, fidelity: Fidelity) -> Option<Scene> {
    let ov = SceneOverrides {
        fidelity: Some(fidelity),
        ..Default::default()
    };
    Scene::load(name, &ov).ok()
}

fn bench_rhs(c: &mut Criterion) {
    let mut group = c.benchmark_group("rhs");
    for (scene_name, label) in [
        ("foucault-azimuth-45n", "foucault"),
        ("harbour-50n", "anschutz-1906"),
        ("run-north-30kn", "anschutz-1906-under-way"),
        ("rolling-intercardinal", "anschutz-1906-rolling"),
    ] {
        for fidelity in [Fidelity::Full, Fidelity::Gyroscopic, Fidelity::Linear] {
            let Some(sc) = scene(scene_name, fidelity) else {
                continue;
            };
            let Ok(sim) = Simulation::new(&sc) else {
                continue;
            };
            if sim.model.fidelity != fidelity {
                continue; // e.g. the one-coordinate gyroscope has no gyroscopic reduction
            }
            let x = sim.model.x0.clone();
            let n = x.len();
            let mut dx = vec![0.0; n];
            group.bench_function(format!("{label}/{fidelity}/rhs (dim {n})"), |b| {
                b.iter(|| black_box(sim.model.rhs(black_box(1.0), black_box(&x), &mut dx)))
            });
            if fidelity != Fidelity::Linear {
                let mut jac = vec![0.0; n * n];
                group.bench_function(format!("{label}/{fidelity}/jacobian (dim {n})"), |b| {
                    b.iter(|| {
                        sim.model.jacobian(black_box(1.0), black_box(&x), &mut jac);
                        black_box(&jac);
                    })
                });
            }
        }
    }
    // Hand-written equations: Villarceau eq. 44 bis and the 4-state linear Anschütz.
    if let Ok((_, v, _)) = foucault_release(90.0, 1.0) {
        let x = [1.0, 0.0];
        let mut dx = [0.0; 2];
        group.bench_function("villarceau-eq44bis/hand-written", |b| {
            b.iter(|| {
                let x = black_box(&x);
                dx[0] = x[1];
                dx[1] = v.acceleration(x[0]);
                black_box(&dx);
            })
        });
    }
    if let Ok(p) = Anschutz4::from_design() {
        let mut sys = LinearSystem {
            a: p.matrix(),
            n: 4,
        };
        let mut dx = [0.0; 4];
        group.bench_function("anschutz-4state/hand-written", |b| {
            b.iter(|| sys.rhs(1.0, black_box(&p.x0), &mut dx))
        });
    }
    group.finish();
}

criterion_group!(benches, bench_rhs);
criterion_main!(benches);
