//! The cases of the study: their names, and each one set up with its exact answer.

use super::problems::{
    Anschutz4, HOURS, LinearSystem, anschutz_text, exact_linear, foucault_release, scene,
    spectral_radius,
};
use crate::run::Simulation;
use crate::solvers::{Method, OutputGrid, Tolerances};
use gyro_model::Fidelity;
use gyro_model::theory::Villarceau;
use std::ops::ControlFlow;
use std::time::Instant;

/// The cases run when none is named (all of them).
pub(super) const DEFAULT_CASES: [&str; 8] = [
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

/// What a case measures.
pub(super) enum Kind {
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

pub(super) struct Case {
    pub(super) name: String,
    pub(super) description: String,
    pub(super) reference: String,
    pub(super) error_measure: String,
    /// Characteristic time (RK4's step scale), s.
    pub(super) t_char: f64,
    /// atol = rtol × this (state units).
    pub(super) atol_factor: f64,
    /// Estimated RHS cost of one unit of work for skipping hopeless RK4 points: RHS evals per
    /// second of simulated time at the RK4 step.
    pub(super) t_end: f64,
    /// Spectral radius of the Jacobian at the start, 1/s (explicit methods' stability limit).
    pub(super) rho: f64,
    pub(super) kind: Kind,
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

pub(super) fn build_case(name: &str) -> Result<Case, String> {
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
