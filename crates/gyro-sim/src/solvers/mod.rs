//! Integrators: the `OdeSystem` interface every model implements, the solver options and
//! statistics, and the driver [`integrate`] that owns everything common to all methods —
//! option checks, stopping exactly at breakpoints, sampling the output grid from dense output,
//! the observer, and the guards (step-size underflow, non-finite state, step limit).
//!
//! The methods themselves live one per file and see only the [`OdeSystem`] trait; they hold no
//! physics. Each implements the small internal `Stepper` trait: attempt a step (with its own
//! error control), evaluate its dense output inside the last accepted step, and restart at a
//! breakpoint.
//!
//! - `dopri5`: Dormand–Prince 5(4), FSAL, 4th-order dense output (Hairer's DOPRI5).
//! - `dop853`: Dormand–Prince 8(5,3) with 7th-order dense output (Hairer's DOP853).
//! - `vern9`: Verner's 9(8) pair with its 9th-order interpolant (tight tolerances).
//! - `rk4`: classic fixed-step RK4, cubic Hermite dense output (the baseline).
//! - `rodas4`: Hairer–Wanner RODAS, L-stable Rosenbrock 4(3), 3rd-order dense output (stiff).
//! - `rodas5p`: Steinebach's Rodas5P, L-stable Rosenbrock 5(4), 4th-order dense output (stiff);
//!   both Rosenbrock methods are one stepper, `rosenbrock`, with two coefficient tableaus.
//! - `radau5`: Hairer–Wanner RADAU5, 3-stage Radau IIA (implicit, order 5, L-stable), its
//!   collocation polynomial as dense output (stiff, tight tolerances).
//!
//! Output never depends on the output rate: steps are never shortened to hit sample times, only
//! to stop at breakpoints and at the end.

// Coefficient tables keep the published digits so they can be checked against the source;
// stage loops index several parallel vectors at once, which reads better than zipped iterators.
#[allow(clippy::excessive_precision, clippy::needless_range_loop)]
mod dop853;
#[allow(clippy::needless_range_loop)]
mod dopri5;
#[allow(clippy::needless_range_loop)]
mod linalg;
#[allow(clippy::excessive_precision, clippy::needless_range_loop)]
mod radau5;
#[allow(clippy::needless_range_loop)]
mod rk4;
#[allow(clippy::excessive_precision)]
mod rodas4;
#[allow(clippy::excessive_precision)]
mod rodas5p;
#[allow(clippy::needless_range_loop)]
mod rosenbrock;
#[allow(clippy::excessive_precision, clippy::needless_range_loop)]
mod vern9;

use std::fmt;
use std::ops::ControlFlow;
use std::str::FromStr;
use std::time::Instant;

/// A first-order system dx/dt = f(t, x). Integrators see nothing else of a model.
pub trait OdeSystem {
    /// Number of states.
    fn dim(&self) -> usize;
    /// dx/dt = f(t, x). Must not allocate.
    fn rhs(&mut self, t: f64, x: &[f64], dxdt: &mut [f64]);
    /// Jacobian df/dx, row-major dim*dim into `jac`. Return false if not provided (the solver then uses finite differences).
    fn jacobian(&mut self, _t: f64, _x: &[f64], _jac: &mut [f64]) -> bool {
        false
    }
    /// Told of every step attempt as the integrator counts it (accepted or rejected), so an
    /// observer can report steps during a run; the final [`SolverStats`] hold the same totals.
    fn step_counted(&mut self, _accepted: bool) {}
    /// True when f does not depend on t (f(t, x) = f(t', x) to the bit): RODAS4 then takes
    /// ∂f/∂t = 0 instead of spending an rhs call per step on a difference that is exactly
    /// zero. A wrapper must forward it; the default, false, is always safe.
    fn is_autonomous(&self) -> bool {
        false
    }
    /// True when df/dx is the same at every t and x (a linear system, as a `linear` model
    /// is): RODAS4 then forms J once per run instead of once per step. A wrapper must forward
    /// it; the default, false, is always safe.
    fn jacobian_is_constant(&self) -> bool {
        false
    }
    /// Whether [`Self::project`] keeps an invariant; the integrators call it only then.
    fn projects(&self) -> bool {
        false
    }
    /// Moves an accepted step's end state `x` back onto the level set of an invariant the exact
    /// solution keeps (a first integral), in place, and says whether it moved it: projection
    /// methods (Hairer, Lubich & Wanner, *Geometric Numerical Integration*, IV.4). The
    /// integrators call it every [`PROJECTION_INTERVAL`] accepted steps and at the end of every
    /// segment, before the step's samples, and then re-evaluate what they carry from the end
    /// state (the first-same-as-last derivative). `tol` is the run's, for the projection's metric.
    fn project(&mut self, _t: f64, _x: &mut [f64], _tol: &Tolerances) -> bool {
        false
    }
}

