//! The Rosenbrock stepper both stiff one-step methods share (RODAS4, `rodas4`; Rodas5P,
//! `rodas5p`): Hairer–Wanner's RODAS formulation (Solving ODE II, §VI.4), a method being only
//! its coefficient [`Tableau`].
//!
//! Per step: f(t, x); the Jacobian df/dx — the system's exact one when it provides it, else
//! central differences (2n rhs calls, increment cbrt(eps)·max(|x_j|, 1e-2)); df/dt by a
//! forward difference in t (1 rhs call; none when the system says it is autonomous, as a model
//! on a stationary base does: the difference is then exactly zero); J once per run instead
//! when the system says it is constant (a `linear` model); one LU of (1/(γh)) I − J
//! (partial pivoting, `linalg`; a model's kinematic rows q̇ = v eliminated first, so an 8-state
//! `full` model factors a 4-square matrix), and from its factors the explicit inverse, so
//! that each stage's solve is one product (`IterationMatrix::with_inverse`: the s solves that
//! follow a factorisation are then sums, not chains of substitutions); s − 1 further rhs
//! calls for s stages. Stage i
//! solves (1/(γh) I − J) kᵢ = f(x + Σ aᵢⱼkⱼ) + Σ (cᵢⱼ/h) kⱼ + h dᵢ ∂f/∂t. Both methods are
//! stiffly accurate: their last stages start from the previous stage's point plus its
//! increment, and the last increment is the error estimate (the difference between the
//! method and its embedded solution). The Jacobian is reused when a step is retried at a
//! smaller h. Step control is Gustafsson's predictive controller as in RODAS, with exponent
//! 1/q for an error estimate of local order q. Dense output is the method's continuous
//! extension, x(θ) = (1 − θ) x₀ + θ (x₁ + (1 − θ) (D₁ + θ D₂ + θ² D₃ …)), the Dᵣ sums of the
//! stage increments. A singular matrix halves the step; five in a row is an error.

use super::linalg::IterationMatrix;
use super::{
    Attempt, InitialStepScratch, OdeSystem, SolveError, SolverStats, Stepper, Tolerances, Window,
    difference_jacobian, error_norm, initial_step, start_derivative,
};

/// Most stages of a shipped tableau.
pub(crate) const MAX_STAGES: usize = 8;
/// Most coefficient vectors of a shipped continuous extension.
pub(crate) const MAX_DENSE: usize = 3;

/// A zero coefficient row.
pub(crate) const Z: [f64; MAX_STAGES] = [0.0; MAX_STAGES];

/// A coefficient row, padded with zeros.
pub(crate) const fn row(v: &[f64]) -> [f64; MAX_STAGES] {
    let mut r = Z;
    let mut i = 0;
    while i < v.len() {
        r[i] = v[i];
        i += 1;
    }
    r
}

/// A Rosenbrock method in RODAS form. Rows and columns past `stages` are zero.
pub(crate) struct Tableau {
    pub stages: usize,
    /// Stages from this one on start from the previous stage's point plus its increment
    /// (aᵢⱼ = aᵢ₋₁,ⱼ, aᵢ,ᵢ₋₁ = 1: the stiffly accurate tail); the new state is the last
    /// stage's point plus the last increment, which is also the error estimate.
    pub tail: usize,
    pub gamma: f64,
    /// aᵢⱼ (j < i) of the stage points, for the stages before `tail`.
    pub a: [[f64; MAX_STAGES]; MAX_STAGES],
    /// cᵢⱼ (j < i), the stage increments' coupling, divided by h in the step.
    pub c: [[f64; MAX_STAGES]; MAX_STAGES],
    /// αᵢ: stage i is evaluated at t + αᵢ h (1 for the tail).
    pub alpha: [f64; MAX_STAGES],
    /// γᵢ = Σⱼ γᵢⱼ: the ∂f/∂t weight h γᵢ of stage i (0 for the tail).
    pub d: [f64; MAX_STAGES],
    /// Dense output: Dᵣ = Σⱼ dense[r][j] kⱼ over the first `dense_stages` increments.
    pub dense: [[f64; MAX_STAGES]; MAX_DENSE],
    pub dense_rows: usize,
    pub dense_stages: usize,
    /// Order of the method, for the initial step; the step controller's exponent is 1/order
    /// (the error estimate is the embedded solution's local error, of order `order`).
    pub order: i32,
}

