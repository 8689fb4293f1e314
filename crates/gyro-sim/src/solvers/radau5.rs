//! RADAU5 (Hairer & Wanner, *Solving Ordinary Differential Equations II*, 2nd ed., §IV.8, and
//! their Fortran RADAU5, version of 2002): the 3-stage Radau IIA collocation method, order 5,
//! stiffly accurate and L-stable. It holds steps set by the slow motion over fast, lightly
//! damped nutation at tolerances where RODAS4 (order 4) has to shorten them.
//!
//! Per step: the stage increments Z = (z₁, z₂, z₃) at c = ((4 − √6)/10, (4 + √6)/10, 1) solve
//! Z = h (A ⊗ I) F(Z) by a simplified Newton iteration on the system transformed by T⁻¹ (T⁻¹A⁻¹T
//! = diag(γ, [[α, −β], [β, α]])), which needs one real LU of (γ/h) I − J and one complex LU of
//! ((α + iβ)/h) I − J (`linalg`, complex arithmetic; a model's kinematic rows q̇ = v eliminated
//! first, so an 8-state `full` model factors 4-square matrices). J is the system's exact Jacobian when
//! it provides one, else central differences (2n rhs calls). Each Newton iteration costs 3 rhs
//! calls; at most 7 iterations, stopped when the predicted remaining error is below
//! `fnewt` = max(10 eps/rtol', min(0.03, √rtol')). Newton starts from the previous step's
//! collocation polynomial extrapolated (zero after a start or a breakpoint). As in RADAU5, J
//! is kept from step to step while the Newton contraction θ ≤ THET
//! ([`Tolerances::jacobian_reuse_contraction`], 0.001 by default as in RADAU5; Hairer advises
//! ≈ 0.1 when Jacobians are dear), and the LUs too while the
//! step is kept (a proposed change of h/h_old in [1, 1.2] is not made); J is recomputed after a
//! rejection only when it is not already fresh. A Newton iteration that diverges (θ ≥ 0.99) or
//! would need more than 7 iterations rejects the step (h/2, or the h predicted from θ).
//!
//! Error: Hairer's embedded estimate filtered by the real iteration matrix,
//! err = ((γ₀/h) I − J)⁻¹ (f(x₀) + (e₁z₁ + e₂z₂ + e₃z₃)/h), and on the first step or after a
//! rejection, when that is ≥ 1, the second filtered estimate ((γ₀/h) I − J)⁻¹ (f(x₀ + err) +
//! (e₁z₁ + e₂z₂ + e₃z₃)/h) (ESTRAD). Step control: h_new/h = 1/clamp(err^¼/fac, 1/8, 5) with
//! fac = min(0.9, 0.9 (1 + 2·7)/(newt + 2·7)), and Gustafsson's predictive controller on
//! accepted steps. Tolerances are mapped as RADAU5 maps them: rtol' = 0.1 rtol^(2/3),
//! atol' = rtol'·atol/rtol, so that the achieved error is about rtol (the error estimate is of
//! order 3 while the solution is of order 5). Dense output is the collocation polynomial of the
//! step (cubic, continuous across steps; RADAU5's CONTR5); its error between step ends is not
//! controlled, which shows when every mode is stiff and the steps are long (Prothero–Robinson).
//! A singular iteration matrix halves the step; five in a row is an error.
//!
//! Why the mapped tolerances: used as given (as SciPy's `Radau` does), the order-3 estimate
//! at tight rtol forces steps that the Newton iteration on the lightly damped nutation then
//! fails to converge on — on the stiff oscillator of the solver tests at rtol 1e-8, 183 599
//! steps and 88 885 rejections against 50 576 and 2 863 mapped, for the same error.
//!
//! Coefficients: c₁, c₂ and e₁/γ₀, e₂/γ₀, e₃/γ₀ (RADAU5's DD1..DD3) in closed form in √6, γ
//! and α ± iβ (eigenvalues of A⁻¹) from the cube roots 81^(1/3), 9^(1/3), T and T⁻¹ with the
//! 20 digits of radau5.f; the tests below check them against their closed forms.
//!
//! Measured by `gyrolab accuracy` (work-precision, with rodas4 and dop853) and by the solver
//! harness (`cargo test --release --workspace -- solvers::`).

