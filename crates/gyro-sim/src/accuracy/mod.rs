//! What accuracy costs in time: a work-precision study of the integrators (and of the model
//! fidelities) on references with exact answers.
//!
//! Every case knows its exact answer, or a reference run much tighter than anything studied:
//! - `villarceau-small`, `villarceau-large`, `villarceau-separatrix`: Foucault's azimuth
//!   gyroscope (full fidelity, the engine) released at rest 10°, 90°, 178° from the meridian. The
//!   motion is periodic with Villarceau's exact period (quadrature of eq. 47, with δ), so after
//!   exactly N periods the state must be the start again: the error is the phase-space distance
//!   √(Δγ² + (Δγ̇/ω₀)²) at t = N·T, relative to the amplitude.
//! - `jacobi-latitude`: the latitude gyroscope (conservative, autonomous) over 10 periods; the
//!   error is the largest drift of Villarceau's first integral (eq. 47, the Jacobi integral of
//!   this system) relative to 2|g/a|.
//! - `anschutz-linear`: the engine's exact linearisation of the Anschütz 1906 at 50°N (8 states,
//!   damped, with its 100 Hz nutation), integrated by each method and compared with its exact
//!   solution x(t) = exp(A t) x₀ at every minute of an hour.
//! - `anschutz-4state`: Beghin's elementary linear Anschütz (ζ, θ and their rates, the
//!   characteristic equation (ℭr² + τ)(𝔅r² + aP) + IΩr(IΩr + κ) = 0 with the mercury drag),
//!   hand-written: the case the Python peer solves too; exact solution by the matrix exponential.
//! - `anschutz-nonlinear`: no closed form. Anschütz 1906 at 50°N released 10° off the meridian,
//!   gyroscopic fidelity, 1 h; the reference is DOP853 at rtol 1e-13. Error: the largest reading
//!   error difference, relative to the release.
//! - `fidelity`: the same scene at `full`, `gyroscopic` and `linear` against a `full` reference
//!   (RODAS4 at rtol 1e-8, which agrees with rtol 1e-9 and with DOP853 to 1e-10 of the release): model error against cost. `linear` is propagated exactly (one
//!   matrix exponential), so it is one point whatever the tolerance.
//!
//! Wall times are the best of a few repetitions of the whole run (model compiled beforehand);
//! RHS counts come from the integrators' own counters. Nothing here is asserted on time: the
//! tests check only the errors.
//!
//! The study is split by what each part knows: `cases` names the cases and sets each up with
//! its exact answer, `problems` holds the hand-written systems and scenes they use,
//! `measurement` runs one case (timing, time budgets, errors), `report` holds the results and
//! their table, and `peer` is gyrolab's side of the Python peer benchmark.
//! `handwritten` holds Villarceau's eq. 44 bis and the Anschütz 1906 written out by hand, the
//! yardstick of the engine's cost (`cargo bench -p gyro-sim --bench handwritten`).

mod cases;
pub mod handwritten;
mod measurement;
mod peer;
mod problems;
mod report;

pub use cases::case_descriptions;
pub use peer::{PeerPoint, PeerReport, peer_report};
pub use problems::{Anschutz4, LinearSystem, foucault_release, foucault_release_scene};
pub use report::{CaseReport, Point, StudyReport};

use crate::solvers::Method;
use cases::{DEFAULT_CASES, build_case};
use gyro_model::Fidelity;
use std::fmt;
use std::time::Instant;

/// What to run.
#[derive(Clone, Debug)]
pub struct StudyOptions {
    /// Integrators studied (RK4's step is chosen per tolerance, see `measurement::rk4_step`).
    pub methods: Vec<Method>,
    /// Relative tolerances studied.
    pub tolerances: Vec<f64>,
    /// Fidelities of the `fidelity` case.
    pub fidelities: Vec<Fidelity>,
    /// Target error of the one-line verdicts.
    pub target_error: f64,
    /// Repeat a run until this much time was spent on it (at most `max_repeats` times) and keep
    /// the fastest: short runs are otherwise dominated by timer and cache noise.
    pub min_timing_s: f64,
    pub max_repeats: u32,
    /// Time budget of one point, s. A point whose predicted cost (explicit methods: the
    /// stability limit of the stiffest mode; RK4: its step) exceeds it is skipped; a run that
    /// takes three times longer is stopped; either way the method's tighter tolerances are
    /// skipped too, and the table says so.
    pub max_point_s: f64,
    /// Time budget of one method on one case and fidelity, s: once spent, its remaining
    /// (tighter) tolerances are skipped. Explicit methods on the stiff Anschütz cases are
    /// stability-bound and cost the same at every tolerance, so a few points tell the story.
    pub max_method_s: f64,
}

impl Default for StudyOptions {
    fn default() -> Self {
        StudyOptions {
            methods: vec![
                Method::Dopri5,
                Method::Dop853,
                Method::Vern9,
                Method::Rodas4,
                Method::Rodas5p,
                Method::Radau5,
                Method::Rk4 {
                    step_s: Method::DEFAULT_RK4_STEP_S,
                },
            ],
            tolerances: (3..=12).map(|k| 10f64.powi(-k)).collect(),
            fidelities: vec![Fidelity::Full, Fidelity::Gyroscopic, Fidelity::Linear],
            target_error: 1e-6,
            min_timing_s: 0.02,
            max_repeats: 5,
            max_point_s: 0.5,
            max_method_s: 2.0,
        }
    }
}

/// Why the study could not run.
#[derive(Clone, Debug, PartialEq)]
pub enum StudyError {
    UnknownCase(String),
    /// A case could not be set up (scene, model or reference run).
    Setup {
        case: String,
        message: String,
    },
}

impl fmt::Display for StudyError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            StudyError::UnknownCase(c) => write!(
                f,
                "unknown accuracy case `{c}` (allowed: {})",
                case_descriptions()
                    .iter()
                    .map(|(n, _)| *n)
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
            StudyError::Setup { case, message } => {
                write!(f, "accuracy case `{case}` cannot be set up: {message}")
            }
        }
    }
}
impl std::error::Error for StudyError {}

/// Runs the named cases (all of [`DEFAULT_CASES`] when `cases` is empty).
pub fn run_study(cases: &[String], opts: &StudyOptions) -> Result<StudyReport, StudyError> {
    let started = Instant::now();
    let names: Vec<String> = if cases.is_empty() {
        DEFAULT_CASES.iter().map(|s| s.to_string()).collect()
    } else {
        cases.to_vec()
    };
    for n in &names {
        if !case_descriptions().iter().any(|(c, _)| c == n) {
            return Err(StudyError::UnknownCase(n.clone()));
        }
    }
    let mut reports = Vec::new();
    for name in &names {
        let setup = |message: String| StudyError::Setup {
            case: name.clone(),
            message,
        };
        let case = build_case(name).map_err(setup)?;
        reports.push(case.study(opts));
    }
    Ok(StudyReport {
        target_error: opts.target_error,
        tolerances: opts.tolerances.clone(),
        cases: reports,
        total_wall_s: started.elapsed().as_secs_f64(),
        version: env!("CARGO_PKG_VERSION").to_string(),
    })
}