/// A Rosenbrock method: its tableau, a compile-time constant so the stage loops see the
/// coefficients as constants.
pub(crate) trait Method {
    const TABLEAU: Tableau;
}

/// Step-ratio limits and safety factor of RODAS.
const FAC_MIN: f64 = 0.2;
const FAC_MAX: f64 = 6.0;
const SAFE: f64 = 0.9;
/// Consecutive singular iteration matrices tolerated before giving up.
const MAX_SINGULAR: u32 = 5;

pub(crate) struct Rosenbrock<M: Method> {
    n: usize,
    /// f(t, x) at the current point; valid while `f0_current`.
    f0: Vec<f64>,
    f0_current: bool,
    /// df/dt at the current point.
    fx: Vec<f64>,
    /// df/dx, row-major; valid for the current point while `jac_current`.
    jac: Vec<f64>,
    jac_current: bool,
    /// J is the system's constant one (`OdeSystem::jacobian_is_constant`) and already formed:
    /// it, and its kinematic rows, are not formed again.
    jac_kept: bool,
    /// Kinematic rows of J (`IterationMatrix::kinematic_rows`), found when J is formed.
    kinematic: usize,
    /// (1/(γh)) I − J, factored.
    matrix: IterationMatrix,
    /// The stage increments kᵢ (only the first `stages` are allocated).
    ak: [Vec<f64>; MAX_STAGES],
    dy: Vec<f64>,
    x_stage: Vec<f64>,
    x_new: Vec<f64>,
    /// The continuous extension's Dᵣ of the last accepted step.
    dense: [Vec<f64>; MAX_DENSE],
    singular_in_row: u32,
    /// Gustafsson controller memory: last accepted h and error; `None` after a reset.
    previous: Option<(f64, f64)>,
    last_rejected: bool,
    scratch: InitialStepScratch,
    method: std::marker::PhantomData<M>,
}

impl<M: Method> Rosenbrock<M> {
    const T: Tableau = M::TABLEAU;

    pub(crate) fn new(n: usize) -> Self {
        Rosenbrock {
            n,
            f0: vec![0.0; n],
            f0_current: false,
            fx: vec![0.0; n],
            jac: vec![0.0; n * n],
            jac_current: false,
            jac_kept: false,
            kinematic: 0,
            matrix: IterationMatrix::with_inverse(n),
            ak: std::array::from_fn(|s| vec![0.0; if s < Self::T.stages { n } else { 0 }]),
            dy: vec![0.0; n],
            x_stage: vec![0.0; n],
            x_new: vec![0.0; n],
            dense: std::array::from_fn(|r| vec![0.0; if r < Self::T.dense_rows { n } else { 0 }]),
            singular_in_row: 0,
            previous: None,
            last_rejected: false,
            scratch: InitialStepScratch::new(n),
            method: std::marker::PhantomData,
        }
    }