use super::linalg::{ComplexIterationMatrix, IterationMatrix};
use super::{
    Attempt, InitialStepScratch, OdeSystem, SolveError, SolverStats, Stepper, Tolerances, Window,
    difference_jacobian, initial_step, start_derivative,
};

/// c₁ = (4 − √6)/10.
const C1: f64 = 0.155_051_025_721_682_190_180_271_592_529_410_860_803_4;
/// c₂ = (4 + √6)/10.
const C2: f64 = 0.644_948_974_278_317_809_819_728_407_470_589_139_196_6;
const C1M1: f64 = C1 - 1.0;
const C2M1: f64 = C2 - 1.0;
const C1MC2: f64 = C1 - C2;
/// −(13 + 7√6)/3.
const DD1: f64 = -10.048_809_399_827_415_562_460_329_507_647_079_914_59;
/// (−13 + 7√6)/3.
const DD2: f64 = 1.382_142_733_160_748_895_793_662_840_980_413_247_92;
const DD3: f64 = -1.0 / 3.0;
/// γ = 30/(6 + 81^(1/3) − 9^(1/3)), the real eigenvalue of A⁻¹.
const U1: f64 = 3.637_834_252_744_495_732_208_418_513_577_775_797_945;
/// α + iβ, the complex eigenvalue of A⁻¹.
const ALPH: f64 = 2.681_082_873_627_752_133_895_790_743_211_112_101_028;
const BETA: f64 = 3.050_430_199_247_410_569_426_377_624_787_567_904_441;
const T11: f64 = 9.123_239_487_089_294_279_2e-2;
const T12: f64 = -0.141_255_295_020_954_208_43;
const T13: f64 = -3.002_919_410_514_742_449_2e-2;
const T21: f64 = 0.241_717_932_707_107_018_96;
const T22: f64 = 0.204_129_352_293_799_931_99;
const T23: f64 = 0.382_942_112_757_261_937_79;
const T31: f64 = 0.966_048_182_615_092_936_19;
const TI11: f64 = 4.325_579_890_063_155_351_0;
const TI12: f64 = 0.339_199_251_815_809_869_54;
const TI13: f64 = 0.541_770_539_935_874_871_19;
const TI21: f64 = -4.178_718_591_551_904_727_3;
const TI22: f64 = -0.327_682_820_761_062_387_08;
const TI23: f64 = 0.476_623_554_500_550_451_96;
const TI31: f64 = -0.502_872_634_945_786_875_95;
const TI32: f64 = 2.571_926_949_855_605_429_2;
const TI33: f64 = -0.596_039_204_828_224_924_97;

/// Newton iterations per step (RADAU5's NIT).
const NIT: u32 = 7;
const SAFE: f64 = 0.9;
/// Bounds of h/h_new (FACR, FACL): 0.2 ≤ h_new/h ≤ 8.
const FACR: f64 = 1.0 / 8.0;
const FACL: f64 = 5.0;
/// A proposed h_new/h in [QUOT1, QUOT2] keeps h (and the LUs).
const QUOT1: f64 = 1.0;
const QUOT2: f64 = 1.2;
/// Consecutive singular iteration matrices tolerated before giving up.
const MAX_SINGULAR: u32 = 5;

/// RADAU5's tolerances from the user's: rtol' = 0.1 rtol^(2/3), atol' = rtol'·atol/rtol.
fn internal_tolerances(tol: &Tolerances) -> Tolerances {
    let rtol = 0.1 * tol.rtol.powf(2.0 / 3.0);
    Tolerances {
        rtol,
        atol: rtol * (tol.atol / tol.rtol),
        ..*tol
    }
}

/// The tolerances RADAU5 works to and Newton's stopping bound, for one pair of user tolerances.
#[derive(Clone, Copy)]
struct Internal {
    /// The user's (rtol, atol) these were computed for.
    user: (f64, f64),
    rtol: f64,
    atol: f64,
    /// Newton's bound: max(10 eps/rtol', min(0.03, √rtol')).
    fnewt: f64,
}

