//! sin and cos as the engine computes them (`gyro_model::sin_cos`, the `libm` crate) against the
//! platform's (`f64::sin_cos`, glibc's `sincos` on Linux), over the angles the engine meets: a
//! gyroscope swinging ±90° (Villarceau's large release) and a wide sweep (±20 rad, where the
//! range reduction works). The measurement behind `dual::sin_cos`.
//!
//! `cargo bench -p gyro-model --bench trig`

use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;

fn angles(amplitude: f64) -> Vec<f64> {
    // A smooth swing, as an integrator walks it (the branches of the range reduction predictable).
    (0..4096)
        .map(|i| amplitude * (i as f64 * std::f64::consts::TAU / 4096.0).sin())
        .collect()
}

fn bench_trig(c: &mut Criterion) {
    let mut group = c.benchmark_group("trig");
    for (label, amplitude) in [
        ("swing 90 deg", std::f64::consts::FRAC_PI_2),
        ("sweep 20 rad", 20.0),
    ] {
        let xs = angles(amplitude);
        group.bench_function(format!("{label}/f64::sin_cos"), |b| {
            b.iter(|| {
                xs.iter()
                    .map(|&x| {
                        let (s, c) = black_box(x).sin_cos();
                        s * c
                    })
                    .sum::<f64>()
            })
        });
        group.bench_function(format!("{label}/gyro_model::sin_cos"), |b| {
            b.iter(|| {
                xs.iter()
                    .map(|&x| {
                        let (s, c) = gyro_model::sin_cos(black_box(x));
                        s * c
                    })
                    .sum::<f64>()
            })
        });
        group.bench_function(format!("{label}/f64::sin"), |b| {
            b.iter(|| xs.iter().map(|&x| black_box(x).sin()).sum::<f64>())
        });
        group.bench_function(format!("{label}/libm::sin"), |b| {
            b.iter(|| xs.iter().map(|&x| libm::sin(black_box(x))).sum::<f64>())
        });
    }
    group.finish();
}

criterion_group!(benches, bench_trig);
criterion_main!(benches);