    /// J and df/dt at the current point (f0 must be current). Uses ak[0] as scratch.
    fn linearise<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        w: Window,
        t: f64,
        x: &[f64],
        stats: &mut SolverStats,
    ) {
        let n = self.n;
        let te = w.at(t);
        if !self.jac_kept {
            stats.jacobian_evals += 1;
            if !sys.jacobian(te, x, &mut self.jac) {
                let [scratch, ..] = &mut self.ak;
                difference_jacobian(
                    sys,
                    te,
                    x,
                    &mut self.jac,
                    &mut self.x_stage,
                    &mut self.dy,
                    scratch,
                    stats,
                );
            }
            self.kinematic = IterationMatrix::kinematic_rows(&self.jac, n);
            self.jac_kept = sys.jacobian_is_constant();
        }
        // df/dt by a forward difference, kept inside the segment; exactly zero, and not
        // computed, when f does not depend on t (the difference would be 0 to the bit).
        let delta = (f64::EPSILON * t.abs().max(1e-5)).sqrt();
        let t_plus = w.at(t + delta);
        let delta = t_plus - te;
        if delta > 0.0 && !sys.is_autonomous() {
            sys.rhs(t_plus, x, &mut self.dy);
            stats.rhs_evals += 1;
            for i in 0..n {
                self.fx[i] = (self.dy[i] - self.f0[i]) / delta;
            }
        } else {
            self.fx.fill(0.0);
        }
        self.jac_current = true;
    }

    /// Right-hand side `dy + hd * fx + sum_j hc_j ak_j` of stage `s`, solved in place into
    /// ak[s]. Summed one stage after another over all components (each component's sum in
    /// the same order as component by component, so the same result to the bit, but as
    /// loops the compiler vectorises).
    fn solve_stage(&mut self, s: usize, hc: &[f64], hd: f64) {
        let (done, rest) = self.ak.split_at_mut(s);
        let out = &mut rest[0];
        for ((o, &d), &f) in out.iter_mut().zip(&self.dy).zip(&self.fx) {
            *o = d + hd * f;
        }
        for (&c, a) in hc.iter().zip(done.iter()) {
            for (o, &v) in out.iter_mut().zip(a) {
                *o += c * v;
            }
        }
        self.matrix.solve(out);
    }

    /// x_stage = x + sum_j a_j ak_j (stage by stage, as in `solve_stage`).
    fn stage_point(&mut self, x: &[f64], a: &[f64]) {
        self.x_stage.copy_from_slice(x);
        for (&aj, k) in a.iter().zip(&self.ak) {
            for (o, &v) in self.x_stage.iter_mut().zip(k) {
                *o += aj * v;
            }
        }
    }
}

impl<M: Method> Stepper for Rosenbrock<M> {
    const STRETCH: f64 = 1.0001;

