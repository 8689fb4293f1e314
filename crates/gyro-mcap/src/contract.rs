//! The recording contract of `docs/recordings.md` as names: what a gyrolab run writes and what its
//! readers look for. The recorder (`gyro-sim`), the analysis, the viewer, the command line and
//! the tests' synthetic recordings all take their topics, schema names and fields, metadata
//! record names and keys, status strings, frame names and the body-shape vocabulary from here,
//! so a name is changed in one place.
//!
//! One module per channel ([`compass_state`], [`ship_state`], [`energy`], [`events`],
//! [`solver_stats`], [`tf`]: its topic, schema name, field names and the schema builder), one per metadata record
//! ([`run_record`], [`result_record`], [`design_constants_record`], [`scene_record`],
//! [`design_record`], [`bodies_record`]), the run's [`status`] strings, the [`attachments`], and
//! [`BodyShape`], the shapes a body is drawn with. Nothing here knows physics: values come from
//! the caller.

use crate::schema::{FieldSpec, RecordSchema};

/// The first field of every record channel: simulated seconds since the start (the log time,
/// exact).
pub const TIME_S: &str = "time_s";

/// `/compass/state`: the compass at every output sample.
pub mod compass_state {
    use super::{FieldSpec, RecordSchema};

    pub const TOPIC: &str = "/compass/state";
    pub const SCHEMA: &str = "gyrolab.CompassState";
    pub use super::TIME_S;
    /// Compass heading − true heading; positive: reads high (north-seeking axis West of North).
    pub const READING_ERROR_RAD: &str = "reading_error_rad";
    pub const COMPASS_HEADING_RAD: &str = "compass_heading_rad";
    pub const TRUE_HEADING_RAD: &str = "true_heading_rad";
    /// North end down positive.
    pub const TILT_RAD: &str = "tilt_rad";
    /// The fields before the design's coordinates.
    pub const LEADING_FIELDS: usize = 5;

    /// The field of a design coordinate's angle: `<coordinate>_rad`.
    pub fn angle_field(coordinate: &str) -> String {
        coordinate_field(coordinate, "rad")
    }

    /// The field of a design coordinate's rate: `<coordinate>_rate_rad_per_s`.
    pub fn rate_field(coordinate: &str) -> String {
        coordinate_rate_field(coordinate, "rad")
    }

    /// The field of a design coordinate in its unit (`rad` for a hinge angle, `m` for a pots'
    /// level): `<coordinate>_<unit>`.
    pub fn coordinate_field(coordinate: &str, unit: &str) -> String {
        format!("{coordinate}_{unit}")
    }

    /// The field of a design coordinate's rate: `<coordinate>_rate_<unit>_per_s`.
    pub fn coordinate_rate_field(coordinate: &str, unit: &str) -> String {
        format!("{coordinate}_rate_{unit}_per_s")
    }

    /// The schema for a design whose coordinates are all angles (in order).
    pub fn schema<S: AsRef<str>>(coordinates: &[S]) -> RecordSchema {
        let with_units: Vec<(&str, &str)> =
            coordinates.iter().map(|c| (c.as_ref(), "rad")).collect();
        schema_with_units(&with_units)
    }

    /// The schema for a design with these (coordinate, unit) pairs in order: the leading
    /// fields, every coordinate, then every coordinate's rate.
    pub fn schema_with_units<S: AsRef<str>>(coordinates: &[(S, &str)]) -> RecordSchema {
        let mut fields = vec![
            FieldSpec::f64(TIME_S, "s"),
            FieldSpec::f64(READING_ERROR_RAD, "rad"),
            FieldSpec::f64(COMPASS_HEADING_RAD, "rad"),
            FieldSpec::f64(TRUE_HEADING_RAD, "rad"),
            FieldSpec::f64(TILT_RAD, "rad"),
        ];
        for (c, unit) in coordinates {
            fields.push(FieldSpec::f64(&coordinate_field(c.as_ref(), unit), unit));
        }
        for (c, unit) in coordinates {
            fields.push(FieldSpec::f64(
                &coordinate_rate_field(c.as_ref(), unit),
                &format!("{unit}/s"),
            ));
        }
        RecordSchema {
            full_name: SCHEMA.into(),
            fields,
        }
    }
}

/// `/ship/state`: the ship at every output sample.
pub mod ship_state {
    use super::{FieldSpec, RecordSchema};

