//! A scene: where the ship starts, what it does (course and speed program), the sea, which compass
//! design it carries (with overrides) and how to simulate it. Read from TOML with units in every
//! key name; errors name the file, the line, the key and what is allowed.

mod compass;
mod program;
mod sea;
mod simulation;
mod start;

use crate::library;
use crate::program::ShipProgram;
use crate::solvers::{Method, Tolerances};
use compass::CompassFile;
use gyro_model::error::{InputError, locate};
use gyro_model::{Design, Effects, Fidelity, InitialCondition, ModelOptions, ShipMotion};
use program::ProgramFile;
use sea::SeaFile;
use serde::Deserialize;
use simulation::SimulationFile;
use start::StartFile;
use std::path::{Path, PathBuf};

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    name: String,
    #[serde(default)]
    description: String,
    duration_s: f64,
    #[serde(default = "default_rate")]
    output_rate_hz: f64,
    start: StartFile,
    compass: CompassFile,
    #[serde(default)]
    program: Vec<ProgramFile>,
    #[serde(default)]
    sea: Option<SeaFile>,
    #[serde(default)]
    simulation: SimulationFile,
}

fn default_rate() -> f64 {
    10.0
}

/// The scene file being read: its errors name the file and find the line in its text.
struct SourceText<'a> {
    file: &'a str,
    text: &'a str,
}

impl SourceText<'_> {
    /// An error at `key` (its line searched after `anchor`), reported under the dotted `path`.
    fn err(&self, anchor: Option<&str>, key: &str, path: &str, message: String) -> InputError {
        InputError {
            file: self.file.to_string(),
            line: locate(self.text, anchor, key),
            key: path.to_string(),
            message,
        }
    }
}

/// A checked scene, ready to compile.
#[derive(Clone, Debug)]
pub struct Scene {
    pub name: String,
    pub description: String,
    pub duration_s: f64,
    pub output_rate_hz: f64,
    pub start_latitude_rad: f64,
    pub start_longitude_rad: f64,
    pub program: ShipProgram,
    pub design: Design,
    pub design_path: String,
    pub design_overrides: Vec<(String, toml::Value)>,
    pub fidelity: Fidelity,
    pub method: Method,
    pub tolerances: Tolerances,
    pub effects: Effects,
    pub initial: InitialCondition,
    pub pivot_m: [f64; 3],
    pub pose_rate_hz: f64,
    /// Whether the run records `/compass/energy`.
    pub record_energy: bool,
    /// Whether the run keeps Jacobi's integral by projection (`[simulation]
    /// keep_jacobi_integral`).
    pub keep_jacobi_integral: bool,
    /// The scene file's text (recorded with every run).
    pub source_text: String,
    pub source_path: String,
}

/// Command-line adjustments applied after reading the file.
#[derive(Clone, Debug, Default)]
pub struct SceneOverrides {
    pub design: Option<String>,
    pub fidelity: Option<Fidelity>,
    pub method: Option<Method>,
    pub rtol: Option<f64>,
    pub atol: Option<f64>,
    /// RADAU5's Jacobian-reuse threshold ([`crate::solvers::Tolerances`]).
    pub jacobian_reuse_contraction: Option<f64>,
    pub output_rate_hz: Option<f64>,
    pub duration_s: Option<f64>,
}

impl Scene {
    /// Reads a scene from a path or a shipped scene name.
    pub fn load(name_or_path: &str, ov: &SceneOverrides) -> Result<Scene, InputError> {
        let (label, text, dir) = library::read_scene(name_or_path)?;
        Scene::from_toml(&label, &text, dir.as_deref(), ov)
    }