/// Accepted steps between two projections onto an invariant ([`OdeSystem::project`]). The
/// drift a projection removes grows by a few local errors a step, so projecting every step or
/// every few dozen gives the same global error; the interval keeps the projection's cost (a
/// gradient of the invariant, one right-hand side) a few per cent of a step's. Measured on
/// Villarceau's 90° release over 100 periods (DOP853): see `docs/accuracy.md`, "Keeping
/// Jacobi's integral".
pub const PROJECTION_INTERVAL: u64 = 16;

/// One Newton step of the standard projection onto the level set I(x) = `target` of an
/// invariant with value `value` and gradient `grad` at `x`, in the metric of the error control
/// (weights sk = atol + rtol·|x|): x ← x − λ·W∇I, W = diag(sk²), λ = (I − target)/(∇Iᵀ W ∇I).
/// The least move, as the error control measures moves, that restores I to second order in
/// the drift. Returns whether it moved `x` (not for a zero or non-finite gradient).
pub fn project_onto_level(
    x: &mut [f64],
    grad: &[f64],
    value: f64,
    target: f64,
    tol: &Tolerances,
) -> bool {
    let sk = |xi: f64| tol.atol + tol.rtol * xi.abs();
    let mut denom = 0.0;
    for (g, &xi) in grad.iter().zip(x.iter()) {
        let w = sk(xi);
        denom += g * g * w * w;
    }
    if !(denom > 0.0 && denom.is_finite()) || value == target || !value.is_finite() {
        return false;
    }
    let lambda = (value - target) / denom;
    for (g, xi) in grad.iter().zip(x.iter_mut()) {
        let w = sk(*xi);
        *xi -= lambda * w * w * g;
    }
    true
}

/// Integration method.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Method {
    /// Dormand–Prince 5(4), adaptive; the default for non-stiff runs.
    Dopri5,
    /// Dormand–Prince 8(5,3), adaptive; cheaper than `Dopri5` at tight tolerances (≲1e-8).
    Dop853,
    /// Verner 9(8), adaptive; for tight errors on smooth problems (1e-6 and below on Foucault's
    /// gyroscope), where its order 9 takes fewer rhs calls than `Dop853` for the same achieved
    /// error — unless samples are as dense as the steps: its interpolant costs 9 rhs calls in
    /// each step that holds one (DOP853's 3).
    Vern9,
    /// Classic RK4 at a fixed step (shortened only at breakpoints and at the end); tolerances
    /// are not used for error control.
    Rk4 { step_s: f64 },
    /// Rosenbrock RODAS4, L-stable; for stiff models (fast lightly damped nutation).
    Rodas4,
    /// Rosenbrock Rodas5P (order 5, L-stable, 4th-order dense output); for stiff models where
    /// RODAS4's steps or its 3rd-order samples are the cost: longer steps for the same error.
    Rodas5p,
    /// Radau IIA of order 5 (Hairer's RADAU5), implicit and L-stable; for stiff models at
    /// tight tolerances, where it holds long steps over the nutation. Its tolerances are mapped
    /// as RADAU5 maps them (rtol → 0.1·rtol^(2/3)), so that the achieved error is near rtol.
    Radau5,
}

impl Method {
    /// Step used when `"rk4"` is parsed without an explicit step (`"rk4:0.001"`).
    pub const DEFAULT_RK4_STEP_S: f64 = 0.01;
}

impl fmt::Display for Method {
    /// `"dopri5"`, `"dop853"`, `"vern9"`, `"rk4"`, `"rodas4"`, `"rodas5p"`, `"radau5"`. The RK4 step is not
    /// printed; the alternate form (`{:#}`) prints it as `"rk4:<step_s>"`, which `FromStr`
    /// reads back.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Method::Dopri5 => f.write_str("dopri5"),
            Method::Dop853 => f.write_str("dop853"),
            Method::Vern9 => f.write_str("vern9"),
            Method::Rk4 { step_s } if f.alternate() => write!(f, "rk4:{step_s}"),
            Method::Rk4 { .. } => f.write_str("rk4"),
            Method::Rodas4 => f.write_str("rodas4"),
            Method::Rodas5p => f.write_str("rodas5p"),
            Method::Radau5 => f.write_str("radau5"),
        }
    }
}

impl FromStr for Method {
    type Err = SolveError;

