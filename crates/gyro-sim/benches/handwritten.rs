//! The engine's overhead as a ratio measured in one run: the engine's `rhs` and `jacobian` (what
//! a run calls: the recorded tape where it pays, the generic engine elsewhere), the recorded
//! tapes alone (`rhs_tape`, `jacobian_tape`) and the generic engine they are recorded from
//! (`rhs_engine`, `jacobian_engine`), against hand-written equations of the same compass (`gyro_sim::accuracy::handwritten`, held
//! to the engine to rounding by `tests/handwritten.rs`), at each scene's initial state, for
//! Foucault's azimuth gyroscope (`foucault-azimuth-45n`, full) and the Anschütz 1906
//! (`harbour-50n`, gyroscopic and full); and a whole Villarceau run (the accuracy study's
//! `villarceau-large`: released 90° off, 10 exact periods, DOP853 at rtol 1e-10, atol 1e-13)
//! through `solvers::integrate`, the engine's model against the hand-written eq. 44 bis.
//!
//! Measured in this thread's CPU time (`support/thread_cpu.rs`, as `engines.rs` does). After
//! criterion's own report it prints a table of the mean CPU time per call of each side (all of
//! criterion's calls, see `Totals`) and the ratios engine / hand-written, with the issue's
//! targets (RHS and Jacobian ≤ 3×, whole run ≤ 1.5×). The hand-written Anschütz Jacobians are
//! forward-mode duals through the hand-written RHS, not closed forms: a closed form would be
//! cheaper, so those two ratios flatter the engine.
//!
//! Then the tape against the engine on compasses without hand-written equations (a moving base,
//! the Sperry 1911, the twin-gyro, the three-gyro with its tank), with each tape's operation
//! count and the engine's: the measurement behind the model's choices of when a tape pays
//! (`rhs_tape_pays`, a timing at compile; `JACOBIAN_TAPE_MIN_RATIO`, a rule on the counts; both
//! in `gyro-model/src/model.rs`).
//!
//! A tape with native code (`gyro-model/src/native.rs`: the shipped Foucault and Anschütz 1906
//! scenes) runs it on the `tape` side too; its rule column says `native`.
//!
//! `cargo bench -p gyro-sim --bench handwritten`

#[path = "support/thread_cpu.rs"]
mod thread_cpu;

use criterion::{Bencher, Criterion, SamplingMode};
use gyro_model::Fidelity;
use gyro_sim::accuracy::foucault_release;
use gyro_sim::accuracy::handwritten::{Anschutz1906, Foucault44Bis};
use gyro_sim::run::ModelSystem;
use gyro_sim::solvers::{Method, OdeSystem, OutputGrid, SolverStats, Tolerances, integrate};
use gyro_sim::{Scene, SceneOverrides, Simulation};
use std::cell::RefCell;
use std::collections::BTreeMap;
use std::hint::black_box;
use std::ops::ControlFlow;
use std::time::Duration;
use thread_cpu::ThreadCpu;

/// CPU ns and iterations summed over every call criterion made (warm-up and samples), by
/// benchmark name. The thread clock (`/proc/thread-self/schedstat`) advances only at scheduler
/// ticks, so one short sample can read zero; the sums over the seconds a benchmark runs are
/// exact to a few ticks.
#[derive(Default)]
struct Totals(RefCell<BTreeMap<String, (u64, u64)>>);

impl Totals {
    /// Times `f` with criterion, adding its CPU time and iterations under `key`.
    fn bench(&self, b: &mut Bencher<ThreadCpu>, clock: &ThreadCpu, key: &str, mut f: impl FnMut()) {
        b.iter_custom(|iters| {
            let start = clock.now_ns();
            for _ in 0..iters {
                f();
            }
            let spent = clock.now_ns().saturating_sub(start);
            let mut map = self.0.borrow_mut();
            let e = map.entry(key.to_string()).or_default();
            e.0 += spent;
            e.1 += iters;
            spent
        })
    }
    /// Mean CPU ns per call.
    fn mean(&self, key: &str) -> Option<f64> {
        let map = self.0.borrow();
        let (ns, iters) = *map.get(key)?;
        (iters > 0 && ns > 0).then(|| ns as f64 / iters as f64)
    }
}

