//! RODAS4 (Hairer–Wanner, Solving ODE II, §VI.4; Fortran RODAS, METH = 1): a 6-stage,
//! order-4(3), stiffly accurate and L-stable Rosenbrock method. It lets the `full` models step
//! over fast, lightly damped nutation with steps set by the slow motion.
//!
//! Per step: f(t, x); the Jacobian df/dx — the system's exact one when it provides it, else
//! central differences (2n rhs calls, increment cbrt(eps)·max(|x_j|, 1e-2)); df/dt by a
//! forward difference in t (1 rhs call; none when the system says it is autonomous, as a model
//! on a stationary base does: the difference is then exactly zero); J once per run instead
//! when the system says it is constant (a `linear` model); one LU of (1/(γh)) I − J
//! (partial pivoting, `linalg`; a model's kinematic rows q̇ = v eliminated first, so an 8-state
//! `full` model factors a 4-square matrix); 5 further rhs calls. The Jacobian is reused when a step is
//! retried at a smaller h. The embedded 3rd-order solution gives the error estimate; step
//! control is Gustafsson's predictive controller as in RODAS. Dense output is RODAS's 3rd-order
//! continuous extension. A singular matrix halves the step; five in a row is an error.

use super::linalg::IterationMatrix;
use super::{
    Attempt, InitialStepScratch, OdeSystem, SolveError, SolverStats, Stepper, Tolerances, Window,
    difference_jacobian, error_norm, initial_step, start_derivative,
};

const C2: f64 = 0.386;
const C3: f64 = 0.21;
const C4: f64 = 0.63;
const D1: f64 = 0.25;
const D2: f64 = -0.1043;
const D3: f64 = 0.1035;
const D4: f64 = -0.362_000_000_000_000_02e-1;
const A21: f64 = 0.1544000000000000e+01;
const A31: f64 = 0.9466785280815826;
const A32: f64 = 0.2557011698983284;
const A41: f64 = 0.3314825187068521e+01;
const A42: f64 = 0.2896124015972201e+01;
const A43: f64 = 0.9986419139977817;
const A51: f64 = 0.1221224509226641e+01;
const A52: f64 = 0.6019134481288629e+01;
const A53: f64 = 0.1253708332932087e+02;
const A54: f64 = -0.6878860361058950;
const C21: f64 = -0.5668800000000000e+01;
const C31: f64 = -0.2430093356833875e+01;
const C32: f64 = -0.2063599157091915;
const C41: f64 = -0.1073529058151375;
const C42: f64 = -0.9594562251023355e+01;
const C43: f64 = -0.2047028614809616e+02;
const C51: f64 = 0.7496443313967647e+01;
const C52: f64 = -0.1024680431464352e+02;
const C53: f64 = -0.3399990352819905e+02;
const C54: f64 = 0.1170890893206160e+02;
const C61: f64 = 0.8083246795921522e+01;
const C62: f64 = -0.7981132988064893e+01;
const C63: f64 = -0.3152159432874371e+02;
const C64: f64 = 0.1631930543123136e+02;
const C65: f64 = -0.6058818238834054e+01;
const GAMMA: f64 = 0.25;
const D21: f64 = 0.1012623508344586e+02;
const D22: f64 = -0.7487995877610167e+01;
const D23: f64 = -0.3480091861555747e+02;
const D24: f64 = -0.7992771707568823e+01;
const D25: f64 = 0.1025137723295662e+01;
const D31: f64 = -0.6762803392801253;
const D32: f64 = 0.6087714651680015e+01;
const D33: f64 = 0.1643084320892478e+02;
const D34: f64 = 0.2476722511418386e+02;
const D35: f64 = -0.6594389125716872e+01;

/// Step-ratio limits and safety factor of RODAS.
const FAC_MIN: f64 = 0.2;
const FAC_MAX: f64 = 6.0;
const SAFE: f64 = 0.9;
/// Consecutive singular iteration matrices tolerated before giving up.
const MAX_SINGULAR: u32 = 5;

pub(crate) struct Rodas4 {
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
    ak: [Vec<f64>; 6],
    dy: Vec<f64>,
    x_stage: Vec<f64>,
    x_new: Vec<f64>,
    dense2: Vec<f64>,
    dense3: Vec<f64>,
    singular_in_row: u32,
    /// Gustafsson controller memory: last accepted h and error; `None` after a reset.
    previous: Option<(f64, f64)>,
    last_rejected: bool,
    scratch: InitialStepScratch,
}

