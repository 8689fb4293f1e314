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

mod bodies;
mod coordinates;
mod document;
mod forces;
mod linkage;
mod pots;
mod reading;
mod stability;
mod tank;

use crate::error::{InputError, locate};
use crate::expr::QuadExpr;
use bodies::BodyFile;
use coordinates::CoordinateFile;
use document::{apply_override, resolve_expressions};
use forces::ForceFile;
pub use linkage::Linkage;
use linkage::LinkageFile;
use pots::PotsFile;
use reading::ReadingFile;
use serde::Deserialize;
pub use stability::StabilityCondition;
use stability::StabilityFile;
use std::collections::BTreeMap;
use tank::TankFile;
pub use tank::{Compartment, Tank, Valves};

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
    /// Whether the design may run with the spin reversed (a negative `spin_rpm`, e.g. from a
    /// scene's override): a compass built for one sense seeks South with the other.
    #[serde(default)]
    pub reversible: bool,
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
    #[serde(default)]
    pots: Vec<PotsFile>,
    #[serde(default)]
    tank: Vec<TankFile>,
    #[serde(default)]
    linkage: Vec<LinkageFile>,
    reading: ReadingFile,
    #[serde(default)]
    stability: Vec<StabilityFile>,
    /// Load the design even if a `[[stability]]` margin is ≤ 0 (set by a scene's
    /// `[compass] allow_unstable = true`).
    #[serde(default)]
    allow_unstable: bool,
}

/// A coordinate of the chain.
#[derive(Clone, Debug, PartialEq)]
pub struct Coordinate {
    pub name: String,
    pub description: String,
    pub role: Option<CoordinateRole>,
    /// `Some` for a servo-driven coordinate: q = relation(q) (linear), substituted after.
    pub servo: Option<QuadExpr>,
    /// The design's word on the gyroscopic fidelity: `Some(false)` keeps the rate a state,
    /// `Some(true)` allows the coordinate to be precessional, `None` lets the engine decide.
    pub precessional: Option<bool>,
    /// Radians for a hinge angle, metres for a pots' level.
    pub unit: CoordinateUnit,
}

/// What a coordinate measures: an angle (a hinge) or a length (the level of communicating pots).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CoordinateUnit {
    Radian,
    Metre,
}

impl CoordinateUnit {
    /// The unit's symbol, as recording field names end (`zeta_rad`, `u_m`).
    pub fn symbol(self) -> &'static str {
        match self {
            CoordinateUnit::Radian => "rad",
            CoordinateUnit::Metre => "m",
        }
    }
}

/// Two communicating pots of liquid on a carrier body, their level difference a coordinate
/// (`[[pots]]`; Beghin §51). Positions and axis in the carrier's axes; the tube path runs from
/// the second pot's base to the first's, endpoints included.
#[derive(Clone, Debug, PartialEq)]
pub struct Pots {
    pub name: String,
    pub description: String,
    pub body: usize,
    /// The coordinate u: the first pot's level above rest (the second's is as much below), m.
    pub level: usize,
    pub bases_m: [[f64; 3]; 2],
    /// Unit axis of both pots (up at rest).
    pub axis: [f64; 3],
    /// Open section ω₀ of each pot, m².
    pub section_m2: f64,
    /// Section of each pot whose liquid the taps hold at rest level, m².
    pub frozen_section_m2: f64,
    /// Column height c at equal levels, m.
    pub rest_level_m: f64,
    pub density_kg_per_m3: f64,
    pub tube_path_m: Vec<[f64; 3]>,
    pub tube_section_m2: f64,
    /// Viscous loss k: the flow's generalised force −k u̇, N·s/m.
    pub friction_n_s_per_m: f64,
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

/// A force element. The variants are the TOML kinds (`damper`, `spring`, `body_force`,
/// `generalized`, `link_spring`).
#[allow(clippy::enum_variant_names)]
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
    /// A spring between two bodies, attached at a point of each (body frame, m): its tension is
    /// `tension + stiffness·(d − length)` at the points' distance d, its potential
    /// V = tension·(d − length) + ½·stiffness·(d − length)². Each engine forms d from its own
    /// kinematics of the two points.
    LinkSpring {
        name: String,
        bodies: [usize; 2],
        points: [[f64; 3]; 2],
        stiffness: f64,
        length: f64,
        tension: f64,
    },
    /// A finite-gain (PD) servo: its motor turns `coordinate` toward the linear `relation` with
    /// the torque −k(q − r(q)) − c(q̇ − ṙ), reacting on the carrier, not on the driver (so it is
    /// a torque on this coordinate's equation only). [`Design::with_pd_servos`] makes these from
    /// a design's ideal servos.
    Servo {
        name: String,
        coordinate: usize,
        relation: QuadExpr,
        stiffness: f64,
        damping: f64,
    },
}

