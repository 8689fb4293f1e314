//! A compass design: a kinematic chain of bodies joined by hinges, with rotors, force elements
//! and the element whose axis the card reads. Read from TOML (units in every key name), checked,
//! and turned into the immutable [`Design`] the engine compiles.
//!
//! The chain starts at a base: `earth` (the local level North–West–Up frame that follows the
//! compass pivot, e.g. a float free in mercury or Foucault's ring on its trunnions) or `ship`
//! (the hull, which yaws, rolls and pitches). A body's orientation is its parent's, then a
//! constant `joint_rotation`, then the hinge rotation about one of the joint's own axes by an
//! angle that is a (≤ quadratic) expression of the coordinates: a passive relation, substituted
//! into the Lagrangian before the equations are formed. A coordinate declared `servo = "…"` is
//! driven: it has no equation of its own, and its relation is substituted only after the
//! equations of the others are formed (Beghin ch. I).

use crate::error::{InputError, locate};
use crate::expr::{self, QuadExpr};
use serde::Deserialize;
use std::collections::BTreeMap;

/// How the rotor's spin is maintained.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SpinMode {
    /// The motor holds the absolute spin (Beghin §25: P + u = Ω): H = C·Ω.
    Held,
    /// No torque about the spin axis (Villarceau): the absolute spin n is conserved,
    /// n = relative spin + the carrier's rate about the axis at the start.
    Free,
}

#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Root {
    Earth,
    Ship,
}

#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RotorSpec {
    /// Spin axis in the body's frame (normalised on load).
    pub axis: [f64; 3],
    pub polar_inertia_kg_m2: f64,
    /// Spin rate: absolute for `held`, relative to the carrier for `free`.
    pub spin_rpm: f64,
    pub spin: SpinMode,
    /// A spin motor (`held` rotors only): the spin is then a state that relaxes to `spin_rpm`.
    #[serde(default)]
    pub motor: Option<MotorSpec>,
}

/// The rotor's motor as a first-order lag: dΩ/dt = (Ω_rated − Ω)/τ (an induction motor whose
/// torque falls linearly to zero at the rated speed, against the rotor's polar inertia).
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MotorSpec {
    /// τ: the time constant of the spin-up, s.
    pub spin_up_time_constant_s: f64,
    /// Spin when the run starts (the rated spin is the rotor's `spin_rpm`).
    pub initial_spin_rpm: f64,
}