impl Internal {
    fn new(tol: &Tolerances) -> Self {
        let itol = internal_tolerances(tol);
        Internal {
            user: (tol.rtol, tol.atol),
            rtol: itol.rtol,
            atol: itol.atol,
            fnewt: (10.0 * f64::EPSILON / itol.rtol).max(0.03f64.min(itol.rtol.sqrt())),
        }
    }
}

pub(crate) struct Radau5 {
    n: usize,
    /// f(t, x) at the current point; valid while `f0_current`.
    f0: Vec<f64>,
    f0_current: bool,
    /// df/dx, row-major.
    jac: Vec<f64>,
    /// J was evaluated at the current point (RADAU5's CALJAC).
    jac_fresh: bool,
    /// J (from an earlier point) may serve this step: the last Newton contraction was fast.
    jac_usable: bool,
    /// J is the system's constant one (`OdeSystem::jacobian_is_constant`): once formed, it
    /// stays usable (forming it again would give the same matrix, and the same LUs at the
    /// same h).
    jac_constant: bool,
    /// Kinematic rows of J (`IterationMatrix::kinematic_rows`), found when J is formed.
    kinematic: usize,
    /// (γ/h) I − J, factored.
    e1: IterationMatrix,
    /// ((α + iβ)/h) I − J, factored.
    e2: ComplexIterationMatrix,
    /// The h the LUs were formed with; `None` when they are stale.
    lu_h: Option<f64>,
    /// Stage increments z_k = X_k − x (after the iteration: of the collocation solution).
    z: [Vec<f64>; 3],
    /// The transformed increments T⁻¹Z.
    w: [Vec<f64>; 3],
    scal: Vec<f64>,
    x_stage: Vec<f64>,
    x_new: Vec<f64>,
    /// Error estimate and the (e·z)/h part of it.
    err_v: Vec<f64>,
    ez: Vec<f64>,
    /// Collocation polynomial of the last accepted step (starting values) and of the step just
    /// accepted (dense output), as divided differences at 1, c₂, c₁, 0 (RADAU5's CONT).
    cont: [Vec<f64>; 3],
    cont_new: [Vec<f64>; 3],
    /// Size of the last accepted step, and of the one just accepted.
    h_old: f64,
    h_new_accepted: f64,
    /// No step accepted since the start or the last breakpoint (FIRST).
    first: bool,
    /// The last attempt was rejected (REJECT).
    rejected: bool,
    faccon: f64,
    singular_in_row: u32,
    /// The internal tolerances of the last attempt's user tolerances (a `powf` and a square root
    /// an attempt otherwise, for values that change only when the tolerances do).
    internal: Option<Internal>,
    /// Gustafsson controller memory: last accepted h and error; `None` after a reset.
    previous: Option<(f64, f64)>,
    scratch: InitialStepScratch,
}

impl Radau5 {
    pub(crate) fn new(n: usize) -> Self {
        let v = || vec![0.0; n];
        Radau5 {
            n,
            f0: v(),
            f0_current: false,
            jac: vec![0.0; n * n],
            jac_fresh: false,
            jac_usable: false,
            jac_constant: false,
            kinematic: 0,
            e1: IterationMatrix::new(n),
            e2: ComplexIterationMatrix::new(n),
            lu_h: None,
            z: std::array::from_fn(|_| v()),
            w: std::array::from_fn(|_| v()),
            scal: v(),
            x_stage: v(),
            x_new: v(),
            err_v: v(),
            ez: v(),
            cont: std::array::from_fn(|_| v()),
            cont_new: std::array::from_fn(|_| v()),
            h_old: 0.0,
            h_new_accepted: 0.0,
            first: true,
            rejected: false,
            faccon: 1.0,
            singular_in_row: 0,
            internal: None,
            previous: None,
            scratch: InitialStepScratch::new(n),
        }
    }