    /// Case-insensitive `"dopri5"`, `"dop853"`, `"vern9"`, `"rodas4"`, `"rodas5p"`, `"radau5"`,
    /// `"rk4"` (step
    /// [`Method::DEFAULT_RK4_STEP_S`]) or `"rk4:<step_s>"`.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let lower = s.trim().to_ascii_lowercase();
        match lower.as_str() {
            "dopri5" => Ok(Method::Dopri5),
            "dop853" => Ok(Method::Dop853),
            "vern9" => Ok(Method::Vern9),
            "rodas4" => Ok(Method::Rodas4),
            "rodas5p" => Ok(Method::Rodas5p),
            "radau5" => Ok(Method::Radau5),
            "rk4" => Ok(Method::Rk4 {
                step_s: Method::DEFAULT_RK4_STEP_S,
            }),
            other => match other.strip_prefix("rk4:") {
                Some(step) => match step.parse::<f64>() {
                    Ok(step_s) if step_s.is_finite() && step_s > 0.0 => Ok(Method::Rk4 { step_s }),
                    _ => Err(SolveError::InvalidOptions(format!(
                        "method {s:?}: the rk4 step after the colon must be a positive number of seconds"
                    ))),
                },
                None => Err(SolveError::InvalidOptions(format!(
                    "unknown method {s:?} (allowed: dopri5, dop853, vern9, rk4, rk4:<step_s>, rodas4, rodas5p, radau5)"
                ))),
            },
        }
    }
}

/// Error-control settings. The local error of a step is accepted when
/// RMS_i(err_i / (atol + rtol * max(|x_i|, |x_new_i|))) <= 1.
#[derive(Clone, Copy, Debug)]
pub struct Tolerances {
    /// Relative tolerance, > 0.
    pub rtol: f64,
    /// Absolute tolerance (state units), >= 0.
    pub atol: f64,
    /// Largest step; `f64::INFINITY` = none.
    pub max_step_s: f64,
    /// First step after the start and after each breakpoint; `None` = Hairer's estimate.
    pub initial_step_s: Option<f64>,
    /// RADAU5 only: the Jacobian is kept from step to step while the simplified Newton
    /// iteration contracts by at most this factor per iteration, in (0, 1). Hairer's THET:
    /// 0.001 by default; ≈ 0.1 where a Jacobian costs many right-hand sides (a slower
    /// iteration is then cheaper than a fresh Jacobian).
    pub jacobian_reuse_contraction: f64,
}

impl Default for Tolerances {
    /// rtol 1e-8, atol 1e-10, no step limit, estimated initial step.
    fn default() -> Self {
        Tolerances {
            rtol: 1e-8,
            atol: 1e-10,
            max_step_s: f64::INFINITY,
            initial_step_s: None,
            jacobian_reuse_contraction: DEFAULT_JACOBIAN_REUSE_CONTRACTION,
        }
    }
}

/// RADAU5's default [`Tolerances::jacobian_reuse_contraction`] (Hairer's THET).
pub const DEFAULT_JACOBIAN_REUSE_CONTRACTION: f64 = 0.001;

/// Work counters of one `integrate` call.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SolverStats {
    /// Accepted steps.
    pub steps: u64,
    /// Rejected step attempts (error too large, singular iteration matrix, or — RADAU5 — a
    /// Newton iteration that diverged or converged too slowly).
    pub rejected_steps: u64,
    /// Calls of `OdeSystem::rhs`, including finite-difference Jacobians and df/dt.
    pub rhs_evals: u64,
    /// Jacobians formed (analytic or finite-difference).
    pub jacobian_evals: u64,
    /// LU decompositions of the iteration matrix (RADAU5: one per pair of its real n×n and
    /// complex n×n matrices, as RADAU5's NDEC counts them).
    pub lu_decompositions: u64,
    /// Wall-clock time spent in `integrate`.
    pub wall_time_s: f64,
}

/// Why `integrate` returned successfully.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum StopReason {
    /// Reached `t_end`.
    Finished,
    /// The observer returned `Break` for the sample at `t`; the state passed back is that sample.
    Interrupted { t: f64 },
}

/// Why `integrate` failed. The state passed in is left at the last accepted step.
#[derive(Clone, Debug, PartialEq)]
pub enum SolveError {
    /// The step size needed to meet the tolerances fell below round-off of `t`.
    StepSizeUnderflow { t: f64, h: f64 },
    /// The state or its derivative became NaN or infinite at `t`.
    NonFiniteState { t: f64 },
    /// More than `limit` step attempts.
    TooManySteps { t: f64, limit: u64 },
    /// The iteration matrix of an implicit method stayed singular after step reductions.
    SingularMatrix { t: f64 },
    /// Options, output grid, breakpoints or initial state are not usable.
    InvalidOptions(String),
}