impl Force {
    pub fn name(&self) -> &str {
        match self {
            Force::Damper { name, .. }
            | Force::Spring { name, .. }
            | Force::BodyForce { name, .. }
            | Force::Generalized { name, .. }
            | Force::LinkSpring { name, .. }
            | Force::Servo { name, .. } => name,
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
    pub pots: Vec<Pots>,
    /// Liquid tanks of N compartments (`[[tank]]`); their levels are the last coordinates.
    pub tanks: Vec<Tank>,
    /// Rods between bodies whose hinges are already tied (`[[linkage]]`), drawn only.
    pub linkages: Vec<Linkage>,
    pub reading_body: usize,
    pub reading_axis: [f64; 3],
    /// The `[[stability]]` conditions, evaluated (all met unless the design allows otherwise).
    pub stability: Vec<StabilityCondition>,
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
    /// The design with every ideal servo replaced by a finite-gain one: the driven coordinate
    /// becomes free, and a [`Force::Servo`] of stiffness `k` (N·m/rad) and damping `c`
    /// (N·m·s/rad) turns it toward its relation. As k grows the motion tends to the ideal
    /// servo's, with a mode of frequency ≈ √(k/I) the integrator must carry.
    pub fn with_pd_servos(&self, stiffness: f64, damping: f64) -> Design {
        let mut d = self.clone();
        for (i, c) in d.coordinates.iter_mut().enumerate() {
            if let Some(relation) = c.servo.take() {
                d.forces.push(Force::Servo {
                    name: format!("servo_{}", c.name),
                    coordinate: i,
                    relation,
                    stiffness,
                    damping,
                });
            }
        }
        d
    }
    /// Named parameter (0 if absent).
    pub fn parameter(&self, name: &str) -> Option<f64> {
        self.parameters.get(name).copied()
    }
}

/// The design file being read: its errors name the file and find the line in its text.
struct SourceText<'a> {
    file: &'a str,
    text: &'a str,
}

impl SourceText<'_> {
    /// An error at `key` (its line searched after `anchor`), reported under the dotted `path`.
    fn err(&self, anchor: Option<&str>, key: &str, path: String, message: String) -> InputError {
        InputError {
            file: self.file.to_string(),
            line: locate(self.text, anchor, key),
            key: path,
            message,
        }
    }
}

/// Checks the typed document section by section (each section's parser is in its own module).
fn build(file: &str, text: &str, f: DesignFile) -> Result<Design, InputError> {
    let src = SourceText { file, text };
    let mut coordinates = coordinates::coordinates(&f.coordinate, &f.parameters, &src)?;
    let coord_names: Vec<String> = f.coordinate.iter().map(|c| c.name.clone()).collect();
    let levels: Vec<usize> = f
        .pots
        .iter()
        .filter_map(|p| coord_names.iter().position(|c| *c == p.level_name()))
        .collect();
    let mut bodies = bodies::bodies(
        &f.body,
        &coordinates,
        &coord_names,
        &levels,
        &f.parameters,
        &src,
    )?;
    let body_names: Vec<String> = f.body.iter().map(|b| b.name.clone()).collect();
    let mut forces = forces::forces(&f.force, &body_names, &coord_names, &f.parameters, &src)?;
    let (pots, pot_forces) = pots::pots(&f.pots, &mut bodies, &body_names, &coordinates, &src)?;
    forces.extend(pot_forces);
    for p in &pots {
        coordinates[p.level].unit = CoordinateUnit::Metre;
    }
    let (tanks, tank_forces) = tank::tanks(&f.tank, &body_names, &mut coordinates, &src)?;
    forces.extend(tank_forces);
    let linkages = linkage::linkages(&f.linkage, &body_names, &src)?;
    let (reading_body, reading_axis) = reading::reading(&f.reading, &body_names, &src)?;
    let stability = stability::stability(&f.stability, f.allow_unstable, &src)?;
    Ok(Design {
        name: f.name,
        description: f.description,
        kind: f.kind,
        root: f.root,
        parameters: f.parameters,
        coordinates,
        bodies,
        forces,
        pots,
        tanks,
        linkages,
        reading_body,
        reading_axis,
        stability,
        source_text: text.to_string(),
    })
}
