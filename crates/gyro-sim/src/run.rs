//! The run loop: compile a scene's design into a model, hand it to an integrator, and pass every
//! output sample to an observer (the recorder, a test, a benchmark). Integrators see only the
//! `OdeSystem` face of the model; the model holds no integrator state.

use crate::program::{Segment, ShipProgram};
use crate::scene::Scene;
use crate::solvers::{
    self, OdeSystem, OutputGrid, SolveError, SolverStats, StopReason, Tolerances,
};
use gyro_model::{CompiledModel, Fidelity, ModelError, ShipMotion};
use std::cell::Cell;
use std::fmt;
use std::ops::ControlFlow;
use std::time::Instant;

/// A scene compiled and ready to run (immutable; run it as often as you like).
pub struct Simulation {
    pub model: CompiledModel<ShipProgram>,
    pub grid: OutputGrid,
    pub breakpoints: Vec<f64>,
    /// Runs project onto Jacobi's integral ([`JacobiKeeper`]).
    pub keep_jacobi_integral: bool,
}

#[derive(Debug)]
pub enum RunError {
    Model(ModelError),
    Solve(SolveError),
    Record(String),
}

impl fmt::Display for RunError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RunError::Model(e) => write!(f, "cannot compile the model: {e}"),
            RunError::Solve(e) => write!(f, "integration failed: {e}"),
            RunError::Record(e) => write!(f, "recording failed: {e}"),
        }
    }
}
impl std::error::Error for RunError {}

/// What a run did.
#[derive(Clone, Debug, PartialEq)]
pub struct RunStats {
    pub solver: SolverStats,
    pub stop: StopReason,
    pub samples: u64,
}

/// The compiled model as an ODE system.
pub struct ModelSystem<'a> {
    pub model: &'a CompiledModel<ShipProgram>,
}

impl OdeSystem for ModelSystem<'_> {
    fn dim(&self) -> usize {
        self.model.dim()
    }
    fn rhs(&mut self, t: f64, x: &[f64], dxdt: &mut [f64]) {
        if !self.model.rhs(t, x, dxdt) {
            // Singular equations: a non-finite derivative makes the integrator stop with an error
            // naming the time, instead of carrying garbage on.
            dxdt.fill(f64::NAN);
        }
    }
    fn jacobian(&mut self, t: f64, x: &[f64], jac: &mut [f64]) -> bool {
        self.model.jacobian(t, x, jac);
        true
    }
    fn is_autonomous(&self) -> bool {
        self.model.is_autonomous()
    }
    fn jacobian_is_constant(&self) -> bool {
        self.model.jacobian_is_constant()
    }
}

/// The solver's work so far, as a run's observer sees it (see [`Simulation::run_with_progress`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Progress {
    /// Steps accepted so far; at the last sample, the solver's `steps`.
    pub steps: u64,
    /// Steps rejected so far; at the last sample, the solver's `rejected_steps`.
    pub rejected_steps: u64,
    /// Right-hand sides evaluated so far; at the last sample, the solver's `rhs_evals`.
    pub rhs_evals: u64,
    /// Jacobians formed so far; at the last sample, the solver's `jacobian_evals`.
    pub jacobian_evals: u64,
    /// Wall-clock seconds since the first sample (so never more than the solver's final
    /// `wall_time_s`, which also counts its set-up).
    pub wall_time_s: f64,
}

/// Counters shared by the counting system (which the integrator drives) and the observer.
#[derive(Default)]
struct Counts {
    steps: Cell<u64>,
    rejected_steps: Cell<u64>,
    rhs_evals: Cell<u64>,
    jacobian_evals: Cell<u64>,
}

/// What an observer of [`Simulation::run_with_progress`] may ask about the run so far.
pub struct RunProbe<'a> {
    counts: &'a Counts,
    started: Instant,
}

impl RunProbe<'_> {
    /// The work done up to now (cheap: two counters and a look at the clock).
    pub fn progress(&self) -> Progress {
        Progress {
            steps: self.counts.steps.get(),
            rejected_steps: self.counts.rejected_steps.get(),
            rhs_evals: self.counts.rhs_evals.get(),
            jacobian_evals: self.counts.jacobian_evals.get(),
            wall_time_s: self.started.elapsed().as_secs_f64(),
        }
    }
}

/// A manoeuvre's start or end, as a run reaches it (see [`RunObserver::event`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ManoeuvreEvent<'a> {
    pub time_s: f64,
    /// Its start (`true`) or its end.
    pub is_start: bool,
    /// Index of the segment in the program, and the segment.
    pub segment_index: usize,
    pub segment: &'a Segment,
    /// Speed and heading at the segment's end (the same in its start and end events).
    pub speed_after_m_per_s: f64,
    pub heading_after_rad: f64,
}