impl fmt::Display for SolveError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SolveError::StepSizeUnderflow { t, h } => {
                write!(f, "step size underflow at t = {t} s (h = {h:e} s)")
            }
            SolveError::NonFiniteState { t } => write!(f, "non-finite state at t = {t} s"),
            SolveError::TooManySteps { t, limit } => {
                write!(f, "more than {limit} steps before t = {t} s")
            }
            SolveError::SingularMatrix { t } => {
                write!(f, "iteration matrix repeatedly singular at t = {t} s")
            }
            SolveError::InvalidOptions(why) => write!(f, "invalid solver options: {why}"),
        }
    }
}

impl std::error::Error for SolveError {}

/// Output sampling: t0 + k*dt for k = 0.. while <= t_end (with a small relative slack so that a
/// grid time equal to `t_end` up to round-off is taken as `t_end`), plus `t_end` itself if it is
/// not on the grid. `t0` is the start of integration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OutputGrid {
    pub t0: f64,
    pub dt: f64,
    pub t_end: f64,
}

/// Upper limit on step attempts (accepted + rejected) in one `integrate` call.
pub const MAX_STEPS: u64 = 50_000_000;

/// Integrate from (t0, x0) to t_end. The integrator stops exactly at every breakpoint in (t0, t_end) (the rhs may be discontinuous there: restart FSAL/derivative info, re-pick the step), samples the solution at the grid times from its dense output (never by shortening steps to hit output times, so recorded values do not depend on the output rate), and calls `observer(t, x)` for each sample in order; the observer returns ControlFlow::Break(()) to interrupt (then StopReason::Interrupted). Returns the final state in x0 (overwritten) and stats.
///
/// Details:
/// - Breakpoints may be unsorted; those outside (t0, t_end) are ignored. Inside a segment
///   between breakpoints the rhs is only evaluated at times strictly inside it (a stage that
///   would fall on the breakpoint is evaluated one ulp before it; after the breakpoint, one ulp
///   after it), so either convention for the value *at* a discontinuity gives one-sided values.
/// - A sample time that coincides with a breakpoint is emitted once, from the step ending there.
/// - On `Interrupted { t }` the state passed back is the sample at `t`; on error it is the state
///   at the last accepted step.
pub fn integrate<S: OdeSystem>(
    sys: &mut S,
    method: Method,
    tol: &Tolerances,
    x: &mut [f64],
    grid: &OutputGrid,
    breakpoints: &[f64],
    mut observer: impl FnMut(f64, &[f64]) -> ControlFlow<()>,
) -> Result<(StopReason, SolverStats), SolveError> {
    let started = Instant::now();
    validate(sys.dim(), method, tol, x, grid, breakpoints)?;
    let segment_ends = segment_ends(grid, breakpoints);
    let mut stats = SolverStats::default();
    let n = x.len();
    let result = match method {
        Method::Dopri5 => run(
            &mut dopri5::Dopri5::new(n),
            sys,
            tol,
            x,
            grid,
            &segment_ends,
            &mut observer,
            &mut stats,
        ),
        Method::Dop853 => run(
            &mut dop853::Dop853::new(n),
            sys,
            tol,
            x,
            grid,
            &segment_ends,
            &mut observer,
            &mut stats,
        ),
        Method::Vern9 => run(
            &mut vern9::Vern9::new(n),
            sys,
            tol,
            x,
            grid,
            &segment_ends,
            &mut observer,
            &mut stats,
        ),
        Method::Rk4 { step_s } => run(
            &mut rk4::Rk4::new(n, step_s),
            sys,
            tol,
            x,
            grid,
            &segment_ends,
            &mut observer,
            &mut stats,
        ),
        Method::Rodas4 => run(
            &mut rosenbrock::Rosenbrock::<rodas4::Rodas4>::new(n),
            sys,
            tol,
            x,
            grid,
            &segment_ends,
            &mut observer,
            &mut stats,
        ),
        Method::Rodas5p => run(
            &mut rosenbrock::Rosenbrock::<rodas5p::Rodas5p>::new(n),
            sys,
            tol,
            x,
            grid,
            &segment_ends,
            &mut observer,
            &mut stats,
        ),
        Method::Radau5 => run(
            &mut radau5::Radau5::new(n),
            sys,
            tol,
            x,
            grid,
            &segment_ends,
            &mut observer,
            &mut stats,
        ),
    };
    stats.wall_time_s = started.elapsed().as_secs_f64();
    result.map(|reason| (reason, stats))
}

