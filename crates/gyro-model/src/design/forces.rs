//! The `[[force]]` entries: dampers, springs, body forces and generalised forces, their
//! expressions parsed against the coordinates and parameters.

use super::{Force, SourceText};
use crate::error::InputError;
use crate::expr;
use serde::Deserialize;
use std::collections::BTreeMap;

#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub(super) enum ForceFile {
    /// Viscous friction on the rate of an expression (Rayleigh function ½c·ė²).
    Damper {
        name: String,
        expr_rad: String,
        coefficient_n_m_s_per_rad: f64,
    },
    /// Spring or torsion wire on an expression: V = ½k(e − rest)² + preload·e.
    Spring {
        name: String,
        expr_rad: String,
        stiffness_n_m_per_rad: f64,
        #[serde(default)]
        rest_rad: f64,
        #[serde(default)]
        preload_n_m: f64,
    },
    /// A force of fixed magnitude along a body-fixed direction, applied at a point of the body
    /// whose coordinates are expressions (e.g. the Anschütz air-jet reaction at (kα, 0, −c)).
    BodyForce {
        name: String,
        body: String,
        direction: [f64; 3],
        force_n: f64,
        point_m: [String; 3],
    },
    /// A generalised force on one coordinate given as an expression of the coordinates
    /// (circulatory forces, e.g. an idealised air-jet damper torque κθ on ζ).
    Generalized {
        name: String,
        coordinate: String,
        torque_n_m: String,
    },
    /// A spring between two bodies attached at a point of each (the twin-gyro's HH′): tension
    /// `tension_n + stiffness_n_per_m·(d − length_m)` at the points' distance d.
    LinkSpring {
        name: String,
        bodies: [String; 2],
        points_m: [[f64; 3]; 2],
        stiffness_n_per_m: f64,
        length_m: f64,
        #[serde(default)]
        tension_n: f64,
    },
}

/// The forces in order, names unique.
pub(super) fn forces(
    force: &[ForceFile],
    body_names: &[String],
    coord_names: &[String],
    parameters: &BTreeMap<String, f64>,
    src: &SourceText,
) -> Result<Vec<Force>, InputError> {
    let mut forces = Vec::new();
    for ff in force {
        let parse_e = |s: &str, name: &str, key: &str| {
            expr::parse(s, coord_names, parameters).map_err(|m| {
                src.err(
                    Some(&format!("name = \"{name}\"")),
                    key,
                    format!("force.{name}.{key}"),
                    m,
                )
            })
        };
        let bad = |name: &str, key: &str, m: String| {
            src.err(
                Some(&format!("name = \"{name}\"")),
                key,
                format!("force.{name}.{key}"),
                m,
            )
        };
        forces.push(match ff {
            ForceFile::Damper { name, expr_rad, coefficient_n_m_s_per_rad } => {
                if !(*coefficient_n_m_s_per_rad >= 0.0 && coefficient_n_m_s_per_rad.is_finite()) {
                    return Err(bad(name, "coefficient_n_m_s_per_rad", format!("{coefficient_n_m_s_per_rad} is out of range (allowed: ≥ 0; a negative damper feeds energy)")));
                }
                Force::Damper { name: name.clone(), expr: parse_e(expr_rad, name, "expr_rad")?, coefficient: *coefficient_n_m_s_per_rad }
            }
            ForceFile::Spring { name, expr_rad, stiffness_n_m_per_rad, rest_rad, preload_n_m } => {
                if ![*stiffness_n_m_per_rad, *rest_rad, *preload_n_m].iter().all(|x| x.is_finite()) {
                    return Err(bad(name, "stiffness_n_m_per_rad", "spring constants must be finite".into()));
                }
                Force::Spring { name: name.clone(), expr: parse_e(expr_rad, name, "expr_rad")?, stiffness: *stiffness_n_m_per_rad, rest: *rest_rad, preload: *preload_n_m }
            }
            ForceFile::BodyForce { name, body, direction, force_n, point_m } => {
                let bi = body_names.iter().position(|n| n == body).ok_or_else(|| bad(name, "body", format!("unknown body `{body}` (allowed: {})", body_names.join(", "))))?;
                let n = (direction[0].powi(2) + direction[1].powi(2) + direction[2].powi(2)).sqrt();
                if !(n > 0.0 && n.is_finite() && force_n.is_finite()) {
                    return Err(bad(name, "direction", "direction must be a non-zero finite vector and force_n finite".into()));
                }
                let p = [parse_e(&point_m[0], name, "point_m")?, parse_e(&point_m[1], name, "point_m")?, parse_e(&point_m[2], name, "point_m")?];
                Force::BodyForce { name: name.clone(), body: bi, direction: direction.map(|x| x / n), force_n: *force_n, point: p }
            }
            ForceFile::Generalized { name, coordinate, torque_n_m } => {
                let ci = coord_names.iter().position(|c| c == coordinate).ok_or_else(|| bad(name, "coordinate", format!("unknown coordinate `{coordinate}` (allowed: {})", coord_names.join(", "))))?;
                Force::Generalized { name: name.clone(), coordinate: ci, torque: parse_e(torque_n_m, name, "torque_n_m")? }
            }
            ForceFile::LinkSpring { name, bodies, points_m, stiffness_n_per_m, length_m, tension_n } => {
                let index = |b: &String| body_names.iter().position(|n| n == b).ok_or_else(|| bad(name, "bodies", format!("unknown body `{b}` (allowed: {})", body_names.join(", "))));
                let ends = [index(&bodies[0])?, index(&bodies[1])?];
                if ends[0] == ends[1] {
                    return Err(bad(name, "bodies", format!("both ends on `{}` (allowed: two different bodies; a spring within one body does no work)", bodies[0])));
                }
                if !points_m.iter().flatten().all(|x| x.is_finite()) {
                    return Err(bad(name, "points_m", "attachment points must be finite".into()));
                }
                if !(*stiffness_n_per_m >= 0.0 && stiffness_n_per_m.is_finite()) {
                    return Err(bad(name, "stiffness_n_per_m", format!("{stiffness_n_per_m} is out of range (allowed: finite, ≥ 0)")));
                }
                if !(*length_m > 0.0 && length_m.is_finite()) {
                    return Err(bad(name, "length_m", format!("{length_m} is out of range (allowed: finite, > 0: the length at which the tension is `tension_n`)")));
                }
                if !tension_n.is_finite() {
                    return Err(bad(name, "tension_n", format!("{tension_n} is out of range (allowed: finite)")));
                }
                Force::LinkSpring { name: name.clone(), bodies: ends, points: *points_m, stiffness: *stiffness_n_per_m, length: *length_m, tension: *tension_n }
            }
        });
    }
    for (i, fo) in forces.iter().enumerate() {
        if forces[..i].iter().any(|g| g.name() == fo.name()) {
            return Err(src.err(
                Some(&format!("name = \"{}\"", fo.name())),
                "name",
                format!("force.{}", fo.name()),
                "duplicate force name".into(),
            ));
        }
    }
    Ok(forces)
}
