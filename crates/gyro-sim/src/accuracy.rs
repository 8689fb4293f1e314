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

use crate::run::{ModelSystem, Simulation};
use crate::scene::{Scene, SceneOverrides};
use crate::solvers::{self, Method, OdeSystem, OutputGrid, SolverStats, Tolerances};
use gyro_model::Fidelity;
use gyro_model::theory::{Villarceau, foucault_villarceau};
use serde::Serialize;
use std::fmt::{self, Write as _};
use std::ops::ControlFlow;
use std::time::Instant;

/// The cases run when none is named (all of them).
pub const DEFAULT_CASES: [&str; 8] = [
    "villarceau-small",
    "villarceau-large",
    "villarceau-separatrix",
    "jacobi-latitude",
    "anschutz-linear",
    "anschutz-4state",
    "anschutz-nonlinear",
    "fidelity",
];

/// Every case with a one-line description.
pub fn case_descriptions() -> Vec<(&'static str, &'static str)> {
    vec![
        (
            "villarceau-small",
            "Foucault azimuth gyroscope, 45°N, released 10° off: state after 10 exact periods",
        ),
        (
            "villarceau-large",
            "Foucault azimuth gyroscope, 45°N, released 90° off: state after 10 exact periods",
        ),
        (
            "villarceau-separatrix",
            "Foucault azimuth gyroscope, 45°N, released 178° off (near the separatrix): state after 4 exact periods",
        ),
        (
            "jacobi-latitude",
            "Foucault latitude gyroscope, released 90° off: drift of the Jacobi integral (eq. 47) over 10 periods",
        ),
        (
            "anschutz-linear",
            "Anschütz 1906 at 50°N, the engine's exact linearisation (8 states): against exp(At) over 1 h",
        ),
        (
            "anschutz-4state",
            "Beghin's elementary linear Anschütz (4 states, the Python peer's case): against exp(At) over 1 h",
        ),
        (
            "anschutz-nonlinear",
            "Anschütz 1906 at 50°N released 10° off, gyroscopic fidelity, 1 h: against DOP853 at rtol 1e-13",
        ),
        (
            "fidelity",
            "Anschütz 1906 at 50°N released 10° off, 1 h, at full, gyroscopic and linear fidelity: against full at RODAS4 rtol 1e-8",
        ),
    ]
}