fn scene(name: &str, fidelity: Fidelity) -> Result<(Simulation, f64), String> {
    let ov = SceneOverrides {
        fidelity: Some(fidelity),
        ..Default::default()
    };
    let sc = Scene::load(name, &ov).map_err(|e| e.to_string())?;
    let sim = Simulation::new(&sc).map_err(|e| e.to_string())?;
    Ok((sim, sc.start_latitude_rad))
}

/// One case of the RHS/Jacobian comparison: the engine's model and the hand-written system.
struct Case {
    label: String,
    sim: Simulation,
    hand: Option<Box<dyn OdeSystem>>,
}

fn cases() -> Result<Vec<Case>, String> {
    let mut out = Vec::new();
    let (sim, lat) = scene("foucault-azimuth-45n", Fidelity::Full)?;
    let hand = Foucault44Bis::from_simulation(&sim, lat)?;
    out.push(Case {
        label: "foucault-azimuth-45n/full".into(),
        sim,
        hand: Some(Box::new(hand)),
    });
    for fidelity in [Fidelity::Gyroscopic, Fidelity::Full] {
        let (sim, lat) = scene("harbour-50n", fidelity)?;
        let hand = Anschutz1906::from_simulation(&sim, lat)?;
        out.push(Case {
            label: format!("harbour-50n/{fidelity}"),
            sim,
            hand: Some(Box::new(hand)),
        });
    }
    // The tape against the engine only: the calibration of when a tape pays.
    for (name, fidelity) in [
        ("turn-90", Fidelity::Gyroscopic),
        ("turn-90", Fidelity::Full),
        ("sperry-harbour-35n", Fidelity::Full),
        ("sperry-turn-90", Fidelity::Gyroscopic),
        ("twin-harbour-35n", Fidelity::Full),
        ("three-gyro-harbour-35n", Fidelity::Gyroscopic),
        ("three-gyro-harbour-35n", Fidelity::Full),
    ] {
        let (sim, _) = scene(name, fidelity)?;
        out.push(Case {
            label: format!("{name}/{fidelity}"),
            sim,
            hand: None,
        });
    }
    Ok(out)
}

/// The accuracy study's `villarceau-large` run: (engine model, hand-written, x0, grid).
fn villarceau_large() -> Result<(Simulation, Foucault44Bis, OutputGrid), String> {
    let amplitude = 90f64.to_radians();
    let (sim, v, _) = foucault_release(90.0, amplitude)?;
    let hand = Foucault44Bis::from_simulation(&sim, sim.latitude_rad(0.0))?;
    let t_end = 10.0 * v.period(amplitude);
    Ok((
        sim,
        hand,
        OutputGrid {
            t0: 0.0,
            dt: t_end,
            t_end,
        },
    ))
}

const RUN_TOL: Tolerances = Tolerances {
    rtol: 1e-10,
    atol: 1e-13,
    max_step_s: f64::INFINITY,
    initial_step_s: None,
    jacobian_reuse_contraction: gyro_sim::solvers::DEFAULT_JACOBIAN_REUSE_CONTRACTION,
};

fn run<S: OdeSystem>(sys: &mut S, x0: &[f64], grid: &OutputGrid) -> (Vec<f64>, SolverStats) {
    let mut x = x0.to_vec();
    match integrate(sys, Method::Dop853, &RUN_TOL, &mut x, grid, &[], |_, _| {
        ControlFlow::Continue(())
    }) {
        Ok((_, stats)) => (x, stats),
        Err(e) => panic!("the Villarceau run failed: {e}"),
    }
}

/// The targets: RHS and Jacobian ≤ 3× the hand-written, a whole run ≤ 1.5×.
const TARGET_EVAL: f64 = 3.0;
const TARGET_RUN: f64 = 1.5;

