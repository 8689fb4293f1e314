//! The `[[body]]` entries: the kinematic chain with its joints, hinges, masses and rotors.

use super::{Body, Coordinate, Hinge, Motor, Rotor, RotorSpec, Shape, SourceText, SpinMode};
use crate::error::InputError;
use crate::expr;
use serde::Deserialize;
use std::collections::BTreeMap;

#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
struct RotationFile {
    axis: String,
    angle_deg: f64,
}

#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
struct HingeFile {
    axis: String,
    angle_rad: String,
}

#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct BodyFile {
    pub(super) name: String,
    parent: String,
    #[serde(default)]
    description: String,
    #[serde(default)]
    joint_origin_m: [f64; 3],
    #[serde(default)]
    joint_rotation: Vec<RotationFile>,
    hinge: Option<HingeFile>,
    #[serde(default)]
    mass_kg: f64,
    #[serde(default)]
    cg_m: [f64; 3],
    /// Principal moments about the centre of gravity along the body axes.
    #[serde(default)]
    inertia_kg_m2: [f64; 3],
    /// Products of inertia (Ixy, Ixz, Iyz) about the centre of gravity.
    #[serde(default)]
    products_of_inertia_kg_m2: [f64; 3],
    rotor: Option<RotorSpec>,
    shape: Option<Shape>,
}

/// The `[[body]]` entries in order (a parent is listed before its children); then every
/// non-driven coordinate must move some body.
pub(super) fn bodies(
    body: &[BodyFile],
    coordinates: &[Coordinate],
    coord_names: &[String],
    pot_levels: &[usize],
    parameters: &BTreeMap<String, f64>,
    src: &SourceText,
) -> Result<Vec<Body>, InputError> {
    let body_names: Vec<String> = body.iter().map(|b| b.name.clone()).collect();
    let mut bodies = Vec::new();
    for (bi, b) in body.iter().enumerate() {
        bodies.push(self::body(
            bi,
            b,
            &body_names,
            coord_names,
            parameters,
            src,
        )?);
    }
    if bodies.is_empty() {
        return Err(src.err(
            None,
            "body",
            "body".into(),
            "a design needs at least one body".into(),
        ));
    }
    // Every non-driven coordinate must move something, or its mass matrix row is empty.
    for (i, c) in coordinates.iter().enumerate() {
        if c.servo.is_some() || pot_levels.contains(&i) {
            continue;
        }
        let used = bodies.iter().any(|b| {
            b.hinge
                .as_ref()
                .is_some_and(|h| h.angle.coordinates().contains(&i))
        });
        if !used {
            return Err(src.err(
                Some(&format!("name = \"{}\"", c.name)),
                "name",
                format!("coordinate.{}", c.name),
                "no hinge angle uses this coordinate (and it is no pots' level)".into(),
            ));
        }
    }
    Ok(bodies)
}

/// One `[[body]]`: its parent among the bodies before it, mass and inertia checked, the joint's
/// constant rotation, the hinge and the rotor.
fn body(
    bi: usize,
    b: &BodyFile,
    body_names: &[String],
    coord_names: &[String],
    parameters: &BTreeMap<String, f64>,
    src: &SourceText,
) -> Result<Body, InputError> {
    let anchor = format!("name = \"{}\"", b.name);
    let a = Some(anchor.as_str());
    let path = |k: &str| format!("body.{}.{k}", b.name);
    if body_names[..bi].contains(&b.name) || b.name == "base" {
        return Err(src.err(
            a,
            "name",
            path("name"),
            "duplicate body name (and `base` is reserved)".into(),
        ));
    }
    let parent = if b.parent == "base" {
        None
    } else {
        match body_names[..bi].iter().position(|n| *n == b.parent) {
            Some(p) => Some(p),
            None => {
                return Err(src.err(
                    a,
                    "parent",
                    path("parent"),
                    format!(
                        "unknown parent `{}` (allowed: base or a body listed before this one: {})",
                        b.parent,
                        body_names[..bi].join(", ")
                    ),
                ));
            }
        }
    };
    let check_finite = |key: &str, xs: &[f64]| -> Result<(), InputError> {
        if xs.iter().all(|x| x.is_finite()) {
            Ok(())
        } else {
            Err(src.err(a, key, path(key), "must be finite numbers".into()))
        }
    };
    check_finite("joint_origin_m", &b.joint_origin_m)?;
    check_finite("cg_m", &b.cg_m)?;
    check_finite("inertia_kg_m2", &b.inertia_kg_m2)?;
    check_finite("products_of_inertia_kg_m2", &b.products_of_inertia_kg_m2)?;
    if !(b.mass_kg >= 0.0 && b.mass_kg.is_finite()) {
        return Err(src.err(
            a,
            "mass_kg",
            path("mass_kg"),
            format!("{} is out of range (allowed: ≥ 0 kg)", b.mass_kg),
        ));
    }
    let [ixx, iyy, izz] = b.inertia_kg_m2;
    if ixx < 0.0 || iyy < 0.0 || izz < 0.0 {
        return Err(src.err(
            a,
            "inertia_kg_m2",
            path("inertia_kg_m2"),
            format!(
                "{:?} has a negative moment (allowed: ≥ 0 kg·m²)",
                b.inertia_kg_m2
            ),
        ));
    }
    if ixx + iyy < izz * (1.0 - 1e-12)
        || iyy + izz < ixx * (1.0 - 1e-12)
        || izz + ixx < iyy * (1.0 - 1e-12)
    {
        return Err(src.err(
            a,
            "inertia_kg_m2",
            path("inertia_kg_m2"),
            format!(
                "{:?} violates the triangle inequality of principal moments (each ≤ sum of the other two)",
                b.inertia_kg_m2
            ),
        ));
    }
    let [pxy, pxz, pyz] = b.products_of_inertia_kg_m2;
    let inertia = [[ixx, -pxy, -pxz], [-pxy, iyy, -pyz], [-pxz, -pyz, izz]];
    let rot = joint_rotation(&b.joint_rotation, a, &path, src)?;
    let hinge = match &b.hinge {
        None => None,
        Some(h) => {
            let ax = axis_index(&h.axis).ok_or_else(|| {
                src.err(
                    a,
                    "axis",
                    path("hinge.axis"),
                    format!("unknown axis `{}` (allowed: x, y, z)", h.axis),
                )
            })?;
            let angle = expr::parse(&h.angle_rad, coord_names, parameters)
                .map_err(|m| src.err(a, "angle_rad", path("hinge.angle_rad"), m))?;
            Some(Hinge { axis: ax, angle })
        }
    };
    let rotor = match &b.rotor {
        None => None,
        Some(r) => Some(rotor(r, a, &path, src)?),
    };
    Ok(Body {
        name: b.name.clone(),
        description: b.description.clone(),
        parent,
        joint_origin_m: b.joint_origin_m,
        joint_rotation: rot,
        hinge,
        mass_kg: b.mass_kg,
        cg_m: b.cg_m,
        inertia_kg_m2: inertia,
        rotor,
        shape: b.shape.clone().unwrap_or(Shape::None),
    })
}

