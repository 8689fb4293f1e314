//! The `[[pots]]` entries: two communicating pots of liquid carried by a body (the Slough's
//! mercury ballistic, Beghin §51), whose level difference is a coordinate in metres.
//!
//! What the file states is geometry and fluid: the pots' bases and common axis in the carrier's
//! axes, the open section ω₀ of each pot, the section whose liquid the taps immobilise, the
//! level c at rest, the density, and the connecting tube (path and section). The engine derives
//! every term of the Lagrangian from these (`crate::reference_engine`, module `pots` there); the
//! reader adds to the carrier what moves with it rigidly: the liquid in the tube and in the
//! closed compartments, and the columns' own moments at rest level.

use super::{Body, Coordinate, Force, Pots, SourceText};
use crate::error::InputError;
use crate::expr::QuadExpr;
use serde::Deserialize;

#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct PotsFile {
    name: String,
    #[serde(default)]
    description: String,
    /// The carrier body.
    body: String,
    /// The coordinate u: the first pot's level above rest (the second's falls by as much), m.
    level: String,
    first_base_m: [f64; 3],
    second_base_m: [f64; 3],
    /// The pots' common axis (up at rest), carrier axes.
    #[serde(default = "up")]
    axis: [f64; 3],
    section_m2: f64,
    #[serde(default)]
    frozen_section_m2: f64,
    rest_level_m: f64,
    fluid_density_kg_per_m3: f64,
    /// Interior points of the tube from the second pot's base to the first's (straight if empty).
    #[serde(default)]
    tube_path_m: Vec<[f64; 3]>,
    tube_section_m2: f64,
    #[serde(default)]
    friction_n_s_per_m: f64,
}

impl PotsFile {
    pub(super) fn level_name(&self) -> &str {
        &self.level
    }
}

fn up() -> [f64; 3] {
    [0.0, 0.0, 1.0]
}