/// What to run.
#[derive(Clone, Debug)]
pub struct StudyOptions {
    /// Integrators studied (RK4's step is chosen per tolerance, see [`rk4_step`]).
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
                Method::Rodas4,
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

/// One run of one configuration.
#[derive(Clone, Debug, Serialize)]
pub struct Point {
    /// `dopri5`, `dop853`, `rodas4`, `rk4`, or `expm` (exact propagation of `linear`).
    pub method: String,
    pub fidelity: String,
    /// Relative tolerance asked for (for RK4: the tolerance its step was chosen from).
    pub rtol: f64,
    /// RK4's fixed step, s.
    pub step_s: Option<f64>,
    /// Achieved error (see the case's `error_measure`); `None` when the run failed.
    pub error: Option<f64>,
    pub wall_s: f64,
    pub rhs_evals: u64,
    pub jacobian_evals: u64,
    pub steps: u64,
    pub rejected_steps: u64,
    /// Why the run failed or was skipped.
    pub note: Option<String>,
}

impl Point {
    /// The curve this point belongs to: the method, and the fidelity when the case has several.
    pub fn curve(&self, several_fidelities: bool) -> String {
        if several_fidelities {
            format!("{}/{}", self.method, self.fidelity)
        } else {
            self.method.clone()
        }
    }
}

/// One case's results.
#[derive(Clone, Debug, Serialize)]
pub struct CaseReport {
    pub name: String,
    pub description: String,
    /// What the exact answer is.
    pub reference: String,
    /// How the error is measured.
    pub error_measure: String,
    /// Wall time of the reference run when there is one, s.
    pub reference_wall_s: Option<f64>,
    pub points: Vec<Point>,
    /// "for 1e-6 on this case, use …, it costs …".
    pub verdict: String,
}

impl CaseReport {
    fn several_fidelities(&self) -> bool {
        let first = self.points.first().map(|p| p.fidelity.as_str());
        self.points
            .iter()
            .any(|p| Some(p.fidelity.as_str()) != first)
    }
}

/// The whole study.
#[derive(Clone, Debug, Serialize)]
pub struct StudyReport {
    pub target_error: f64,
    pub tolerances: Vec<f64>,
    pub cases: Vec<CaseReport>,
    pub total_wall_s: f64,
    pub version: String,
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
    Plot(String),
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
            StudyError::Plot(m) => write!(f, "cannot write the plot: {m}"),
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

/// RK4's step for a tolerance on a problem with characteristic time `t_char`: a fourth-order
/// method's error per unit time scales as (h/t_char)⁴, so h = t_char · (tol/10)^¼ / 4 puts its
/// points on the same error scale as the adaptive methods' tolerances.
pub fn rk4_step(t_char: f64, tol: f64) -> f64 {
    0.25 * t_char * (0.1 * tol).powf(0.25)
}

// ---------------------------------------------------------------------------------------------
// Cases

/// What a case measures.
enum Kind {
    /// Periodic engine model: state after `periods` exact periods vs the start.
    Periodic {
        sim: Simulation,
        x0: Vec<f64>,
        omega0: f64,
        amplitude: f64,
        t_end: f64,
    },
    /// Largest drift of Villarceau's first integral.
    FirstIntegral {
        sim: Simulation,
        v: Villarceau,
        centre_offset: f64,
        dt: f64,
        t_end: f64,
    },
    /// ẋ = A x against exp(A t) x₀ on a grid; error = max |Δx_i| / scale over `compare` indices.
    Linear {
        sys: LinearSystem,
        x0: Vec<f64>,
        exact: Vec<Vec<f64>>,
        grid: OutputGrid,
        compare: Vec<usize>,
        scale: f64,
        atol_factor: f64,
    },
    /// Engine scenes at one or more fidelities against a reference reading-error series.
    Reference {
        sims: Vec<(Fidelity, Simulation)>,
        reference: Vec<f64>,
        reference_wall_s: f64,
        scale: f64,
    },
}

struct Case {
    name: String,
    description: String,
    reference: String,
    error_measure: String,
    /// Characteristic time (RK4's step scale), s.
    t_char: f64,
    /// atol = rtol × this (state units).
    atol_factor: f64,
    /// Estimated RHS cost of one unit of work for skipping hopeless RK4 points: RHS evals per
    /// second of simulated time at the RK4 step.
    t_end: f64,
    /// Spectral radius of the Jacobian at the start, 1/s (explicit methods' stability limit).
    rho: f64,
    kind: Kind,
}

fn scene(text: &str, fidelity: Option<Fidelity>) -> Result<Scene, String> {
    let ov = SceneOverrides {
        fidelity,
        ..Default::default()
    };
    Scene::from_toml("<accuracy case>", text, None, &ov).map_err(|e| e.to_string())
}

fn foucault_text(ring_axis_elevation_deg: f64) -> String {
    format!(
        r#"name = "accuracy-foucault"
duration_s = 1.0
[start]
latitude_deg = 45.0
[compass]
design = "foucault-gyroscope"
design_overrides = {{ "parameters.ring_axis_elevation_deg" = {ring_axis_elevation_deg} }}
start_from_equilibrium = false
[simulation]
fidelity = "full"
integrator = "dop853"
"#
    )
}

/// A Foucault gyroscope released at rest `amplitude` from its centre: the simulation, Villarceau's
/// constants for this start, and the hinge angle of the centre.
pub fn foucault_release(
    ring_axis_elevation_deg: f64,
    amplitude_rad: f64,
) -> Result<(Simulation, Villarceau, f64), String> {
    let sc = scene(&foucault_text(ring_axis_elevation_deg), None)?;
    foucault_release_scene(sc, amplitude_rad)
}

/// [`foucault_release`] for any scene whose design is built like `foucault-gyroscope` (a `ring`
/// with coordinate `gamma` carrying a `torus`): the scene's own start offsets are replaced.
pub fn foucault_release_scene(
    mut sc: Scene,
    amplitude_rad: f64,
) -> Result<(Simulation, Villarceau, f64), String> {
    let lat = sc.start_latitude_rad;
    let gi = sc
        .design
        .coordinate_index("gamma")
        .ok_or("no coordinate gamma")?;
    let probe = Simulation::new(&sc).map_err(|e| e.to_string())?;
    let torus = probe
        .model
        .design
        .body_index("torus")
        .ok_or("no body torus")?;
    let (v0, offset) =
        foucault_villarceau(&probe.model.design, probe.model.spin_momentum[torus], lat)
            .ok_or("not a Foucault gyroscope")?;
    let centre = offset + v0.centre();
    sc.initial.offsets_rad = vec![(gi, centre + amplitude_rad)];
    let sim = Simulation::new(&sc).map_err(|e| e.to_string())?;
    // n = w + ω cos θ₀ depends on the start: Villarceau's constants of this model.
    let (v, _) = foucault_villarceau(&sim.model.design, sim.model.spin_momentum[torus], lat)
        .ok_or("not a Foucault gyroscope")?;
    Ok((sim, v, centre))
}

fn periodic_case(name: &str, amplitude_deg: f64, periods: f64) -> Result<Case, String> {
    let amplitude = amplitude_deg.to_radians();
    let (sim, v, _) = foucault_release(90.0, amplitude)?;
    let period = v.period(amplitude);
    let t_end = periods * period;
    Ok(Case {
        name: name.into(),
        description: String::new(),
        reference: format!(
            "Villarceau's exact period T = {period:.12} s (quadrature of eq. 47, δ = {:.3e}); the state after {periods} T equals the start",
            v.delta
        ),
        error_measure: "√(Δγ² + (Δγ̇/ω₀)²) / γ₀ at t = N·T".into(),
        t_char: period,
        atol_factor: 1e-3,
        t_end,
        rho: 0.0,
        kind: Kind::Periodic {
            x0: sim.model.x0.clone(),
            sim,
            omega0: v.g_over_a.abs().sqrt(),
            amplitude,
            t_end,
        },
    })
}

fn jacobi_case() -> Result<Case, String> {
    let amplitude = 90f64.to_radians();
    let (sim, v, centre) = foucault_release(0.0, amplitude)?;
    let period = v.period(amplitude);
    let t_end = 10.0 * period;
    Ok(Case {
        name: "jacobi-latitude".into(),
        description: String::new(),
        reference: format!(
            "Villarceau's first integral γ′² − (2g/a)(cos γ − δ cos²γ) is constant (g/a = {:.6e} /s², δ = {:.3e})",
            v.g_over_a, v.delta
        ),
        error_measure: "max |I(t) − I(0)| / (2|g/a|), sampled 50 times per period".into(),
        t_char: period,
        atol_factor: 1e-3,
        t_end,
        rho: 0.0,
        kind: Kind::FirstIntegral {
            sim,
            v,
            centre_offset: centre - v.centre(),
            dt: period / 50.0,
            t_end,
        },
    })
}

/// ẋ = A x.
#[derive(Clone, Debug)]
pub struct LinearSystem {
    pub a: Vec<f64>,
    pub n: usize,
}

impl OdeSystem for LinearSystem {
    fn dim(&self) -> usize {
        self.n
    }
    fn rhs(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) {
        for (i, d) in dx.iter_mut().enumerate() {
            let row = &self.a[i * self.n..(i + 1) * self.n];
            *d = row.iter().zip(x).map(|(a, b)| a * b).sum();
        }
    }
    fn jacobian(&mut self, _t: f64, _x: &[f64], jac: &mut [f64]) -> bool {
        jac.copy_from_slice(&self.a);
        true
    }
}

/// Length of the Anschütz cases: about one damped period (4110 s at 50°N).
const HOURS: f64 = 1.0;

fn anschutz_text(fidelity: &str, hours: f64, azimuth_offset_deg: f64) -> String {
    format!(
        r#"name = "accuracy-anschutz"
duration_s = {}
output_rate_hz = {}
[start]
latitude_deg = 50.0
[compass]
design = "anschutz-1906"
azimuth_offset_deg = {azimuth_offset_deg}
[simulation]
fidelity = "{fidelity}"
integrator = "rodas4"
"#,
        hours * 3600.0,
        1.0 / 60.0
    )
}

/// Exact solution of ẋ = A x at the grid times.
fn exact_linear(a: &[f64], n: usize, x0: &[f64], grid: &OutputGrid) -> Vec<Vec<f64>> {
    let e = gyro_model::linalg::expm(a, n, grid.dt);
    let steps = ((grid.t_end - grid.t0) / grid.dt).round() as usize;
    let mut out = vec![x0.to_vec()];
    for _ in 0..steps {
        let last = out.last().map(|v| v.to_vec()).unwrap_or_default();
        out.push(
            (0..n)
                .map(|i| (0..n).map(|j| e[i * n + j] * last[j]).sum())
                .collect(),
        );
    }
    out
}

fn anschutz_linear_case() -> Result<Case, String> {
    let sc = scene(&anschutz_text("linear", HOURS, 2.0), None)?;
    let sim = Simulation::new(&sc).map_err(|e| e.to_string())?;
    let n = sim.model.dim();
    let a = sim.model.linear_matrix().to_vec();
    let x0: Vec<f64> = sim
        .model
        .x0
        .iter()
        .zip(&sim.model.x_equilibrium)
        .map(|(a, b)| a - b)
        .collect();
    let grid = sim.grid;
    let exact = exact_linear(&a, n, &x0, &grid);
    let ni = n / 2;
    Ok(Case {
        name: "anschutz-linear".into(),
        description: String::new(),
        reference: "exact solution exp(A t)·x₀ of the engine's linearisation (scaling and squaring, degree 18)".into(),
        error_measure: "max over minutes and coordinates of |Δq| / 2° release".into(),
        t_char: 4110.0,
        atol_factor: 1e-4,
        t_end: grid.t_end,
        rho: spectral_radius(&a, n),
        kind: Kind::Linear {
            sys: LinearSystem { a, n },
            x0,
            exact,
            grid,
            compare: (0..ni).collect(),
            scale: 2f64.to_radians(),
            atol_factor: 1e-4,
        },
    })
}

/// Beghin's elementary linear Anschütz with the design's numbers (the Python peer's case):
/// ℭζ̈ + dζ̇ + τζ − IΩθ̇ = 0, 𝔅θ̈ + dθ̇ + aPθ + IΩζ̇ + κζ = 0; state (ζ, θ, ζ̇, θ̇).
#[derive(Clone, Debug, Serialize)]
pub struct Anschutz4 {
    pub spin_momentum: f64,
    pub pendulous_moment: f64,
    pub kappa: f64,
    pub tau: f64,
    pub inertia_vertical: f64,
    pub inertia_east_west: f64,
    pub drag: f64,
    /// Start: ζ₀ (rad), θ₀ = 0, rates from the precession equations (no nutation excited).
    pub x0: [f64; 4],
    pub t_end: f64,
    pub dt: f64,
}

impl Anschutz4 {
    pub fn from_design() -> Result<Anschutz4, String> {
        let sc = scene(&anschutz_text("gyroscopic", HOURS, 2.0), None)?;
        let d = &sc.design;
        let p = |k: &str| d.parameter(k).ok_or(format!("design has no parameter {k}"));
        let h = p("spin_momentum_n_m_s")?;
        let ap = p("pendulous_moment_n_m")?;
        let kappa = p("kappa_n_m")?;
        let drag = p("mercury_drag_n_m_s_per_rad")?;
        let tau = h * gyro_model::constants::EARTH_RATE_RAD_PER_S * sc.start_latitude_rad.cos();
        let z0 = 2f64.to_radians();
        Ok(Anschutz4 {
            spin_momentum: h,
            pendulous_moment: ap,
            kappa,
            tau,
            inertia_vertical: 0.08,
            inertia_east_west: 0.08,
            drag,
            x0: [z0, 0.0, -kappa * z0 / h, tau * z0 / h],
            t_end: HOURS * 3600.0,
            dt: 60.0,
        })
    }