fn validate(
    dim: usize,
    method: Method,
    tol: &Tolerances,
    x: &[f64],
    grid: &OutputGrid,
    breakpoints: &[f64],
) -> Result<(), SolveError> {
    let bad = |why: String| Err(SolveError::InvalidOptions(why));
    if x.len() != dim {
        return bad(format!(
            "state has {} entries, system dim is {dim}",
            x.len()
        ));
    }
    if !(tol.rtol.is_finite() && tol.rtol > 0.0) {
        return bad(format!("rtol must be finite and > 0, got {}", tol.rtol));
    }
    if !(tol.atol.is_finite() && tol.atol >= 0.0) {
        return bad(format!("atol must be finite and >= 0, got {}", tol.atol));
    }
    if tol.max_step_s.is_nan() || tol.max_step_s <= 0.0 {
        return bad(format!("max_step_s must be > 0, got {}", tol.max_step_s));
    }
    if let Some(h0) = tol.initial_step_s
        && !(h0.is_finite() && h0 > 0.0)
    {
        return bad(format!("initial_step_s must be finite and > 0, got {h0}"));
    }
    let theta = tol.jacobian_reuse_contraction;
    if !(theta > 0.0 && theta < 1.0) {
        return bad(format!(
            "jacobian_reuse_contraction must be in (0, 1), got {theta}"
        ));
    }
    if let Method::Rk4 { step_s } = method
        && !(step_s.is_finite() && step_s > 0.0)
    {
        return bad(format!("rk4 step_s must be finite and > 0, got {step_s}"));
    }
    if !(grid.t0.is_finite() && grid.t_end.is_finite() && grid.t_end >= grid.t0) {
        return bad(format!(
            "need finite t0 <= t_end, got t0 = {}, t_end = {}",
            grid.t0, grid.t_end
        ));
    }
    if !(grid.dt.is_finite() && grid.dt > 0.0) {
        return bad(format!("output dt must be finite and > 0, got {}", grid.dt));
    }
    if breakpoints.iter().any(|b| b.is_nan()) {
        return bad("breakpoint is NaN".to_owned());
    }
    if x.iter().any(|v| !v.is_finite()) {
        return Err(SolveError::NonFiniteState { t: grid.t0 });
    }
    Ok(())
}

/// Sorted ends of the integration segments: the breakpoints inside (t0, t_end), then t_end.
/// Breakpoints closer than round-off to t0, t_end or each other are merged.
fn segment_ends(grid: &OutputGrid, breakpoints: &[f64]) -> Vec<f64> {
    let tiny = |t: f64| 64.0 * f64::EPSILON * t.abs().max(grid.t_end.abs()).max(1e-300);
    let mut ends: Vec<f64> = breakpoints
        .iter()
        .copied()
        .filter(|&b| b - grid.t0 > tiny(b) && grid.t_end - b > tiny(b))
        .collect();
    ends.sort_by(f64::total_cmp);
    ends.dedup_by(|later, earlier| *later - *earlier <= tiny(*later));
    ends.push(grid.t_end);
    ends
}

/// Output times in order, computed as t0 + k*dt (no accumulation of round-off).
struct SampleClock {
    t0: f64,
    dt: f64,
    t_end: f64,
    slack: f64,
    k: u64,
    done: bool,
}

impl SampleClock {
    fn new(grid: &OutputGrid) -> Self {
        let scale = grid.t0.abs().max(grid.t_end.abs());
        let slack = (1e-9 * grid.dt)
            .max(8.0 * f64::EPSILON * scale)
            .min(0.25 * grid.dt);
        SampleClock {
            t0: grid.t0,
            dt: grid.dt,
            t_end: grid.t_end,
            slack,
            k: 0,
            done: false,
        }
    }

    #[inline]
    fn peek(&self) -> Option<f64> {
        if self.done {
            return None;
        }
        let tk = self.t0 + self.k as f64 * self.dt;
        Some(if tk < self.t_end - self.slack {
            tk
        } else {
            self.t_end
        })
    }

    #[inline]
    fn advance(&mut self) {
        if self.peek() == Some(self.t_end) {
            self.done = true;
        } else {
            self.k += 1;
        }
    }
}

/// Times at which a stepper may evaluate the rhs inside the current segment: strictly inside
/// (one ulp in from) breakpoints, so a discontinuous rhs is only ever seen from one side.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Window {
    lo: f64,
    hi: f64,
}

impl Window {
    /// The evaluation time for nominal time `t`.
    #[inline]
    pub(crate) fn at(&self, t: f64) -> f64 {
        t.clamp(self.lo, self.hi)
    }
}

/// Outcome of one step attempt.
pub(crate) struct Attempt {
    pub accepted: bool,
    /// Proposed size of the next attempt (after acceptance: the next step; after rejection:
    /// the retry).
    pub h_next: f64,
}

/// One integration method, driven by [`run`]. Workspaces are allocated in the constructor;
/// no method may allocate.
pub(crate) trait Stepper {
    /// A step may be stretched by this factor to land on a segment end instead of leaving a
    /// sliver step (Hairer uses 1.01).
    const STRETCH: f64;