/// The model through the generic engine it records its tape from (`rhs_engine`,
/// `jacobian_engine`): what a run cost before the tape.
struct GenericSystem<'a, M: gyro_model::ShipMotion>(&'a gyro_model::CompiledModel<M>);

impl<M: gyro_model::ShipMotion> OdeSystem for GenericSystem<'_, M> {
    fn dim(&self) -> usize {
        self.0.dim()
    }
    fn rhs(&mut self, t: f64, x: &[f64], dx: &mut [f64]) {
        if !self.0.rhs_engine(t, x, dx) {
            dx.fill(f64::NAN);
        }
    }
    fn jacobian(&mut self, t: f64, x: &[f64], jac: &mut [f64]) -> bool {
        self.0.jacobian_engine(t, x, jac);
        true
    }
}

fn main() {
    let clock = ThreadCpu::new();
    let samples = Totals::default();
    let mut c = Criterion::default()
        .with_measurement(ThreadCpu::new())
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3))
        .configure_from_args();
    let (mut cases, (vsim, mut vhand, vgrid)) =
        match cases().and_then(|c| Ok((c, villarceau_large()?))) {
            Ok(c) => c,
            Err(e) => {
                eprintln!("cannot set up the cases: {e}");
                std::process::exit(1);
            }
        };
    let mut group = c.benchmark_group("handwritten");
    // Every sample the same length (tens of ms): none shorter than a scheduler tick.
    group.sampling_mode(SamplingMode::Flat);
    for Case { label, sim, hand } in &mut cases {
        let m = &sim.model;
        let x = m.x0.clone();
        let dim = x.len();
        let mut dx = vec![0.0; dim];
        let mut jac = vec![0.0; dim * dim];
        for side in ["engine", "tape", "generic", "hand-written"] {
            if side == "hand-written" && hand.is_none() {
                continue;
            }
            let key = format!("{label}/rhs/{side}");
            group.bench_function(&key, |b| {
                samples.bench(b, &clock, &key, || {
                    if side == "engine" {
                        black_box(m.rhs(black_box(1.0), black_box(&x), &mut dx));
                    } else if side == "tape" {
                        black_box(m.rhs_tape(black_box(1.0), black_box(&x), &mut dx));
                    } else if side == "generic" {
                        black_box(m.rhs_engine(black_box(1.0), black_box(&x), &mut dx));
                    } else if let Some(hand) = hand {
                        hand.rhs(black_box(1.0), black_box(&x), &mut dx);
                    }
                    black_box(&dx);
                })
            });
        }
        for side in ["engine", "tape", "generic", "hand-written"] {
            if side == "hand-written" && hand.is_none() {
                continue;
            }
            let key = format!("{label}/jacobian/{side}");
            group.bench_function(&key, |b| {
                samples.bench(b, &clock, &key, || {
                    if side == "engine" {
                        m.jacobian(black_box(1.0), black_box(&x), &mut jac);
                    } else if side == "tape" {
                        black_box(m.jacobian_tape(black_box(1.0), black_box(&x), &mut jac));
                    } else if side == "generic" {
                        m.jacobian_engine(black_box(1.0), black_box(&x), &mut jac);
                    } else if let Some(hand) = hand {
                        hand.jacobian(black_box(1.0), black_box(&x), &mut jac);
                    }
                    black_box(&jac);
                })
            });
        }
    }
    // The whole run, both sides through the same integrator and tolerances.
    let x0 = vsim.model.x0.clone();
    let (xe, se) = run(&mut ModelSystem { model: &vsim.model }, &x0, &vgrid);
    let (xh, sh) = run(&mut vhand, &x0, &vgrid);
    group.sample_size(20);
    for side in ["engine", "generic", "hand-written"] {
        let key = format!("villarceau-large/run/{side}");
        group.bench_function(&key, |b| {
            samples.bench(b, &clock, &key, || {
                if side == "engine" {
                    black_box(run(&mut ModelSystem { model: &vsim.model }, &x0, &vgrid));
                } else if side == "generic" {
                    black_box(run(&mut GenericSystem(&vsim.model), &x0, &vgrid));
                } else {
                    black_box(run(&mut vhand, &x0, &vgrid));
                }
            })
        });
    }
    group.finish();
    c.final_summary();

    print_ratios(&samples, &cases, (&xe, &se), (&xh, &sh));
    print_calibration(&samples, &cases);
}