    pub const TOPIC: &str = "/ship/state";
    pub const SCHEMA: &str = "gyrolab.ShipState";
    pub use super::TIME_S;
    pub const LATITUDE_RAD: &str = "latitude_rad";
    pub const LONGITUDE_RAD: &str = "longitude_rad";
    /// Navigational: clockwise from North.
    pub const HEADING_RAD: &str = "heading_rad";
    pub const SPEED_M_PER_S: &str = "speed_m_per_s";
    pub const ROLL_RAD: &str = "roll_rad";
    pub const PITCH_RAD: &str = "pitch_rad";
    /// Apparent gravity at the pivot (−g·Z minus the pivot's acceleration), local North–West–Up.
    pub const GRAVITY_NORTH_M_PER_S2: &str = "gravity_north_m_per_s2";
    pub const GRAVITY_WEST_M_PER_S2: &str = "gravity_west_m_per_s2";
    pub const GRAVITY_UP_M_PER_S2: &str = "gravity_up_m_per_s2";

    /// Field names and units, in order.
    pub const FIELDS: [(&str, &str); 10] = [
        (TIME_S, "s"),
        (LATITUDE_RAD, "rad"),
        (LONGITUDE_RAD, "rad"),
        (HEADING_RAD, "rad"),
        (SPEED_M_PER_S, "m/s"),
        (ROLL_RAD, "rad"),
        (PITCH_RAD, "rad"),
        (GRAVITY_NORTH_M_PER_S2, "m/s^2"),
        (GRAVITY_WEST_M_PER_S2, "m/s^2"),
        (GRAVITY_UP_M_PER_S2, "m/s^2"),
    ];

    pub fn schema() -> RecordSchema {
        RecordSchema {
            full_name: SCHEMA.into(),
            fields: FIELDS.iter().map(|(n, u)| FieldSpec::f64(n, u)).collect(),
        }
    }
}

/// `/compass/energy`: the energy balance at every output sample, when the scene asks for it
/// (`record_energy = true`): Jacobi's integral h = T₂ − T₀ + V and the powers that change it.
pub mod energy {
    use super::{FieldSpec, RecordSchema};

    pub const TOPIC: &str = "/compass/energy";
    pub const SCHEMA: &str = "gyrolab.Energy";
    pub use super::TIME_S;
    pub const ENERGY_J: &str = "energy_j";
    pub const KINETIC_J: &str = "kinetic_j";
    pub const FRAME_KINETIC_J: &str = "frame_kinetic_j";
    pub const POTENTIAL_J: &str = "potential_j";
    pub const SERVO_POWER_W: &str = "servo_power_w";
    pub const DAMPER_POWER_W: &str = "damper_power_w";
    pub const APPLIED_POWER_W: &str = "applied_power_w";

    /// Field names and units, in order.
    pub const FIELDS: [(&str, &str); 8] = [
        (TIME_S, "s"),
        (ENERGY_J, "J"),
        (KINETIC_J, "J"),
        (FRAME_KINETIC_J, "J"),
        (POTENTIAL_J, "J"),
        (SERVO_POWER_W, "W"),
        (DAMPER_POWER_W, "W"),
        (APPLIED_POWER_W, "W"),
    ];

    pub fn schema() -> RecordSchema {
        RecordSchema {
            full_name: SCHEMA.into(),
            fields: FIELDS.iter().map(|(n, u)| FieldSpec::f64(n, u)).collect(),
        }
    }
}

/// `/events`: a manoeuvre's start and end.
pub mod events {
    use super::{FieldSpec, RecordSchema};

    pub const TOPIC: &str = "/events";
    pub const SCHEMA: &str = "gyrolab.ManoeuvreEvent";
    pub use super::TIME_S;
    /// [`START`] or [`END`].
    pub const PHASE: &str = "phase";
    /// The manoeuvre's kind as the scene's program names it (`speed_change`, `turn`, `zigzag`).
    pub const MANOEUVRE: &str = "manoeuvre";
    /// Index of the segment in the scene's program.
    pub const SEGMENT: &str = "segment";
    pub const DESCRIPTION: &str = "description";
    pub const SPEED_BEFORE_M_PER_S: &str = "speed_before_m_per_s";
    pub const SPEED_AFTER_M_PER_S: &str = "speed_after_m_per_s";
    pub const HEADING_BEFORE_RAD: &str = "heading_before_rad";
    pub const HEADING_AFTER_RAD: &str = "heading_after_rad";
    pub const DURATION_S: &str = "duration_s";
    /// [`PHASE`] of a manoeuvre's start.
    pub const START: &str = "start";
    /// [`PHASE`] of a manoeuvre's end.
    pub const END: &str = "end";
    /// The program's name for a segment without a manoeuvre: it has no events.
    pub const STEADY: &str = "steady";

