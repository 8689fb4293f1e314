//! The `[parameters]` table's checks and the `[[coordinate]]` entries.

use super::{Coordinate, CoordinateRole, CoordinateUnit, SourceText};
use crate::error::InputError;
use crate::expr;
use serde::Deserialize;
use std::collections::BTreeMap;

#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct CoordinateFile {
    pub(super) name: String,
    #[serde(default)]
    description: String,
    /// `azimuth` or `tilt`: where a scene's initial offsets go.
    role: Option<String>,
    /// Servo relation (this coordinate is driven to equal the expression).
    servo: Option<String>,
    /// In `gyroscopic` fidelity: force this coordinate's rate to be a state (`false`, e.g. a
    /// pendulous crosspiece whose own inertia sets its motion) or allow it to be precessional
    /// (`true`). Unset: the engine decides from the gyroscopic couplings.
    precessional: Option<bool>,
}

/// Checks the parameters (finite) and reads the coordinates: names unique and apart from the
/// parameters', roles known, servo relations linear and reading only non-driven coordinates.
pub(super) fn coordinates(
    coordinate: &[CoordinateFile],
    parameters: &BTreeMap<String, f64>,
    src: &SourceText,
) -> Result<Vec<Coordinate>, InputError> {
    if coordinate.is_empty() {
        return Err(src.err(
            None,
            "coordinate",
            "coordinate".into(),
            "a design needs at least one coordinate".into(),
        ));
    }
    for (k, v) in parameters {
        if !v.is_finite() {
            return Err(src.err(
                Some("[parameters]"),
                k,
                format!("parameters.{k}"),
                "must be a finite number".into(),
            ));
        }
    }
    let coord_names: Vec<String> = coordinate.iter().map(|c| c.name.clone()).collect();
    for (i, c) in coordinate.iter().enumerate() {
        if coord_names[..i].contains(&c.name) {
            return Err(src.err(
                Some(&format!("name = \"{}\"", c.name)),
                "name",
                format!("coordinate.{}", c.name),
                "duplicate coordinate name".into(),
            ));
        }
        if parameters.contains_key(&c.name) {
            return Err(src.err(
                Some(&format!("name = \"{}\"", c.name)),
                "name",
                format!("coordinate.{}", c.name),
                "a coordinate and a parameter share this name".into(),
            ));
        }
    }
    let mut coordinates = Vec::new();
    for c in coordinate {
        let anchor = format!("name = \"{}\"", c.name);
        let role = match c.role.as_deref() {
            None => None,
            Some("azimuth") => Some(CoordinateRole::Azimuth),
            Some("tilt") => Some(CoordinateRole::Tilt),
            Some(r) => {
                return Err(src.err(
                    Some(&anchor),
                    "role",
                    format!("coordinate.{}.role", c.name),
                    format!("unknown role `{r}` (allowed: azimuth, tilt)"),
                ));
            }
        };
        let servo = match &c.servo {
            None => None,
            Some(s) => {
                let e = expr::parse(s, &coord_names, parameters).map_err(|m| {
                    src.err(
                        Some(&anchor),
                        "servo",
                        format!("coordinate.{}.servo", c.name),
                        m,
                    )
                })?;
                if !e.is_linear() {
                    return Err(src.err(
                        Some(&anchor),
                        "servo",
                        format!("coordinate.{}.servo", c.name),
                        "servo relations must be linear in the coordinates".into(),
                    ));
                }
                Some(e)
            }
        };
        coordinates.push(Coordinate {
            name: c.name.clone(),
            description: c.description.clone(),
            role,
            servo,
            precessional: c.precessional,
            unit: CoordinateUnit::Radian,
        });
    }
    // A servo relation must read only non-driven coordinates (no chains of servos).
    for c in &coordinates {
        if let Some(s) = &c.servo {
            for i in s.coordinates() {
                if coordinates[i].servo.is_some() {
                    return Err(src.err(
                        Some(&format!("name = \"{}\"", c.name)),
                        "servo",
                        format!("coordinate.{}.servo", c.name),
                        format!(
                            "reads `{}`, itself servo-driven (allowed: non-driven coordinates)",
                            coordinates[i].name
                        ),
                    ));
                }
            }
        }
    }
    if coordinates.iter().all(|c| c.servo.is_some()) {
        return Err(src.err(
            None,
            "coordinate",
            "coordinate".into(),
            "every coordinate is servo-driven: nothing left to move".into(),
        ));
    }
    Ok(coordinates)
}
