//! A scene: where the ship starts, what it does (course and speed program), the sea, which compass
//! design it carries (with overrides) and how to simulate it. Read from TOML with units in every
//! key name; errors name the file, the line, the key and what is allowed.

use crate::library;
use crate::program::{SeaState, Segment, SegmentKind, ShipProgram};
use crate::solvers::{Method, Tolerances};
use gyro_model::constants::KNOT_IN_M_PER_S;
use gyro_model::error::{InputError, locate};
use gyro_model::{CoordinateRole, Design, Effects, Fidelity, InitialCondition, ModelOptions};
use serde::Deserialize;
use std::collections::BTreeMap;
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

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct StartFile {
    latitude_deg: f64,
    #[serde(default)]
    longitude_deg: f64,
    #[serde(default)]
    heading_deg: f64,
    #[serde(default)]
    speed_kn: f64,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct CompassFile {
    design: String,
    #[serde(default)]
    design_overrides: BTreeMap<String, toml::Value>,
    #[serde(default)]
    azimuth_offset_deg: f64,
    #[serde(default)]
    tilt_offset_deg: f64,
    /// Other coordinates' offsets by name, degrees.
    #[serde(default)]
    offsets_deg: BTreeMap<String, f64>,
    #[serde(default = "yes")]
    start_from_equilibrium: bool,
    /// `slow`: precessional rates from the precession equations (no nutation excited);
    /// `rest`: every coordinate at rest relative to the Earth (a held compass let go).
    #[serde(default = "slow")]
    start_rates: String,
    /// Compass pivot relative to the ship's roll centre: forward, port, up (m).
    #[serde(default)]
    pivot_m: [f64; 3],
}

fn yes() -> bool {
    true
}
fn slow() -> String {
    "slow".into()
}

#[derive(Clone, Debug, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
enum ProgramFile {
    Steady {
        duration_s: f64,
    },
    SpeedChange {
        to_speed_kn: f64,
        #[serde(default)]
        acceleration_m_per_s2: Option<f64>,
        #[serde(default)]
        duration_s: Option<f64>,
    },
    Turn {
        #[serde(default)]
        to_heading_deg: Option<f64>,
        #[serde(default)]
        by_deg: Option<f64>,
        #[serde(default)]
        rate_deg_per_s: Option<f64>,
        #[serde(default)]
        radius_m: Option<f64>,
    },
    /// Alternating turns about a mean course: heading swings between mean ± swing.
    Zigzag {
        mean_heading_deg: f64,
        swing_deg: f64,
        legs: u32,
        leg_duration_s: f64,
        #[serde(default)]
        rate_deg_per_s: Option<f64>,
        #[serde(default)]
        radius_m: Option<f64>,
    },
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SeaFile {
    #[serde(default)]
    roll_amplitude_deg: f64,
    #[serde(default = "ten")]
    roll_period_s: f64,
    #[serde(default)]
    pitch_amplitude_deg: f64,
    #[serde(default = "ten")]
    pitch_period_s: f64,
}

fn ten() -> f64 {
    10.0
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SimulationFile {
    #[serde(default = "default_fidelity")]
    fidelity: String,
    #[serde(default = "default_integrator")]
    integrator: String,
    #[serde(default = "default_rtol")]
    rtol: f64,
    #[serde(default = "default_atol")]
    atol: f64,
    #[serde(default)]
    max_step_s: Option<f64>,
    /// `auto` (what the scene needs) or `all` (every effect compiled in, even at zero amplitude).
    #[serde(default = "default_effects")]
    effects: String,
    #[serde(default)]
    disable_effects: Vec<String>,
    /// Pose messages at most this often (the state series keeps the full output rate).
    #[serde(default)]
    pose_rate_hz: Option<f64>,
}

impl Default for SimulationFile {
    fn default() -> Self {
        SimulationFile {
            fidelity: default_fidelity(),
            integrator: default_integrator(),
            rtol: default_rtol(),
            atol: default_atol(),
            max_step_s: None,
            effects: default_effects(),
            disable_effects: Vec::new(),
            pose_rate_hz: None,
        }
    }
}
fn default_fidelity() -> String {
    "gyroscopic".into()
}
fn default_integrator() -> String {
    "rodas4".into()
}
fn default_rtol() -> f64 {
    1e-8
}
fn default_atol() -> f64 {
    1e-10
}
fn default_effects() -> String {
    "auto".into()
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
    pub output_rate_hz: Option<f64>,
    pub duration_s: Option<f64>,
}

impl Scene {
    /// Reads a scene from a path or a shipped scene name.
    pub fn load(name_or_path: &str, ov: &SceneOverrides) -> Result<Scene, InputError> {
        let (label, text, dir) = library::read_scene(name_or_path)?;
        Scene::from_toml(&label, &text, dir.as_deref(), ov)
    }

    pub fn from_toml(
        file: &str,
        text: &str,
        dir: Option<&Path>,
        ov: &SceneOverrides,
    ) -> Result<Scene, InputError> {
        let f: SceneFile =
            toml::from_str(text).map_err(|e| gyro_model::error::from_toml(file, text, &e))?;
        let err = |anchor: Option<&str>, key: &str, path: &str, message: String| InputError {
            file: file.to_string(),
            line: locate(text, anchor, key),
            key: path.to_string(),
            message,
        };
        let duration = ov.duration_s.unwrap_or(f.duration_s);
        if !(duration > 0.0 && duration.is_finite() && duration <= 400.0 * 86400.0) {
            return Err(err(
                None,
                "duration_s",
                "duration_s",
                format!("{duration} is out of range (allowed: 0 < duration ≤ 400 days)"),
            ));
        }
        let rate = ov.output_rate_hz.unwrap_or(f.output_rate_hz);
        if !(rate > 0.0 && rate.is_finite() && rate <= 1000.0) {
            return Err(err(
                None,
                "output_rate_hz",
                "output_rate_hz",
                format!("{rate} is out of range (allowed: 0 < rate ≤ 1000 Hz)"),
            ));
        }
        let s = &f.start;
        if !(s.latitude_deg.is_finite() && s.latitude_deg.abs() < 90.0) {
            return Err(err(
                Some("[start]"),
                "latitude_deg",
                "start.latitude_deg",
                format!(
                    "{} is out of range (allowed: −90 < latitude < 90; at the poles North is undefined and so is a gyrocompass)",
                    s.latitude_deg
                ),
            ));
        }
        if !(s.longitude_deg.is_finite()
            && s.heading_deg.is_finite()
            && s.speed_kn.is_finite()
            && s.speed_kn >= 0.0)
        {
            return Err(err(
                Some("[start]"),
                "speed_kn",
                "start",
                "longitude, heading must be finite and speed ≥ 0".into(),
            ));
        }
        // Ship program: build segments with chained start states.
        let mut segments = Vec::new();
        let mut t = 0.0;
        let mut lat = s.latitude_deg.to_radians();
        let mut v = s.speed_kn * KNOT_IN_M_PER_S;
        let mut h = s.heading_deg.to_radians();
        let push = |segments: &mut Vec<Segment>,
                    kind: SegmentKind,
                    dur: f64,
                    t: &mut f64,
                    lat: &mut f64,
                    v: &mut f64,
                    h: &mut f64,
                    manoeuvre: &str,
                    entry: usize,
                    description: String| {
            let seg = Segment {
                kind,
                start_s: *t,
                duration_s: dur,
                latitude0_rad: *lat,
                speed0_m_per_s: *v,
                heading0_rad: *h,
                manoeuvre: manoeuvre.into(),
                entry,
                description,
            };
            let (l1, v1, h1) = ShipProgram::end_state(&seg);
            *lat = l1;
            *v = v1;
            *h = h1;
            *t += dur;
            segments.push(seg);
        };
        let turn_rate = |rate: Option<f64>,
                         radius: Option<f64>,
                         v: f64,
                         entry: usize|
         -> Result<f64, InputError> {
            let key_anchor = None;
            match (rate, radius) {
                (Some(r), None) if r > 0.0 && r.is_finite() => Ok(r.to_radians()),
                (None, Some(rad)) if rad > 0.0 && rad.is_finite() && v > 0.0 => Ok(v / rad),
                (None, Some(_)) => Err(err(
                    key_anchor,
                    "radius_m",
                    &format!("program.{entry}.radius_m"),
                    "a turn by radius needs a positive radius and the ship under way (speed > 0)"
                        .into(),
                )),
                (Some(_), Some(_)) => Err(err(
                    key_anchor,
                    "rate_deg_per_s",
                    &format!("program.{entry}"),
                    "give either rate_deg_per_s or radius_m, not both (contradictory options)"
                        .into(),
                )),
                _ => Err(err(
                    key_anchor,
                    "rate_deg_per_s",
                    &format!("program.{entry}.rate_deg_per_s"),
                    "a turn needs rate_deg_per_s > 0 or radius_m > 0".into(),
                )),
            }
        };
        for (i, p) in f.program.iter().enumerate() {
            match p {
                ProgramFile::Steady { duration_s } => {
                    if !(*duration_s > 0.0 && duration_s.is_finite()) {
                        return Err(err(
                            None,
                            "duration_s",
                            &format!("program.{i}.duration_s"),
                            format!("{duration_s} is out of range (allowed: > 0 s)"),
                        ));
                    }
                    let desc = format!(
                        "steady {:.1} kn on {:.1}°",
                        v / KNOT_IN_M_PER_S,
                        h.to_degrees()
                    );
                    push(
                        &mut segments,
                        SegmentKind::Steady,
                        *duration_s,
                        &mut t,
                        &mut lat,
                        &mut v,
                        &mut h,
                        "steady",
                        i,
                        desc,
                    );
                }
                ProgramFile::SpeedChange {
                    to_speed_kn,
                    acceleration_m_per_s2,
                    duration_s,
                } => {
                    let target = to_speed_kn * KNOT_IN_M_PER_S;
                    if !(target >= 0.0 && target.is_finite()) {
                        return Err(err(
                            None,
                            "to_speed_kn",
                            &format!("program.{i}.to_speed_kn"),
                            format!("{to_speed_kn} is out of range (allowed: ≥ 0 kn)"),
                        ));
                    }
                    let dv = target - v;
                    let dur = match (acceleration_m_per_s2, duration_s) {
                        (Some(a), None) if *a > 0.0 && a.is_finite() => dv.abs() / a,
                        (None, Some(d)) if *d > 0.0 && d.is_finite() => *d,
                        (Some(_), Some(_)) => return Err(err(None, "acceleration_m_per_s2", &format!("program.{i}"), "give either acceleration_m_per_s2 or duration_s, not both (contradictory options)".into())),
                        _ => return Err(err(None, "acceleration_m_per_s2", &format!("program.{i}"), "a speed change needs acceleration_m_per_s2 > 0 or duration_s > 0".into())),
                    };
                    if dur == 0.0 {
                        continue;
                    }
                    let a = dv / dur;
                    let desc = format!(
                        "speed {:.1} → {:.1} kn in {:.0} s",
                        v / KNOT_IN_M_PER_S,
                        to_speed_kn,
                        dur
                    );
                    push(
                        &mut segments,
                        SegmentKind::SpeedChange {
                            acceleration_m_per_s2: a,
                        },
                        dur,
                        &mut t,
                        &mut lat,
                        &mut v,
                        &mut h,
                        "speed_change",
                        i,
                        desc,
                    );
                }
                ProgramFile::Turn {
                    to_heading_deg,
                    by_deg,
                    rate_deg_per_s,
                    radius_m,
                } => {
                    let delta = match (to_heading_deg, by_deg) {
                        (Some(to), None) => {
                            let d = (to.to_radians() - h).rem_euclid(std::f64::consts::TAU);
                            if d > std::f64::consts::PI { d - std::f64::consts::TAU } else { d }
                        }
                        (None, Some(by)) => by.to_radians(),
                        _ => return Err(err(None, "to_heading_deg", &format!("program.{i}"), "a turn needs exactly one of to_heading_deg (shorter way) or by_deg (signed, + to starboard)".into())),
                    };
                    let r = turn_rate(*rate_deg_per_s, *radius_m, v, i)?;
                    if delta == 0.0 {
                        continue;
                    }
                    let desc = format!(
                        "turn {:+.1}° at {:.3}°/s",
                        delta.to_degrees(),
                        r.to_degrees()
                    );
                    push(
                        &mut segments,
                        SegmentKind::Turn {
                            rate_rad_per_s: r * delta.signum(),
                        },
                        delta.abs() / r,
                        &mut t,
                        &mut lat,
                        &mut v,
                        &mut h,
                        "turn",
                        i,
                        desc,
                    );
                }
                ProgramFile::Zigzag {
                    mean_heading_deg,
                    swing_deg,
                    legs,
                    leg_duration_s,
                    rate_deg_per_s,
                    radius_m,
                } => {
                    let r = turn_rate(*rate_deg_per_s, *radius_m, v, i)?;
                    if !(*legs >= 1
                        && *leg_duration_s >= 0.0
                        && swing_deg.is_finite()
                        && *swing_deg > 0.0)
                    {
                        return Err(err(
                            None,
                            "legs",
                            &format!("program.{i}"),
                            "a zig-zag needs legs ≥ 1, leg_duration_s ≥ 0, swing_deg > 0".into(),
                        ));
                    }
                    let mean = mean_heading_deg.to_radians();
                    let swing = swing_deg.to_radians();
                    for leg in 0..*legs {
                        let target = if leg % 2 == 0 {
                            mean + swing
                        } else {
                            mean - swing
                        };
                        let d = target - h;
                        let d = (d + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
                            - std::f64::consts::PI;
                        if d != 0.0 {
                            let desc =
                                format!("zig-zag leg {} turn {:+.1}°", leg + 1, d.to_degrees());
                            push(
                                &mut segments,
                                SegmentKind::Turn {
                                    rate_rad_per_s: r * d.signum(),
                                },
                                d.abs() / r,
                                &mut t,
                                &mut lat,
                                &mut v,
                                &mut h,
                                "zigzag",
                                i,
                                desc,
                            );
                        }
                        if *leg_duration_s > 0.0 {
                            push(
                                &mut segments,
                                SegmentKind::Steady,
                                *leg_duration_s,
                                &mut t,
                                &mut lat,
                                &mut v,
                                &mut h,
                                "steady",
                                i,
                                format!("zig-zag leg {} steady", leg + 1),
                            );
                        }
                    }
                }
            }
        }
        // The last state holds to the end of the scene.
        if t < duration || segments.is_empty() {
            let rest =
                (duration - t)
                    .max(0.0)
                    .max(if segments.is_empty() { duration } else { 0.0 });
            push(
                &mut segments,
                SegmentKind::Steady,
                rest.max(1e-9),
                &mut t,
                &mut lat,
                &mut v,
                &mut h,
                "steady",
                f.program.len(),
                "steady to the end".into(),
            );
        }
        let sea = match &f.sea {
            None => SeaState::default(),
            Some(sf) => {
                if !(sf.roll_amplitude_deg.abs() < 60.0
                    && sf.pitch_amplitude_deg.abs() < 30.0
                    && sf.roll_period_s > 0.5
                    && sf.pitch_period_s > 0.5)
                {
                    return Err(err(
                        Some("[sea]"),
                        "roll_amplitude_deg",
                        "sea",
                        "out of range (allowed: |roll| < 60°, |pitch| < 30°, periods > 0.5 s)"
                            .into(),
                    ));
                }
                SeaState {
                    roll_amplitude_rad: sf.roll_amplitude_deg.to_radians(),
                    roll_period_s: sf.roll_period_s,
                    roll_phase_rad: 0.0,
                    pitch_amplitude_rad: sf.pitch_amplitude_deg.to_radians(),
                    pitch_period_s: sf.pitch_period_s,
                    pitch_phase_rad: 0.0,
                }
            }
        };
        let sim = &f.simulation;
        let force_all = match sim.effects.as_str() {
            "auto" => false,
            "all" => true,
            other => {
                return Err(err(
                    Some("[simulation]"),
                    "effects",
                    "simulation.effects",
                    format!("unknown value `{other}` (allowed: auto, all)"),
                ));
            }
        };
        let program = ShipProgram {
            segments,
            sea,
            end_s: duration,
            force_moving: force_all,
        };
        use gyro_model::ShipMotion;
        let max_lat = program.max_abs_latitude_rad(duration);
        if max_lat >= 89.99f64.to_radians() {
            return Err(err(
                None,
                "program",
                "program",
                format!(
                    "the ship reaches latitude {:.3}°: gyrolab stops short of the pole (allowed: |latitude| < 89.99° throughout)",
                    max_lat.to_degrees()
                ),
            ));
        }
        // Effects: what the scene calls for, or everything.
        let mut effects = if force_all {
            gyro_model::Effects::all()
        } else {
            Effects::default()
        };
        if !force_all {
            effects.base.earth_rotation = true;
            effects.damper = true;
            effects.friction = true;
            let speed = program.has_speed();
            effects.base.transport_rate = speed;
            effects.base.ship_acceleration = speed || program.has_turns();
            effects.base.base_coriolis = speed;
            effects.base.turn_rate = program.has_turns();
            effects.base.roll_pitch = !program.sea.is_calm();
        }
        for name in &sim.disable_effects {
            effects.set(name, false).map_err(|m| {
                err(
                    Some("[simulation]"),
                    "disable_effects",
                    "simulation.disable_effects",
                    m,
                )
            })?;
        }
        let fidelity: Fidelity = match ov.fidelity {
            Some(x) => x,
            None => sim.fidelity.parse().map_err(|m: String| {
                err(Some("[simulation]"), "fidelity", "simulation.fidelity", m)
            })?,
        };
        let method: Method = match ov.method {
            Some(m) => m,
            None => sim.integrator.parse().map_err(|e| {
                err(
                    Some("[simulation]"),
                    "integrator",
                    "simulation.integrator",
                    format!("{e} (allowed: dopri5, dop853, rk4[:step_s], rodas4)"),
                )
            })?,
        };
        let rtol = ov.rtol.unwrap_or(sim.rtol);
        let atol = ov.atol.unwrap_or(sim.atol);
        if !(rtol > 0.0 && rtol < 1.0 && atol > 0.0 && atol.is_finite()) {
            return Err(err(
                Some("[simulation]"),
                "rtol",
                "simulation.rtol",
                format!("rtol {rtol}, atol {atol} out of range (allowed: 0 < rtol < 1, atol > 0)"),
            ));
        }
        let max_step = sim.max_step_s.unwrap_or(f64::INFINITY);
        if max_step.is_nan() || max_step <= 0.0 {
            return Err(err(
                Some("[simulation]"),
                "max_step_s",
                "simulation.max_step_s",
                "must be > 0".into(),
            ));
        }
        // Design.
        let c = &f.compass;
        let design_ref = ov.design.clone().unwrap_or_else(|| c.design.clone());
        let (design_label, design_text) = library::read_design(&design_ref, dir)?;
        let overrides: Vec<(String, toml::Value)> = c
            .design_overrides
            .iter()
            .map(|(k, v)| (k.clone(), v.clone()))
            .collect();
        let design = Design::from_toml(&design_label, &design_text, &overrides)?;
        // Spin-motor dynamics: compiled when the design has a motor and the scene does not
        // disable it (with `effects = "all"` it is asked for; a motorless design compiles none).
        if !force_all {
            let has_motor = design
                .bodies
                .iter()
                .any(|b| b.rotor.as_ref().is_some_and(|r| r.motor.is_some()));
            effects.spin_motor =
                has_motor && !sim.disable_effects.iter().any(|e| e == "spin_motor");
        }
        // Initial condition.
        let mut offsets = Vec::new();
        for (role, deg, key) in [
            (
                CoordinateRole::Azimuth,
                c.azimuth_offset_deg,
                "azimuth_offset_deg",
            ),
            (CoordinateRole::Tilt, c.tilt_offset_deg, "tilt_offset_deg"),
        ] {
            if !deg.is_finite() {
                return Err(err(
                    Some("[compass]"),
                    key,
                    &format!("compass.{key}"),
                    "must be finite".into(),
                ));
            }
            if deg != 0.0 {
                let i = design.role_index(role).ok_or_else(|| {
                    err(
                        Some("[compass]"),
                        key,
                        &format!("compass.{key}"),
                        format!("design `{}` has no coordinate with this role", design.name),
                    )
                })?;
                offsets.push((i, deg.to_radians()));
            }
        }
        for (name, deg) in &c.offsets_deg {
            let i = design.coordinate_index(name).ok_or_else(|| {
                err(
                    Some("[compass"),
                    name,
                    &format!("compass.offsets_deg.{name}"),
                    format!(
                        "unknown coordinate (allowed: {})",
                        design
                            .coordinates
                            .iter()
                            .map(|c| c.name.as_str())
                            .collect::<Vec<_>>()
                            .join(", ")
                    ),
                )
            })?;
            offsets.push((i, deg.to_radians()));
        }
        let pose_rate = sim.pose_rate_hz.unwrap_or(rate.min(10.0));
        if pose_rate.is_nan() || pose_rate <= 0.0 {
            return Err(err(
                Some("[simulation]"),
                "pose_rate_hz",
                "simulation.pose_rate_hz",
                "must be > 0".into(),
            ));
        }
        Ok(Scene {
            name: f.name,
            description: f.description,
            duration_s: duration,
            output_rate_hz: rate,
            start_latitude_rad: s.latitude_deg.to_radians(),
            start_longitude_rad: s.longitude_deg.to_radians(),
            program,
            design,
            design_path: design_label,
            design_overrides: overrides,
            fidelity,
            method,
            tolerances: Tolerances {
                rtol,
                atol,
                max_step_s: max_step,
                initial_step_s: None,
            },
            effects,
            initial: InitialCondition {
                from_equilibrium: c.start_from_equilibrium,
                offsets_rad: offsets,
                rates_rad_per_s: vec![],
                slow_start: match c.start_rates.as_str() {
                    "slow" => true,
                    "rest" => false,
                    other => {
                        return Err(err(
                            Some("[compass]"),
                            "start_rates",
                            "compass.start_rates",
                            format!("unknown value `{other}` (allowed: slow, rest)"),
                        ));
                    }
                },
            },
            pivot_m: c.pivot_m,
            pose_rate_hz: pose_rate,
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
pub fn resolve_path(reference: &str, dir: Option<&Path>, folder: &str) -> Option<PathBuf> {
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
