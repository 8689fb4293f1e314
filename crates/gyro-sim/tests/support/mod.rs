//! Helpers shared by the physics tests: load shipped scenes with overrides, run them in memory,
//! locate crossings in sampled output.
#![allow(dead_code)]

use gyro_sim::solvers::{Method, Tolerances};
use gyro_sim::{Scene, SceneOverrides, Simulation};
use std::ops::ControlFlow;

use gyro_model::{
    CompiledModel, Design, Effects, Fidelity, InitialCondition, ModelOptions, Moored,
};

/// `d` moored at `lat_deg` on heading 000° with only the Earth's rotation, started from its
/// equilibrium; friction (the design's dampers) on or off.
pub fn moored(
    d: Design,
    lat_deg: f64,
    fidelity: Fidelity,
    friction: bool,
) -> CompiledModel<Moored> {
    let mut fx = Effects::all();
    fx.base = gyro_model::BaseEffects {
        earth_rotation: true,
        ..Default::default()
    };
    fx.friction = friction;
    CompiledModel::compile(
        d,
        Moored {
            latitude_rad: lat_deg.to_radians(),
            heading_rad: 0.0,
        },
        ModelOptions {
            fidelity,
            effects: fx,
            pivot_m: [0.0; 3],
            initial: InitialCondition {
                from_equilibrium: true,
                ..Default::default()
            },
        },
    )
    .expect("compiles")
}

/// The text of the shipped design `designs/NAME.toml`.
pub fn design_text(name: &str) -> String {
    std::fs::read_to_string(gyro_testkit::repo_root!().join(format!("designs/{name}.toml")))
        .expect("shipped design")
}

pub fn scene_text(name: &str) -> String {
    std::fs::read_to_string(gyro_testkit::repo_root!().join(format!("scenes/{name}.toml")))
        .expect("shipped scene")
}

/// Loads a scene from TOML text (designs resolved from the repository's designs/ folder).
pub fn scene_from(text: &str, ov: &SceneOverrides) -> Scene {
    let dir = gyro_testkit::repo_root!().join("scenes");
    match Scene::from_toml("test-scene.toml", text, Some(&dir), ov) {
        Ok(s) => s,
        Err(e) => panic!("scene: {e}"),
    }
}

/// Runs a scene and returns (t, state) samples.
pub fn run(
    scene: &Scene,
    method: Method,
    tol: Tolerances,
) -> (Simulation, Vec<(f64, Vec<f64>)>, gyro_sim::RunStats) {
    let sim = Simulation::new(scene).unwrap_or_else(|e| panic!("{e}"));
    let mut out = Vec::new();
    let stats = sim.run(method, &tol, |t, x| {
        out.push((t, x.to_vec()));
        ControlFlow::Continue(())
    });
    let stats = stats.unwrap_or_else(|e| panic!("{e}"));
    (sim, out, stats)
}

/// A harbour scene of `design` at `lat`, `hours` long, sampled at `rate_hz`, with extra
/// `[compass]` lines; gyroscopic, RODAS4 at rtol 1e-9 / atol 1e-12.
pub fn harbour_scene(design: &str, lat: f64, compass: &str, hours: f64, rate_hz: f64) -> String {
    format!(
        r#"name = "t"
duration_s = {}
output_rate_hz = {rate_hz}
[start]
latitude_deg = {lat}
[compass]
design = "{design}"
{compass}
[simulation]
fidelity = "gyroscopic"
integrator = "rodas4"
rtol = 1e-9
atol = 1e-12
"#,
        hours * 3600.0
    )
}

/// `design` (its parameters overridden) moored at 50°N on `heading_deg`, `duration_s` long,
/// sampled at 2 Hz, 10.035 m above the roll axis, DOP853 at rtol 1e-7 and `fidelity`: with the
/// standard sea (10-s roll of 4°, 0.70 m at the compass) or calm (the scenes the rolling tests
/// difference).
pub fn rolling_scene(
    design: &str,
    overrides: &[(&str, f64)],
    heading_deg: f64,
    duration_s: f64,
    fidelity: &str,
    sea: bool,
) -> Scene {
    let ov: Vec<String> = overrides
        .iter()
        .map(|(k, v)| format!("\"parameters.{k}\" = {v:e}"))
        .collect();
    let text = format!(
        r#"name = "t"
duration_s = {duration_s:e}
output_rate_hz = 2.0
[start]
latitude_deg = 50.0
heading_deg = {heading_deg:e}
[compass]
design = "{design}"
design_overrides = {{ {} }}
pivot_m = [0.0, 0.0, 10.035]
{}
[simulation]
fidelity = "{fidelity}"
integrator = "dop853"
rtol = 1e-7
"#,
        ov.join(", "),
        if sea {
            "[sea]\nroll_amplitude_deg = 4.0\nroll_period_s = 10.0"
        } else {
            ""
        }
    );
    scene_from(&text, &SceneOverrides::default())
}

/// The index of a coordinate by name in the readout's `q`.
pub fn coordinate(sim: &Simulation, name: &str) -> usize {
    sim.model.design.coordinate_index(name).expect(name)
}

pub fn tol(rtol: f64, atol: f64) -> Tolerances {
    Tolerances {
        rtol,
        atol,
        max_step_s: f64::INFINITY,
        initial_step_s: None,
        jacobian_reuse_contraction: gyro_sim::solvers::DEFAULT_JACOBIAN_REUSE_CONTRACTION,
    }
}

/// Times where y crosses zero upward, from samples of y and its rate (cubic Hermite + bisection).
pub fn upward_crossings(t: &[f64], y: &[f64], yd: &[f64]) -> Vec<f64> {
    let mut out = Vec::new();
    for k in 0..t.len().saturating_sub(1) {
        if y[k] < 0.0 && y[k + 1] >= 0.0 {
            let h = t[k + 1] - t[k];
            let p = |s: f64| {
                let s2 = s * s;
                let s3 = s2 * s;
                (2.0 * s3 - 3.0 * s2 + 1.0) * y[k]
                    + (s3 - 2.0 * s2 + s) * h * yd[k]
                    + (-2.0 * s3 + 3.0 * s2) * y[k + 1]
                    + (s3 - s2) * h * yd[k + 1]
            };
            let (mut a, mut b) = (0.0, 1.0);
            for _ in 0..80 {
                let m = 0.5 * (a + b);
                if p(m) < 0.0 { a = m } else { b = m }
            }
            out.push(t[k] + 0.5 * (a + b) * h);
        }
    }
    out
}

/// Mean period from crossing times.
pub fn mean_period(c: &[f64]) -> f64 {
    (c[c.len() - 1] - c[0]) / (c.len() - 1) as f64
}

/// Every shipped scene compiled at each nonlinear fidelity it keeps (a scene whose effects
/// force another fidelity is left out at that one): (label `scene/fidelity`, design name,
/// simulation).
pub fn shipped_models() -> Vec<(String, String, Simulation)> {
    let mut models = Vec::new();
    for (name, _) in gyro_sim::library::SCENES {
        for fidelity in [Fidelity::Full, Fidelity::Gyroscopic] {
            let ov = SceneOverrides {
                fidelity: Some(fidelity),
                ..Default::default()
            };
            let scene = Scene::load(name, &ov).expect("shipped scene loads");
            let sim = Simulation::new(&scene).expect("compiles");
            if sim.model.fidelity == fidelity {
                models.push((format!("{name}/{fidelity}"), scene.design.name, sim));
            }
        }
    }
    models
}