    /// J at the current point (exact, or central differences).
    fn linearise<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        te: f64,
        x: &[f64],
        stats: &mut SolverStats,
    ) {
        stats.jacobian_evals += 1;
        if !sys.jacobian(te, x, &mut self.jac) {
            let [up, down, _] = &mut self.z;
            difference_jacobian(
                sys,
                te,
                x,
                &mut self.jac,
                &mut self.x_stage,
                up,
                down,
                stats,
            );
        }
        self.kinematic = IterationMatrix::kinematic_rows(&self.jac, self.n);
        self.jac_constant = sys.jacobian_is_constant();
        self.jac_fresh = true;
        self.jac_usable = true;
        self.lu_h = None;
    }

    /// LUs of (γ/h) I − J and ((α + iβ)/h) I − J; false when either is singular.
    fn decompose(&mut self, h: f64, stats: &mut SolverStats) -> bool {
        let (fac1, alphn, betan) = (U1 / h, ALPH / h, BETA / h);
        stats.lu_decompositions += 1;
        let m = self.kinematic;
        let ok = self.e1.factor(&self.jac, m, fac1) && self.e2.factor(&self.jac, m, alphn, betan);
        self.lu_h = if ok { Some(h) } else { None };
        ok
    }

    /// Rejects the attempt and proposes `h_next`; J is recomputed next time unless it is fresh
    /// (RADAU5: `IF (CALJAC) GOTO 20; GOTO 10`).
    fn reject(&mut self, h_next: f64) -> Attempt {
        self.rejected = true;
        if !self.jac_fresh && !self.jac_constant {
            self.jac_usable = false;
        }
        Attempt {
            accepted: false,
            h_next,
        }
    }

    /// RMS of v_i / scal_i.
    fn scaled_norm(&self, v: &[f64]) -> f64 {
        let sum: f64 = v
            .iter()
            .zip(&self.scal)
            .map(|(a, s)| (a / s) * (a / s))
            .sum();
        (sum / self.n.max(1) as f64).sqrt()
    }

    /// Newton's starting values: zero after a start or a breakpoint, else the last step's
    /// collocation polynomial extrapolated to the stages of a step h (z, and w = T⁻¹ z).
    fn start_values(&mut self, h: f64) {
        if self.first {
            for k in 0..3 {
                self.z[k].fill(0.0);
                self.w[k].fill(0.0);
            }
            return;
        }
        let c3q = h / self.h_old;
        let (c1q, c2q) = (C1 * c3q, C2 * c3q);
        let [ak1, ak2, ak3] = &self.cont;
        for i in 0..self.n {
            let at = |cq: f64| cq * (ak1[i] + (cq - C2M1) * (ak2[i] + (cq - C1M1) * ak3[i]));
            let (z1, z2, z3) = (at(c1q), at(c2q), at(c3q));
            self.z[0][i] = z1;
            self.z[1][i] = z2;
            self.z[2][i] = z3;
            self.w[0][i] = TI11 * z1 + TI12 * z2 + TI13 * z3;
            self.w[1][i] = TI21 * z1 + TI22 * z2 + TI23 * z3;
            self.w[2][i] = TI31 * z1 + TI32 * z2 + TI33 * z3;
        }
    }

    /// The scaled error of the converged step (ESTRAD), floored at 1e-10; after a start or a
    /// rejection a large estimate is refined by one more right-hand side, as RADAU5 does.
    fn error_estimate<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        te: f64,
        x: &[f64],
        h: f64,
        stats: &mut SolverStats,
    ) -> f64 {
        let n = self.n;
        let (hee1, hee2, hee3) = (DD1 / h, DD2 / h, DD3 / h);
        for i in 0..n {
            self.ez[i] = hee1 * self.z[0][i] + hee2 * self.z[1][i] + hee3 * self.z[2][i];
            self.err_v[i] = self.ez[i] + self.f0[i];
        }
        self.e1.solve(&mut self.err_v);
        let err = self.scaled_norm(&self.err_v).max(1e-10);
        if !(err >= 1.0 && (self.first || self.rejected)) {
            return err;
        }
        for i in 0..n {
            self.x_stage[i] = x[i] + self.err_v[i];
        }
        sys.rhs(te, &self.x_stage, &mut self.err_v);
        stats.rhs_evals += 1;
        for i in 0..n {
            self.err_v[i] += self.ez[i];
        }
        self.e1.solve(&mut self.err_v);
        self.scaled_norm(&self.err_v).max(1e-10)
    }

    /// An accepted step: the new state x + z₃ and the collocation polynomial's coefficients
    /// (dense output, and the next step's starting values once accepted).
    fn store_solution(&mut self, x: &[f64]) {
        let [z1, z2, z3] = &self.z;
        let [k1, k2, k3] = &mut self.cont_new;
        for i in 0..self.n {
            self.x_new[i] = x[i] + z3[i];
            k1[i] = (z2[i] - z3[i]) / C2M1;
            let ak = (z1[i] - z2[i]) / C1MC2;
            let acont3 = (ak - z1[i] / C1) / C2;
            k2[i] = (ak - k1[i]) / C1M1;
            k3[i] = k2[i] - acont3;
        }
    }

    /// The simplified Newton iteration for the stage increments z, from the starting values:
    /// the iterations taken and the last contraction θ, or the rejection (with the h to retry)
    /// when it diverges or would not converge in the iterations left.
    #[allow(clippy::too_many_arguments)]
    fn newton<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        w: Window,
        t: f64,
        x: &[f64],
        h: f64,
        fnewt: f64,
        tol: &Tolerances,
        stats: &mut SolverStats,
    ) -> Result<(u32, f64), Attempt> {
        let n = self.n;
        let (fac1, alphn, betan) = (U1 / h, ALPH / h, BETA / h);
        self.faccon = self.faccon.max(f64::EPSILON).powf(0.8);
        let mut theta = tol.jacobian_reuse_contraction;
        let mut newt = 0u32;
        let mut dynold = 0.0;
        let mut thqold = 0.0;
        loop {
            if newt >= NIT {
                return Err(self.reject(0.5 * h));
            }
            for (k, c) in [C1, C2, 1.0].into_iter().enumerate() {
                for i in 0..n {
                    self.x_stage[i] = x[i] + self.z[k][i];
                }
                sys.rhs(w.at(t + c * h), &self.x_stage, &mut self.z[k]);
            }
            stats.rhs_evals += 3;
            let [z1, z2, z3] = &mut self.z;
            let [w1, w2, w3] = &self.w;
            for i in 0..n {
                let (a1, a2, a3) = (z1[i], z2[i], z3[i]);
                let s1 = TI11 * a1 + TI12 * a2 + TI13 * a3;
                let s2 = TI21 * a1 + TI22 * a2 + TI23 * a3;
                let s3 = TI31 * a1 + TI32 * a2 + TI33 * a3;
                // SLVRAD: right-hand sides of the real and the complex system.
                z1[i] = s1 - w1[i] * fac1;
                z2[i] = s2 - w2[i] * alphn + w3[i] * betan;
                z3[i] = s3 - w3[i] * alphn - w2[i] * betan;
            }
            self.e1.solve(z1);
            self.e2.solve(z2, z3);
            newt += 1;
            let mut dyno = 0.0;
            for i in 0..n {
                let s = self.scal[i];
                dyno += (z1[i] / s).powi(2) + (z2[i] / s).powi(2) + (z3[i] / s).powi(2);
            }
            let dyno = (dyno / (3 * n).max(1) as f64).sqrt();
            if !dyno.is_finite() {
                return Err(self.reject(0.5 * h));
            }
            if newt > 1 && newt < NIT {
                let thq = dyno / dynold;
                theta = if newt == 2 {
                    thq
                } else {
                    (thq * thqold).sqrt()
                };
                thqold = thq;
                if theta < 0.99 {
                    self.faccon = theta / (1.0 - theta);
                    let left = NIT - 1 - newt;
                    let dyth = self.faccon * dyno * theta.powi(left as i32) / fnewt;
                    if dyth >= 1.0 {
                        // Too slow to converge in the iterations left: retry at a smaller h.
                        let qnewt = dyth.clamp(1e-4, 20.0);
                        let hhfac = 0.8 * qnewt.powf(-1.0 / (4.0 + f64::from(left)));
                        return Err(self.reject(hhfac * h));
                    }
                } else {
                    return Err(self.reject(0.5 * h));
                }
            }
            dynold = dyno.max(f64::EPSILON);
            let [w1, w2, w3] = &mut self.w;
            for i in 0..n {
                w1[i] += z1[i];
                w2[i] += z2[i];
                w3[i] += z3[i];
                let (f1, f2, f3) = (w1[i], w2[i], w3[i]);
                z1[i] = T11 * f1 + T12 * f2 + T13 * f3;
                z2[i] = T21 * f1 + T22 * f2 + T23 * f3;
                z3[i] = T31 * f1 + f2;
            }
            if self.faccon * dyno <= fnewt {
                break;
            }
        }
        Ok((newt, theta))
    }
}