/// Reads the pots, checks them, and returns them with the force elements they add (the flow's
/// viscous loss as a damper on the level). The carriers' mass properties are updated in place.
pub(super) fn pots(
    pots: &[PotsFile],
    bodies: &mut [Body],
    body_names: &[String],
    coordinates: &[Coordinate],
    src: &SourceText,
) -> Result<(Vec<Pots>, Vec<Force>), InputError> {
    let mut out: Vec<Pots> = Vec::new();
    let mut forces = Vec::new();
    for p in pots {
        let anchor = format!("name = \"{}\"", p.name);
        let bad =
            |key: &str, m: String| src.err(Some(&anchor), key, format!("pots.{}.{key}", p.name), m);
        if out.iter().any(|o| o.name == p.name) {
            return Err(bad("name", "duplicate pots name".into()));
        }
        let body = body_names
            .iter()
            .position(|n| *n == p.body)
            .ok_or_else(|| {
                bad(
                    "body",
                    format!(
                        "unknown body `{}` (allowed: {})",
                        p.body,
                        body_names.join(", ")
                    ),
                )
            })?;
        let names: Vec<&str> = coordinates.iter().map(|c| c.name.as_str()).collect();
        let level = names.iter().position(|n| *n == p.level).ok_or_else(|| {
            bad(
                "level",
                format!(
                    "unknown coordinate `{}` (allowed: {})",
                    p.level,
                    names.join(", ")
                ),
            )
        })?;
        if coordinates[level].servo.is_some() {
            return Err(bad(
                "level",
                format!("`{}` is servo-driven (allowed: a free coordinate)", p.level),
            ));
        }
        if out.iter().any(|o| o.level == level) {
            return Err(bad(
                "level",
                format!("`{}` is already the level of other pots", p.level),
            ));
        }
        let uses_hinge = bodies.iter().any(|b| {
            b.hinge
                .as_ref()
                .is_some_and(|h| h.angle.coordinates().contains(&level))
        });
        if uses_hinge {
            return Err(bad(
                "level",
                format!(
                    "`{}` is a hinge angle too (allowed: a coordinate only the pots use, in metres)",
                    p.level
                ),
            ));
        }
        for (key, x) in [
            ("section_m2", p.section_m2),
            ("tube_section_m2", p.tube_section_m2),
            ("rest_level_m", p.rest_level_m),
            ("fluid_density_kg_per_m3", p.fluid_density_kg_per_m3),
        ] {
            if !(x > 0.0 && x.is_finite()) {
                return Err(bad(key, format!("{x} is out of range (allowed: > 0)")));
            }
        }
        for (key, x) in [
            ("frozen_section_m2", p.frozen_section_m2),
            ("friction_n_s_per_m", p.friction_n_s_per_m),
        ] {
            if !(x >= 0.0 && x.is_finite()) {
                return Err(bad(key, format!("{x} is out of range (allowed: ≥ 0)")));
            }
        }
        let n = (p.axis.iter().map(|x| x * x).sum::<f64>()).sqrt();
        if !(n > 0.0 && n.is_finite()) {
            return Err(bad("axis", "must be a non-zero finite vector".into()));
        }
        let all_finite = p
            .first_base_m
            .iter()
            .chain(&p.second_base_m)
            .chain(p.tube_path_m.iter().flatten())
            .all(|x| x.is_finite());
        if !all_finite {
            return Err(bad("first_base_m", "positions must be finite".into()));
        }
        let mut path = vec![p.second_base_m];
        path.extend(p.tube_path_m.iter().copied());
        path.push(p.first_base_m);
        let pots = Pots {
            name: p.name.clone(),
            description: p.description.clone(),
            body,
            level,
            bases_m: [p.first_base_m, p.second_base_m],
            axis: p.axis.map(|x| x / n),
            section_m2: p.section_m2,
            frozen_section_m2: p.frozen_section_m2,
            rest_level_m: p.rest_level_m,
            density_kg_per_m3: p.fluid_density_kg_per_m3,
            tube_path_m: path,
            tube_section_m2: p.tube_section_m2,
            friction_n_s_per_m: p.friction_n_s_per_m,
        };
        if pots.tube_length_m() == 0.0 {
            return Err(bad(
                "second_base_m",
                "the pots' bases coincide: no tube between them".into(),
            ));
        }
        add_rigid_liquid(&mut bodies[body], &pots);
        if pots.friction_n_s_per_m > 0.0 {
            forces.push(Force::Damper {
                name: format!("{}_flow_friction", pots.name),
                expr: QuadExpr::coordinate(level),
                coefficient: pots.friction_n_s_per_m,
            });
        }
        out.push(pots);
    }
    Ok((out, forces))
}