    pub fn matrix(&self) -> Vec<f64> {
        let (c, b, h, d) = (
            self.inertia_vertical,
            self.inertia_east_west,
            self.spin_momentum,
            self.drag,
        );
        #[rustfmt::skip]
        let a = vec![
            0.0, 0.0, 1.0, 0.0,
            0.0, 0.0, 0.0, 1.0,
            -self.tau / c, 0.0, -d / c, h / c,
            -self.kappa / b, -self.pendulous_moment / b, -h / b, -d / b,
        ];
        a
    }
}

fn spectral_radius(a: &[f64], n: usize) -> f64 {
    gyro_model::linalg::eigenvalues(a, n)
        .iter()
        .map(|(re, im)| re.hypot(*im))
        .fold(0.0, f64::max)
}

fn anschutz_4state_case() -> Result<Case, String> {
    let p = Anschutz4::from_design()?;
    let a = p.matrix();
    let grid = OutputGrid {
        t0: 0.0,
        dt: p.dt,
        t_end: p.t_end,
    };
    let exact = exact_linear(&a, 4, &p.x0, &grid);
    Ok(Case {
        name: "anschutz-4state".into(),
        description: String::new(),
        reference: "exact solution exp(A t)·x₀ of Beghin's elementary linear Anschütz".into(),
        error_measure: "max over minutes of |Δζ|, |Δθ| / 2° release".into(),
        t_char: 4110.0,
        atol_factor: 1e-4,
        t_end: p.t_end,
        rho: spectral_radius(&a, 4),
        kind: Kind::Linear {
            sys: LinearSystem { a, n: 4 },
            x0: p.x0.to_vec(),
            exact,
            grid,
            compare: vec![0, 1],
            scale: 2f64.to_radians(),
            atol_factor: 1e-4,
        },
    })
}

fn reading_series(sim: &Simulation, method: Method, tol: &Tolerances) -> Result<Vec<f64>, String> {
    let mut out = Vec::new();
    sim.run(method, tol, |t, x| {
        out.push(sim.model.readout(t, x).reading_error_rad);
        ControlFlow::Continue(())
    })
    .map_err(|e| e.to_string())?;
    Ok(out)
}

fn reference_case(name: &str, fidelities: &[Fidelity]) -> Result<Case, String> {
    let hours = HOURS;
    let release = 10f64.to_radians();
    let mut sims = Vec::new();
    for &f in fidelities {
        let sc = scene(&anschutz_text("gyroscopic", hours, 10.0), Some(f))?;
        sims.push((f, Simulation::new(&sc).map_err(|e| e.to_string())?));
    }
    let (ref_fid, ref_method, ref_rtol) = if name == "fidelity" {
        (Fidelity::Full, Method::Rodas4, 1e-8)
    } else {
        (Fidelity::Gyroscopic, Method::Dop853, 1e-13)
    };
    let sc = scene(&anschutz_text("gyroscopic", hours, 10.0), Some(ref_fid))?;
    let ref_sim = Simulation::new(&sc).map_err(|e| e.to_string())?;
    let started = Instant::now();
    let reference = reading_series(
        &ref_sim,
        ref_method,
        &Tolerances {
            rtol: ref_rtol,
            atol: ref_rtol * 1e-4,
            ..Default::default()
        },
    )?;
    let reference_wall_s = started.elapsed().as_secs_f64();
    Ok(Case {
        name: name.into(),
        description: String::new(),
        reference: format!("{ref_fid} fidelity, {ref_method} at rtol {ref_rtol:e}"),
        error_measure: "max over minutes of |Δ reading error| / 10° release".into(),
        t_char: 4110.0,
        atol_factor: 1e-4,
        t_end: hours * 3600.0,
        // The vane's and the heel's fast modes (and, in `full`, the 90 Hz nutation) bound the
        // explicit methods' steps: filled in per fidelity by `study`.
        rho: 0.0,
        kind: Kind::Reference {
            sims,
            reference,
            reference_wall_s,
            scale: release,
        },
    })
}

fn build_case(name: &str) -> Result<Case, String> {
    let mut case = match name {
        "villarceau-small" => periodic_case(name, 10.0, 10.0)?,
        "villarceau-large" => periodic_case(name, 90.0, 10.0)?,
        "villarceau-separatrix" => periodic_case(name, 178.0, 4.0)?,
        "jacobi-latitude" => jacobi_case()?,
        "anschutz-linear" => anschutz_linear_case()?,
        "anschutz-4state" => anschutz_4state_case()?,
        "anschutz-nonlinear" => reference_case(name, &[Fidelity::Gyroscopic])?,
        "fidelity" => reference_case(
            name,
            &[Fidelity::Full, Fidelity::Gyroscopic, Fidelity::Linear],
        )?,
        other => return Err(format!("unknown case {other}")),
    };
    case.description = case_descriptions()
        .iter()
        .find(|(n, _)| *n == name)
        .map(|(_, d)| d.to_string())
        .unwrap_or_default();
    Ok(case)
}

// ---------------------------------------------------------------------------------------------
// Running a case

/// Best wall time over repetitions of `f`, with the result of the first run.
fn timed<T>(opts: &StudyOptions, mut f: impl FnMut() -> T) -> (T, f64) {
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
struct Budget<S> {
    inner: S,
    deadline: Instant,
    calls: u32,
    over: bool,
}

impl<S: OdeSystem> Budget<S> {
    fn new(inner: S, seconds: f64) -> Self {
        Budget {
            inner,
            deadline: Instant::now() + std::time::Duration::from_secs_f64(seconds),
            calls: 0,
            over: false,
        }
    }
    fn result<T>(&self, r: Result<T, solvers::SolveError>) -> Result<T, String> {
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

    fn study(&self, opts: &StudyOptions) -> CaseReport {
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
                    steps: 0,
                    rejected_steps: 0,
                    note: Some("exact propagation by one matrix exponential".into()),
                });
                continue;
            }
            let rho = self.spectral_radius(fi);
            let rhs_cost = self.rhs_cost_s(fi);
            for &m in &opts.methods {
                let mut stopped: Option<String> = None;
                let mut spent = 0.0;
                for &rtol in &opts.tolerances {
                    if stopped.is_none() && spent > opts.max_method_s {
                        stopped = Some(format!(
                            "skipped: {} already spent on this case (budget {})",
                            fmt_time(spent),
                            fmt_time(opts.max_method_s)
                        ));
                    }
                    let method = match m {
                        Method::Rk4 { .. } => Method::Rk4 {
                            step_s: rk4_step(self.t_char, rtol).min(if rho > 0.0 {
                                2.5 / rho
                            } else {
                                f64::INFINITY
                            }),
                        },
                        other => other,
                    };
                    let mut p = Point {
                        method: method.to_string(),
                        fidelity: fidelity.to_string(),
                        rtol,
                        step_s: match method {
                            Method::Rk4 { step_s } => Some(step_s),
                            _ => None,
                        },
                        error: None,
                        wall_s: 0.0,
                        rhs_evals: 0,
                        jacobian_evals: 0,
                        steps: 0,
                        rejected_steps: 0,
                        note: None,
                    };
                    if let Some(why) = &stopped {
                        p.note = Some(why.clone());
                        points.push(p);
                        continue;
                    }
                    // Explicit methods: the stiffest mode bounds the step whatever the tolerance.
                    let predicted = match method {
                        Method::Rk4 { step_s } => 4.0 * self.t_end / step_s,
                        Method::Dopri5 => 6.0 * self.t_end * rho / 3.3,
                        Method::Dop853 => 12.0 * self.t_end * rho / 6.0,
                        Method::Rodas4 => 0.0,
                    };
                    if predicted * rhs_cost > opts.max_point_s {
                        let why = format!(
                            "skipped: stability- or step-bound, ≈ {predicted:.1e} RHS ≈ {} predicted",
                            fmt_time(predicted * rhs_cost)
                        );
                        p.note = Some(why.clone());
                        stopped = Some(why);
                        points.push(p);
                        continue;
                    }
                    let deadline = 3.0 * opts.max_point_s;
                    let started = Instant::now();
                    let (res, wall) = timed(opts, || self.solve(fi, method, rtol, deadline));
                    spent += started.elapsed().as_secs_f64();
                    p.wall_s = wall;
                    match res {
                        Ok((err, stats)) => {
                            p.error = Some(err);
                            p.rhs_evals = stats.rhs_evals;
                            p.jacobian_evals = stats.jacobian_evals;
                            p.steps = stats.steps;
                            p.rejected_steps = stats.rejected_steps;
                        }
                        Err(e) if e == OVER_BUDGET => {
                            let why = format!(
                                "stopped: over the time budget of {} (tighter tolerances skipped)",
                                fmt_time(deadline)
                            );
                            p.note = Some(why.clone());
                            stopped =
                                Some("skipped: a looser tolerance was over the time budget".into());
                        }
                        Err(e) => p.note = Some(format!("failed: {e}")),
                    }
                    points.push(p);
                    // At its stability limit RK4's step no longer follows the tolerance: the
                    // remaining points would repeat this one.
                    if let Method::Rk4 { step_s } = method
                        && step_s < rk4_step(self.t_char, rtol)
                    {
                        stopped = Some(format!(
                            "skipped: RK4 at its stability limit h = {step_s:.2e} s (same as above)"
                        ));
                    }
                }
            }
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

fn describe_config(p: &Point) -> String {
    let fid = if p.method == "expm" {
        String::new()
    } else {
        format!(" at {} fidelity", p.fidelity)
    };
    match (p.method.as_str(), p.step_s) {
        ("expm", _) => "the linear model (exact matrix exponential)".into(),
        (_, Some(h)) => format!("rk4 with h = {h:.3e} s{fid}"),
        (m, None) => format!("{m} at rtol {:.0e}{fid}", p.rtol),
    }
}

fn verdict(r: &CaseReport, target: f64) -> String {
    let best = r
        .points
        .iter()
        .filter(|p| p.error.is_some_and(|e| e <= target))
        .min_by(|a, b| a.wall_s.total_cmp(&b.wall_s));
    match best {
        Some(p) => format!(
            "for {target:.0e} on {}, use {}: it costs {} ({} RHS, {} steps), error {:.1e}",
            r.name,
            describe_config(p),
            fmt_time(p.wall_s),
            p.rhs_evals,
            p.steps,
            p.error.unwrap_or(f64::NAN)
        ),
        None => {
            let closest = r
                .points
                .iter()
                .filter(|p| p.error.is_some())
                .min_by(|a, b| {
                    a.error
                        .unwrap_or(f64::INFINITY)
                        .total_cmp(&b.error.unwrap_or(f64::INFINITY))
                });
            match closest {
                Some(p) => format!(
                    "{target:.0e} is out of reach on {}: the best is {:.1e} with {} ({})",
                    r.name,
                    p.error.unwrap_or(f64::NAN),
                    describe_config(p),
                    fmt_time(p.wall_s)
                ),
                None => format!("no run succeeded on {}", r.name),
            }
        }
    }
}

fn fmt_time(s: f64) -> String {
    if s < 1e-3 {
        format!("{:.0} µs", s * 1e6)
    } else if s < 1.0 {
        format!("{:.2} ms", s * 1e3)
    } else {
        format!("{s:.2} s")
    }
}

// ---------------------------------------------------------------------------------------------
// Output

impl StudyReport {
    /// A plain-text table per case, then the verdicts.
    pub fn table(&self) -> String {
        let mut s = String::new();
        for c in &self.cases {
            let _ = writeln!(s, "== {} — {}", c.name, c.description);
            let _ = writeln!(s, "   reference: {}", c.reference);
            let _ = writeln!(s, "   error:     {}", c.error_measure);
            if let Some(w) = c.reference_wall_s {
                let _ = writeln!(s, "   reference run: {}", fmt_time(w));
            }
            let _ = writeln!(
                s,
                "   {:<8} {:<11} {:>7} {:>10} {:>10} {:>11} {:>9} {:>8} {:>6}",
                "method", "fidelity", "rtol", "rk4 step", "error", "wall", "rhs", "steps", "jac"
            );
            for p in &c.points {
                let err = match p.error {
                    Some(e) => format!("{e:.2e}"),
                    None => "—".into(),
                };
                let _ = writeln!(
                    s,
                    "   {:<8} {:<11} {:>7} {:>10} {:>10} {:>11} {:>9} {:>8} {:>6}{}",
                    p.method,
                    p.fidelity,
                    if p.rtol > 0.0 {
                        format!("{:.0e}", p.rtol)
                    } else {
                        "—".into()
                    },
                    p.step_s.map_or("—".into(), |h| format!("{h:.2e}")),
                    err,
                    if p.error.is_some() {
                        fmt_time(p.wall_s)
                    } else {
                        "—".into()
                    },
                    p.rhs_evals,
                    p.steps,
                    p.jacobian_evals,
                    p.note.as_ref().map_or(String::new(), |n| format!("  {n}"))
                );
            }
            let _ = writeln!(s);
        }
        let _ = writeln!(s, "Verdicts (target error {:.0e}):", self.target_error);
        for c in &self.cases {
            let _ = writeln!(s, "  {}", c.verdict);
        }
        let _ = writeln!(s, "study wall time: {:.1} s", self.total_wall_s);
        s
    }

    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).unwrap_or_else(|e| format!("{{\"error\": \"{e}\"}}"))
    }