    /// Forget derivative (FSAL) and controller history and evaluate what the first step from
    /// (t, x) needs. Called at the start and after every breakpoint.
    fn reset<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        w: Window,
        t: f64,
        x: &[f64],
        stats: &mut SolverStats,
    ) -> Result<(), SolveError>;

    /// First step size after a reset when the user gave none.
    #[allow(clippy::too_many_arguments)]
    fn first_step<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        w: Window,
        t: f64,
        x: &[f64],
        tol: &Tolerances,
        h_max: f64,
        stats: &mut SolverStats,
    ) -> f64;

    /// Attempt a step of size `h` from (t, x); on acceptance `x_new` and the dense output refer
    /// to this step until `accept` is called.
    #[allow(clippy::too_many_arguments)]
    fn attempt<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        w: Window,
        t: f64,
        x: &[f64],
        h: f64,
        tol: &Tolerances,
        stats: &mut SolverStats,
    ) -> Result<Attempt, SolveError>;

    /// State at the end of the last accepted attempt.
    fn x_new(&self) -> &[f64];

    /// The same for a projection to move ([`OdeSystem::project`]), with the slot of the
    /// derivative the stepper carries from it into the next step (first-same-as-last), which
    /// [`run`] re-evaluates after a move; `None` for steppers that evaluate everything afresh
    /// at a step's start.
    fn end_state_mut(&mut self) -> (&mut [f64], Option<&mut [f64]>);

    /// Compute whatever the dense output needs beyond the step itself (extra stages); called
    /// at most once per accepted step, only when a sample falls strictly inside it.
    fn prepare_dense<S: OdeSystem>(
        &mut self,
        _sys: &mut S,
        _w: Window,
        _t: f64,
        _x: &[f64],
        _h: f64,
        _stats: &mut SolverStats,
    ) {
    }

    /// Dense output at t + theta*h inside the accepted step from (t, x_old) of size h.
    fn dense(&self, x_old: &[f64], theta: f64, h: f64, out: &mut [f64]);

    /// The accepted step becomes the current point (FSAL shifts).
    fn accept(&mut self);
}

#[allow(clippy::too_many_arguments)]
fn run<S: OdeSystem, St: Stepper>(
    st: &mut St,
    sys: &mut S,
    tol: &Tolerances,
    x: &mut [f64],
    grid: &OutputGrid,
    segment_ends: &[f64],
    observer: &mut impl FnMut(f64, &[f64]) -> ControlFlow<()>,
    stats: &mut SolverStats,
) -> Result<StopReason, SolveError> {
    let mut sample = vec![0.0; x.len()];
    let projects = sys.projects();
    let mut clock = SampleClock::new(grid);
    let mut t = grid.t0;

    // Samples at the start (one, or the only one when t_end == t0).
    while let Some(ts) = clock.peek() {
        if ts > t {
            break;
        }
        clock.advance();
        if observer(ts, x).is_break() {
            return Ok(StopReason::Interrupted { t: ts });
        }
    }

    let mut seg_start = grid.t0;
    for &seg_end in segment_ends {
        if seg_end <= t {
            continue; // t_end == t0: nothing to integrate.
        }
        let w = Window {
            lo: if seg_start == grid.t0 {
                f64::NEG_INFINITY
            } else {
                seg_start.next_up()
            },
            hi: if seg_end == grid.t_end {
                f64::INFINITY
            } else {
                seg_end.next_down()
            },
        };
        st.reset(sys, w, t, x, stats)?;
        let mut h = match tol.initial_step_s {
            Some(h0) => h0,
            None => st.first_step(sys, w, t, x, tol, tol.max_step_s.min(seg_end - t), stats),
        };
        loop {
            if stats.steps + stats.rejected_steps >= MAX_STEPS {
                return Err(SolveError::TooManySteps {
                    t,
                    limit: MAX_STEPS,
                });
            }
            h = h.min(tol.max_step_s);
            let remaining = seg_end - t;
            let last = h * St::STRETCH >= remaining;
            if last {
                h = remaining;
            }
            if h.is_nan() || h <= 0.0 || 0.1 * h <= t.abs() * f64::EPSILON {
                return Err(SolveError::StepSizeUnderflow { t, h });
            }
            let attempt = st.attempt(sys, w, t, x, h, tol, stats)?;
            if !attempt.accepted {
                stats.rejected_steps += 1;
                sys.step_counted(false);
                h = attempt.h_next;
                continue;
            }
            let t_new = if last { seg_end } else { t + h };
            if st.x_new().iter().any(|v| !v.is_finite()) {
                return Err(SolveError::NonFiniteState { t: t_new });
            }
            stats.steps += 1;
            sys.step_counted(true);
            if projects && (last || stats.steps.is_multiple_of(PROJECTION_INTERVAL)) {
                let (x_new, f_new) = st.end_state_mut();
                if sys.project(t_new, x_new, tol) {
                    if x_new.iter().any(|v| !v.is_finite()) {
                        return Err(SolveError::NonFiniteState { t: t_new });
                    }
                    if let Some(f) = f_new {
                        sys.rhs(w.at(t_new), x_new, f);
                        stats.rhs_evals += 1;
                    }
                }
            }

            let mut dense_ready = false;
            while let Some(ts) = clock.peek() {
                if ts > t_new {
                    break;
                }
                clock.advance();
                if ts >= t_new {
                    sample.copy_from_slice(st.x_new());
                } else {
                    if !dense_ready {
                        st.prepare_dense(sys, w, t, x, h, stats);
                        dense_ready = true;
                    }
                    st.dense(x, (ts - t) / h, h, &mut sample);
                }
                if observer(ts, &sample).is_break() {
                    x.copy_from_slice(&sample);
                    return Ok(StopReason::Interrupted { t: ts });
                }
            }

            st.accept();
            x.copy_from_slice(st.x_new());
            t = t_new;
            h = attempt.h_next;
            if last {
                break;
            }
        }
        seg_start = seg_end;
    }
    Ok(StopReason::Finished)
}

