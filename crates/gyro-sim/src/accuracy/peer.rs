//! The Python peer's cases (analysis/bench/peer.py runs the same equations with SciPy).

use super::StudyError;
use super::StudyOptions;
use super::measurement::{Budget, timed};
use super::problems::{
    Anschutz4, HOURS, LinearSystem, anschutz_text, exact_linear, foucault_release, scene,
};
use crate::Simulation;
use crate::run::{KeptModelSystem, ModelSystem};
use crate::solvers::{self, Method, OdeSystem, OutputGrid, SolverStats, Tolerances};
use gyro_model::theory::Villarceau;
use serde::Serialize;
use std::ops::ControlFlow;

/// Villarceau's eq. 44 bis written by hand: γ″ = (g/a)(−sin γ + 2δ sin γ cos γ), state (γ, γ′);
/// with `Some(I₀)`, its first integral (eq. 47) kept at I₀ by projection, as a scene's
/// `keep_jacobi_integral` keeps the engine's.
#[derive(Clone, Copy, Debug)]
struct Eq44Bis(Villarceau, Option<f64>);

impl OdeSystem for Eq44Bis {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) {
        dx[0] = x[1];
        dx[1] = self.0.acceleration(x[0]);
    }
    fn jacobian(&mut self, _t: f64, x: &[f64], jac: &mut [f64]) -> bool {
        let (s, c) = gyro_model::sin_cos(x[0]);
        jac.copy_from_slice(&[
            0.0,
            1.0,
            self.0.g_over_a * (-c + 2.0 * self.0.delta * (c * c - s * s)),
            0.0,
        ]);
        true
    }
    fn is_autonomous(&self) -> bool {
        true
    }
    fn projects(&self) -> bool {
        self.1.is_some()
    }
    fn project(&mut self, _t: f64, x: &mut [f64], tol: &Tolerances) -> bool {
        let Some(target) = self.1 else {
            return false;
        };
        // I = γ′² − (2g/a)(cos γ − δ cos²γ): ∂I/∂γ = −2γ″, ∂I/∂γ′ = 2γ′.
        let grad = [-2.0 * self.0.acceleration(x[0]), 2.0 * x[1]];
        let value = self.0.first_integral(x[0], x[1]);
        solvers::project_onto_level(x, &grad, value, target, tol)
    }
}

/// One peer measurement.
#[derive(Clone, Debug, Serialize)]
pub struct PeerPoint {
    /// `gyrolab eq44bis` (hand-written), `gyrolab engine` (the Lagrangian engine's model),
    /// `gyrolab 4state` (Beghin's 4-state Anschütz, hand-written), `gyrolab engine-linear` (the
    /// engine's `linear` Anschütz 1906); `… kept`: the same with the first integral (eq. 47,
    /// Jacobi's integral for the engine) kept by projection.
    pub implementation: String,
    pub method: String,
    pub rtol: f64,
    pub atol: f64,
    pub error: Option<f64>,
    pub wall_s: f64,
    pub rhs_evals: u64,
}

impl PeerPoint {
    /// The point of one timed run: its error (`None` if it failed) and its solver counts.
    fn new(
        implementation: &str,
        method: Method,
        tol: &Tolerances,
        error: Option<f64>,
        wall_s: f64,
        stats: &SolverStats,
    ) -> Self {
        PeerPoint {
            implementation: implementation.into(),
            method: method.to_string(),
            rtol: tol.rtol,
            atol: tol.atol,
            error,
            wall_s,
            rhs_evals: stats.rhs_evals,
        }
    }
}

/// The peer cases and gyrolab's side of them.
#[derive(Clone, Debug, Serialize)]
pub struct PeerReport {
    /// Villarceau eq. 44 bis: g/a, δ, release γ₀ (rad, from the centre), exact period, periods.
    pub villarceau: serde_json::Value,
    pub anschutz4: Anschutz4,
    /// The engine's `linear` Anschütz 1906 (harbour, 50°N, 2° off the meridian, 1 h): ẏ = A y
    /// for the deviation y = x − x_e from equilibrium; SciPy solves the same matrix.
    pub anschutz_linear: LinearPeer,
    /// atol = rtol × this, on both sides.
    pub atol_factor: f64,
    pub points: Vec<PeerPoint>,
}

/// The engine's linear Anschütz as the peer sees it.
#[derive(Clone, Debug, Serialize)]
pub struct LinearPeer {
    pub n: usize,
    /// Row-major n×n: the exact Jacobian of the full equations at the equilibrium.
    pub a: Vec<f64>,
    /// Deviation from equilibrium at the start.
    pub y0: Vec<f64>,
    /// State indices compared (the coordinates, not their rates).
    pub compare: Vec<usize>,
    /// Error scale (rad): the 2° release.
    pub scale: f64,
    pub t_end: f64,
    pub dt: f64,
    /// atol = rtol × this, on both sides.
    pub atol_factor: f64,
}