/// What watches a run (the recorder, a test, a benchmark): the program's manoeuvre events as the
/// run reaches them, every output sample, and how the run ended. Returning
/// `ControlFlow::Break` stops the run where it is (its stop reason is then `Interrupted`).
pub trait RunObserver {
    /// A manoeuvre start or end at or before the sample about to be reported (in program order).
    fn event(&mut self, _event: &ManoeuvreEvent<'_>) -> ControlFlow<()> {
        ControlFlow::Continue(())
    }
    /// An output sample: time, state, and the solver's work so far.
    fn sample(&mut self, t: f64, x: &[f64], probe: &RunProbe) -> ControlFlow<()>;
    /// The run ended (finished or interrupted); not called when the integration fails.
    fn finish(&mut self, _stats: &RunStats) {}
}

/// The model as an ODE system that counts what the integrator asks of it.
struct CountingSystem<'a> {
    inner: ModelSystem<'a>,
    counts: &'a Counts,
    keeper: Option<JacobiKeeper>,
}

impl OdeSystem for CountingSystem<'_> {
    fn dim(&self) -> usize {
        self.inner.dim()
    }
    fn rhs(&mut self, t: f64, x: &[f64], dxdt: &mut [f64]) {
        self.counts.rhs_evals.set(self.counts.rhs_evals.get() + 1);
        self.inner.rhs(t, x, dxdt);
    }
    fn jacobian(&mut self, t: f64, x: &[f64], jac: &mut [f64]) -> bool {
        let provided = self.inner.jacobian(t, x, jac);
        if provided {
            // Not provided, the integrator forms it from rhs calls, which count as such.
            self.counts
                .jacobian_evals
                .set(self.counts.jacobian_evals.get() + 1);
        }
        provided
    }
    fn step_counted(&mut self, accepted: bool) {
        let c = if accepted {
            &self.counts.steps
        } else {
            &self.counts.rejected_steps
        };
        c.set(c.get() + 1);
    }
    fn is_autonomous(&self) -> bool {
        self.inner.is_autonomous()
    }
    fn jacobian_is_constant(&self) -> bool {
        self.inner.jacobian_is_constant()
    }
    fn projects(&self) -> bool {
        self.keeper.is_some()
    }
    fn project(&mut self, t: f64, x: &mut [f64], tol: &Tolerances) -> bool {
        match &mut self.keeper {
            Some(k) => k.project(self.inner.model, t, x, tol),
            None => false,
        }
    }
}

/// Keeps a model's Jacobi integral h = T₂ − T₀ + V at its starting value: after an accepted
/// step, one Newton step along the integral's gradient in the metric of the step's error
/// control, x ← x − λ·W∇h with W = diag(sk²), sk = atol + rtol·|x| and λ = (h(x) − h₀)/(∇hᵀW∇h):
/// the least move, as the error control measures moves, that puts x back on the level set
/// (to second order in a drift of the size of a few local errors). The exact solution keeps h,
/// so this removes the component of the integrators' error that grows fastest: a drift of h is
/// a drift of the period, and its phase error grows as the square of time. Hairer, Lubich &
/// Wanner, *Geometric Numerical Integration*, IV.4 (standard projection).
pub struct JacobiKeeper {
    h0: f64,
    grad: Vec<f64>,
}

impl JacobiKeeper {
    /// The integral at (t0, x0); an error when the model does not keep it.
    pub fn new(
        model: &gyro_model::CompiledModel<ShipProgram>,
        t0: f64,
        x0: &[f64],
    ) -> Result<JacobiKeeper, SolveError> {
        if let Some(why) = model.jacobi_integral_broken_by() {
            return Err(SolveError::InvalidOptions(format!(
                "Jacobi's integral is not a first integral of this model ({why})"
            )));
        }
        let mut grad = vec![0.0; x0.len()];
        let h0 = model.jacobi_integral(t0, x0, &mut grad).ok_or_else(|| {
            SolveError::InvalidOptions("Jacobi's integral is not finite at the start".into())
        })?;
        Ok(JacobiKeeper { h0, grad })
    }

    /// Projects `x` onto h = h₀ (see the type); whether it moved it.
    pub fn project(
        &mut self,
        model: &gyro_model::CompiledModel<ShipProgram>,
        t: f64,
        x: &mut [f64],
        tol: &Tolerances,
    ) -> bool {
        match model.jacobi_integral(t, x, &mut self.grad) {
            Some(h) => solvers::project_onto_level(x, &self.grad, h, self.h0, tol),
            None => false,
        }
    }
}