/// The derivative f(t, x) at a segment start into `f0`, counted, and refused when it is not
/// finite: what every stepper's `reset` evaluates before its own bookkeeping.
pub(crate) fn start_derivative<S: OdeSystem>(
    sys: &mut S,
    w: Window,
    t: f64,
    x: &[f64],
    f0: &mut [f64],
    stats: &mut SolverStats,
) -> Result<(), SolveError> {
    sys.rhs(w.at(t), x, f0);
    stats.rhs_evals += 1;
    if f0.iter().any(|v| !v.is_finite()) {
        return Err(SolveError::NonFiniteState { t });
    }
    Ok(())
}

/// RMS of err_i / (atol + rtol * max(|x_i|, |x_new_i|)).
pub(crate) fn error_norm(err: &[f64], x: &[f64], x_new: &[f64], tol: &Tolerances) -> f64 {
    let mut sum = 0.0;
    for ((e, a), b) in err.iter().zip(x).zip(x_new) {
        let sk = tol.atol + tol.rtol * a.abs().max(b.abs());
        let r = e / sk;
        sum += r * r;
    }
    (sum / err.len().max(1) as f64).sqrt()
}

/// Scratch vectors for [`initial_step`].
pub(crate) struct InitialStepScratch {
    pub x1: Vec<f64>,
    pub f1: Vec<f64>,
}

impl InitialStepScratch {
    pub(crate) fn new(n: usize) -> Self {
        InitialStepScratch {
            x1: vec![0.0; n],
            f1: vec![0.0; n],
        }
    }
}

/// Hairer's initial step estimate (HNW I, II.4; `HINIT` in DOPRI5): a step for which an explicit
/// Euler step is small against the tolerance and the second derivative estimate
/// ||f(t+h, x+h f) - f|| / h keeps the local error of a method of `order` near 0.01.
/// Costs one rhs evaluation. `f0` = f(t, x).
#[allow(clippy::too_many_arguments)]
pub(crate) fn initial_step<S: OdeSystem>(
    sys: &mut S,
    w: Window,
    t: f64,
    x: &[f64],
    f0: &[f64],
    order: i32,
    tol: &Tolerances,
    h_max: f64,
    scratch: &mut InitialStepScratch,
    stats: &mut SolverStats,
) -> f64 {
    let n = x.len().max(1) as f64;
    let (mut dnf, mut dny) = (0.0, 0.0);
    for (xi, fi) in x.iter().zip(f0) {
        let sk = tol.atol + tol.rtol * xi.abs();
        dnf += (fi / sk).powi(2);
        dny += (xi / sk).powi(2);
    }
    let (dnf, dny) = ((dnf / n).sqrt(), (dny / n).sqrt());
    let mut h = if dnf <= 1e-5 || dny <= 1e-5 {
        1e-6
    } else {
        0.01 * dny / dnf
    };
    h = h.min(h_max);
    for ((x1, xi), fi) in scratch.x1.iter_mut().zip(x).zip(f0) {
        *x1 = xi + h * fi;
    }
    sys.rhs(w.at(t + h), &scratch.x1, &mut scratch.f1);
    stats.rhs_evals += 1;
    let mut der2 = 0.0;
    for ((f1, fi), xi) in scratch.f1.iter().zip(f0).zip(x) {
        let sk = tol.atol + tol.rtol * xi.abs();
        der2 += ((f1 - fi) / sk).powi(2);
    }
    let der2 = (der2 / n).sqrt() / h;
    let der12 = der2.abs().max(dnf);
    let h1 = if der12 <= 1e-15 {
        (h * 1e-3).max(1e-6)
    } else {
        (0.01 / der12).powf(1.0 / f64::from(order))
    };
    let h = (100.0 * h).min(h1).min(h_max);
    if h.is_finite() && h > 0.0 {
        h
    } else {
        1e-6_f64.min(h_max)
    }
}