impl Rodas4 {
    pub(crate) fn new(n: usize) -> Self {
        Rodas4 {
            n,
            f0: vec![0.0; n],
            f0_current: false,
            fx: vec![0.0; n],
            jac: vec![0.0; n * n],
            jac_current: false,
            jac_kept: false,
            kinematic: 0,
            matrix: IterationMatrix::new(n),
            ak: std::array::from_fn(|_| vec![0.0; n]),
            dy: vec![0.0; n],
            x_stage: vec![0.0; n],
            x_new: vec![0.0; n],
            dense2: vec![0.0; n],
            dense3: vec![0.0; n],
            singular_in_row: 0,
            previous: None,
            last_rejected: false,
            scratch: InitialStepScratch::new(n),
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

impl Stepper for Rodas4 {
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
            4,
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
            .factor(&self.jac, self.kinematic, 1.0 / (h * GAMMA))
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

        // Stage 1.
        self.dy.copy_from_slice(&self.f0);
        self.solve_stage(0, &[], h * D1);
        // Stage 2.
        self.stage_point(x, &[A21]);
        sys.rhs(w.at(t + C2 * h), &self.x_stage, &mut self.dy);
        self.solve_stage(1, &[C21 / h], h * D2);
        // Stage 3.
        self.stage_point(x, &[A31, A32]);
        sys.rhs(w.at(t + C3 * h), &self.x_stage, &mut self.dy);
        self.solve_stage(2, &[C31 / h, C32 / h], h * D3);
        // Stage 4.
        self.stage_point(x, &[A41, A42, A43]);
        sys.rhs(w.at(t + C4 * h), &self.x_stage, &mut self.dy);
        self.solve_stage(3, &[C41 / h, C42 / h, C43 / h], h * D4);
        // Stage 5.
        self.stage_point(x, &[A51, A52, A53, A54]);
        sys.rhs(w.at(t + h), &self.x_stage, &mut self.dy);
        self.solve_stage(4, &[C51 / h, C52 / h, C53 / h, C54 / h], 0.0);
        // Embedded solution, then stage 6 = error estimate.
        for i in 0..n {
            self.x_stage[i] += self.ak[4][i];
        }
        sys.rhs(w.at(t + h), &self.x_stage, &mut self.dy);
        self.solve_stage(5, &[C61 / h, C62 / h, C63 / h, C64 / h, C65 / h], 0.0);
        for i in 0..n {
            self.x_new[i] = self.x_stage[i] + self.ak[5][i];
        }
        stats.rhs_evals += 5;

        let err = error_norm(&self.ak[5], x, &self.x_new, tol);
        if !err.is_finite() {
            self.last_rejected = true;
            return Ok(Attempt {
                accepted: false,
                h_next: FAC_MIN * h,
            });
        }
        let mut fac = (err.powf(0.25) / SAFE).clamp(1.0 / FAC_MAX, 1.0 / FAC_MIN);
        if err <= 1.0 {
            if let Some((h_prev, err_prev)) = self.previous {
                let fac_pred = (h_prev / h * (err * err / err_prev).powf(0.25) / SAFE)
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
        let [a1, a2, a3, a4, a5, _] = &self.ak;
        for i in 0..self.n {
            self.dense2[i] = D21 * a1[i] + D22 * a2[i] + D23 * a3[i] + D24 * a4[i] + D25 * a5[i];
            self.dense3[i] = D31 * a1[i] + D32 * a2[i] + D33 * a3[i] + D34 * a4[i] + D35 * a5[i];
        }
    }

    fn dense(&self, x_old: &[f64], theta: f64, _h: f64, out: &mut [f64]) {
        let s1 = 1.0 - theta;
        for i in 0..out.len() {
            out[i] = x_old[i] * s1
                + theta * (self.x_new[i] + s1 * (self.dense2[i] + theta * self.dense3[i]));
        }
    }

    fn accept(&mut self) {
        // The next attempt starts at x_new and re-evaluates f0, J and df/dt there.
        self.f0_current = false;
        self.jac_current = false;
    }
}
