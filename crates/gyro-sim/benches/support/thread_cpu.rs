//! Thread CPU time as a criterion measurement, for benches on a machine shared with builds;
//! `#[path]`-included by `engines.rs` and `handwritten.rs`.

use criterion::Throughput;
use criterion::measurement::{Measurement, ValueFormatter};
use std::time::Instant;

/// CPU time of the calling thread, ns, from the first field of `/proc/thread-self/schedstat`.
pub fn thread_cpu_ns() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    s.split_whitespace().next()?.parse().ok()
}

/// Criterion measurement: this thread's CPU nanoseconds (wall-clock ns where not available).
pub struct ThreadCpu {
    available: bool,
    origin: Instant,
}

impl ThreadCpu {
    pub fn new() -> ThreadCpu {
        let available = thread_cpu_ns().is_some();
        if !available {
            eprintln!("no /proc/thread-self/schedstat here: measuring wall-clock time instead");
        }
        ThreadCpu {
            available,
            origin: Instant::now(),
        }
    }
    pub fn now_ns(&self) -> u64 {
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