    pub fn schema() -> RecordSchema {
        RecordSchema {
            full_name: SCHEMA.into(),
            fields: vec![
                FieldSpec::f64(TIME_S, "s"),
                FieldSpec::str(PHASE),
                FieldSpec::str(MANOEUVRE),
                FieldSpec::u64(SEGMENT),
                FieldSpec::str(DESCRIPTION),
                FieldSpec::f64(SPEED_BEFORE_M_PER_S, "m/s"),
                FieldSpec::f64(SPEED_AFTER_M_PER_S, "m/s"),
                FieldSpec::f64(HEADING_BEFORE_RAD, "rad"),
                FieldSpec::f64(HEADING_AFTER_RAD, "rad"),
                FieldSpec::f64(DURATION_S, "s"),
            ],
        }
    }
}

/// `/solver/stats`: progress reports during the run and the final statistics at its end.
pub mod solver_stats {
    use super::{FieldSpec, RecordSchema};

    pub const TOPIC: &str = "/solver/stats";
    pub const SCHEMA: &str = "gyrolab.SolverStats";
    pub use super::TIME_S;
    pub const STEPS: &str = "steps";
    pub const REJECTED_STEPS: &str = "rejected_steps";
    pub const RHS_EVALS: &str = "rhs_evals";
    pub const JACOBIAN_EVALS: &str = "jacobian_evals";
    pub const WALL_TIME_S: &str = "wall_time_s";
    /// Simulated seconds between two progress reports (the first sample at or after each
    /// multiple, before the end, carries one).
    pub const REPORT_EVERY_S: f64 = 3600.0;

    pub fn schema() -> RecordSchema {
        RecordSchema {
            full_name: SCHEMA.into(),
            fields: vec![
                FieldSpec::f64(TIME_S, "s"),
                FieldSpec::u64(STEPS),
                FieldSpec::u64(REJECTED_STEPS),
                FieldSpec::u64(RHS_EVALS),
                FieldSpec::u64(JACOBIAN_EVALS),
                FieldSpec::f64(WALL_TIME_S, "s"),
            ],
        }
    }
}

/// `/tf`: poses (`foxglove.FrameTransform`, [`SCHEMA`](tf::SCHEMA)) of the ship and of every
/// body, each in its parent frame.
pub mod tf {
    pub const TOPIC: &str = "/tf";
    pub const SCHEMA: &str = crate::schema::POSE_SCHEMA_NAME;
    /// The local level frame at the pivot: the root of every pose tree.
    pub const EARTH_FRAME: &str = "earth";
    /// The hull, child of [`EARTH_FRAME`].
    pub const SHIP_FRAME: &str = "ship";
}

/// The `run` metadata record: what was run and how, written before the first sample (so a
/// recovered file keeps it).
pub mod run_record {
    pub const NAME: &str = "run";
    pub const PROGRAM_VERSION: &str = "program_version";
    pub const SCENE_NAME: &str = "scene_name";
    pub const DESIGN_NAME: &str = "design_name";
    pub const DESIGN_KIND: &str = "design_kind";
    pub const FIDELITY: &str = "fidelity";
    pub const INTEGRATOR: &str = "integrator";
    pub const RTOL: &str = "rtol";
    pub const ATOL: &str = "atol";
    /// RADAU5's Jacobian-reuse threshold (the Newton contraction below which it keeps its
    /// Jacobian); absent from files of earlier builds, which all ran 0.001.
    pub const JACOBIAN_REUSE_CONTRACTION: &str = "jacobian_reuse_contraction";
    /// Comma-separated active effects.
    pub const EFFECTS: &str = "effects";
    /// Comma-separated coordinates of the design.
    pub const COORDINATES: &str = "coordinates";
    pub const OUTPUT_RATE_HZ: &str = "output_rate_hz";
    pub const DURATION_S: &str = "duration_s";
    /// At the start.
    pub const LATITUDE_DEG: &str = "latitude_deg";
    pub const RHS_COST_NS: &str = "rhs_cost_ns";
    pub const POSE_EVERY_N_SAMPLES: &str = "pose_every_n_samples";
    /// `true` when the run kept Jacobi's integral by projection (`[simulation]
    /// keep_jacobi_integral`); absent otherwise.
    pub const KEEP_JACOBI_INTEGRAL: &str = "keep_jacobi_integral";
}

