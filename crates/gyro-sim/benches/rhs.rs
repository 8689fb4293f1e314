//! Cost of one right-hand side (and of one exact Jacobian) per shipped design and fidelity, at
//! the scene's initial state: the unit every integrator pays for. Also the hand-written
//! equations the accuracy study and the Python peer use (Villarceau eq. 44 bis, Beghin's 4-state
//! linear Anschütz), to show what the engine's generality costs per evaluation.
//!
//! The compasses of chs. IV–VI at their 35°N harbour scenes, and the three-gyro again with its
//! tank's valves closed: the difference is the oil tank's share (its seven levels and the
//! liquid's terms).
//!
//! `cargo bench -p gyro-sim --bench rhs`

use criterion::{Criterion, criterion_group, criterion_main};
use gyro_model::Fidelity;
use gyro_sim::accuracy::{Anschutz4, LinearSystem, foucault_release};
use gyro_sim::solvers::OdeSystem;
use gyro_sim::{Scene, SceneOverrides, Simulation};
use std::hint::black_box;

/// A shipped scene at `fidelity`, with `compass_lines` added to its `[compass]` table.
fn scene(name: &str, fidelity: Fidelity, compass_lines: &str) -> Option<Scene> {
    let ov = SceneOverrides {
        fidelity: Some(fidelity),
        ..Default::default()
    };
    let text = gyro_sim::library::SCENES
        .iter()
        .find(|(n, _)| *n == name)?
        .1
        .replace("[compass]\n", &format!("[compass]\n{compass_lines}\n"));
    Scene::from_toml(name, &text, None, &ov).ok()
}

fn bench_rhs(c: &mut Criterion) {
    let mut group = c.benchmark_group("rhs");
    let closed = "design_overrides = { \"tank.oil.valves\" = \"closed\" }";
    for (scene_name, label, lines) in [
        ("foucault-azimuth-45n", "foucault", ""),
        ("harbour-50n", "anschutz-1906", ""),
        ("run-north-30kn", "anschutz-1906-under-way", ""),
        ("rolling-intercardinal", "anschutz-1906-rolling", ""),
        ("sperry-harbour-35n", "sperry-1911", ""),
        ("slough-harbour-35n", "slough", ""),
        ("twin-harbour-35n", "sperry-twin-1918", ""),
        ("three-gyro-harbour-35n", "anschutz-three-gyro-1912", ""),
        (
            "three-gyro-harbour-35n",
            "anschutz-three-gyro-1912-valves-closed",
            closed,
        ),
    ] {
        for fidelity in [Fidelity::Full, Fidelity::Gyroscopic, Fidelity::Linear] {
            let Some(sc) = scene(scene_name, fidelity, lines) else {
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