impl Stepper for Radau5 {
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
        self.jac_fresh = false;
        self.jac_usable = self.jac_constant;
        self.lu_h = None;
        self.first = true;
        self.rejected = false;
        self.faccon = 1.0;
        self.singular_in_row = 0;
        self.previous = None;
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
        // The error estimate is of order 3 (local error O(h⁴)).
        initial_step(
            sys,
            w,
            t,
            x,
            &self.f0,
            4,
            &internal_tolerances(tol),
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
        let itol = match self.internal {
            Some(i) if i.user == (tol.rtol, tol.atol) => i,
            _ => *self.internal.insert(Internal::new(tol)),
        };
        let fnewt = itol.fnewt;
        let te = w.at(t);
        if !self.f0_current {
            sys.rhs(te, x, &mut self.f0);
            stats.rhs_evals += 1;
            self.f0_current = true;
            if self.f0.iter().any(|v| !v.is_finite()) {
                return Err(SolveError::NonFiniteState { t });
            }
        }
        if !self.jac_usable {
            self.linearise(sys, te, x, stats);
        }
        if self.lu_h != Some(h) && !self.decompose(h, stats) {
            self.singular_in_row += 1;
            if self.singular_in_row >= MAX_SINGULAR {
                return Err(SolveError::SingularMatrix { t });
            }
            return Ok(self.reject(0.5 * h));
        }
        self.singular_in_row = 0;
        for (s, xi) in self.scal.iter_mut().zip(x) {
            *s = itol.atol + itol.rtol * xi.abs();
        }

        self.start_values(h);

        let (newt, theta) = match self.newton(sys, w, t, x, h, fnewt, tol, stats) {
            Ok(done) => done,
            Err(rejected) => return Ok(rejected),
        };

        let err = self.error_estimate(sys, te, x, h, stats);
        if !err.is_finite() {
            return Ok(self.reject(0.2 * h));
        }

        // Step size.
        let cfac = SAFE * f64::from(1 + 2 * NIT);
        let fac = SAFE.min(cfac / f64::from(newt + 2 * NIT));
        let mut quot = (err.powf(0.25) / fac).clamp(FACR, FACL);
        let mut h_new = h / quot;
        if err < 1.0 {
            if let Some((h_acc, err_acc)) = self.previous {
                let facgus =
                    (h_acc / h * (err * err / err_acc).powf(0.25) / SAFE).clamp(FACR, FACL);
                quot = quot.max(facgus);
                h_new = h / quot;
            }
            self.previous = Some((h, err.max(1e-2)));
            self.first = false;
            self.store_solution(x);
            self.h_new_accepted = h;
            if self.rejected {
                h_new = h_new.min(h);
            }
            self.rejected = false;
            // Keep J for the next step while Newton contracts fast; keep h (and the LUs) when
            // the change would be small.
            self.jac_usable = self.jac_constant || theta <= tol.jacobian_reuse_contraction;
            let qt = h_new / h;
            if theta <= tol.jacobian_reuse_contraction && (QUOT1..=QUOT2).contains(&qt) {
                h_new = h;
            }
            Ok(Attempt {
                accepted: true,
                h_next: h_new,
            })
        } else {
            let h_next = if self.first { 0.1 * h } else { h_new };
            Ok(self.reject(h_next))
        }
    }