/// The `result` metadata record: how the run ended, written when it closes its file (absent from
/// a recovered file). Files of earlier builds carry these keys in [`run_record`].
pub mod result_record {
    pub const NAME: &str = "result";
    /// One of the [`super::status`] strings.
    pub const STATUS: &str = "status";
    pub use super::solver_stats::{JACOBIAN_EVALS, REJECTED_STEPS, RHS_EVALS, STEPS, WALL_TIME_S};
}

/// The `design_constants` metadata record: values the analysis compares against.
pub mod design_constants_record {
    pub const NAME: &str = "design_constants";
    pub const SPIN_MOMENTUM_N_M_S: &str = "spin_momentum_n_m_s";
    pub const PENDULOUS_MOMENT_N_M: &str = "pendulous_moment_n_m";
    pub const DAMPER_KAPPA_N_M: &str = "damper_kappa_n_m";
    /// Closed form at the start latitude.
    pub const UNDAMPED_PERIOD_S: &str = "undamped_period_s";
    pub const SCHULER_PERIOD_S: &str = "schuler_period_s";
    /// The slow mode of the linearisation at the start.
    pub const MODE_PERIOD_S: &str = "mode_period_s";
    pub const MODE_DECAY_RATE_PER_S: &str = "mode_decay_rate_per_s";
}

/// The `scene` metadata record.
pub mod scene_record {
    pub const NAME: &str = "scene";
    /// The scene file's text.
    pub const TOML: &str = "toml";
    pub const PATH: &str = "path";
}

/// The `design` metadata record.
pub mod design_record {
    pub const NAME: &str = "design";
    /// The design file's text.
    pub const TOML: &str = "toml";
    pub const PATH: &str = "path";
    /// The scene's overrides, `key = value` joined by `; `.
    pub const OVERRIDES: &str = "overrides";
}

/// The `bodies` metadata record: keys `<body>.<what>`, see [`key`].
pub mod bodies_record {
    pub const NAME: &str = "bodies";
    /// The parent body, or [`super::tf::SHIP_FRAME`] / [`super::tf::EARTH_FRAME`] for the
    /// chain's root.
    pub const PARENT: &str = "parent";
    /// A [`super::BodyShape`]'s [`super::BodyShape::metadata_value`].
    pub const SHAPE: &str = "shape";
    /// A rotor's spin axis in the body frame, `[x, y, z]`.
    pub const SPIN_AXIS: &str = "spin_axis";
    pub const SPIN_RAD_PER_S: &str = "spin_rad_per_s";
    /// Communicating pots the body carries: `<body>.pots.<name>`, a
    /// [`super::PotsDrawing`]'s [`super::PotsDrawing::metadata_value`].
    pub const POTS: &str = "pots";
    /// A liquid tank the body carries: `<body>.tank.<name>`, a [`super::TankDrawing`]'s
    /// [`super::TankDrawing::metadata_value`].
    pub const TANK: &str = "tank";
    /// A spring from the body to another: `<body>.spring.<name>`, a [`super::SpringDrawing`]'s
    /// [`super::SpringDrawing::metadata_value`].
    pub const SPRING: &str = "spring";
    /// A linkage's rod from the body to another: `<body>.linkage.<name>`, a
    /// [`super::SpringDrawing`]'s [`super::SpringDrawing::metadata_value`] (the same line).
    pub const LINKAGE: &str = "linkage";

    /// The key of one body's entry: `<body>.<what>`.
    pub fn key(body: &str, what: &str) -> String {
        format!("{body}.{what}")
    }

    /// The key of the pots `name` carried by `body`: `<body>.pots.<name>`.
    pub fn pots_key(body: &str, name: &str) -> String {
        format!("{body}.{POTS}.{name}")
    }

    /// The key of the spring `name` attached to `body`: `<body>.spring.<name>`.
    pub fn spring_key(body: &str, name: &str) -> String {
        format!("{body}.{SPRING}.{name}")
    }

    /// The key of the linkage `name` attached to `body`: `<body>.linkage.<name>`.
    pub fn linkage_key(body: &str, name: &str) -> String {
        format!("{body}.{LINKAGE}.{name}")
    }

    /// The key of the tank `name` carried by `body`: `<body>.tank.<name>`.
    pub fn tank_key(body: &str, name: &str) -> String {
        format!("{body}.{TANK}.{name}")
    }
}