    /// Log-log plot: one panel per case (error against wall time), one polyline per method
    /// (per method and fidelity in the `fidelity` case), with a legend.
    pub fn svg(&self) -> String {
        let cols = 2usize.min(self.cases.len().max(1));
        let rows = self.cases.len().div_ceil(cols).max(1);
        let (pw, ph) = (560.0, 380.0);
        let (w, h) = (pw * cols as f64, ph * rows as f64 + 40.0);
        let mut s = String::new();
        let _ = writeln!(
            s,
            r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}" font-family="sans-serif" font-size="11">"#
        );
        let _ = writeln!(s, r#"<rect width="{w}" height="{h}" fill="white"/>"#);
        let _ = writeln!(
            s,
            r#"<text x="{}" y="24" font-size="15" text-anchor="middle">gyrolab accuracy: achieved error against wall time (log-log), one curve per method</text>"#,
            w / 2.0
        );
        for (i, c) in self.cases.iter().enumerate() {
            let x0 = (i % cols) as f64 * pw;
            let y0 = 40.0 + (i / cols) as f64 * ph;
            panel(&mut s, c, x0, y0, pw, ph, self.target_error);
        }
        s.push_str("</svg>\n");
        s
    }

    /// Writes the plot: `.svg` only (PNG would need a rasteriser; convert the SVG, e.g. with
    /// `rsvg-convert`).
    pub fn write_plot(&self, path: &std::path::Path) -> Result<(), StudyError> {
        match path.extension().and_then(|e| e.to_str()) {
            Some(e) if e.eq_ignore_ascii_case("svg") => std::fs::write(path, self.svg())
                .map_err(|e| StudyError::Plot(format!("{}: {e}", path.display()))),
            _ => Err(StudyError::Plot(format!(
                "{}: only .svg is written (convert it to PNG with e.g. `rsvg-convert -o plot.png plot.svg`)",
                path.display()
            ))),
        }
    }
}

const KNOWN_CURVES: [&str; 10] = [
    "dopri5",
    "dop853",
    "rodas4",
    "rk4",
    "expm",
    "rodas4/full",
    "rodas4/gyroscopic",
    "expm/linear",
    "dop853/gyroscopic",
    "dopri5/gyroscopic",
];

const COLOURS: [&str; 10] = [
    "#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#e377c2", "#7f7f7f",
    "#bcbd22", "#17becf",
];

fn decade_range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite() && *v > 0.0) {
        lo = lo.min(v.log10());
        hi = hi.max(v.log10());
    }
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    let (lo, hi) = (lo.floor(), hi.ceil());
    if hi <= lo { (lo, lo + 1.0) } else { (lo, hi) }
}

