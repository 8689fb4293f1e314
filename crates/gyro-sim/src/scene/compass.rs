//! The `[compass]` table: which design the ship carries (with overrides), and how it starts.

use super::SourceText;
use crate::library;
use gyro_model::error::InputError;
use gyro_model::{CoordinateRole, Design};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::Path;

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct CompassFile {
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
    pub(super) start_from_equilibrium: bool,
    /// `slow`: precessional rates from the precession equations (no nutation excited);
    /// `rest`: every coordinate at rest relative to the Earth (a held compass let go).
    #[serde(default = "slow")]
    start_rates: String,
    /// Compass pivot relative to the ship's roll centre: forward, port, up (m).
    #[serde(default)]
    pub(super) pivot_m: [f64; 3],
    /// How the design's servos are built: `{ kind = "ideal" }` (the relation holds exactly, the
    /// default) or `{ kind = "pd", stiffness_n_m_per_rad, damping_n_m_s_per_rad }`.
    #[serde(default)]
    servo: Option<ServoFile>,
    /// Run the design even outside the stable region its `[[stability]]` entries state (to
    /// show the instability on purpose); otherwise such a design is refused.
    #[serde(default)]
    allow_unstable: bool,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
enum ServoFile {
    Ideal,
    Pd {
        stiffness_n_m_per_rad: f64,
        damping_n_m_s_per_rad: f64,
    },
}

fn yes() -> bool {
    true
}
fn slow() -> String {
    "slow".into()
}

/// The design as read: its label (path or shipped name), the overrides applied, the design.
pub(super) struct LoadedDesign {
    pub(super) label: String,
    pub(super) overrides: Vec<(String, toml::Value)>,
    pub(super) design: Design,
}

/// The design parameter a scene sets to its starting latitude (degrees).
pub const LATITUDE_DIAL: &str = "latitude_dial_deg";

/// Reads the design the scene names (or `design_override`), found next to the scene or shipped.
pub(super) fn design(
    c: &CompassFile,
    design_override: Option<&String>,
    dir: Option<&Path>,
    latitude_deg: f64,
) -> Result<LoadedDesign, InputError> {
    let design_ref = design_override.cloned().unwrap_or_else(|| c.design.clone());
    let (label, design_text) = library::read_design(&design_ref, dir)?;
    let mut overrides: Vec<(String, toml::Value)> = c
        .design_overrides
        .iter()
        .map(|(k, v)| (k.clone(), v.clone()))
        .collect();
    // A latitude dial (a design parameter `latitude_dial_deg`, e.g. the Sperry's bail setting)
    // is set to the scene's starting latitude, as the navigator sets it, unless the scene sets it.
    let dial = format!("parameters.{LATITUDE_DIAL}");
    let has_dial = toml::from_str::<toml::Value>(&design_text)
        .ok()
        .and_then(|v| v.get("parameters")?.get(LATITUDE_DIAL).cloned())
        .is_some();
    if has_dial && !overrides.iter().any(|(k, _)| *k == dial) {
        overrides.push((dial, toml::Value::Float(latitude_deg)));
    }
    if c.allow_unstable {
        overrides.push(("allow_unstable".into(), toml::Value::Boolean(true)));
    }
    let design = Design::from_toml(&label, &design_text, &overrides)?;
    Ok(LoadedDesign {
        label,
        overrides,
        design,
    })
}

/// Whether the design has a spin motor (with `effects = "auto"` it is then compiled in unless
/// the scene disables it; a motorless design compiles none).
pub(super) fn has_motor(design: &Design) -> bool {
    design
        .bodies
        .iter()
        .any(|b| b.rotor.as_ref().is_some_and(|r| r.motor.is_some()))
}

/// The start offsets, (coordinate index, rad): azimuth and tilt by role, others by name.
pub(super) fn offsets(
    c: &CompassFile,
    design: &Design,
    src: &SourceText,
) -> Result<Vec<(usize, f64)>, InputError> {
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
            return Err(src.err(
                Some("[compass]"),
                key,
                &format!("compass.{key}"),
                "must be finite".into(),
            ));
        }
        if deg != 0.0 {
            let i = design.role_index(role).ok_or_else(|| {
                src.err(
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
            src.err(
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
    Ok(offsets)
}

/// `start_rates`: `slow` (true) or `rest` (false).
/// The design with its servos as the scene asks: ideal (unchanged) or finite-gain PD motors.
pub(super) fn servo(
    c: &CompassFile,
    design: Design,
    src: &SourceText,
) -> Result<Design, InputError> {
    let Some(ServoFile::Pd {
        stiffness_n_m_per_rad: k,
        damping_n_m_s_per_rad: d,
    }) = c.servo
    else {
        return Ok(design);
    };
    let err =
        |key: &str, m: String| src.err(Some("servo"), key, &format!("compass.servo.{key}"), m);
    if !(k.is_finite() && k > 0.0) {
        return Err(err(
            "stiffness_n_m_per_rad",
            format!("{k} is out of range (allowed: > 0)"),
        ));
    }
    if !(d.is_finite() && d >= 0.0) {
        return Err(err(
            "damping_n_m_s_per_rad",
            format!("{d} is out of range (allowed: ≥ 0)"),
        ));
    }
    if design.coordinates.iter().all(|c| c.servo.is_none()) {
        return Err(src.err(
            Some("servo"),
            "kind",
            "compass.servo.kind",
            format!("design `{}` has no servo-driven coordinate", design.name),
        ));
    }
    Ok(design.with_pd_servos(k, d))
}

/// A finite-gain servo's follower starts where its relation puts it: the start offsets of its
/// drivers, carried through the (linear) relation, as an ideal servo would place it.
pub(super) fn follow_offsets(design: &Design, offsets: &mut Vec<(usize, f64)>) {
    for f in &design.forces {
        if let gyro_model::Force::Servo {
            coordinate,
            relation,
            ..
        } = f
        {
            let carried: f64 = relation
                .linear
                .iter()
                .map(|&(j, a)| {
                    a * offsets
                        .iter()
                        .filter(|(i, _)| *i == j)
                        .map(|(_, o)| o)
                        .sum::<f64>()
                })
                .sum();
            if carried != 0.0 {
                offsets.push((*coordinate, carried));
            }
        }
    }
}

pub(super) fn slow_start(c: &CompassFile, src: &SourceText) -> Result<bool, InputError> {
    match c.start_rates.as_str() {
        "slow" => Ok(true),
        "rest" => Ok(false),
        other => Err(src.err(
            Some("[compass]"),
            "start_rates",
            "compass.start_rates",
            format!("unknown value `{other}` (allowed: slow, rest)"),
        )),
    }
}