/// How a run ended: the `status` of the [`result_record`].
pub mod status {
    /// The run reached its end.
    pub const COMPLETE: &str = "complete";
    /// The start of the status of a run stopped early (see [`interrupted_at`]).
    pub const INTERRUPTED_PREFIX: &str = "interrupted at t = ";
    /// What readers report for a file with no `result` record.
    pub const RECOVERED: &str = "incomplete (no result record: recovered from a killed run)";

    /// The status of a run stopped at simulated time `t_s`: `interrupted at t = … s`.
    pub fn interrupted_at(t_s: f64) -> String {
        format!("{INTERRUPTED_PREFIX}{t_s} s")
    }
}

/// The attachments of a recording.
pub mod attachments {
    pub const SCENE_TOML: &str = "scene.toml";
    pub const DESIGN_TOML: &str = "design.toml";
    pub const TOML_MEDIA_TYPE: &str = "application/toml";
}

/// What a body is drawn as (sizes in metres): the vocabulary of the design file's `shape` tables,
/// recorded as `<body>.shape` in the [`bodies_record`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum BodyShape {
    /// A ring about the body's z axis.
    Ring {
        radius_m: f64,
        width_m: f64,
    },
    /// A disc (rotor) about the body's spin axis.
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

/// The words of [`BodyShape`]'s TOML inline table.
pub mod shape {
    pub const KIND: &str = "kind";
    pub const RING: &str = "ring";
    pub const DISC: &str = "disc";
    pub const BOX: &str = "box";
    pub const SPHERE: &str = "sphere";
    pub const HULL: &str = "hull";
    pub const NONE: &str = "none";
    pub const RADIUS_M: &str = "radius_m";
    pub const WIDTH_M: &str = "width_m";
    pub const THICKNESS_M: &str = "thickness_m";
    pub const SIZE_M: &str = "size_m";
}

impl BodyShape {
    /// The shape's kind, e.g. `"ring"`.
    pub fn kind(&self) -> &'static str {
        match self {
            BodyShape::Ring { .. } => shape::RING,
            BodyShape::Disc { .. } => shape::DISC,
            BodyShape::Box { .. } => shape::BOX,
            BodyShape::Sphere { .. } => shape::SPHERE,
            BodyShape::Hull { .. } => shape::HULL,
            BodyShape::None => shape::NONE,
        }
    }

    /// The TOML inline table a design file would give it, e.g.
    /// `{ kind = "ring", radius_m = 0.085, width_m = 0.012 }`.
    pub fn metadata_value(&self) -> String {
        let vector = |v: &[f64; 3]| format!("[{}, {}, {}]", v[0], v[1], v[2]);
        let sizes: Vec<(&str, String)> = match self {
            BodyShape::Ring { radius_m, width_m } => vec![
                (shape::RADIUS_M, radius_m.to_string()),
                (shape::WIDTH_M, width_m.to_string()),
            ],
            BodyShape::Disc {
                radius_m,
                thickness_m,
            } => vec![
                (shape::RADIUS_M, radius_m.to_string()),
                (shape::THICKNESS_M, thickness_m.to_string()),
            ],
            BodyShape::Box { size_m } | BodyShape::Hull { size_m } => {
                vec![(shape::SIZE_M, vector(size_m))]
            }
            BodyShape::Sphere { radius_m } => vec![(shape::RADIUS_M, radius_m.to_string())],
            BodyShape::None => Vec::new(),
        };
        let mut text = format!("{{ {} = \"{}\"", shape::KIND, self.kind());
        for (key, value) in sizes {
            text.push_str(&format!(", {key} = {value}"));
        }
        text.push_str(" }");
        text
    }
}

/// Communicating pots as the viewer draws them (carrier's frame, metres): two columns of liquid
/// standing `rest_level_m ± level` on their bases along `axis`, the level read from the compass
/// state's field `level_field`, and the tube between them.
#[derive(Debug, Clone, PartialEq)]
pub struct PotsDrawing {
    pub level_field: String,
    pub first_base_m: [f64; 3],
    pub second_base_m: [f64; 3],
    pub axis: [f64; 3],
    /// Radius of a pot of the open section.
    pub radius_m: f64,
    pub rest_level_m: f64,
    /// From the second pot's base to the first's, both included.
    pub tube_path_m: Vec<[f64; 3]>,
}

