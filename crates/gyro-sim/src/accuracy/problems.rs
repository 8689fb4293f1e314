//! The problems the cases solve: Foucault gyroscopes released from rest, the Anschütz scenes,
//! and the hand-written linear systems with their exact solutions.

use crate::run::Simulation;
use crate::scene::{Scene, SceneOverrides};
use crate::solvers::{OdeSystem, OutputGrid};
use gyro_model::Fidelity;
use gyro_model::theory::{Villarceau, foucault_villarceau};
use serde::Serialize;

pub(super) fn scene(text: &str, fidelity: Option<Fidelity>) -> Result<Scene, String> {
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
    fn is_autonomous(&self) -> bool {
        true
    }
    fn jacobian_is_constant(&self) -> bool {
        true
    }
}

/// Length of the Anschütz cases: about one damped period (4110 s at 50°N).
pub(super) const HOURS: f64 = 1.0;

pub(super) fn anschutz_text(fidelity: &str, hours: f64, azimuth_offset_deg: f64) -> String {
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
pub(super) fn exact_linear(a: &[f64], n: usize, x0: &[f64], grid: &OutputGrid) -> Vec<Vec<f64>> {
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

pub(super) fn spectral_radius(a: &[f64], n: usize) -> f64 {
    gyro_model::linalg::eigenvalues(a, n)
        .iter()
        .map(|(re, im)| re.hypot(*im))
        .fold(0.0, f64::max)
}
