//! The `[[tank]]` entries: a liquid damper of N compartments carried by a body, joined by tubes
//! (the Anschütz three-gyro's annular oil tank, Beghin §66–67).
//!
//! The file states geometry and fluid: each compartment's horizontal centroid, floor area and
//! free-surface moments in the carrier's axes, the oil depth at rest, and which compartments
//! each tube joins with its flow resistance b (Q = Δhead / b, Beghin's (37)) and its bore. The
//! reader adds the levels of the first N − 1 compartments as coordinates in metres (the last
//! follows from the volume, Σ Sᵢhᵢ = 0), and forms from the tube network the two constant
//! matrices of the levels' rates:
//!
//! - the **dissipation**: the flows are the ones Kirchhoff's laws give (those that carry the
//!   level rates with least loss, Thomson), so the Rayleigh function in the level rates is
//!   ½ ẏᵀ L⁺ ẏ with ẏ = Sḣ and L the network's conductance Laplacian; grounding the last
//!   compartment gives D = S L_g⁻¹ S on the independent levels. It enters as dampers on
//!   the columns of D's Cholesky factor (the `friction` effect);
//! - the **flow's own inertia** (plug flow in the columns and the tubes), which only `full`
//!   fidelity carries: there it is a fast, overdamped mode; `gyroscopic` drops it and the
//!   levels obey Beghin's first-order equations (37).
//!
//! `valves = "closed"` (Beghin §71's suggestion: lock the oil during manoeuvres) adds no level
//! coordinates: the oil stays at rest in its compartments, with its weight and free surfaces.

use super::{Coordinate, CoordinateUnit, Force, SourceText};
use crate::error::InputError;
use crate::expr::QuadExpr;
use serde::Deserialize;

#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct TankFile {
    name: String,
    #[serde(default)]
    description: String,
    /// The carrier body.
    body: String,
    fluid_density_kg_per_m3: f64,
    /// c: the oil depth at rest in every compartment, m.
    rest_depth_m: f64,
    /// Height of the compartments' floor in the carrier's axes (z), m.
    floor_height_m: f64,
    #[serde(default)]
    valves: Valves,
    compartment: Vec<CompartmentFile>,
    tube: Vec<TubeFile>,
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Valves {
    #[default]
    Open,
    Closed,
}

#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
struct CompartmentFile {
    name: String,
    /// Horizontal centroid of the free surface, carrier axes (x, y), m.
    centroid_m: [f64; 2],
    area_m2: f64,
    /// Second moments of the free surface about axes through its centroid parallel to the
    /// carrier's x and y, m⁴ (Beghin's F and E terms).
    #[serde(default)]
    free_surface_m4: [f64; 2],
}

#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
struct TubeFile {
    /// The two compartments the tube joins, by name.
    between: [String; 2],
    /// b: the flow Q (m³/s) is the head difference (m) over b.
    flow_resistance_s_per_m2: f64,
    /// The tube's length and bore: its plug flow's inertia (`full` fidelity only).
    length_m: f64,
    section_m2: f64,
}

/// A checked tank: compartments, the level coordinates, and the constant rate matrices.
#[derive(Clone, Debug, PartialEq)]
pub struct Tank {
    pub name: String,
    pub description: String,
    pub body: usize,
    pub density_kg_per_m3: f64,
    pub rest_depth_m: f64,
    pub floor_height_m: f64,
    pub valves: Valves,
    pub compartments: Vec<Compartment>,
    /// Tubes as (first, second) compartment indices, b (s/m²), length (m), section (m²).
    pub tubes: Vec<(usize, usize, f64, f64, f64)>,
    /// Coordinate indices of the first N − 1 compartments' levels (empty with closed valves).
    pub levels: Vec<usize>,
    /// D (N − 1 square, row-major): the Rayleigh matrix of the level rates, N·s/m.
    pub dissipation: Vec<f64>,
    /// The flow's own inertia matrix in the level rates (columns and tubes), kg.
    pub flow_inertia: Vec<f64>,
    /// Per compartment, its level's coefficients on the independent levels (formed once: the
    /// engine reads them at every evaluation).
    level_map: Vec<Vec<f64>>,
}

