//! Dormand–Prince 5(4) (Hairer's DOPRI5): 7 stages, first-same-as-last (6 rhs calls per
//! step), 4th-order embedded error estimate, Hairer's PI step control (beta = 0.04), and
//! Shampine's 4th-order continuous extension for dense output.
//! Coefficients: Hairer–Nørsett–Wanner, Solving ODE I, Table II.5.2 and DOPRI5's CONTD5.

use super::{
    Attempt, InitialStepScratch, OdeSystem, PiController, SolveError, SolverStats, Stepper,
    Tolerances, Window, error_norm, initial_step, start_derivative,
};

const C2: f64 = 1.0 / 5.0;
const C3: f64 = 3.0 / 10.0;
const C4: f64 = 4.0 / 5.0;
const C5: f64 = 8.0 / 9.0;
const A21: f64 = 1.0 / 5.0;
const A31: f64 = 3.0 / 40.0;
const A32: f64 = 9.0 / 40.0;
const A41: f64 = 44.0 / 45.0;
const A42: f64 = -56.0 / 15.0;
const A43: f64 = 32.0 / 9.0;
const A51: f64 = 19372.0 / 6561.0;
const A52: f64 = -25360.0 / 2187.0;
const A53: f64 = 64448.0 / 6561.0;
const A54: f64 = -212.0 / 729.0;
const A61: f64 = 9017.0 / 3168.0;
const A62: f64 = -355.0 / 33.0;
const A63: f64 = 46732.0 / 5247.0;
const A64: f64 = 49.0 / 176.0;
const A65: f64 = -5103.0 / 18656.0;
const A71: f64 = 35.0 / 384.0;
const A73: f64 = 500.0 / 1113.0;
const A74: f64 = 125.0 / 192.0;
const A75: f64 = -2187.0 / 6784.0;
const A76: f64 = 11.0 / 84.0;
// Error coefficients: 5th-order weights minus 4th-order weights.
const E1: f64 = 71.0 / 57600.0;
const E3: f64 = -71.0 / 16695.0;
const E4: f64 = 71.0 / 1920.0;
const E5: f64 = -17253.0 / 339200.0;
const E6: f64 = 22.0 / 525.0;
const E7: f64 = -1.0 / 40.0;
// Dense output of Shampine (1986).
const D1: f64 = -12715105075.0 / 11282082432.0;
const D3: f64 = 87487479700.0 / 32700410799.0;
const D4: f64 = -10690763975.0 / 1880347072.0;
const D5: f64 = 701980252875.0 / 199316789632.0;
const D6: f64 = -1453857185.0 / 822651844.0;
const D7: f64 = 69997945.0 / 29380423.0;

pub(crate) struct Dopri5 {
    k: [Vec<f64>; 7],
    x_stage: Vec<f64>,
    x_new: Vec<f64>,
    err: Vec<f64>,
    /// h * (D1 k1 + D3 k3 + ... + D7 k7) of the last accepted step.
    dense5: Vec<f64>,
    control: PiController,
    scratch: InitialStepScratch,
}

impl Dopri5 {
    pub(crate) fn new(n: usize) -> Self {
        Dopri5 {
            k: std::array::from_fn(|_| vec![0.0; n]),
            x_stage: vec![0.0; n],
            x_new: vec![0.0; n],
            err: vec![0.0; n],
            dense5: vec![0.0; n],
            control: PiController::new(0.2 - 0.75 * 0.04, 0.04, 0.2, 10.0),
            scratch: InitialStepScratch::new(n),
        }
    }
}

impl Stepper for Dopri5 {
    const STRETCH: f64 = 1.01;

    fn reset<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        w: Window,
        t: f64,
        x: &[f64],
        stats: &mut SolverStats,
    ) -> Result<(), SolveError> {
        self.control.reset();
        start_derivative(sys, w, t, x, &mut self.k[0], stats)
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
            &self.k[0],
            5,
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
        let [k1, k2, k3, k4, k5, k6, k7] = &mut self.k;
        let xs = &mut self.x_stage;
        for i in 0..x.len() {
            xs[i] = x[i] + h * A21 * k1[i];
        }
        sys.rhs(w.at(t + C2 * h), xs, k2);
        for i in 0..x.len() {
            xs[i] = x[i] + h * (A31 * k1[i] + A32 * k2[i]);
        }
        sys.rhs(w.at(t + C3 * h), xs, k3);
        for i in 0..x.len() {
            xs[i] = x[i] + h * (A41 * k1[i] + A42 * k2[i] + A43 * k3[i]);
        }
        sys.rhs(w.at(t + C4 * h), xs, k4);
        for i in 0..x.len() {
            xs[i] = x[i] + h * (A51 * k1[i] + A52 * k2[i] + A53 * k3[i] + A54 * k4[i]);
        }
        sys.rhs(w.at(t + C5 * h), xs, k5);
        for i in 0..x.len() {
            xs[i] =
                x[i] + h * (A61 * k1[i] + A62 * k2[i] + A63 * k3[i] + A64 * k4[i] + A65 * k5[i]);
        }
        sys.rhs(w.at(t + h), xs, k6);
        let xn = &mut self.x_new;
        for i in 0..x.len() {
            xn[i] =
                x[i] + h * (A71 * k1[i] + A73 * k3[i] + A74 * k4[i] + A75 * k5[i] + A76 * k6[i]);
        }
        sys.rhs(w.at(t + h), xn, k7);
        stats.rhs_evals += 6;
        for i in 0..x.len() {
            self.err[i] =
                h * (E1 * k1[i] + E3 * k3[i] + E4 * k4[i] + E5 * k5[i] + E6 * k6[i] + E7 * k7[i]);
        }
        let err = error_norm(&self.err, x, &self.x_new, tol);
        Ok(self.control.decide(err, h))
    }

    fn x_new(&self) -> &[f64] {
        &self.x_new
    }

    fn end_state_mut(&mut self) -> (&mut [f64], Option<&mut [f64]>) {
        (&mut self.x_new, Some(&mut self.k[6]))
    }

    fn prepare_dense<S: OdeSystem>(
        &mut self,
        _sys: &mut S,
        _w: Window,
        _t: f64,
        _x: &[f64],
        h: f64,
        _stats: &mut SolverStats,
    ) {
        let [k1, _, k3, k4, k5, k6, k7] = &self.k;
        for i in 0..self.dense5.len() {
            self.dense5[i] =
                h * (D1 * k1[i] + D3 * k3[i] + D4 * k4[i] + D5 * k5[i] + D6 * k6[i] + D7 * k7[i]);
        }
    }

    fn dense(&self, x_old: &[f64], theta: f64, h: f64, out: &mut [f64]) {
        let theta1 = 1.0 - theta;
        let (k1, k7) = (&self.k[0], &self.k[6]);
        for i in 0..out.len() {
            let ydiff = self.x_new[i] - x_old[i];
            let bspl = h * k1[i] - ydiff;
            let r4 = ydiff - h * k7[i] - bspl;
            out[i] = x_old[i]
                + theta * (ydiff + theta1 * (bspl + theta * (r4 + theta1 * self.dense5[i])));
        }
    }

    fn accept(&mut self) {
        self.k.swap(0, 6);
    }
}