    fn reset<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        w: Window,
        t: f64,
        x: &[f64],
        stats: &mut SolverStats,
    ) -> Result<(), SolveError> {
        self.f0_current = true;
        self.jac_current = false;
        self.previous = None;
        self.last_rejected = false;
        self.singular_in_row = 0;
        start_derivative(sys, w, t, x, &mut self.f0, stats)
    }

    fn first_step<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        w: Window,
        t: f64,
        x: &[f64],
        tol: &Tolerances,
        h_max: f64,
        stats: &mut SolverStats,
    ) -> f64 {
        initial_step(
            sys,
            w,
            t,
            x,
            &self.f0,
            Self::T.order,
            tol,
            h_max,
            &mut self.scratch,
            stats,
        )
    }

    fn attempt<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        w: Window,
        t: f64,
        x: &[f64],
        h: f64,
        tol: &Tolerances,
        stats: &mut SolverStats,
    ) -> Result<Attempt, SolveError> {
        let n = self.n;
        let tab = Self::T;
        let s = tab.stages;
        if !self.f0_current {
            sys.rhs(w.at(t), x, &mut self.f0);
            stats.rhs_evals += 1;
            self.f0_current = true;
        }
        if !self.jac_current {
            self.linearise(sys, w, t, x, stats);
        }
        stats.lu_decompositions += 1;
        if !self
            .matrix
            .factor(&self.jac, self.kinematic, 1.0 / (h * tab.gamma))
        {
            self.singular_in_row += 1;
            if self.singular_in_row >= MAX_SINGULAR {
                return Err(SolveError::SingularMatrix { t });
            }
            self.last_rejected = true;
            return Ok(Attempt {
                accepted: false,
                h_next: 0.5 * h,
            });
        }
        self.singular_in_row = 0;

        let mut hc = [0.0; MAX_STAGES];
        // Stage 1.
        self.dy.copy_from_slice(&self.f0);
        self.solve_stage(0, &[], h * tab.d[0]);
        for i in 1..s {
            if i < tab.tail {
                self.stage_point(x, &tab.a[i][..i]);
            } else {
                for (o, &v) in self.x_stage.iter_mut().zip(&self.ak[i - 1]) {
                    *o += v;
                }
            }
            sys.rhs(w.at(t + tab.alpha[i] * h), &self.x_stage, &mut self.dy);
            for j in 0..i {
                hc[j] = tab.c[i][j] / h;
            }
            self.solve_stage(i, &hc[..i], h * tab.d[i]);
        }
        for i in 0..n {
            self.x_new[i] = self.x_stage[i] + self.ak[s - 1][i];
        }
        stats.rhs_evals += s as u64 - 1;

        let err = error_norm(&self.ak[s - 1], x, &self.x_new, tol);
        if !err.is_finite() {
            self.last_rejected = true;
            return Ok(Attempt {
                accepted: false,
                h_next: FAC_MIN * h,
            });
        }
        let exponent = 1.0 / f64::from(tab.order);
        let mut fac = (err.powf(exponent) / SAFE).clamp(1.0 / FAC_MAX, 1.0 / FAC_MIN);
        if err <= 1.0 {
            if let Some((h_prev, err_prev)) = self.previous {
                let fac_pred = (h_prev / h * (err * err / err_prev).powf(exponent) / SAFE)
                    .clamp(1.0 / FAC_MAX, 1.0 / FAC_MIN);
                fac = fac.max(fac_pred);
            }
            self.previous = Some((h, err.max(1e-2)));
            let mut h_next = h / fac;
            if self.last_rejected {
                h_next = h_next.min(h);
            }
            self.last_rejected = false;
            Ok(Attempt {
                accepted: true,
                h_next,
            })
        } else {
            self.last_rejected = true;
            Ok(Attempt {
                accepted: false,
                h_next: h / fac,
            })
        }
    }

    fn x_new(&self) -> &[f64] {
        &self.x_new
    }

    fn end_state_mut(&mut self) -> (&mut [f64], Option<&mut [f64]>) {
        (&mut self.x_new, None)
    }

    fn prepare_dense<S: OdeSystem>(
        &mut self,
        _sys: &mut S,
        _w: Window,
        _t: f64,
        _x: &[f64],
        _h: f64,
        _stats: &mut SolverStats,
    ) {
        let tab = Self::T;
        // Dᵣ = Σⱼ dense[r][j] kⱼ, summed stage by stage (each component left to right).
        for (r, out) in self.dense.iter_mut().take(tab.dense_rows).enumerate() {
            let row = &tab.dense[r];
            for (o, &v) in out.iter_mut().zip(&self.ak[0]) {
                *o = row[0] * v;
            }
            for (&c, k) in row[1..tab.dense_stages].iter().zip(&self.ak[1..]) {
                for (o, &v) in out.iter_mut().zip(k) {
                    *o += c * v;
                }
            }
        }
    }

    fn dense(&self, x_old: &[f64], theta: f64, _h: f64, out: &mut [f64]) {
        let rows = Self::T.dense_rows;
        let s1 = 1.0 - theta;
        for i in 0..out.len() {
            // Horner in θ over D₁ … D_rows.
            let mut poly = self.dense[rows - 1][i];
            for r in (0..rows - 1).rev() {
                poly = self.dense[r][i] + theta * poly;
            }
            out[i] = x_old[i] * s1 + theta * (self.x_new[i] + s1 * poly);
        }
    }

    fn accept(&mut self) {
        // The next attempt starts at x_new and re-evaluates f0, J and df/dt there.
        self.f0_current = false;
        self.jac_current = false;
    }
}
