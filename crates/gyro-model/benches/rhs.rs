//! The engine alone (no scene, no ship program): one right-hand side and one exact Jacobian of
//! the shipped designs moored at 50°N, per fidelity, by the body-axes engine the model uses and
//! by the world-axes reference engine (`rhs_reference`; its Jacobian column by column on nested
//! duals), so what the body-axes engine saves stays measurable.
//!
//! `cargo bench -p gyro-model --bench rhs`

use criterion::{Criterion, criterion_group, criterion_main};
use gyro_model::{
    BaseEffects, CompiledModel, Design, Effects, Fidelity, InitialCondition, Jet, ModelOptions,
    Moored,
};
use std::hint::black_box;

fn design(name: &str) -> Option<Design> {
    let path = gyro_testkit::repo_root!().join(format!("designs/{name}.toml"));
    let text = std::fs::read_to_string(path).ok()?;
    Design::from_toml(&format!("{name}.toml"), &text, &[]).ok()
}

fn model(d: Design, fidelity: Fidelity) -> Option<CompiledModel<Moored>> {
    let mut effects = Effects::all();
    effects.base = BaseEffects {
        earth_rotation: true,
        ..Default::default()
    };
    CompiledModel::compile(
        d,
        Moored {
            latitude_rad: 50f64.to_radians(),
            heading_rad: 0.0,
        },
        ModelOptions {
            fidelity,
            effects,
            pivot_m: [0.0; 3],
            initial: InitialCondition {
                from_equilibrium: true,
                offsets_rad: vec![(0, 0.1)],
                ..Default::default()
            },
        },
    )
    .ok()
}

fn bench_engine(c: &mut Criterion) {
    let mut group = c.benchmark_group("engine");
    for name in [
        "anschutz-1906",
        "foucault-gyroscope",
        "sperry-1911",
        "slough",
    ] {
        for fidelity in [Fidelity::Full, Fidelity::Gyroscopic] {
            let Some(m) = design(name).and_then(|d| model(d, fidelity)) else {
                continue;
            };
            if m.fidelity != fidelity {
                continue;
            }
            let x = m.x0.clone();
            let dim = x.len();
            let mut dx = vec![0.0; dim];
            group.bench_function(format!("{name}/{fidelity}/rhs"), |b| {
                b.iter(|| black_box(m.rhs(black_box(1.0), black_box(&x), &mut dx)))
            });
            group.bench_function(format!("{name}/{fidelity}/rhs-reference"), |b| {
                b.iter(|| {
                    black_box(m.rhs_reference(fidelity, black_box(1.0), black_box(&x), &mut dx))
                })
            });
            let mut jac = vec![0.0; dim * dim];
            group.bench_function(format!("{name}/{fidelity}/jacobian"), |b| {
                b.iter(|| {
                    m.jacobian(black_box(1.0), black_box(&x), &mut jac);
                    black_box(&jac);
                })
            });
            let mut xj = vec![Jet::<f64, 1>::constant(0.0); dim];
            let mut dxj = vec![Jet::<f64, 1>::constant(0.0); dim];
            group.bench_function(format!("{name}/{fidelity}/jacobian-reference"), |b| {
                b.iter(|| {
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
                })
            });
        }
    }
    group.finish();
}

criterion_group!(benches, bench_engine);
criterion_main!(benches);
