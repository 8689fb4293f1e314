//! Running a case: each configuration timed (best of a few repetitions), held to a time budget,
//! and its error measured against the case's exact answer.

use super::StudyOptions;
use super::cases::{Case, Kind};
use super::problems::spectral_radius;
use super::report::{CaseReport, Point, fmt_time, verdict};
use crate::run::ModelSystem;
use crate::solvers::{self, Method, OdeSystem, OutputGrid, SolverStats, Tolerances};
use gyro_model::Fidelity;
use std::ops::ControlFlow;
use std::time::Instant;

/// RK4's step for a tolerance on a problem with characteristic time `t_char`: a fourth-order
/// method's error per unit time scales as (h/t_char)⁴, so h = t_char · (tol/10)^¼ / 4 puts its
/// points on the same error scale as the adaptive methods' tolerances.
pub(super) fn rk4_step(t_char: f64, tol: f64) -> f64 {
    0.25 * t_char * (0.1 * tol).powf(0.25)
}

/// Best wall time over repetitions of `f`, with the result of the first run.
pub(super) fn timed<T>(opts: &StudyOptions, mut f: impl FnMut() -> T) -> (T, f64) {
    let t0 = Instant::now();
    let first = f();
    let mut best = t0.elapsed().as_secs_f64();
    let mut spent = best;
    let mut reps = 1;
    while spent < opts.min_timing_s && reps < opts.max_repeats {
        let t = Instant::now();
        std::hint::black_box(f());
        let dt = t.elapsed().as_secs_f64();
        best = best.min(dt);
        spent += dt;
        reps += 1;
    }
    (first, best)
}

type RunResult = Result<(f64, SolverStats), String>;

/// The error text of a run stopped by its time budget.
const OVER_BUDGET: &str = "over the time budget";

/// An `OdeSystem` that turns non-finite after a deadline, so that a hopeless run stops (the
/// integrator reports a non-finite state or a step-size underflow; [`Budget::result`] tells).
pub(super) struct Budget<S> {
    inner: S,
    deadline: Instant,
    calls: u32,
    over: bool,
}

impl<S: OdeSystem> Budget<S> {
    pub(super) fn new(inner: S, seconds: f64) -> Self {
        Budget {
            inner,
            deadline: Instant::now() + std::time::Duration::from_secs_f64(seconds),
            calls: 0,
            over: false,
        }
    }
    pub(super) fn result<T>(&self, r: Result<T, solvers::SolveError>) -> Result<T, String> {
        match r {
            Ok(v) => Ok(v),
            Err(_) if self.over => Err(OVER_BUDGET.into()),
            Err(e) => Err(e.to_string()),
        }
    }
}

impl<S: OdeSystem> OdeSystem for Budget<S> {
    fn dim(&self) -> usize {
        self.inner.dim()
    }
    fn rhs(&mut self, t: f64, x: &[f64], dx: &mut [f64]) {
        self.calls = self.calls.wrapping_add(1);
        if self.calls.is_multiple_of(512) && Instant::now() > self.deadline {
            self.over = true;
        }
        if self.over {
            dx.fill(f64::NAN);
        } else {
            self.inner.rhs(t, x, dx);
        }
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
        self.inner.projects()
    }
    fn project(&mut self, t: f64, x: &mut [f64], tol: &Tolerances) -> bool {
        self.inner.project(t, x, tol)
    }
}

/// Where a point of the study is taken: fidelity (index and name), method, tolerance, and the
/// case's spectral radius and RHS cost at that fidelity.
struct Setting {
    fi: usize,
    fidelity: Fidelity,
    method: Method,
    rtol: f64,
    rho: f64,
    rhs_cost: f64,
}

/// A method's progress along the tolerances of one case and fidelity: time spent, and why its
/// remaining points are skipped once they are.
#[derive(Default)]
struct Track {
    stopped: Option<String>,
    spent: f64,
}

impl Case {
    fn tolerances(&self, rtol: f64) -> Tolerances {
        Tolerances {
            rtol,
            atol: rtol * self.atol_factor,
            ..Default::default()
        }
    }