/// [`ModelSystem`] with its Jacobi integral kept ([`JacobiKeeper`]): what a scene with
/// `keep_jacobi_integral` runs, for callers of [`solvers::integrate`] that drive the model
/// themselves (the accuracy study, the peer benchmark).
pub struct KeptModelSystem<'a> {
    pub inner: ModelSystem<'a>,
    keeper: JacobiKeeper,
}

impl<'a> KeptModelSystem<'a> {
    /// The integral taken at (t0, x0); an error when the model does not keep it.
    pub fn new(
        model: &'a CompiledModel<ShipProgram>,
        t0: f64,
        x0: &[f64],
    ) -> Result<Self, SolveError> {
        Ok(KeptModelSystem {
            inner: ModelSystem { model },
            keeper: JacobiKeeper::new(model, t0, x0)?,
        })
    }
}

impl OdeSystem for KeptModelSystem<'_> {
    fn dim(&self) -> usize {
        self.inner.dim()
    }
    fn rhs(&mut self, t: f64, x: &[f64], dxdt: &mut [f64]) {
        self.inner.rhs(t, x, dxdt);
    }
    fn jacobian(&mut self, t: f64, x: &[f64], jac: &mut [f64]) -> bool {
        self.inner.jacobian(t, x, jac)
    }
    fn is_autonomous(&self) -> bool {
        self.inner.is_autonomous()
    }
    fn jacobian_is_constant(&self) -> bool {
        self.inner.jacobian_is_constant()
    }
    fn projects(&self) -> bool {
        true
    }
    fn project(&mut self, t: f64, x: &mut [f64], tol: &Tolerances) -> bool {
        self.keeper.project(self.inner.model, t, x, tol)
    }
}

impl Simulation {
    pub fn new(scene: &Scene) -> Result<Simulation, RunError> {
        let model = CompiledModel::compile(
            scene.design.clone(),
            scene.program.clone(),
            scene.model_options(),
        )
        .map_err(RunError::Model)?;
        let grid = OutputGrid {
            t0: 0.0,
            dt: 1.0 / scene.output_rate_hz,
            t_end: scene.duration_s,
        };
        let breakpoints = scene.program.breakpoints();
        if scene.keep_jacobi_integral
            && let Some(why) = model.jacobi_integral_broken_by()
        {
            return Err(RunError::Model(ModelError::Invalid(format!(
                "`simulation.keep_jacobi_integral`: Jacobi's integral is not a first integral of \
                 this model, because of {why} (allowed for a `full` model at rest, without servo, \
                 damper, applied force or liquid)"
            ))));
        }
        Ok(Simulation {
            model,
            grid,
            breakpoints,
            keep_jacobi_integral: scene.keep_jacobi_integral,
        })
    }

    /// Runs the scene, calling `observer(t, x)` at every output time.
    pub fn run(
        &self,
        method: solvers::Method,
        tol: &solvers::Tolerances,
        mut observer: impl FnMut(f64, &[f64]) -> ControlFlow<()>,
    ) -> Result<RunStats, RunError> {
        self.run_with_progress(method, tol, |t, x, _| observer(t, x))
    }

    /// Runs the scene, calling `observer(t, x, probe)` at every output time; `probe.progress()`
    /// tells the solver's work so far (for progress reports during a run).
    pub fn run_with_progress(
        &self,
        method: solvers::Method,
        tol: &solvers::Tolerances,
        mut observer: impl FnMut(f64, &[f64], &RunProbe) -> ControlFlow<()>,
    ) -> Result<RunStats, RunError> {
        let mut x = self.model.x0.clone();
        let mut samples = 0u64;
        let counts = Counts::default();
        let mut probe: Option<RunProbe> = None;
        let mut observe = |t: f64, x: &[f64]| {
            let probe = probe.get_or_insert_with(|| RunProbe {
                counts: &counts,
                started: Instant::now(),
            });
            observer(t, x, probe)
        };
        if self.model.fidelity == Fidelity::Linear && self.model.is_autonomous() {
            return Ok(self.run_linear_exact(&mut x, observe));
        }
        let keeper = if self.keep_jacobi_integral {
            Some(JacobiKeeper::new(&self.model, self.grid.t0, &x).map_err(RunError::Solve)?)
        } else {
            None
        };
        let mut sys = CountingSystem {
            inner: ModelSystem { model: &self.model },
            counts: &counts,
            keeper,
        };
        let (stop, solver) = solvers::integrate(
            &mut sys,
            method,
            tol,
            &mut x,
            &self.grid,
            &self.breakpoints,
            |t, x| {
                samples += 1;
                observe(t, x)
            },
        )
        .map_err(RunError::Solve)?;
        Ok(RunStats {
            solver,
            stop,
            samples,
        })
    }