    fn x_new(&self) -> &[f64] {
        &self.x_new
    }

    fn end_state_mut(&mut self) -> (&mut [f64], Option<&mut [f64]>) {
        (&mut self.x_new, None)
    }

    fn dense(&self, _x_old: &[f64], theta: f64, _h: f64, out: &mut [f64]) {
        // CONTR5, with s = θ − 1 measured from the end of the step.
        let s = theta - 1.0;
        let [k1, k2, k3] = &self.cont_new;
        for i in 0..out.len() {
            out[i] = self.x_new[i] + s * (k1[i] + (s - C2M1) * (k2[i] + (s - C1M1) * k3[i]));
        }
    }

    fn accept(&mut self) {
        std::mem::swap(&mut self.cont, &mut self.cont_new);
        self.h_old = self.h_new_accepted;
        self.f0_current = false;
        self.jac_fresh = false;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Radau IIA's A (Hairer–Wanner II, Table IV.5.6), closed forms in √6.
    fn butcher_a() -> [[f64; 3]; 3] {
        let s6 = 6f64.sqrt();
        [
            [
                (88.0 - 7.0 * s6) / 360.0,
                (296.0 - 169.0 * s6) / 1800.0,
                (-2.0 + 3.0 * s6) / 225.0,
            ],
            [
                (296.0 + 169.0 * s6) / 1800.0,
                (88.0 + 7.0 * s6) / 360.0,
                (-2.0 - 3.0 * s6) / 225.0,
            ],
            [(16.0 - s6) / 36.0, (16.0 + s6) / 36.0, 1.0 / 9.0],
        ]
    }

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-14 * b.abs().max(1.0)
    }