/// df/dx at (te, x) by central differences into the row-major `jac` (2n rhs calls, increment
/// cbrt(eps)·max(|x_j|, 1e-2)); `xs`, `f_up`, `f_down` are scratch of length n.
///
/// Central, not Hairer's forward differences (increment sqrt(eps·|x_j|)): those carry round-off
/// eps·|f|/δ; on slow motion plus stiff nutation that error, scaled by the nutation's stiffness,
/// swamped the slow mode's entries of J and cut Rodas4's steps ~200-fold (stiff test: 10633 →
/// 496 steps per 1000 s; exact J: 56).
#[allow(clippy::too_many_arguments)]
pub(crate) fn difference_jacobian<S: OdeSystem>(
    sys: &mut S,
    te: f64,
    x: &[f64],
    jac: &mut [f64],
    xs: &mut [f64],
    f_up: &mut [f64],
    f_down: &mut [f64],
    stats: &mut SolverStats,
) {
    let n = x.len();
    xs.copy_from_slice(x);
    for j in 0..n {
        let saved = xs[j];
        let delta = f64::EPSILON.cbrt() * saved.abs().max(1e-2);
        xs[j] = saved + delta;
        let up = xs[j];
        sys.rhs(te, xs, f_up);
        xs[j] = saved - delta;
        let down = xs[j];
        sys.rhs(te, xs, f_down);
        for (i, (u, d)) in f_up.iter().zip(f_down.iter()).enumerate() {
            jac[i * n + j] = (u - d) / (up - down);
        }
        xs[j] = saved;
    }
    stats.rhs_evals += 2 * n as u64;
}

/// Hairer's PI step-size controller of DOPRI5/DOP853 (HNW I, IV.2): h_new = h / fac with
/// fac = err^expo1 / err_prev^beta / safe, clamped so that h_new is in
/// [h * fac_min, h * fac_max]; no growth right after a rejection. DOPRI5 uses
/// expo1 = 1/5 - 0.75 beta, DOP853 expo1 = 1/8 - 0.2 beta.
#[derive(Clone, Copy, Debug)]
pub(crate) struct PiController {
    expo1: f64,
    beta: f64,
    /// Smallest ratio h_new / h.
    fac_min: f64,
    /// Largest ratio h_new / h.
    fac_max: f64,
    safe: f64,
    /// ln of the last accepted step's error (floored at 1e-4).
    ln_err_prev: f64,
    last_rejected: bool,
}

/// ln 1e-4: the floor of the remembered error, as DOPRI5's and DOP853's `FACOLD`.
const LN_ERR_PREV_FLOOR: f64 = -9.210_340_371_976_182;

impl PiController {
    pub(crate) fn new(expo1: f64, beta: f64, fac_min: f64, fac_max: f64) -> Self {
        PiController {
            expo1,
            beta,
            fac_min,
            fac_max,
            safe: 0.9,
            ln_err_prev: LN_ERR_PREV_FLOOR,
            last_rejected: false,
        }
    }

    pub(crate) fn reset(&mut self) {
        self.ln_err_prev = LN_ERR_PREV_FLOOR;
        self.last_rejected = false;
    }

    pub(crate) fn decide(&mut self, err: f64, h: f64) -> Attempt {
        if !err.is_finite() {
            self.last_rejected = true;
            return Attempt {
                accepted: false,
                h_next: h * self.fac_min,
            };
        }
        // err^expo1 / err_prev^beta as one exp of logarithms: two `powf` per step were a tenth
        // of a small system's run (Villarceau's eq. 44 bis, `benches/handwritten.rs`); the
        // step sizes differ from the powf form by rounding only.
        let ln_err = err.ln();
        if err <= 1.0 {
            let fac = ((self.expo1 * ln_err - self.beta * self.ln_err_prev).exp() / self.safe)
                .clamp(1.0 / self.fac_max, 1.0 / self.fac_min);
            let mut h_next = h / fac;
            if self.last_rejected {
                h_next = h_next.min(h);
            }
            self.ln_err_prev = ln_err.max(LN_ERR_PREV_FLOOR);
            self.last_rejected = false;
            Attempt {
                accepted: true,
                h_next,
            }
        } else {
            self.last_rejected = true;
            Attempt {
                accepted: false,
                h_next: h / ((self.expo1 * ln_err).exp() / self.safe).min(1.0 / self.fac_min),
            }
        }
    }
}