/// Per compartment, the coefficients of its level on the first N − 1 compartments' levels.
fn level_map(compartments: &[Compartment]) -> Vec<Vec<f64>> {
    let m = compartments.len() - 1;
    let last = compartments[m].area_m2;
    (0..=m)
        .map(|i| {
            (0..m)
                .map(|j| {
                    if i < m {
                        (i == j) as u8 as f64
                    } else {
                        -compartments[j].area_m2 / last
                    }
                })
                .collect()
        })
        .collect()
}

#[derive(Clone, Debug, PartialEq)]
pub struct Compartment {
    pub name: String,
    pub centroid_m: [f64; 2],
    pub area_m2: f64,
    pub free_surface_m4: [f64; 2],
}

impl Tank {
    /// Each compartment's level as Σ coefficient × independent level (index into `levels`):
    /// the first N − 1 are their own; the last keeps the volume, −Σ Sᵢhᵢ / S_N. Empty with
    /// the valves closed.
    pub fn level_coefficients(&self, compartment: usize) -> &[f64] {
        self.level_map.get(compartment).map_or(&[], Vec::as_slice)
    }
    /// Total oil mass, kg.
    pub fn oil_mass_kg(&self) -> f64 {
        self.density_kg_per_m3
            * self.rest_depth_m
            * self.compartments.iter().map(|c| c.area_m2).sum::<f64>()
    }
}