    /// Runs the scene, reporting to `observer`: at every output time first the manoeuvre events
    /// reached by then, then the sample; at the end, [`RunObserver::finish`].
    pub fn observe(
        &self,
        method: solvers::Method,
        tol: &solvers::Tolerances,
        observer: &mut impl RunObserver,
    ) -> Result<RunStats, RunError> {
        let events = self.manoeuvre_events();
        let mut next_event = 0;
        let stats = self.run_with_progress(method, tol, |t, x, probe| {
            while let Some(event) = events.get(next_event)
                && event.time_s <= t + 1e-9
            {
                if observer.event(event).is_break() {
                    return ControlFlow::Break(());
                }
                next_event += 1;
            }
            observer.sample(t, x, probe)
        })?;
        observer.finish(&stats);
        Ok(stats)
    }

    /// The start and end of every manoeuvre (steady segments have none) inside the run, in
    /// program order.
    pub fn manoeuvre_events(&self) -> Vec<ManoeuvreEvent<'_>> {
        let mut events = Vec::new();
        for (i, segment) in self.model.motion.segments.iter().enumerate() {
            if segment.manoeuvre == gyro_mcap::contract::events::STEADY {
                continue;
            }
            let (_, speed_after_m_per_s, heading_after_rad) = ShipProgram::end_state(segment);
            let end_s = segment.start_s + segment.duration_s;
            for (is_start, time_s) in [(true, segment.start_s), (false, end_s)] {
                if time_s > self.grid.t_end {
                    continue;
                }
                events.push(ManoeuvreEvent {
                    time_s,
                    is_start,
                    segment_index: i,
                    segment,
                    speed_after_m_per_s,
                    heading_after_rad,
                });
            }
        }
        events
    }

    /// `linear` fidelity of an autonomous scene: x(t) = x_eq + exp(A t)(x0 − x_eq), propagated
    /// exactly from sample to sample with one matrix exponential.
    fn run_linear_exact(
        &self,
        x: &mut [f64],
        mut observer: impl FnMut(f64, &[f64]) -> ControlFlow<()>,
    ) -> RunStats {
        let start = Instant::now();
        let n = x.len();
        let a = self.model.linear_matrix();
        let xe = &self.model.x_equilibrium;
        let e = gyro_model::linalg::expm(a, n, self.grid.dt);
        let mut dev: Vec<f64> = x.iter().zip(xe).map(|(a, b)| a - b).collect();
        let mut tmp = vec![0.0; n];
        let mut samples = 0;
        let mut k = 0u64;
        let mut stop = StopReason::Finished;
        loop {
            let t = self.grid.t0 + k as f64 * self.grid.dt;
            if t > self.grid.t_end * (1.0 + 1e-12) {
                break;
            }
            for i in 0..n {
                x[i] = xe[i] + dev[i];
            }
            samples += 1;
            if observer(t, x).is_break() {
                stop = StopReason::Interrupted { t };
                break;
            }
            for i in 0..n {
                tmp[i] = (0..n).map(|j| e[i * n + j] * dev[j]).sum();
            }
            std::mem::swap(&mut dev, &mut tmp);
            k += 1;
        }
        let solver = SolverStats {
            wall_time_s: start.elapsed().as_secs_f64(),
            ..Default::default()
        };
        RunStats {
            solver,
            stop,
            samples,
        }
    }

    /// Measured cost of one right-hand side at the initial state, ns (median of 5 batches).
    pub fn rhs_cost_ns(&self) -> f64 {
        let x = self.model.x0.clone();
        let mut dx = vec![0.0; x.len()];
        let mut times = Vec::new();
        for _ in 0..5 {
            let n = 400;
            let t0 = Instant::now();
            for i in 0..n {
                self.model.rhs(i as f64 * 1e-3, &x, &mut dx);
            }
            times.push(t0.elapsed().as_secs_f64() * 1e9 / n as f64);
            std::hint::black_box(&dx);
        }
        times.sort_by(f64::total_cmp);
        times[2]
    }

    /// Breakpoints of the program (manoeuvre starts and ends) inside the run.
    pub fn breakpoints(&self) -> &[f64] {
        &self.breakpoints
    }

    pub fn motion(&self) -> &ShipProgram {
        &self.model.motion
    }

    /// Latitude of the ship at time t.
    pub fn latitude_rad(&self, t: f64) -> f64 {
        self.model.motion.kinematics(t).latitude_rad
    }
}