/// What the viewer draws for a body (sizes in metres).
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase", deny_unknown_fields)]
pub enum Shape {
    /// A ring about the body's z axis.
    Ring {
        radius_m: f64,
        width_m: f64,
    },
    /// A disc (rotor) about the body's `axis`.
    Disc {
        radius_m: f64,
        thickness_m: f64,
    },
    Box {
        size_m: [f64; 3],
    },
    Sphere {
        radius_m: f64,
    },
    /// A ship hull outline (box with a bow).
    Hull {
        size_m: [f64; 3],
    },
    None,
}

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
struct BodyFile {
    name: String,
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

#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
struct CoordinateFile {
    name: String,
    #[serde(default)]
    description: String,
    /// `azimuth` or `tilt`: where a scene's initial offsets go.
    role: Option<String>,
    /// Servo relation (this coordinate is driven to equal the expression).
    servo: Option<String>,
}

#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
enum ForceFile {
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
}

#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
struct ReadingFile {
    /// The body whose axis defines the indicated North (usually the gyro case or float).
    body: String,
    /// That axis in the body's frame.
    axis: [f64; 3],
}

#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
struct DesignFile {
    name: String,
    description: String,
    #[serde(default)]
    kind: String,
    root: Root,
    #[serde(default)]
    parameters: BTreeMap<String, f64>,
    coordinate: Vec<CoordinateFile>,
    body: Vec<BodyFile>,
    #[serde(default)]
    force: Vec<ForceFile>,
    reading: ReadingFile,
}

/// A coordinate of the chain.
#[derive(Clone, Debug, PartialEq)]
pub struct Coordinate {
    pub name: String,
    pub description: String,
    pub role: Option<CoordinateRole>,
    /// `Some` for a servo-driven coordinate: q = relation(q) (linear), substituted after.
    pub servo: Option<QuadExpr>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CoordinateRole {
    Azimuth,
    Tilt,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Hinge {
    /// Axis 0 = x, 1 = y, 2 = z of the joint frame.
    pub axis: usize,
    pub angle: QuadExpr,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Body {
    pub name: String,
    pub description: String,
    /// Index of the parent body, `None` for the base.
    pub parent: Option<usize>,
    pub joint_origin_m: [f64; 3],
    /// parent_from_joint (constant).
    pub joint_rotation: [[f64; 3]; 3],
    pub hinge: Option<Hinge>,
    pub mass_kg: f64,
    pub cg_m: [f64; 3],
    /// Inertia tensor about the centre of gravity in body axes. For a rotor this excludes the
    /// polar moment (it enters through the held momentum instead).
    pub inertia_kg_m2: [[f64; 3]; 3],
    pub rotor: Option<Rotor>,
    pub shape: Shape,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Rotor {
    /// Unit spin axis in body axes.
    pub axis: [f64; 3],
    pub polar_inertia_kg_m2: f64,
    pub spin_rad_per_s: f64,
    pub mode: SpinMode,
    pub motor: Option<Motor>,
}

/// A spin motor: the absolute spin Ω is a state with dΩ/dt = (Ω_rated − Ω)/τ, Ω_rated being the
/// rotor's `spin_rad_per_s`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Motor {
    pub time_constant_s: f64,
    pub initial_spin_rad_per_s: f64,
}

#[derive(Clone, Debug, PartialEq)]
pub enum Force {
    Damper {
        name: String,
        expr: QuadExpr,
        coefficient: f64,
    },
    Spring {
        name: String,
        expr: QuadExpr,
        stiffness: f64,
        rest: f64,
        preload: f64,
    },
    BodyForce {
        name: String,
        body: usize,
        direction: [f64; 3],
        force_n: f64,
        point: [QuadExpr; 3],
    },
    Generalized {
        name: String,
        coordinate: usize,
        torque: QuadExpr,
    },
}

impl Force {
    pub fn name(&self) -> &str {
        match self {
            Force::Damper { name, .. }
            | Force::Spring { name, .. }
            | Force::BodyForce { name, .. }
            | Force::Generalized { name, .. } => name,
        }
    }
    /// Dampers dissipate; the others are potential or circulatory. Used by the effect list.
    pub fn is_dissipative(&self) -> bool {
        matches!(self, Force::Damper { .. })
    }
}

/// A checked design: immutable input of the engine.
#[derive(Clone, Debug, PartialEq)]
pub struct Design {
    pub name: String,
    pub description: String,
    pub kind: String,
    pub root: Root,
    pub parameters: BTreeMap<String, f64>,
    pub coordinates: Vec<Coordinate>,
    pub bodies: Vec<Body>,
    pub forces: Vec<Force>,
    pub reading_body: usize,
    pub reading_axis: [f64; 3],
    /// The TOML text the design was read from (recorded with every run).
    pub source_text: String,
}

impl Design {
    /// Reads a design from TOML text. `file` names it in errors; `overrides` are dotted key paths
    /// (`parameters.kappa_n_m`, `body.rotor.rotor.spin_rpm`) with values, applied before checks.
    pub fn from_toml(
        file: &str,
        text: &str,
        overrides: &[(String, toml::Value)],
    ) -> Result<Design, InputError> {
        let mut value: toml::Value =
            toml::from_str(text).map_err(|e| crate::error::from_toml(file, text, &e))?;
        for (path, v) in overrides {
            apply_override(&mut value, path, v.clone()).map_err(|m| InputError {
                file: format!("{file} (override)"),
                line: None,
                key: path.clone(),
                message: m,
            })?;
        }
        resolve_expressions(&mut value).map_err(|(key, message)| InputError {
            file: file.to_string(),
            line: locate(text, None, key.rsplit('.').next().unwrap_or(&key)),
            key,
            message,
        })?;
        let parsed: DesignFile = value.try_into().map_err(|e: toml::de::Error| {
            let message = e.message().to_string();
            let key = message.split('`').nth(1).unwrap_or("(design)").to_string();
            InputError {
                file: file.to_string(),
                line: locate(text, None, &key),
                key,
                message,
            }
        })?;
        build(file, text, parsed)
    }

    pub fn coordinate_index(&self, name: &str) -> Option<usize> {
        self.coordinates.iter().position(|c| c.name == name)
    }
    pub fn body_index(&self, name: &str) -> Option<usize> {
        self.bodies.iter().position(|b| b.name == name)
    }
    pub fn role_index(&self, role: CoordinateRole) -> Option<usize> {
        self.coordinates.iter().position(|c| c.role == Some(role))
    }
    /// Total mass of the moving element, kg.
    pub fn total_mass_kg(&self) -> f64 {
        self.bodies.iter().map(|b| b.mass_kg).sum()
    }
    /// Named parameter (0 if absent).
    pub fn parameter(&self, name: &str) -> Option<f64> {
        self.parameters.get(name).copied()
    }
}

/// Evaluates the `[parameters]` table in order (numbers, or `"= expression"` of the parameters
/// before it), then replaces every `"= expression"` string elsewhere by its value. Hinge angles
/// and other relations stay strings (they are expressions of the coordinates, parsed later).
fn resolve_expressions(doc: &mut toml::Value) -> Result<(), (String, String)> {
    let mut params: BTreeMap<String, f64> = BTreeMap::new();
    if let Some(toml::Value::Table(t)) = doc.get_mut("parameters") {
        for (k, v) in t.iter_mut() {
            let x = match v {
                toml::Value::Float(x) => *x,
                toml::Value::Integer(i) => *i as f64,
                toml::Value::String(s) if s.trim_start().starts_with('=') => {
                    let e = expr::parse(s.trim_start()[1..].trim(), &[], &params)
                        .map_err(|m| (format!("parameters.{k}"), m))?;
                    e.constant
                }
                _ => {
                    return Err((
                        format!("parameters.{k}"),
                        "must be a number or \"= expression\" of earlier parameters".into(),
                    ));
                }
            };
            if !x.is_finite() {
                return Err((
                    format!("parameters.{k}"),
                    format!("evaluates to {x} (allowed: finite)"),
                ));
            }
            params.insert(k.clone(), x);
            *v = toml::Value::Float(x);
        }
    }
    fn walk(
        v: &mut toml::Value,
        path: &str,
        params: &BTreeMap<String, f64>,
    ) -> Result<(), (String, String)> {
        match v {
            toml::Value::String(s) if s.trim_start().starts_with('=') => {
                let e = expr::parse(s.trim_start()[1..].trim(), &[], params)
                    .map_err(|m| (path.to_string(), m))?;
                if !e.constant.is_finite() {
                    return Err((
                        path.to_string(),
                        format!("evaluates to {} (allowed: finite)", e.constant),
                    ));
                }
                *v = toml::Value::Float(e.constant);
            }
            toml::Value::Table(t) => {
                for (k, x) in t.iter_mut() {
                    if path.is_empty() && k == "parameters" {
                        continue;
                    }
                    let name = x.get("name").and_then(|n| n.as_str()).map(str::to_string);
                    let p = if path.is_empty() {
                        k.clone()
                    } else {
                        format!("{path}.{k}")
                    };
                    let _ = name;
                    walk(x, &p, params)?;
                }
            }
            toml::Value::Array(a) => {
                for (i, x) in a.iter_mut().enumerate() {
                    let label = x
                        .get("name")
                        .and_then(|n| n.as_str())
                        .map_or(i.to_string(), str::to_string);
                    walk(x, &format!("{path}.{label}"), params)?;
                }
            }
            _ => {}
        }
        Ok(())
    }
    walk(doc, "", &params)
}

/// Applies `path = value` to a TOML document; arrays of tables are addressed by their `name`.
pub fn apply_override(doc: &mut toml::Value, path: &str, value: toml::Value) -> Result<(), String> {
    let parts: Vec<&str> = path.split('.').collect();
    let mut cur = doc;
    for (k, part) in parts.iter().enumerate() {
        let last = k + 1 == parts.len();
        match cur {
            toml::Value::Table(t) => {
                if last {
                    if !t.contains_key(*part) && k > 0 && parts[k - 1] != "parameters" {
                        // New keys are allowed only where the schema has optional fields; the
                        // typed pass after this reports anything unknown.
                    }
                    t.insert(part.to_string(), value);
                    return Ok(());
                }
                let keys: Vec<String> = t.keys().cloned().collect();
                cur = t
                    .get_mut(*part)
                    .ok_or_else(|| format!("no `{part}` here (present: {})", keys.join(", ")))?;
            }
            toml::Value::Array(a) => {
                let names: Vec<String> = a
                    .iter()
                    .filter_map(|x| x.get("name").and_then(|n| n.as_str()).map(str::to_string))
                    .collect();
                let idx = a
                    .iter()
                    .position(|x| x.get("name").and_then(|n| n.as_str()) == Some(part))
                    .or_else(|| part.parse::<usize>().ok().filter(|i| *i < a.len()))
                    .ok_or_else(|| {
                        format!("no entry named `{part}` (entries: {})", names.join(", "))
                    })?;
                if last {
                    a[idx] = value;
                    return Ok(());
                }
                cur = &mut a[idx];
            }
            _ => return Err(format!("`{part}` is inside a value that is not a table")),
        }
    }
    Err("empty override path".into())
}

fn axis_index(s: &str) -> Option<usize> {
    match s {
        "x" => Some(0),
        "y" => Some(1),
        "z" => Some(2),
        _ => None,
    }
}

fn build(file: &str, text: &str, f: DesignFile) -> Result<Design, InputError> {
    let err = |anchor: Option<&str>, key: &str, path: String, message: String| InputError {
        file: file.to_string(),
        line: locate(text, anchor, key),
        key: path,
        message,
    };
    if f.coordinate.is_empty() {
        return Err(err(
            None,
            "coordinate",
            "coordinate".into(),
            "a design needs at least one coordinate".into(),
        ));
    }
    for (k, v) in &f.parameters {
        if !v.is_finite() {
            return Err(err(
                Some("[parameters]"),
                k,
                format!("parameters.{k}"),
                "must be a finite number".into(),
            ));
        }
    }
    let coord_names: Vec<String> = f.coordinate.iter().map(|c| c.name.clone()).collect();
    for (i, c) in f.coordinate.iter().enumerate() {
        if coord_names[..i].contains(&c.name) {
            return Err(err(
                Some(&format!("name = \"{}\"", c.name)),
                "name",
                format!("coordinate.{}", c.name),
                "duplicate coordinate name".into(),
            ));
        }
        if f.parameters.contains_key(&c.name) {
            return Err(err(
                Some(&format!("name = \"{}\"", c.name)),
                "name",
                format!("coordinate.{}", c.name),
                "a coordinate and a parameter share this name".into(),
            ));
        }
    }
    let mut coordinates = Vec::new();
    for c in &f.coordinate {
        let anchor = format!("name = \"{}\"", c.name);
        let role = match c.role.as_deref() {
            None => None,
            Some("azimuth") => Some(CoordinateRole::Azimuth),
            Some("tilt") => Some(CoordinateRole::Tilt),
            Some(r) => {
                return Err(err(
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
                let e = expr::parse(s, &coord_names, &f.parameters).map_err(|m| {
                    err(
                        Some(&anchor),
                        "servo",
                        format!("coordinate.{}.servo", c.name),
                        m,
                    )
                })?;
                if !e.is_linear() {
                    return Err(err(
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
        });
    }
    // A servo relation must read only non-driven coordinates (no chains of servos).
    for c in &coordinates {
        if let Some(s) = &c.servo {
            for i in s.coordinates() {
                if coordinates[i].servo.is_some() {
                    return Err(err(
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
        return Err(err(
            None,
            "coordinate",
            "coordinate".into(),
            "every coordinate is servo-driven: nothing left to move".into(),
        ));
    }

    let body_names: Vec<String> = f.body.iter().map(|b| b.name.clone()).collect();
    let mut bodies = Vec::new();
    for (bi, b) in f.body.iter().enumerate() {
        let anchor = format!("name = \"{}\"", b.name);
        let a = Some(anchor.as_str());
        let path = |k: &str| format!("body.{}.{k}", b.name);
        if body_names[..bi].contains(&b.name) || b.name == "base" {
            return Err(err(
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
                    return Err(err(
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
                Err(err(a, key, path(key), "must be finite numbers".into()))
            }
        };
        check_finite("joint_origin_m", &b.joint_origin_m)?;
        check_finite("cg_m", &b.cg_m)?;
        check_finite("inertia_kg_m2", &b.inertia_kg_m2)?;
        check_finite("products_of_inertia_kg_m2", &b.products_of_inertia_kg_m2)?;
        if !(b.mass_kg >= 0.0 && b.mass_kg.is_finite()) {
            return Err(err(
                a,
                "mass_kg",
                path("mass_kg"),
                format!("{} is out of range (allowed: ≥ 0 kg)", b.mass_kg),
            ));
        }
        let [ixx, iyy, izz] = b.inertia_kg_m2;
        if ixx < 0.0 || iyy < 0.0 || izz < 0.0 {
            return Err(err(
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
            return Err(err(
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
        let mut rot = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        for r in &b.joint_rotation {
            let ax = axis_index(&r.axis).ok_or_else(|| {
                err(
                    a,
                    "axis",
                    path("joint_rotation.axis"),
                    format!("unknown axis `{}` (allowed: x, y, z)", r.axis),
                )
            })?;
            let angle_deg = r.angle_deg;
            if !angle_deg.is_finite() {
                return Err(err(
                    a,
                    "angle_deg",
                    path("joint_rotation.angle_deg"),
                    "must be finite".into(),
                ));
            }
            rot = crate::real::M3::<f64>(rot)
                .mul_m(&crate::real::rot_axis(ax, angle_deg.to_radians()))
                .0;
        }
        let hinge = match &b.hinge {
            None => None,
            Some(h) => {
                let ax = axis_index(&h.axis).ok_or_else(|| {
                    err(
                        a,
                        "axis",
                        path("hinge.axis"),
                        format!("unknown axis `{}` (allowed: x, y, z)", h.axis),
                    )
                })?;
                let angle = expr::parse(&h.angle_rad, &coord_names, &f.parameters)
                    .map_err(|m| err(a, "angle_rad", path("hinge.angle_rad"), m))?;
                Some(Hinge { axis: ax, angle })
            }
        };
        let rotor = match &b.rotor {
            None => None,
            Some(r) => {
                let n = (r.axis[0].powi(2) + r.axis[1].powi(2) + r.axis[2].powi(2)).sqrt();
                if !(n > 0.0 && n.is_finite()) {
                    return Err(err(
                        a,
                        "axis",
                        path("rotor.axis"),
                        "must be a non-zero finite vector".into(),
                    ));
                }
                if !(r.polar_inertia_kg_m2 > 0.0 && r.polar_inertia_kg_m2.is_finite()) {
                    return Err(err(
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
                    return Err(err(
                        a,
                        "spin_rpm",
                        path("rotor.spin_rpm"),
                        format!(
                            "{} is out of range (allowed: non-zero, finite; negative reverses the spin)",
                            r.spin_rpm
                        ),
                    ));
                }
                let motor = match &r.motor {
                    None => None,
                    Some(m) => {
                        if r.spin != SpinMode::Held {
                            return Err(err(
                                a,
                                "motor",
                                path("rotor.motor"),
                                "a spin motor drives a `held` rotor (contradictory options: a free rotor has no torque about its axis)".into(),
                            ));
                        }
                        let tau = m.spin_up_time_constant_s;
                        if !(tau > 0.0 && tau.is_finite()) {
                            return Err(err(
                                a,
                                "spin_up_time_constant_s",
                                path("rotor.motor.spin_up_time_constant_s"),
                                format!("{tau} is out of range (allowed: > 0 s)"),
                            ));
                        }
                        if !m.initial_spin_rpm.is_finite() {
                            return Err(err(
                                a,
                                "initial_spin_rpm",
                                path("rotor.motor.initial_spin_rpm"),
                                "must be finite".into(),
                            ));
                        }
                        Some(Motor {
                            time_constant_s: tau,
                            initial_spin_rad_per_s: m.initial_spin_rpm
                                * crate::constants::RPM_IN_RAD_PER_S,
                        })
                    }
                };
                Some(Rotor {
                    axis: [r.axis[0] / n, r.axis[1] / n, r.axis[2] / n],
                    polar_inertia_kg_m2: r.polar_inertia_kg_m2,
                    spin_rad_per_s: r.spin_rpm * crate::constants::RPM_IN_RAD_PER_S,
                    mode: r.spin,
                    motor,
                })
            }
        };
        bodies.push(Body {
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
        });
    }
    if bodies.is_empty() {
        return Err(err(
            None,
            "body",
            "body".into(),
            "a design needs at least one body".into(),
        ));
    }
    // Every non-driven coordinate must move something, or its mass matrix row is empty.
    for (i, c) in coordinates.iter().enumerate() {
        if c.servo.is_some() {
            continue;
        }
        let used = bodies.iter().any(|b| {
            b.hinge
                .as_ref()
                .is_some_and(|h| h.angle.coordinates().contains(&i))
        });
        if !used {
            return Err(err(
                Some(&format!("name = \"{}\"", c.name)),
                "name",
                format!("coordinate.{}", c.name),
                "no hinge angle uses this coordinate".into(),
            ));
        }
    }

    let mut forces = Vec::new();
    for ff in &f.force {
        let parse_e = |s: &str, name: &str, key: &str| {
            expr::parse(s, &coord_names, &f.parameters).map_err(|m| {
                err(
                    Some(&format!("name = \"{name}\"")),
                    key,
                    format!("force.{name}.{key}"),
                    m,
                )
            })
        };
        let bad = |name: &str, key: &str, m: String| {
            err(
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
        });
    }
    for (i, fo) in forces.iter().enumerate() {
        if forces[..i].iter().any(|g| g.name() == fo.name()) {
            return Err(err(
                Some(&format!("name = \"{}\"", fo.name())),
                "name",
                format!("force.{}", fo.name()),
                "duplicate force name".into(),
            ));
        }
    }
    let reading_body = body_names
        .iter()
        .position(|n| *n == f.reading.body)
        .ok_or_else(|| {
            err(
                Some("[reading]"),
                "body",
                "reading.body".into(),
                format!(
                    "unknown body `{}` (allowed: {})",
                    f.reading.body,
                    body_names.join(", ")
                ),
            )
        })?;
    let ra = f.reading.axis;
    let rn = (ra[0] * ra[0] + ra[1] * ra[1] + ra[2] * ra[2]).sqrt();
    if !(rn > 0.0 && rn.is_finite()) {
        return Err(err(
            Some("[reading]"),
            "axis",
            "reading.axis".into(),
            "must be a non-zero finite vector".into(),
        ));
    }
    Ok(Design {
        name: f.name,
        description: f.description,
        kind: f.kind,
        root: f.root,
        parameters: f.parameters,
        coordinates,
        bodies,
        forces,
        reading_body,
        reading_axis: ra.map(|x| x / rn),
        source_text: text.to_string(),
    })
}