    /// One run: achieved error and work.
    fn solve(&self, fidelity_index: usize, method: Method, rtol: f64, budget_s: f64) -> RunResult {
        let tol = self.tolerances(rtol);
        match &self.kind {
            Kind::Periodic {
                sim,
                x0,
                omega0,
                amplitude,
                t_end,
            } => {
                let mut last = x0.clone();
                let mut s = Budget::new(ModelSystem { model: &sim.model }, budget_s);
                let mut x = x0.clone();
                let grid = OutputGrid {
                    t0: 0.0,
                    dt: *t_end,
                    t_end: *t_end,
                };
                let r = solvers::integrate(&mut s, method, &tol, &mut x, &grid, &[], |_, xs| {
                    last.copy_from_slice(xs);
                    ControlFlow::Continue(())
                });
                let (_, stats) = s.result(r)?;
                let dg = last[0] - x0[0];
                let dr = (last[1] - x0[1]) / omega0;
                Ok((dg.hypot(dr) / amplitude, stats))
            }
            Kind::FirstIntegral {
                sim,
                v,
                centre_offset,
                dt,
                t_end,
            } => {
                let mut s = Budget::new(ModelSystem { model: &sim.model }, budget_s);
                let mut x = sim.model.x0.clone();
                let i0 = v.first_integral(x[0] - centre_offset, x[1]);
                let mut worst: f64 = 0.0;
                let grid = OutputGrid {
                    t0: 0.0,
                    dt: *dt,
                    t_end: *t_end,
                };
                let r = solvers::integrate(&mut s, method, &tol, &mut x, &grid, &[], |_, xs| {
                    worst = worst.max((v.first_integral(xs[0] - centre_offset, xs[1]) - i0).abs());
                    ControlFlow::Continue(())
                });
                let (_, stats) = s.result(r)?;
                Ok((worst / (2.0 * v.g_over_a.abs()), stats))
            }
            Kind::Linear {
                sys,
                x0,
                exact,
                grid,
                compare,
                scale,
                atol_factor,
            } => {
                let tol = Tolerances {
                    atol: rtol * atol_factor,
                    ..tol
                };
                let mut s = Budget::new(sys.clone(), budget_s);
                let mut x = x0.clone();
                let mut k = 0;
                let mut worst: f64 = 0.0;
                let r = solvers::integrate(&mut s, method, &tol, &mut x, grid, &[], |_, xs| {
                    if let Some(e) = exact.get(k) {
                        for &i in compare {
                            worst = worst.max((xs[i] - e[i]).abs());
                        }
                    }
                    k += 1;
                    ControlFlow::Continue(())
                });
                let (_, stats) = s.result(r)?;
                Ok((worst / scale, stats))
            }
            Kind::Reference {
                sims,
                reference,
                scale,
                ..
            } => {
                let sim = &sims[fidelity_index].1;
                let mut k = 0;
                let mut worst: f64 = 0.0;
                let mut observe = |t: f64, x: &[f64]| {
                    if let Some(r) = reference.get(k) {
                        worst = worst.max((sim.model.readout(t, x).reading_error_rad - r).abs());
                    }
                    k += 1;
                    ControlFlow::Continue(())
                };
                let stats = if sim.model.fidelity == Fidelity::Linear {
                    sim.run(method, &tol, observe)
                        .map_err(|e| e.to_string())?
                        .solver
                } else {
                    let mut s = Budget::new(ModelSystem { model: &sim.model }, budget_s);
                    let mut x = sim.model.x0.clone();
                    let r = solvers::integrate(
                        &mut s,
                        method,
                        &tol,
                        &mut x,
                        &sim.grid,
                        &sim.breakpoints,
                        &mut observe,
                    );
                    s.result(r)?.1
                };
                Ok((worst / scale, stats))
            }
        }
    }

    fn fidelities(&self) -> Vec<Fidelity> {
        match &self.kind {
            Kind::Reference { sims, .. } => sims.iter().map(|s| s.0).collect(),
            Kind::Linear { .. } => vec![Fidelity::Linear],
            _ => vec![Fidelity::Full],
        }
    }