    #[test]
    fn coefficients_match_their_closed_forms() {
        let s6 = 6f64.sqrt();
        assert!(close(C1, (4.0 - s6) / 10.0));
        assert!(close(C2, (4.0 + s6) / 10.0));
        assert!(close(DD1, -(13.0 + 7.0 * s6) / 3.0));
        assert!(close(DD2, (-13.0 + 7.0 * s6) / 3.0));
        let (c81, c9) = (81f64.cbrt(), 9f64.cbrt());
        let u1 = (6.0 + c81 - c9) / 30.0;
        let al = (12.0 - c81 + c9) / 60.0;
        let be = (c81 + c9) * 3f64.sqrt() / 60.0;
        let cno = al * al + be * be;
        assert!(close(U1, 1.0 / u1));
        assert!(close(ALPH, al / cno));
        assert!(close(BETA, be / cno));
        // Row sums of A are the nodes; its last row is the weights (stiffly accurate).
        let a = butcher_a();
        for (row, c) in a.iter().zip([C1, C2, 1.0]) {
            assert!(close(row.iter().sum(), c));
        }
    }

    /// T⁻¹ T = I and T⁻¹ A⁻¹ T = diag(γ, [[α, −β], [β, α]]): a digit dropped from T or T⁻¹
    /// breaks one of these far above 1e-12.
    #[test]
    fn transformation_diagonalises_a_inverse() {
        let t = [[T11, T12, T13], [T21, T22, T23], [T31, 1.0, 0.0]];
        let ti = [[TI11, TI12, TI13], [TI21, TI22, TI23], [TI31, TI32, TI33]];
        let mul = |a: &[[f64; 3]; 3], b: &[[f64; 3]; 3]| {
            let mut c = [[0.0; 3]; 3];
            for i in 0..3 {
                for j in 0..3 {
                    c[i][j] = (0..3).map(|k| a[i][k] * b[k][j]).sum();
                }
            }
            c
        };
        let id = mul(&ti, &t);
        for i in 0..3 {
            for j in 0..3 {
                let e = if i == j { 1.0 } else { 0.0 };
                assert!(
                    (id[i][j] - e).abs() < 1e-12,
                    "T⁻¹T[{i}][{j}] = {}",
                    id[i][j]
                );
            }
        }
        // TI · A⁻¹ · T = Λ  ⇔  A · T · Λ = T.
        let lambda = [[U1, 0.0, 0.0], [0.0, ALPH, -BETA], [0.0, BETA, ALPH]];
        let lhs = mul(&mul(&butcher_a(), &t), &lambda);
        for i in 0..3 {
            for j in 0..3 {
                assert!(
                    (lhs[i][j] - t[i][j]).abs() < 1e-12,
                    "(A T Λ)[{i}][{j}] = {} vs T = {}",
                    lhs[i][j],
                    t[i][j]
                );
            }
        }
    }
}