/// The table of engine / hand-written ratios against the targets, and the Villarceau
/// run's work on both sides (end state and counters of engine and hand-written).
fn print_ratios(
    samples: &Totals,
    cases: &[Case],
    (xe, se): (&[f64], &SolverStats),
    (xh, sh): (&[f64], &SolverStats),
) {
    println!(
        "\nengine / hand-written, thread CPU time per call, mean over all of criterion's calls:"
    );
    println!(
        "{:<40} {:>12} {:>12} {:>8}  target",
        "case", "engine", "hand", "ratio"
    );
    let row = |key: &str, unit: &str, div: f64, target: f64| {
        let (Some(e), Some(h)) = (
            samples.mean(&format!("{key}/engine")),
            samples.mean(&format!("{key}/hand-written")),
        ) else {
            return; // filtered out on the command line
        };
        let ratio = e / h;
        let verdict = if ratio <= target { "met" } else { "missed" };
        let generic = samples
            .mean(&format!("{key}/generic"))
            .map_or(String::new(), |g| {
                format!(
                    " (generic engine, before the tape: {:.1} {unit}, {:.2}×)",
                    g / div,
                    g / h
                )
            });
        println!(
            "{key:<40} {:>9.1} {unit} {:>9.1} {unit} {ratio:>7.2}×  ≤ {target}× {verdict}{generic}",
            e / div,
            h / div
        );
    };
    for case in cases.iter().filter(|c| c.hand.is_some()) {
        for what in ["rhs", "jacobian"] {
            row(&format!("{}/{what}", case.label), "ns", 1.0, TARGET_EVAL);
        }
    }
    row("villarceau-large/run", "µs", 1e3, TARGET_RUN);
    let gap = xe
        .iter()
        .zip(xh)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    println!(
        "villarceau-large: {} vs {} RHS calls, {} vs {} steps (engine vs hand-written); end states differ by {gap:.1e}",
        se.rhs_evals, sh.rhs_evals, se.steps, sh.steps
    );
}

/// The tape against the generic engine, with the operation counts the model's rules read.
fn print_calibration(samples: &Totals, cases: &[Case]) {
    // When a tape pays: its time against the engine's, beside the operation counts the model's
    // rule decides on (engine operations per tape operation).
    println!("\ntape / generic engine, thread CPU time per call, and the counts the rule reads:");
    println!(
        "{:<44} {:>11} {:>11} {:>7} {:>8} {:>9} {:>7}  rule",
        "case", "tape", "generic", "ratio", "tape ops", "engine", "e/t"
    );
    for case in cases {
        let m = &case.sim.model;
        let sizes = [
            ("rhs", m.tape_size(m.fidelity)),
            ("jacobian", m.jacobian_tape_size()),
        ];
        for (what, size) in sizes {
            let key = format!("{}/{what}", case.label);
            let (Some(t), Some(g), Some(size)) = (
                samples.mean(&format!("{key}/tape")),
                samples.mean(&format!("{key}/generic")),
                size,
            ) else {
                continue;
            };
            let faster = t < g;
            let verdict = match (size.used, faster) {
                (true, true) | (false, false) => "right",
                (true, false) => "wrong: the tape is slower",
                (false, true) => "wrong: the tape is faster",
            };
            println!(
                "{key:<44} {:>8.1} ns {:>8.1} ns {:>6.2}× {:>8} {:>9} {:>7.1}  {} ({verdict})",
                t,
                g,
                t / g,
                size.ops,
                size.engine_ops,
                size.engine_ops as f64 / size.ops as f64,
                if size.native {
                    "native"
                } else if size.used {
                    "tape"
                } else {
                    "engine"
                },
            );
        }
    }
}