fn panel(s: &mut String, c: &CaseReport, x0: f64, y0: f64, pw: f64, ph: f64, target: f64) {
    let (l, r, t, b) = (x0 + 62.0, x0 + pw - 150.0, y0 + 28.0, y0 + ph - 42.0);
    let ok: Vec<&Point> = c
        .points
        .iter()
        .filter(|p| p.error.is_some() && p.wall_s > 0.0)
        .collect();
    // Errors below 1e-16 are plotted at 1e-16 (round-off).
    let err = |p: &Point| p.error.unwrap_or(1.0).max(1e-16);
    let (xl, xh) = decade_range(ok.iter().map(|p| p.wall_s));
    let (yl, yh) = decade_range(ok.iter().map(|p| err(p)).chain([target]));
    let px = |v: f64| l + (v.log10() - xl) / (xh - xl) * (r - l);
    let py = |v: f64| b - (v.log10() - yl) / (yh - yl) * (b - t);
    let _ = writeln!(
        s,
        r#"<text x="{}" y="{}" font-size="13" font-weight="bold">{}</text>"#,
        l,
        y0 + 18.0,
        c.name
    );
    let _ = writeln!(
        s,
        r##"<rect x="{l}" y="{t}" width="{}" height="{}" fill="none" stroke="#444"/>"##,
        r - l,
        b - t
    );
    let mut d = xl as i32;
    while d as f64 <= xh {
        let x = px(10f64.powi(d));
        let _ = writeln!(
            s,
            r##"<line x1="{x}" y1="{t}" x2="{x}" y2="{b}" stroke="#ddd"/><text x="{x}" y="{}" text-anchor="middle">1e{d}</text>"##,
            b + 14.0
        );
        d += 1;
    }
    let step = if yh - yl > 10.0 { 2 } else { 1 };
    let mut d = yl as i32;
    while d as f64 <= yh {
        let y = py(10f64.powi(d));
        let _ = writeln!(
            s,
            r##"<line x1="{l}" y1="{y}" x2="{r}" y2="{y}" stroke="#ddd"/><text x="{}" y="{}" text-anchor="end">1e{d}</text>"##,
            l - 4.0,
            y + 4.0
        );
        d += step;
    }
    let ty = py(target);
    let _ = writeln!(
        s,
        r##"<line x1="{l}" y1="{ty}" x2="{r}" y2="{ty}" stroke="#888" stroke-dasharray="4 3"/>"##
    );
    let _ = writeln!(
        s,
        r#"<text x="{}" y="{}" text-anchor="middle">wall time, s</text><text x="{}" y="{}" text-anchor="middle" transform="rotate(-90 {} {})">error</text>"#,
        (l + r) / 2.0,
        b + 30.0,
        x0 + 16.0,
        (t + b) / 2.0,
        x0 + 16.0,
        (t + b) / 2.0
    );
    let several = c.several_fidelities();
    let mut curves: Vec<String> = Vec::new();
    for p in &ok {
        let k = p.curve(several);
        if !curves.contains(&k) {
            curves.push(k);
        }
    }
    for (ci, k) in curves.iter().enumerate() {
        // The same method (or method/fidelity) has the same colour in every panel.
        let colour = KNOWN_CURVES
            .iter()
            .position(|c| c == k)
            .map_or(COLOURS[ci % COLOURS.len()], |i| COLOURS[i % COLOURS.len()]);
        let mut pts: Vec<&&Point> = ok.iter().filter(|p| &p.curve(several) == k).collect();
        pts.sort_by(|a, b| a.wall_s.total_cmp(&b.wall_s));
        let line: Vec<String> = pts
            .iter()
            .map(|p| format!("{:.1},{:.1}", px(p.wall_s), py(err(p))))
            .collect();
        let _ = writeln!(
            s,
            r#"<polyline points="{}" fill="none" stroke="{colour}" stroke-width="1.6"/>"#,
            line.join(" ")
        );
        for p in &pts {
            let _ = writeln!(
                s,
                r#"<circle cx="{:.1}" cy="{:.1}" r="{}" fill="{colour}"><title>{} rtol {:.0e}: error {:.2e}, {}</title></circle>"#,
                px(p.wall_s),
                py(err(p)),
                if pts.len() == 1 { 4.5 } else { 2.6 },
                k,
                p.rtol,
                err(p),
                fmt_time(p.wall_s)
            );
        }
        let ly = t + 8.0 + ci as f64 * 16.0;
        let _ = writeln!(
            s,
            r#"<line x1="{}" y1="{ly}" x2="{}" y2="{ly}" stroke="{colour}" stroke-width="2"/><text x="{}" y="{}">{k}</text>"#,
            r + 10.0,
            r + 30.0,
            r + 35.0,
            ly + 4.0
        );
    }
}