    pub(super) fn study(&self, opts: &StudyOptions) -> CaseReport {
        let mut points = Vec::new();
        for (fi, fidelity) in self.fidelities().into_iter().enumerate() {
            let exact_linear =
                matches!(self.kind, Kind::Reference { .. }) && fidelity == Fidelity::Linear;
            if exact_linear {
                // Propagated exactly: one point, whatever the method and tolerance.
                let ((res, stats), wall) = timed(opts, || {
                    self.solve(fi, Method::Rodas4, 1e-8, f64::INFINITY)
                        .map(|(e, s)| (Some(e), s))
                        .unwrap_or((None, SolverStats::default()))
                });
                let _ = stats;
                points.push(Point {
                    method: "expm".into(),
                    fidelity: fidelity.to_string(),
                    rtol: 0.0,
                    step_s: None,
                    error: res,
                    wall_s: wall,
                    rhs_evals: 0,
                    jacobian_evals: 0,
                    lu_decompositions: 0,
                    steps: 0,
                    rejected_steps: 0,
                    note: Some("exact propagation by one matrix exponential".into()),
                });
                continue;
            }
            let rho = self.spectral_radius(fi);
            let rhs_cost = self.rhs_cost_s(fi);
            // Tolerance-major: every method's point at one tolerance, then the next tolerance,
            // reported method by method. The host runs slow or fast for seconds at a time:
            // measured a method at a time, one method's whole curve could fall in a slow
            // stretch and lose a verdict it wins in the next run (docs/accuracy.md).
            let mut tracks: Vec<Track> = opts.methods.iter().map(|_| Track::default()).collect();
            let mut curves: Vec<Vec<Point>> = opts.methods.iter().map(|_| Vec::new()).collect();
            for &rtol in &opts.tolerances {
                for ((&m, track), curve) in opts.methods.iter().zip(&mut tracks).zip(&mut curves) {
                    let at = Setting {
                        fi,
                        fidelity,
                        method: m,
                        rtol,
                        rho,
                        rhs_cost,
                    };
                    curve.push(self.point(opts, &at, track));
                }
            }
            points.extend(curves.into_iter().flatten());
        }
        let mut report = CaseReport {
            name: self.name.clone(),
            description: self.description.clone(),
            reference: self.reference.clone(),
            error_measure: self.error_measure.clone(),
            reference_wall_s: match &self.kind {
                Kind::Reference {
                    reference_wall_s, ..
                } => Some(*reference_wall_s),
                _ => None,
            },
            points,
            verdict: String::new(),
        };
        report.verdict = verdict(&report, opts.target_error);
        report
    }

