//! CPU cost of one right-hand side and one exact Jacobian, per shipped scene and fidelity, at
//! the scene's initial state, three ways in one run: the recorded tape the model runs (`rhs`,
//! `jacobian`), the generic body-axes engine it is recorded from (`engine rhs`, `engine
//! jacobian`: what `rhs` cost before the tape), and the world-axes reference engine
//! (`reference rhs`, its Jacobian by column-by-column duals).
//!
//! Measured in this thread's CPU time (`/proc/thread-self/schedstat`, nanoseconds), not
//! criterion's wall clock, so that a machine shared with other builds gives the figures of an
//! idle one; where that file is missing (not Linux) it falls back to the wall clock and says so.
//!
//! `cargo bench -p gyro-sim --bench engines`

use criterion::measurement::{Measurement, ValueFormatter};
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use gyro_model::{Fidelity, Jet};
use gyro_sim::{Scene, SceneOverrides, Simulation};
use std::hint::black_box;
use std::time::Instant;

/// CPU time of the calling thread, ns, from the first field of `/proc/thread-self/schedstat`.
fn thread_cpu_ns() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    s.split_whitespace().next()?.parse().ok()
}

/// Criterion measurement: this thread's CPU nanoseconds (wall-clock ns where not available).
struct ThreadCpu {
    available: bool,
    origin: Instant,
}

impl ThreadCpu {
    fn new() -> ThreadCpu {
        let available = thread_cpu_ns().is_some();
        if !available {
            eprintln!("no /proc/thread-self/schedstat here: measuring wall-clock time instead");
        }
        ThreadCpu {
            available,
            origin: Instant::now(),
        }
    }
    fn now_ns(&self) -> u64 {
        match self.available.then(thread_cpu_ns).flatten() {
            Some(ns) => ns,
            None => self.origin.elapsed().as_nanos() as u64,
        }
    }
}

impl Measurement for ThreadCpu {
    type Intermediate = u64;
    type Value = u64;
    fn start(&self) -> u64 {
        self.now_ns()
    }
    fn end(&self, start: u64) -> u64 {
        self.now_ns().saturating_sub(start)
    }
    fn add(&self, a: &u64, b: &u64) -> u64 {
        a + b
    }
    fn zero(&self) -> u64 {
        0
    }
    fn to_f64(&self, v: &u64) -> f64 {
        *v as f64
    }
    fn formatter(&self) -> &dyn ValueFormatter {
        &CpuNanos
    }
}

/// Formats CPU nanoseconds like criterion's own durations.
struct CpuNanos;

impl ValueFormatter for CpuNanos {
    fn scale_values(&self, ns: f64, values: &mut [f64]) -> &'static str {
        let (factor, unit) = if ns < 1e3 {
            (1.0, "ns cpu")
        } else if ns < 1e6 {
            (1e-3, "µs cpu")
        } else if ns < 1e9 {
            (1e-6, "ms cpu")
        } else {
            (1e-9, "s cpu")
        };
        for v in values {
            *v *= factor;
        }
        unit
    }
    /// Units (bytes, elements, bits) per CPU second; no benchmark here sets a throughput.
    fn scale_throughputs(
        &self,
        _typical: f64,
        throughput: &Throughput,
        values: &mut [f64],
    ) -> &'static str {
        let (Throughput::Bytes(n)
        | Throughput::BytesDecimal(n)
        | Throughput::Elements(n)
        | Throughput::Bits(n)) = *throughput;
        for v in values {
            *v = n as f64 * 1e9 / *v;
        }
        "/s cpu"
    }
    fn scale_for_machines(&self, _values: &mut [f64]) -> &'static str {
        "ns"
    }
}

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