// ---------------------------------------------------------------------------------------------
// The Python peer's cases (analysis/bench/peer.py runs the same equations with SciPy)

/// Villarceau's eq. 44 bis written by hand: γ″ = (g/a)(−sin γ + 2δ sin γ cos γ), state (γ, γ′).
#[derive(Clone, Copy, Debug)]
pub struct Eq44Bis(pub Villarceau);

impl OdeSystem for Eq44Bis {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) {
        dx[0] = x[1];
        dx[1] = self.0.acceleration(x[0]);
    }
    fn jacobian(&mut self, _t: f64, x: &[f64], jac: &mut [f64]) -> bool {
        let (s, c) = x[0].sin_cos();
        jac.copy_from_slice(&[
            0.0,
            1.0,
            self.0.g_over_a * (-c + 2.0 * self.0.delta * (c * c - s * s)),
            0.0,
        ]);
        true
    }
}

/// One peer measurement.
#[derive(Clone, Debug, Serialize)]
pub struct PeerPoint {
    /// `gyrolab eq44bis` (hand-written), `gyrolab engine` (the Lagrangian engine's model),
    /// `gyrolab 4state`.
    pub implementation: String,
    pub method: String,
    pub rtol: f64,
    pub atol: f64,
    pub error: Option<f64>,
    pub wall_s: f64,
    pub rhs_evals: u64,
}

