//! Classic 4th-order Runge–Kutta at a fixed step (the baseline). The step is shortened only to
//! land on a breakpoint or the end. Dense output is the cubic Hermite interpolant through the
//! step's end values and slopes; the end slope is reused as the next step's first stage, so a
//! step costs 4 rhs calls. Tolerances are not used.

use super::{
    Attempt, OdeSystem, SolveError, SolverStats, Stepper, Tolerances, Window, start_derivative,
};

pub(crate) struct Rk4 {
    step_s: f64,
    /// f at the current point, then k2, k3, k4, and f at the new point.
    k: [Vec<f64>; 5],
    x_stage: Vec<f64>,
    x_new: Vec<f64>,
}

impl Rk4 {
    pub(crate) fn new(n: usize, step_s: f64) -> Self {
        Rk4 {
            step_s,
            k: std::array::from_fn(|_| vec![0.0; n]),
            x_stage: vec![0.0; n],
            x_new: vec![0.0; n],
        }
    }
}

impl Stepper for Rk4 {
    /// Absorb only round-off of t: the step stays fixed.
    const STRETCH: f64 = 1.0 + 1e-9;

    fn reset<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        w: Window,
        t: f64,
        x: &[f64],
        stats: &mut SolverStats,
    ) -> Result<(), SolveError> {
        start_derivative(sys, w, t, x, &mut self.k[0], stats)
    }

    fn first_step<S: OdeSystem>(
        &mut self,
        _sys: &mut S,
        _w: Window,
        _t: f64,
        _x: &[f64],
        _tol: &Tolerances,
        _h_max: f64,
        _stats: &mut SolverStats,
    ) -> f64 {
        self.step_s
    }

    fn attempt<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        w: Window,
        t: f64,
        x: &[f64],
        h: f64,
        _tol: &Tolerances,
        stats: &mut SolverStats,
    ) -> Result<Attempt, SolveError> {
        let [k1, k2, k3, k4, k5] = &mut self.k;
        let xs = &mut self.x_stage;
        let half = 0.5 * h;
        for i in 0..x.len() {
            xs[i] = x[i] + half * k1[i];
        }
        sys.rhs(w.at(t + half), xs, k2);
        for i in 0..x.len() {
            xs[i] = x[i] + half * k2[i];
        }
        sys.rhs(w.at(t + half), xs, k3);
        for i in 0..x.len() {
            xs[i] = x[i] + h * k3[i];
        }
        sys.rhs(w.at(t + h), xs, k4);
        for i in 0..x.len() {
            self.x_new[i] = x[i] + h / 6.0 * (k1[i] + 2.0 * (k2[i] + k3[i]) + k4[i]);
        }
        sys.rhs(w.at(t + h), &self.x_new, k5);
        stats.rhs_evals += 4;
        Ok(Attempt {
            accepted: true,
            h_next: self.step_s,
        })
    }

    fn x_new(&self) -> &[f64] {
        &self.x_new
    }

    fn end_state_mut(&mut self) -> (&mut [f64], Option<&mut [f64]>) {
        (&mut self.x_new, Some(&mut self.k[4]))
    }

    fn dense(&self, x_old: &[f64], theta: f64, h: f64, out: &mut [f64]) {
        let (f0, f1) = (&self.k[0], &self.k[4]);
        for i in 0..out.len() {
            let dy = self.x_new[i] - x_old[i];
            out[i] = (1.0 - theta) * x_old[i]
                + theta * self.x_new[i]
                + theta
                    * (theta - 1.0)
                    * ((1.0 - 2.0 * theta) * dy + (theta - 1.0) * h * f0[i] + theta * h * f1[i]);
        }
    }

    fn accept(&mut self) {
        self.k.swap(0, 4);
    }
}