/// Reads the tanks, appends their level coordinates to `coordinates`, and returns them with
/// the dampers of their flow.
pub(super) fn tanks(
    files: &[TankFile],
    body_names: &[String],
    coordinates: &mut Vec<Coordinate>,
    src: &SourceText,
) -> Result<(Vec<Tank>, Vec<Force>), InputError> {
    let mut out: Vec<Tank> = Vec::new();
    let mut forces = Vec::new();
    for t in files {
        let anchor = format!("name = \"{}\"", t.name);
        let bad =
            |key: &str, m: String| src.err(Some(&anchor), key, format!("tank.{}.{key}", t.name), m);
        if out.iter().any(|o| o.name == t.name) {
            return Err(bad("name", "duplicate tank name".into()));
        }
        let body = body_names
            .iter()
            .position(|n| *n == t.body)
            .ok_or_else(|| {
                bad(
                    "body",
                    format!(
                        "unknown body `{}` (allowed: {})",
                        t.body,
                        body_names.join(", ")
                    ),
                )
            })?;
        for (key, x) in [
            ("fluid_density_kg_per_m3", t.fluid_density_kg_per_m3),
            ("rest_depth_m", t.rest_depth_m),
        ] {
            if !(x > 0.0 && x.is_finite()) {
                return Err(bad(key, format!("{x} is out of range (allowed: > 0)")));
            }
        }
        if !t.floor_height_m.is_finite() {
            return Err(bad("floor_height_m", "must be finite".into()));
        }
        let nc = t.compartment.len();
        if nc < 2 {
            return Err(bad(
                "compartment",
                format!("{nc} compartment(s) (allowed: at least 2, joined by tubes)"),
            ));
        }
        let mut compartments: Vec<Compartment> = Vec::with_capacity(nc);
        for c in &t.compartment {
            if compartments.iter().any(|o| o.name == c.name) {
                return Err(bad(
                    "compartment",
                    format!("duplicate compartment `{}`", c.name),
                ));
            }
            if !(c.area_m2 > 0.0 && c.area_m2.is_finite()) {
                return Err(bad(
                    "area_m2",
                    format!(
                        "compartment `{}`: {} is out of range (allowed: > 0)",
                        c.name, c.area_m2
                    ),
                ));
            }
            if !c.centroid_m.iter().all(|x| x.is_finite())
                || !c.free_surface_m4.iter().all(|x| *x >= 0.0 && x.is_finite())
            {
                return Err(bad(
                    "centroid_m",
                    format!(
                        "compartment `{}`: centroid must be finite and free_surface_m4 finite, ≥ 0",
                        c.name
                    ),
                ));
            }
            compartments.push(Compartment {
                name: c.name.clone(),
                centroid_m: c.centroid_m,
                area_m2: c.area_m2,
                free_surface_m4: c.free_surface_m4,
            });
        }
        let names: Vec<&str> = compartments.iter().map(|c| c.name.as_str()).collect();
        let mut tubes = Vec::new();
        for tube in &t.tube {
            let find = |s: &String| {
                names.iter().position(|n| n == s).ok_or_else(|| {
                    bad(
                        "between",
                        format!("unknown compartment `{s}` (allowed: {})", names.join(", ")),
                    )
                })
            };
            let (a, b) = (find(&tube.between[0])?, find(&tube.between[1])?);
            if a == b {
                return Err(bad(
                    "between",
                    format!("a tube from `{}` to itself", tube.between[0]),
                ));
            }
            for (key, x) in [
                ("flow_resistance_s_per_m2", tube.flow_resistance_s_per_m2),
                ("length_m", tube.length_m),
                ("section_m2", tube.section_m2),
            ] {
                if !(x > 0.0 && x.is_finite()) {
                    return Err(bad(key, format!("{x} is out of range (allowed: > 0)")));
                }
            }
            tubes.push((
                a,
                b,
                tube.flow_resistance_s_per_m2,
                tube.length_m,
                tube.section_m2,
            ));
        }
        // Every compartment joined to the first through the tubes (checked on the graph: the
        // grounded Laplacian of a split network is singular only up to round-off).
        let mut joined = vec![false; nc];
        joined[0] = true;
        let mut grew = true;
        while grew {
            grew = false;
            for &(a, b, ..) in &tubes {
                if joined[a] != joined[b] {
                    joined[a] = true;
                    joined[b] = true;
                    grew = true;
                }
            }
        }
        let apart: Vec<&str> = (0..nc).filter(|&i| !joined[i]).map(|i| names[i]).collect();
        if !apart.is_empty() {
            return Err(bad(
                "tube",
                format!(
                    "the tubes do not join {} to `{}` (allowed: a connected network)",
                    apart
                        .iter()
                        .map(|n| format!("`{n}`"))
                        .collect::<Vec<_>>()
                        .join(", "),
                    names[0]
                ),
            ));
        }
        let mut tank = Tank {
            name: t.name.clone(),
            description: t.description.clone(),
            body,
            density_kg_per_m3: t.fluid_density_kg_per_m3,
            rest_depth_m: t.rest_depth_m,
            floor_height_m: t.floor_height_m,
            valves: t.valves,
            compartments,
            tubes,
            levels: Vec::new(),
            dissipation: Vec::new(),
            flow_inertia: Vec::new(),
            level_map: Vec::new(),
        };
        if t.valves == Valves::Open {
            let (d, m) = rate_matrices(&tank).ok_or_else(|| {
                bad(
                    "tube",
                    "the tubes do not join every compartment to the others (allowed: a connected network)".into(),
                )
            })?;
            tank.dissipation = d;
            tank.flow_inertia = m;
            tank.level_map = level_map(&tank.compartments);
            for c in &tank.compartments[..nc - 1] {
                let name = format!("{}_{}", t.name, c.name);
                if coordinates.iter().any(|o| o.name == name) {
                    return Err(bad(
                        "name",
                        format!("the level coordinate `{name}` clashes with a declared coordinate"),
                    ));
                }
                tank.levels.push(coordinates.len());
                coordinates.push(Coordinate {
                    name,
                    description: format!(
                        "oil level in compartment `{}` of tank `{}` above rest",
                        c.name, t.name
                    ),
                    role: None,
                    servo: None,
                    precessional: None,
                    unit: CoordinateUnit::Metre,
                });
            }
            forces.extend(flow_dampers(&tank));
        }
        out.push(tank);
    }
    Ok((out, forces))
}