/// Adds to the carrier the liquid that moves rigidly with it: the tube's, the closed
/// compartments' (at rest level), and the open columns' own transverse moments at rest level
/// (m c²/12 about their centres; the columns' masses themselves are the engine's, as functions
/// of the level).
fn add_rigid_liquid(carrier: &mut Body, pots: &Pots) {
    let rho = pots.density_kg_per_m3;
    let c = pots.rest_level_m;
    let a = pots.axis;
    // (mass, centre, own inertia) of each piece, carrier axes.
    let mut pieces: Vec<(f64, [f64; 3], [[f64; 3]; 3])> =
        vec![(carrier.mass_kg, carrier.cg_m, carrier.inertia_kg_m2)];
    let transverse = |m: f64, len: f64| {
        let k = m * len * len / 12.0;
        let mut i = [[0.0; 3]; 3];
        for r in 0..3 {
            for s in 0..3 {
                i[r][s] = k * ((r == s) as u8 as f64 - a[r] * a[s]);
            }
        }
        i
    };
    for b in pots.bases_m {
        let centre = [0, 1, 2].map(|k| b[k] + 0.5 * c * a[k]);
        let open = rho * pots.section_m2 * c;
        pieces.push((0.0, centre, transverse(open, c)));
        let frozen = rho * pots.frozen_section_m2 * c;
        if frozen > 0.0 {
            pieces.push((frozen, centre, transverse(frozen, c)));
        }
    }
    for w in pots.tube_path_m.windows(2) {
        let len = dist(&w[0], &w[1]);
        let mid = [0, 1, 2].map(|k| 0.5 * (w[0][k] + w[1][k]));
        pieces.push((rho * pots.tube_section_m2 * len, mid, [[0.0; 3]; 3]));
    }
    let m: f64 = pieces.iter().map(|p| p.0).sum();
    let mut cg = [0.0; 3];
    if m > 0.0 {
        for k in 0..3 {
            cg[k] = pieces.iter().map(|p| p.0 * p.1[k]).sum::<f64>() / m;
        }
    }
    let mut inertia = [[0.0; 3]; 3];
    for (mk, ck, ik) in &pieces {
        let d = [0, 1, 2].map(|k| ck[k] - cg[k]);
        let d2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        for r in 0..3 {
            for s in 0..3 {
                let delta = if r == s { d2 } else { 0.0 };
                inertia[r][s] += ik[r][s] + mk * (delta - d[r] * d[s]);
            }
        }
    }
    carrier.mass_kg = m;
    carrier.cg_m = cg;
    carrier.inertia_kg_m2 = inertia;
}

fn dist(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

impl Pots {
    /// Length of the connecting tube, m.
    pub fn tube_length_m(&self) -> f64 {
        self.tube_path_m
            .windows(2)
            .map(|w| dist(&w[0], &w[1]))
            .sum()
    }
    /// ℰ: the inertia of the relative flow, ½ℰu̇² being its kinetic energy (plug flow at the mean
    /// velocity of each section, Beghin §51 (2), (6)): ℰ = ρω₀(2c + ω₀ L/F), kg. Independent of
    /// the level, since the columns lengthen and shorten by as much.
    pub fn flow_inertia_kg(&self) -> f64 {
        let w0 = self.section_m2;
        self.density_kg_per_m3
            * w0
            * (2.0 * self.rest_level_m + w0 * self.tube_length_m() / self.tube_section_m2)
    }
    /// Mass of the liquid that flows (both open columns at rest), kg.
    pub fn moving_mass_kg(&self) -> f64 {
        2.0 * self.density_kg_per_m3 * self.section_m2 * self.rest_level_m
    }
    /// Total liquid, kg: open and closed columns and the tube.
    pub fn liquid_mass_kg(&self) -> f64 {
        self.moving_mass_kg()
            + 2.0 * self.density_kg_per_m3 * self.frozen_section_m2 * self.rest_level_m
            + self.density_kg_per_m3 * self.tube_section_m2 * self.tube_length_m()
    }
    /// The level's stiffness with the carrier held upright: V = ρgω₀u² ⇒ 2ρgω₀, N/m.
    pub fn level_stiffness_n_per_m(&self, gravity_m_per_s2: f64) -> f64 {
        2.0 * self.density_kg_per_m3 * gravity_m_per_s2 * self.section_m2
    }
    /// Undamped period of the liquid in its pots held fixed, 2π√(ℰ/(2ρgω₀)), s.
    pub fn own_period_s(&self, gravity_m_per_s2: f64) -> f64 {
        std::f64::consts::TAU
            * (self.flow_inertia_kg() / self.level_stiffness_n_per_m(gravity_m_per_s2)).sqrt()
    }
    /// Half the pots' spacing measured across their axis, h, m.
    pub fn half_spacing_m(&self) -> f64 {
        let d = [0, 1, 2].map(|k| self.bases_m[0][k] - self.bases_m[1][k]);
        let along = d[0] * self.axis[0] + d[1] * self.axis[1] + d[2] * self.axis[2];
        0.5 * (d.iter().map(|x| x * x).sum::<f64>() - along * along).sqrt()
    }
}