/// The peer cases and gyrolab's side of them.
#[derive(Clone, Debug, Serialize)]
pub struct PeerReport {
    /// Villarceau eq. 44 bis: g/a, δ, release γ₀ (rad, from the centre), exact period, periods.
    pub villarceau: serde_json::Value,
    pub anschutz4: Anschutz4,
    /// atol = rtol × this, on both sides.
    pub atol_factor: f64,
    pub points: Vec<PeerPoint>,
}

/// Villarceau's peer case: the large-amplitude azimuth gyroscope, 100 exact periods.
pub const PEER_PERIODS: f64 = 100.0;

/// Runs gyrolab's side of the peer benchmark: for each tolerance, Villarceau over 100 periods
/// (hand-written eq. 44 bis and the engine) and the 4-state Anschütz, with DOP853, DOPRI5 and
/// RODAS4. Errors are measured exactly as `analysis/bench/peer.py` measures SciPy's.
pub fn peer_report(opts: &StudyOptions) -> Result<PeerReport, StudyError> {
    let setup = |message: String| StudyError::Setup {
        case: "peer".into(),
        message,
    };
    let amplitude = 90f64.to_radians();
    let (sim, v, _) = foucault_release(90.0, amplitude).map_err(setup)?;
    let period = v.period(amplitude);
    let t_end = PEER_PERIODS * period;
    let w0 = v.g_over_a.abs().sqrt();
    let atol_factor = 1e-3;
    let a4 = Anschutz4::from_design().map_err(setup)?;
    let a4m = a4.matrix();
    let grid4 = OutputGrid {
        t0: 0.0,
        dt: a4.dt,
        t_end: a4.t_end,
    };
    let exact4 = exact_linear(&a4m, 4, &a4.x0, &grid4);
    let mut points = Vec::new();
    for &rtol in &opts.tolerances {
        let tol = Tolerances {
            rtol,
            atol: rtol * atol_factor,
            ..Default::default()
        };
        for method in [Method::Dop853, Method::Dopri5, Method::Rodas4] {
            let end_error = |last: &[f64], x0: &[f64]| {
                (last[0] - x0[0]).hypot((last[1] - x0[1]) / w0) / amplitude
            };
            let grid = OutputGrid {
                t0: 0.0,
                dt: t_end,
                t_end,
            };
            // Hand-written eq. 44 bis.
            let ((res, stats), wall) = timed(opts, || {
                let x0 = [amplitude, 0.0];
                let mut x = x0;
                let mut last = x0;
                let r = solvers::integrate(
                    &mut Eq44Bis(v),
                    method,
                    &tol,
                    &mut x,
                    &grid,
                    &[],
                    |_, xs| {
                        last.copy_from_slice(xs);
                        ControlFlow::Continue(())
                    },
                );
                match r {
                    Ok((_, s)) => (Some(end_error(&last, &x0)), s),
                    Err(_) => (None, SolverStats::default()),
                }
            });
            points.push(PeerPoint {
                implementation: "gyrolab eq44bis".into(),
                method: method.to_string(),
                rtol,
                atol: tol.atol,
                error: res,
                wall_s: wall,
                rhs_evals: stats.rhs_evals,
            });
            // The engine (explicit methods only: RODAS4's AD Jacobian is not the point here).
            if method != Method::Rodas4 {
                let ((res, stats), wall) = timed(opts, || {
                    let x0 = sim.model.x0.clone();
                    let mut x = x0.clone();
                    let mut last = x0.clone();
                    let r = solvers::integrate(
                        &mut ModelSystem { model: &sim.model },
                        method,
                        &tol,
                        &mut x,
                        &grid,
                        &[],
                        |_, xs| {
                            last.copy_from_slice(xs);
                            ControlFlow::Continue(())
                        },
                    );
                    match r {
                        Ok((_, s)) => (Some(end_error(&last, &x0)), s),
                        Err(_) => (None, SolverStats::default()),
                    }
                });
                points.push(PeerPoint {
                    implementation: "gyrolab engine".into(),
                    method: method.to_string(),
                    rtol,
                    atol: tol.atol,
                    error: res,
                    wall_s: wall,
                    rhs_evals: stats.rhs_evals,
                });
            }
            // 4-state Anschütz (explicit methods are stability-bound: loosest tolerance only).
            if method == Method::Rodas4 || rtol == opts.tolerances[0] {
                let tol4 = Tolerances {
                    atol: rtol * 1e-4,
                    ..tol
                };
                let ((res, stats), wall) = timed(opts, || {
                    let mut x = a4.x0.to_vec();
                    let mut k = 0;
                    let mut worst: f64 = 0.0;
                    let mut s = Budget::new(
                        LinearSystem {
                            a: a4m.clone(),
                            n: 4,
                        },
                        3.0 * opts.max_point_s,
                    );
                    let r =
                        solvers::integrate(&mut s, method, &tol4, &mut x, &grid4, &[], |_, xs| {
                            if let Some(e) = exact4.get(k) {
                                worst = worst.max((xs[0] - e[0]).abs()).max((xs[1] - e[1]).abs());
                            }
                            k += 1;
                            ControlFlow::Continue(())
                        });
                    match s.result(r) {
                        Ok((_, st)) => (Some(worst / 2f64.to_radians()), st),
                        Err(_) => (None, SolverStats::default()),
                    }
                });
                points.push(PeerPoint {
                    implementation: "gyrolab 4state".into(),
                    method: method.to_string(),
                    rtol,
                    atol: tol4.atol,
                    error: res,
                    wall_s: wall,
                    rhs_evals: stats.rhs_evals,
                });
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
        atol_factor,
        points,
    })
}