/// Villarceau's peer case: the large-amplitude azimuth gyroscope, 100 exact periods.
const PEER_PERIODS: f64 = 100.0;

/// Runs gyrolab's side of the peer benchmark: for each tolerance, Villarceau over 100 periods
/// (hand-written eq. 44 bis and the engine) and the 4-state Anschütz, with DOP853, DOPRI5,
/// RODAS4 and RADAU5. Errors are measured exactly as `analysis/bench/peer.py` measures SciPy's.
pub fn peer_report(opts: &StudyOptions) -> Result<PeerReport, StudyError> {
    let setup = |message: String| StudyError::Setup {
        case: "peer".into(),
        message,
    };
    let amplitude = 90f64.to_radians();
    let (sim, v, _) = foucault_release(90.0, amplitude).map_err(setup)?;
    let period = v.period(amplitude);
    let t_end = PEER_PERIODS * period;
    let atol_factor = 1e-3;
    let a4 = Anschutz4::from_design().map_err(setup)?;
    let a4m = a4.matrix();
    let grid4 = OutputGrid {
        t0: 0.0,
        dt: a4.dt,
        t_end: a4.t_end,
    };
    let exact4 = exact_linear(&a4m, 4, &a4.x0, &grid4);
    let lin_sc = scene(&anschutz_text("linear", HOURS, 2.0), None).map_err(setup)?;
    let lin = Simulation::new(&lin_sc).map_err(|e| setup(e.to_string()))?;
    let xe = lin.model.x_equilibrium.clone();
    let lin_peer = LinearPeer {
        n: lin.model.dim(),
        a: lin.model.linear_matrix().to_vec(),
        y0: lin.model.x0.iter().zip(&xe).map(|(x, e)| x - e).collect(),
        compare: (0..lin.model.dim() / 2).collect(),
        scale: 2f64.to_radians(),
        t_end: lin.grid.t_end,
        dt: lin.grid.dt,
        atol_factor: 1e-4,
    };
    let exact_lin = exact_linear(&lin_peer.a, lin_peer.n, &lin_peer.y0, &lin.grid);
    // The kept rows' system, checked once (the runs below build it afresh, as a run would).
    KeptModelSystem::new(&sim.model, 0.0, &sim.model.x0).map_err(|e| setup(e.to_string()))?;
    let mut points = Vec::new();
    for &rtol in &opts.tolerances {
        let tol = Tolerances {
            rtol,
            atol: rtol * atol_factor,
            ..Default::default()
        };
        for method in [
            Method::Dop853,
            Method::Vern9,
            Method::Dopri5,
            Method::Rodas4,
            Method::Rodas5p,
            Method::Radau5,
        ] {
            let implicit = matches!(method, Method::Rodas4 | Method::Rodas5p | Method::Radau5);
            points.extend(villarceau_points(
                opts, &sim, v, amplitude, t_end, method, &tol,
            ));
            // 4-state Anschütz (explicit methods are stability-bound: loosest tolerance only).
            if implicit || rtol == opts.tolerances[0] {
                let tol4 = Tolerances {
                    atol: rtol * 1e-4,
                    ..tol
                };
                let four = LinearRun {
                    x0: &a4.x0,
                    offset: &[0.0; 4],
                    compare: &[0, 1],
                    exact: &exact4,
                    scale: 2f64.to_radians(),
                    grid: &grid4,
                    breakpoints: &[],
                };
                let system = || LinearSystem {
                    a: a4m.clone(),
                    n: 4,
                };
                points.push(four.point(opts, "gyrolab 4state", system, method, &tol4));
                // The same through the engine: its `linear` model of the whole compass.
                let toll = Tolerances {
                    atol: rtol * lin_peer.atol_factor,
                    ..tol
                };
                let engine = LinearRun {
                    x0: &lin.model.x0,
                    offset: &xe,
                    compare: &lin_peer.compare,
                    exact: &exact_lin,
                    scale: lin_peer.scale,
                    grid: &lin.grid,
                    breakpoints: &lin.breakpoints,
                };
                let system = || ModelSystem { model: &lin.model };
                points.push(engine.point(opts, "gyrolab engine-linear", system, method, &toll));
            }
        }
    }
    Ok(PeerReport {
        villarceau: serde_json::json!({
            "g_over_a": v.g_over_a,
            "delta": v.delta,
            "gamma0": amplitude,
            "period": period,
            "periods": PEER_PERIODS,
            "engine_rhs_ns": sim.rhs_cost_ns(),
        }),
        anschutz4: a4,
        anschutz_linear: lin_peer,
        atol_factor,
        points,
    })
}