/// The joint's constant rotation: the listed rotations about the joint's axes, in order.
fn joint_rotation(
    rotations: &[RotationFile],
    a: Option<&str>,
    path: &dyn Fn(&str) -> String,
    src: &SourceText,
) -> Result<[[f64; 3]; 3], InputError> {
    let mut rot = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for r in rotations {
        let ax = axis_index(&r.axis).ok_or_else(|| {
            src.err(
                a,
                "axis",
                path("joint_rotation.axis"),
                format!("unknown axis `{}` (allowed: x, y, z)", r.axis),
            )
        })?;
        let angle_deg = r.angle_deg;
        if !angle_deg.is_finite() {
            return Err(src.err(
                a,
                "angle_deg",
                path("joint_rotation.angle_deg"),
                "must be finite".into(),
            ));
        }
        rot = crate::dual::M3::<f64>(rot)
            .mul_m(&crate::dual::rot_axis(ax, angle_deg.to_radians()))
            .0;
    }
    Ok(rot)
}

/// A body's rotor: a unit axis, a positive polar inertia, a non-zero spin, and a motor only on a
/// `held` rotor.
fn rotor(
    r: &RotorSpec,
    a: Option<&str>,
    path: &dyn Fn(&str) -> String,
    src: &SourceText,
) -> Result<Rotor, InputError> {
    let n = (r.axis[0].powi(2) + r.axis[1].powi(2) + r.axis[2].powi(2)).sqrt();
    if !(n > 0.0 && n.is_finite()) {
        return Err(src.err(
            a,
            "axis",
            path("rotor.axis"),
            "must be a non-zero finite vector".into(),
        ));
    }
    if !(r.polar_inertia_kg_m2 > 0.0 && r.polar_inertia_kg_m2.is_finite()) {
        return Err(src.err(
            a,
            "polar_inertia_kg_m2",
            path("rotor.polar_inertia_kg_m2"),
            format!(
                "{} is out of range (allowed: > 0 kg·m²)",
                r.polar_inertia_kg_m2
            ),
        ));
    }
    if !(r.spin_rpm.is_finite() && r.spin_rpm != 0.0) {
        return Err(src.err(
            a,
            "spin_rpm",
            path("rotor.spin_rpm"),
            format!(
                "{} is out of range (allowed: non-zero, finite; negative reverses the spin)",
                r.spin_rpm
            ),
        ));
    }
    if r.spin_rpm < 0.0 && !r.reversible {
        return Err(src.err(
            a,
            "spin_rpm",
            path("rotor.spin_rpm"),
            format!(
                "{} reverses the spin, which this design does not allow (allowed: > 0, or set `reversible = true` on a rotor meant to run either way)",
                r.spin_rpm
            ),
        ));
    }
    let motor = match &r.motor {
        None => None,
        Some(m) => {
            if r.spin != SpinMode::Held {
                return Err(src.err(
                    a,
                    "motor",
                    path("rotor.motor"),
                    "a spin motor drives a `held` rotor (contradictory options: a free rotor has no torque about its axis)".into(),
                ));
            }
            let tau = m.spin_up_time_constant_s;
            if !(tau > 0.0 && tau.is_finite()) {
                return Err(src.err(
                    a,
                    "spin_up_time_constant_s",
                    path("rotor.motor.spin_up_time_constant_s"),
                    format!("{tau} is out of range (allowed: > 0 s)"),
                ));
            }
            if !m.initial_spin_rpm.is_finite() {
                return Err(src.err(
                    a,
                    "initial_spin_rpm",
                    path("rotor.motor.initial_spin_rpm"),
                    "must be finite".into(),
                ));
            }
            Some(Motor {
                time_constant_s: tau,
                initial_spin_rad_per_s: m.initial_spin_rpm * crate::constants::RPM_IN_RAD_PER_S,
            })
        }
    };
    Ok(Rotor {
        axis: [r.axis[0] / n, r.axis[1] / n, r.axis[2] / n],
        polar_inertia_kg_m2: r.polar_inertia_kg_m2,
        spin_rad_per_s: r.spin_rpm * crate::constants::RPM_IN_RAD_PER_S,
        mode: r.spin,
        motor,
    })
}

fn axis_index(s: &str) -> Option<usize> {
    match s {
        "x" => Some(0),
        "y" => Some(1),
        "z" => Some(2),
        _ => None,
    }
}