    /// One point: `at`'s method at `at`'s tolerance, unless `track` says its method has stopped
    /// on this case (over its budget, or RK4 at its stability limit).
    fn point(&self, opts: &StudyOptions, at: &Setting, track: &mut Track) -> Point {
        if track.stopped.is_none() && track.spent > opts.max_method_s {
            track.stopped = Some(format!(
                "skipped: {} already spent on this case (budget {})",
                fmt_time(track.spent),
                fmt_time(opts.max_method_s)
            ));
        }
        let (fi, rtol) = (at.fi, at.rtol);
        let method = match at.method {
            Method::Rk4 { .. } => Method::Rk4 {
                step_s: rk4_step(self.t_char, rtol).min(if at.rho > 0.0 {
                    2.5 / at.rho
                } else {
                    f64::INFINITY
                }),
            },
            other => other,
        };
        let mut p = Point {
            method: method.to_string(),
            fidelity: at.fidelity.to_string(),
            rtol,
            step_s: match method {
                Method::Rk4 { step_s } => Some(step_s),
                _ => None,
            },
            error: None,
            wall_s: 0.0,
            rhs_evals: 0,
            jacobian_evals: 0,
            lu_decompositions: 0,
            steps: 0,
            rejected_steps: 0,
            note: None,
        };
        if let Some(why) = &track.stopped {
            p.note = Some(why.clone());
            return p;
        }
        // Explicit methods: the stiffest mode bounds the step whatever the tolerance.
        let predicted = match method {
            Method::Rk4 { step_s } => 4.0 * self.t_end / step_s,
            Method::Dopri5 => 6.0 * self.t_end * at.rho / 3.3,
            Method::Dop853 => 12.0 * self.t_end * at.rho / 6.0,
            // Verner's 9(8): |R(−x)| ≤ 1 up to x ≈ 4.48 (its stability
            // polynomial from the tableau).
            Method::Vern9 => 16.0 * self.t_end * at.rho / 4.48,
            Method::Rodas4 | Method::Rodas5p | Method::Radau5 => 0.0,
        };
        if predicted * at.rhs_cost > opts.max_point_s {
            let why = format!(
                "skipped: stability- or step-bound, ≈ {predicted:.1e} RHS ≈ {} predicted",
                fmt_time(predicted * at.rhs_cost)
            );
            p.note = Some(why.clone());
            track.stopped = Some(why);
            return p;
        }
        let deadline = 3.0 * opts.max_point_s;
        let started = Instant::now();
        let (res, wall) = timed(opts, || self.solve(fi, method, rtol, deadline));
        track.spent += started.elapsed().as_secs_f64();
        p.wall_s = wall;
        match res {
            Ok((err, stats)) => {
                p.error = Some(err);
                p.rhs_evals = stats.rhs_evals;
                p.jacobian_evals = stats.jacobian_evals;
                p.lu_decompositions = stats.lu_decompositions;
                p.steps = stats.steps;
                p.rejected_steps = stats.rejected_steps;
            }
            Err(e) if e == OVER_BUDGET => {
                let why = format!(
                    "stopped: over the time budget of {} (tighter tolerances skipped)",
                    fmt_time(deadline)
                );
                p.note = Some(why.clone());
                track.stopped = Some("skipped: a looser tolerance was over the time budget".into());
            }
            Err(e) => p.note = Some(format!("failed: {e}")),
        }
        // At its stability limit RK4's step no longer follows the tolerance: the
        // remaining points would repeat this one.
        if let Method::Rk4 { step_s } = method
            && step_s < rk4_step(self.t_char, rtol)
        {
            track.stopped = Some(format!(
                "skipped: RK4 at its stability limit h = {step_s:.2e} s (same as above)"
            ));
        }
        p
    }

    /// Spectral radius of the Jacobian at the start (fidelity `fi`).
    fn spectral_radius(&self, fi: usize) -> f64 {
        let model = match &self.kind {
            Kind::Linear { .. } => return self.rho,
            Kind::Periodic { sim, .. } | Kind::FirstIntegral { sim, .. } => &sim.model,
            Kind::Reference { sims, .. } => &sims[fi].1.model,
        };
        let n = model.dim();
        let mut j = vec![0.0; n * n];
        model.jacobian(0.0, &model.x0, &mut j);
        spectral_radius(&j, n)
    }

    /// Cost of one RHS at the start, s.
    fn rhs_cost_s(&self, fi: usize) -> f64 {
        let reps = 2000;
        let t0 = Instant::now();
        match &self.kind {
            Kind::Linear { sys, x0, .. } => {
                let mut s = sys.clone();
                let mut dx = vec![0.0; x0.len()];
                for _ in 0..reps {
                    s.rhs(0.0, std::hint::black_box(x0), &mut dx);
                }
                std::hint::black_box(&dx);
            }
            Kind::Periodic { sim, .. } | Kind::FirstIntegral { sim, .. } => {
                engine_rhs_loop(&sim.model, reps)
            }
            Kind::Reference { sims, .. } => engine_rhs_loop(&sims[fi].1.model, reps),
        }
        t0.elapsed().as_secs_f64() / reps as f64
    }
}

fn engine_rhs_loop(model: &gyro_model::CompiledModel<crate::program::ShipProgram>, reps: usize) {
    let mut dx = vec![0.0; model.dim()];
    for _ in 0..reps {
        model.rhs(0.0, std::hint::black_box(&model.x0), &mut dx);
    }
    std::hint::black_box(&dx);
}