/// D = S_g L_g⁻¹ S_g and the flow's inertia, on the first N − 1 levels; `None` if the network
/// is not connected (L_g singular).
fn rate_matrices(t: &Tank) -> Option<(Vec<f64>, Vec<f64>)> {
    let m = t.compartments.len() - 1;
    let rho = t.density_kg_per_m3;
    let g = crate::constants::STANDARD_GRAVITY_M_PER_S2;
    // Conductance Laplacian of the network, grounded at the last compartment; R = ρ g b.
    let mut lg = vec![0.0; m * m];
    for &(a, b, res, _, _) in &t.tubes {
        let w = 1.0 / (rho * g * res);
        for (i, j) in [(a, b), (b, a)] {
            if i < m {
                lg[i * m + i] += w;
                if j < m {
                    lg[i * m + j] -= w;
                }
            }
        }
    }
    // X = L_g⁻¹ S_g (column by column): the pressures −P per unit level rate.
    let mut x = vec![0.0; m * m];
    for col in 0..m {
        let mut a = lg.clone();
        let mut rhs = vec![0.0; m];
        rhs[col] = t.compartments[col].area_m2;
        if !crate::linalg::solve_in_place(&mut a, &mut rhs, m) {
            return None;
        }
        for r in 0..m {
            x[r * m + col] = rhs[r];
        }
    }
    let mut d = vec![0.0; m * m];
    for r in 0..m {
        for c in 0..m {
            d[r * m + c] = t.compartments[r].area_m2 * x[r * m + c];
        }
    }
    // Symmetrise the round-off.
    for r in 0..m {
        for c in 0..r {
            let s = 0.5 * (d[r * m + c] + d[c * m + r]);
            d[r * m + c] = s;
            d[c * m + r] = s;
        }
    }
    // Inertia: columns ½ρcΣSᵢḣᵢ², tubes ½ρ(L/F)Q², Q = (P_a − P_b)/R per unit level rates.
    let c = t.rest_depth_m;
    let s_last = t.compartments[m].area_m2;
    let mut inertia = vec![0.0; m * m];
    for r in 0..m {
        for k in 0..m {
            let sr = t.compartments[r].area_m2;
            let sk = t.compartments[k].area_m2;
            inertia[r * m + k] = rho * c * (if r == k { sr } else { 0.0 } + sr * sk / s_last);
        }
    }
    for &(a, b, res, len, sec) in &t.tubes {
        let w = 1.0 / (rho * g * res);
        // ∂Q/∂ḣ_j = −w (X[a][j] − X[b][j]) (P = −X ḣ, the last compartment grounded).
        let grad: Vec<f64> = (0..m)
            .map(|j| {
                let pa = if a < m { x[a * m + j] } else { 0.0 };
                let pb = if b < m { x[b * m + j] } else { 0.0 };
                -w * (pa - pb)
            })
            .collect();
        let lam = rho * len / sec;
        for r in 0..m {
            for k in 0..m {
                inertia[r * m + k] += lam * grad[r] * grad[k];
            }
        }
    }
    Some((d, inertia))
}

/// The dissipation D = Σ lₖlₖᵀ (Cholesky), as dampers of coefficient 1 on eₖ = lₖ·h.
fn flow_dampers(t: &Tank) -> Vec<Force> {
    let m = t.levels.len();
    let d = &t.dissipation;
    let mut l = vec![0.0; m * m];
    for j in 0..m {
        let mut s = d[j * m + j];
        for k in 0..j {
            s -= l[j * m + k] * l[j * m + k];
        }
        let ljj = s.max(0.0).sqrt();
        l[j * m + j] = ljj;
        for i in j + 1..m {
            let mut s = d[i * m + j];
            for k in 0..j {
                s -= l[i * m + k] * l[j * m + k];
            }
            l[i * m + j] = if ljj > 0.0 { s / ljj } else { 0.0 };
        }
    }
    (0..m)
        .map(|k| Force::Damper {
            name: format!("{}_flow_{}", t.name, k + 1),
            expr: QuadExpr {
                constant: 0.0,
                linear: (k..m)
                    .filter(|&i| l[i * m + k] != 0.0)
                    .map(|i| (t.levels[i], l[i * m + k]))
                    .collect(),
                quadratic: Vec::new(),
            },
            coefficient: 1.0,
        })
        .collect()
}