/// Villarceau's points at one tolerance and method: hand-written eq. 44 bis, the engine
/// (explicit methods only: the implicit ones' AD Jacobian is not the point here), and under
/// DOP853 both again with the first integral kept by projection.
fn villarceau_points(
    opts: &StudyOptions,
    sim: &Simulation,
    v: Villarceau,
    amplitude: f64,
    t_end: f64,
    method: Method,
    tol: &Tolerances,
) -> Vec<PeerPoint> {
    let implicit = matches!(method, Method::Rodas4 | Method::Rodas5p | Method::Radau5);
    let w0 = v.g_over_a.abs().sqrt();
    let mut points = Vec::new();
    let end_error =
        |last: &[f64], x0: &[f64]| (last[0] - x0[0]).hypot((last[1] - x0[1]) / w0) / amplitude;
    let grid = OutputGrid {
        t0: 0.0,
        dt: t_end,
        t_end,
    };
    // Hand-written eq. 44 bis.
    points.push(end_state_point(
        opts,
        "gyrolab eq44bis",
        || Eq44Bis(v, None),
        &[amplitude, 0.0],
        method,
        tol,
        &grid,
        &end_error,
    ));
    // The engine (explicit methods only: the implicit ones' AD Jacobian is not the point
    // here).
    if !implicit {
        points.push(end_state_point(
            opts,
            "gyrolab engine",
            || ModelSystem { model: &sim.model },
            &sim.model.x0,
            method,
            tol,
            &grid,
            &end_error,
        ));
    }
    // Both with the first integral kept by projection (DOP853, the explicit method
    // these rows choose).
    if method == Method::Dop853 {
        let i0 = v.first_integral(amplitude, 0.0);
        points.push(end_state_point(
            opts,
            "gyrolab eq44bis kept",
            || Eq44Bis(v, Some(i0)),
            &[amplitude, 0.0],
            method,
            tol,
            &grid,
            &end_error,
        ));
        points.push(end_state_point(
            opts,
            "gyrolab engine kept",
            || {
                KeptModelSystem::new(&sim.model, 0.0, &sim.model.x0)
                    .expect("Foucault's gyroscope at rest keeps Jacobi's integral")
            },
            &sim.model.x0,
            method,
            tol,
            &grid,
            &end_error,
        ));
    }
    points
}

/// A linear case with its exact solution at the grid times.
struct LinearRun<'a> {
    x0: &'a [f64],
    /// Subtracted from the state before comparing (the equilibrium, for the engine's model).
    offset: &'a [f64],
    /// State indices compared.
    compare: &'a [usize],
    exact: &'a [Vec<f64>],
    scale: f64,
    grid: &'a OutputGrid,
    breakpoints: &'a [f64],
}

impl LinearRun<'_> {
    /// One run (best wall time of a few) within a budget, its error the largest
    /// |x_i − offset_i − exact_i| over the samples and the compared states, over `scale`.
    fn point<S: OdeSystem>(
        &self,
        opts: &StudyOptions,
        implementation: &str,
        system: impl Fn() -> S,
        method: Method,
        tol: &Tolerances,
    ) -> PeerPoint {
        let ((res, stats), wall) = timed(opts, || {
            let mut x = self.x0.to_vec();
            let mut k = 0;
            let mut worst: f64 = 0.0;
            let mut s = Budget::new(system(), 3.0 * opts.max_point_s);
            let r = solvers::integrate(
                &mut s,
                method,
                tol,
                &mut x,
                self.grid,
                self.breakpoints,
                |_, xs| {
                    if let Some(e) = self.exact.get(k) {
                        for &i in self.compare {
                            worst = worst.max((xs[i] - self.offset[i] - e[i]).abs());
                        }
                    }
                    k += 1;
                    ControlFlow::Continue(())
                },
            );
            match s.result(r) {
                Ok((_, st)) => (Some(worst / self.scale), st),
                Err(_) => (None, SolverStats::default()),
            }
        });
        PeerPoint::new(implementation, method, tol, res, wall, &stats)
    }
}

/// One run of `system` from `x0` to the end of `grid` (best wall time of a few), its error
/// measured on the end state by `end_error(last, x0)`.
#[allow(clippy::too_many_arguments)]
fn end_state_point<S: OdeSystem>(
    opts: &StudyOptions,
    implementation: &str,
    system: impl Fn() -> S,
    x0: &[f64],
    method: Method,
    tol: &Tolerances,
    grid: &OutputGrid,
    end_error: &dyn Fn(&[f64], &[f64]) -> f64,
) -> PeerPoint {
    let ((res, stats), wall) = timed(opts, || {
        let mut x = x0.to_vec();
        let mut last = x0.to_vec();
        let r = solvers::integrate(&mut system(), method, tol, &mut x, grid, &[], |_, xs| {
            last.copy_from_slice(xs);
            ControlFlow::Continue(())
        });
        match r {
            Ok((_, s)) => (Some(end_error(&last, x0)), s),
            Err(_) => (None, SolverStats::default()),
        }
    });
    PeerPoint::new(implementation, method, tol, res, wall, &stats)
}