impl PotsDrawing {
    /// A TOML inline table with the struct's field names as keys.
    pub fn metadata_value(&self) -> String {
        let vector = |v: &[f64; 3]| format!("[{}, {}, {}]", v[0], v[1], v[2]);
        let path: Vec<String> = self.tube_path_m.iter().map(vector).collect();
        format!(
            "{{ level_field = \"{}\", first_base_m = {}, second_base_m = {}, axis = {}, radius_m = {}, rest_level_m = {}, tube_path_m = [{}] }}",
            self.level_field,
            vector(&self.first_base_m),
            vector(&self.second_base_m),
            vector(&self.axis),
            self.radius_m,
            self.rest_level_m,
            path.join(", ")
        )
    }
}

/// A spring between two bodies (the twin-gyro's HH′) or a linkage's rod (the three-gyro's, between
/// G′ and G″), as the viewer draws it: a line from `point_m` in the body whose key holds it to
/// `other_point_m` in `other_body` (each in its body's frame).
#[derive(Debug, Clone, PartialEq)]
pub struct SpringDrawing {
    pub other_body: String,
    pub point_m: [f64; 3],
    pub other_point_m: [f64; 3],
}

impl SpringDrawing {
    /// A TOML inline table with the struct's field names as keys.
    pub fn metadata_value(&self) -> String {
        let v = |p: &[f64; 3]| format!("[{:?}, {:?}, {:?}]", p[0], p[1], p[2]);
        format!(
            "{{ other_body = \"{}\", point_m = {}, other_point_m = {} }}",
            self.other_body,
            v(&self.point_m),
            v(&self.other_point_m)
        )
    }
}

/// A liquid tank on its carrier (the carrier's frame), as the viewer draws it: each compartment
/// a column of oil over its floor at `floor_height_m`, `rest_depth_m` plus its level high, the
/// level Σ coefficient × compass-state field (the last compartment's follows from the others').
#[derive(Debug, Clone, PartialEq)]
pub struct TankDrawing {
    pub rest_depth_m: f64,
    pub floor_height_m: f64,
    pub compartments: Vec<TankCompartmentDrawing>,
}

/// One compartment of a [`TankDrawing`].
#[derive(Debug, Clone, PartialEq)]
pub struct TankCompartmentDrawing {
    pub centroid_m: [f64; 2],
    /// Radius of a circle of the compartment's area.
    pub radius_m: f64,
    pub level_fields: Vec<String>,
    pub level_coefficients: Vec<f64>,
}

impl TankDrawing {
    /// A TOML inline table with the struct's field names as keys.
    pub fn metadata_value(&self) -> String {
        let comps: Vec<String> = self
            .compartments
            .iter()
            .map(|c| {
                let fields: Vec<String> =
                    c.level_fields.iter().map(|f| format!("\"{f}\"")).collect();
                let coefs: Vec<String> =
                    c.level_coefficients.iter().map(|x| format!("{x:?}")).collect();
                format!(
                    "{{ centroid_m = [{:?}, {:?}], radius_m = {:?}, level_fields = [{}], level_coefficients = [{}] }}",
                    c.centroid_m[0],
                    c.centroid_m[1],
                    c.radius_m,
                    fields.join(", "),
                    coefs.join(", ")
                )
            })
            .collect();
        format!(
            "{{ rest_depth_m = {:?}, floor_height_m = {:?}, compartments = [{}] }}",
            self.rest_depth_m,
            self.floor_height_m,
            comps.join(", ")
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shapes_are_written_as_design_tables() {
        let ring = BodyShape::Ring {
            radius_m: 0.085,
            width_m: 0.012,
        };
        assert_eq!(
            ring.metadata_value(),
            r#"{ kind = "ring", radius_m = 0.085, width_m = 0.012 }"#
        );
        assert_eq!(
            BodyShape::Hull {
                size_m: [120.0, 14.5, 8.0]
            }
            .metadata_value(),
            r#"{ kind = "hull", size_m = [120, 14.5, 8] }"#
        );
        assert_eq!(BodyShape::None.metadata_value(), r#"{ kind = "none" }"#);
    }

    #[test]
    fn compass_fields_follow_the_coordinates() {
        let s = compass_state::schema(&["zeta", "theta"]);
        let names: Vec<&str> = s.fields.iter().map(|f| f.name.as_str()).collect();
        assert_eq!(
            names,
            [
                "time_s",
                "reading_error_rad",
                "compass_heading_rad",
                "true_heading_rad",
                "tilt_rad",
                "zeta_rad",
                "theta_rad",
                "zeta_rate_rad_per_s",
                "theta_rate_rad_per_s"
            ]
        );
        assert_eq!(status::interrupted_at(12.5), "interrupted at t = 12.5 s");
    }
}