    /// Reads and checks a scene, section by section (each section's parser is in its own
    /// module), then reads its design. `dir` is where a design path is looked for first.
    pub fn from_toml(
        file: &str,
        text: &str,
        dir: Option<&Path>,
        ov: &SceneOverrides,
    ) -> Result<Scene, InputError> {
        let f: SceneFile =
            toml::from_str(text).map_err(|e| gyro_model::error::from_toml(file, text, &e))?;
        let src = SourceText { file, text };
        let (duration, rate) = run_length(&f, ov, &src)?;
        start::check(&f.start, &src)?;
        let segments = program::segments(&f.program, &f.start, duration, &src)?;
        let sea = sea::sea_state(f.sea.as_ref(), &src)?;
        let sim = &f.simulation;
        let force_all = simulation::force_all(sim, &src)?;
        let program = ShipProgram {
            segments,
            sea,
            end_s: duration,
            force_moving: force_all,
        };
        check_latitudes(&program, duration, &src)?;
        let mut effects = simulation::effects(sim, &program, force_all, &src)?;
        let (fidelity, method, tolerances) = simulation::solver(sim, ov, &src)?;
        let c = &f.compass;
        let mut loaded = compass::design(c, ov.design.as_ref(), dir, f.start.latitude_deg)?;
        loaded.design = compass::servo(c, loaded.design, &src)?;
        // Spin-motor dynamics: compiled when the design has a motor and the scene does not
        // disable it (with `effects = "all"` it is asked for; a motorless design compiles none).
        if !force_all {
            effects.spin_motor = compass::has_motor(&loaded.design)
                && !sim.disable_effects.iter().any(|e| e == "spin_motor");
        }
        let mut offsets = compass::offsets(c, &loaded.design, &src)?;
        compass::follow_offsets(&loaded.design, &mut offsets);
        let pose_rate = simulation::pose_rate_hz(sim, rate, &src)?;
        let initial = InitialCondition {
            from_equilibrium: c.start_from_equilibrium,
            offsets_rad: offsets,
            rates_rad_per_s: vec![],
            slow_start: compass::slow_start(c, &src)?,
        };
        Ok(Scene {
            name: f.name,
            description: f.description,
            duration_s: duration,
            output_rate_hz: rate,
            start_latitude_rad: f.start.latitude_deg.to_radians(),
            start_longitude_rad: f.start.longitude_deg.to_radians(),
            program,
            design: loaded.design,
            design_path: loaded.label,
            design_overrides: loaded.overrides,
            fidelity,
            method,
            tolerances,
            effects,
            initial,
            pivot_m: c.pivot_m,
            pose_rate_hz: pose_rate,
            record_energy: sim.record_energy,
            keep_jacobi_integral: sim.keep_jacobi_integral,
            source_text: text.to_string(),
            source_path: file.to_string(),
        })
    }

    pub fn model_options(&self) -> ModelOptions {
        ModelOptions {
            fidelity: self.fidelity,
            effects: self.effects,
            pivot_m: self.pivot_m,
            initial: self.initial.clone(),
        }
    }
}

/// Where a scene or design reference points: a path, or a shipped name.
pub(crate) fn resolve_path(reference: &str, dir: Option<&Path>, folder: &str) -> Option<PathBuf> {
    let p = Path::new(reference);
    if p.is_file() {
        return Some(p.to_path_buf());
    }
    if let Some(d) = dir {
        let q = d.join(reference);
        if q.is_file() {
            return Some(q);
        }
        let q = d.join("..").join(folder).join(format!("{reference}.toml"));
        if q.is_file() {
            return Some(q);
        }
    }
    let q = Path::new(folder).join(format!("{reference}.toml"));
    if q.is_file() {
        return Some(q);
    }
    None
}

/// The run's duration and output rate (the command line's first), checked.
fn run_length(
    f: &SceneFile,
    ov: &SceneOverrides,
    src: &SourceText,
) -> Result<(f64, f64), InputError> {
    let duration = ov.duration_s.unwrap_or(f.duration_s);
    if !(duration > 0.0 && duration.is_finite() && duration <= 400.0 * 86400.0) {
        return Err(src.err(
            None,
            "duration_s",
            "duration_s",
            format!("{duration} is out of range (allowed: 0 < duration ≤ 400 days)"),
        ));
    }
    let rate = ov.output_rate_hz.unwrap_or(f.output_rate_hz);
    if !(rate > 0.0 && rate.is_finite() && rate <= 1000.0) {
        return Err(src.err(
            None,
            "output_rate_hz",
            "output_rate_hz",
            format!("{rate} is out of range (allowed: 0 < rate ≤ 1000 Hz)"),
        ));
    }
    Ok((duration, rate))
}

/// gyrolab stops short of the pole: the whole track stays below 89.99°.
fn check_latitudes(
    program: &ShipProgram,
    duration: f64,
    src: &SourceText,
) -> Result<(), InputError> {
    let max_lat = program.max_abs_latitude_rad(duration);
    if max_lat >= 89.99f64.to_radians() {
        return Err(src.err(
            None,
            "program",
            "program",
            format!(
                "the ship reaches latitude {:.3}°: gyrolab stops short of the pole (allowed: |latitude| < 89.99° throughout)",
                max_lat.to_degrees()
            ),
        ));
    }
    Ok(())
}
