//! One recording read into what the viewer draws: series columns, pose tracks per frame, body
//! shapes and rotor axes from the metadata, manoeuvre events.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use gyro_mcap::contract::{
    bodies_record, compass_state, design_record, events as events_channel, result_record,
    run_record, ship_state, status, tf,
};
use gyro_mcap::{Column, Recording};
use gyro_model::Shape;
use serde::Deserialize;

use crate::ViewError;

/// The local level frame at the pivot: the root of every pose tree.
pub(crate) const EARTH_FRAME: &str = tf::EARTH_FRAME;

/// Columns of one record channel (full rate), by field name.
#[derive(Debug, Default)]
pub(crate) struct Series {
    pub time_ns: Vec<i64>,
    pub columns: BTreeMap<String, Vec<f64>>,
}

impl Series {
    pub(crate) fn get(&self, name: &str) -> Option<&[f64]> {
        self.columns.get(name).map(Vec::as_slice)
    }
    pub(crate) fn take(&mut self, name: &str) -> Option<Vec<f64>> {
        self.columns.remove(name)
    }
}

/// The poses of one frame in its parent, sorted by time.
#[derive(Debug)]
pub(crate) struct Track {
    pub parent: String,
    pub time_ns: Vec<i64>,
    pub translation_m: Vec<[f64; 3]>,
    pub rotation_xyzw: Vec<[f64; 4]>,
}

/// A body of the design as the viewer draws it.
#[derive(Debug, Clone)]
pub(crate) struct BodyInfo {
    pub shape: Shape,
    /// Spin axis (unit, body frame) and sign of the spin, for rotors.
    pub rotor: Option<([f64; 3], f64)>,
    /// Communicating pots the body carries, by name.
    pub pots: Vec<(String, PotsInfo)>,
    /// Liquid tanks the body carries, by name.
    pub tanks: Vec<(String, TankInfo)>,
    /// Springs from this body to others, by name.
    pub springs: Vec<(String, SpringInfo)>,
    /// Linkages' rods from this body to others, by name (drawn as springs are).
    pub linkages: Vec<(String, SpringInfo)>,
}

/// A spring or a linkage's rod between two bodies as recorded
/// (`gyro_mcap::contract::SpringDrawing`).
#[derive(Debug, Clone, Deserialize)]
pub(crate) struct SpringInfo {
    pub other_body: String,
    pub point_m: [f64; 3],
    pub other_point_m: [f64; 3],
}

#[derive(Deserialize)]
struct SpringHolder {
    spring: SpringInfo,
}

/// Parses a `<body>.spring.<name>` metadata value.
pub(crate) fn parse_spring(text: &str) -> Result<SpringInfo, String> {
    let s = toml::from_str::<SpringHolder>(&format!("spring = {text}"))
        .map(|h| h.spring)
        .map_err(|e| e.message().to_owned())?;
    if !s
        .point_m
        .iter()
        .chain(&s.other_point_m)
        .all(|x| x.is_finite())
    {
        return Err("a spring needs finite attachment points".into());
    }
    Ok(s)
}

/// A liquid tank as recorded (`gyro_mcap::contract::TankDrawing`, carrier's frame).
#[derive(Debug, Clone, Deserialize)]
pub(crate) struct TankInfo {
    pub rest_depth_m: f64,
    pub floor_height_m: f64,
    pub compartments: Vec<TankCompartmentInfo>,
}

#[derive(Debug, Clone, Deserialize)]
pub(crate) struct TankCompartmentInfo {
    pub centroid_m: [f64; 2],
    pub radius_m: f64,
    #[serde(default)]
    pub level_fields: Vec<String>,
    #[serde(default)]
    pub level_coefficients: Vec<f64>,
}

#[derive(Deserialize)]
struct TankHolder {
    tank: TankInfo,
}

/// Parses a `<body>.tank.<name>` metadata value.
pub(crate) fn parse_tank(text: &str) -> Result<TankInfo, String> {
    let t = toml::from_str::<TankHolder>(&format!("tank = {text}"))
        .map(|h| h.tank)
        .map_err(|e| e.message().to_owned())?;
    let fine = t.rest_depth_m > 0.0
        && t.rest_depth_m.is_finite()
        && t.floor_height_m.is_finite()
        && !t.compartments.is_empty()
        && t.compartments.iter().all(|c| {
            c.centroid_m.iter().all(|x| x.is_finite())
                && c.radius_m > 0.0
                && c.radius_m.is_finite()
                && c.level_fields.len() == c.level_coefficients.len()
                && c.level_coefficients.iter().all(|x| x.is_finite())
        });
    if !fine {
        return Err("a tank needs a positive depth, compartments with finite centroids, positive radii and one coefficient per level field".into());
    }
    Ok(t)
}

/// Communicating pots as recorded (`gyro_mcap::contract::PotsDrawing`, carrier's frame).
#[derive(Debug, Clone, Deserialize)]
pub(crate) struct PotsInfo {
    pub level_field: String,
    pub first_base_m: [f64; 3],
    pub second_base_m: [f64; 3],
    pub axis: [f64; 3],
    pub radius_m: f64,
    pub rest_level_m: f64,
    #[serde(default)]
    pub tube_path_m: Vec<[f64; 3]>,
}

#[derive(Deserialize)]
struct PotsHolder {
    pots: PotsInfo,
}

/// Parses a `<body>.pots.<name>` metadata value.
pub(crate) fn parse_pots(text: &str) -> Result<PotsInfo, String> {
    let p = toml::from_str::<PotsHolder>(&format!("pots = {text}"))
        .map(|h| h.pots)
        .map_err(|e| e.message().to_owned())?;
    let finite = p
        .first_base_m
        .iter()
        .chain(&p.second_base_m)
        .chain(&p.axis)
        .chain(p.tube_path_m.iter().flatten())
        .chain([&p.radius_m, &p.rest_level_m])
        .all(|x| x.is_finite());
    let n = p.axis.iter().map(|x| x * x).sum::<f64>().sqrt();
    if !finite || n == 0.0 || p.radius_m <= 0.0 || p.rest_level_m <= 0.0 {
        return Err(
            "pots need finite positions, a non-zero axis and a positive radius and level".into(),
        );
    }
    Ok(PotsInfo {
        axis: p.axis.map(|x| x / n),
        ..p
    })
}

#[derive(Debug, Clone)]
pub(crate) struct Event {
    pub time_ns: i64,
    pub phase: String,
    pub manoeuvre: String,
    pub description: String,
}

/// Everything the viewer takes from one recording.
#[derive(Debug)]
pub(crate) struct RunData {
    pub path: PathBuf,
    /// Entity-path-safe name, unique among the runs viewed together.
    pub name: String,
    pub compass: Series,
    pub ship: Series,
    pub events: Vec<Event>,
    /// Frame name → poses; frames in the order first seen.
    pub tracks: Vec<(String, Track)>,
    pub bodies: BTreeMap<String, BodyInfo>,
    pub metadata: BTreeMap<String, BTreeMap<String, String>>,
}

fn series(rec: &Recording, topic: &str) -> Result<Series, ViewError> {
    if !rec.channels().iter().any(|c| c.topic == topic) {
        return Ok(Series::default());
    }
    let table = rec.read_records(topic)?;
    let time_ns = to_i64_ns(&table.log_time_ns);
    let columns = table
        .columns
        .into_iter()
        .filter_map(|(name, col)| match col {
            Column::F64(v) => Some((name, v)),
            _ => None,
        })
        .collect();
    Ok(Series { time_ns, columns })
}

fn to_i64_ns(t: &[u64]) -> Vec<i64> {
    t.iter()
        .map(|&x| i64::try_from(x).unwrap_or(i64::MAX))
        .collect()
}

fn events(rec: &Recording) -> Result<Vec<Event>, ViewError> {
    if !rec
        .channels()
        .iter()
        .any(|c| c.topic == events_channel::TOPIC)
    {
        return Ok(Vec::new());
    }
    let table = rec.read_records(events_channel::TOPIC)?;
    let strings = |name: &str| -> Vec<String> {
        table
            .column(name)
            .and_then(Column::as_str)
            .map(<[String]>::to_vec)
            .unwrap_or_else(|| vec![String::new(); table.len()])
    };
    let (phase, manoeuvre, description) = (
        strings(events_channel::PHASE),
        strings(events_channel::MANOEUVRE),
        strings(events_channel::DESCRIPTION),
    );
    let time_ns = to_i64_ns(&table.log_time_ns);
    Ok((0..table.len())
        .map(|i| Event {
            time_ns: time_ns[i],
            phase: phase.get(i).cloned().unwrap_or_default(),
            manoeuvre: manoeuvre.get(i).cloned().unwrap_or_default(),
            description: description.get(i).cloned().unwrap_or_default(),
        })
        .collect())
}

fn tracks(rec: &Recording) -> Result<Vec<(String, Track)>, ViewError> {
    if !rec.channels().iter().any(|c| c.topic == tf::TOPIC) {
        return Ok(Vec::new());
    }
    let poses = rec.read_poses(tf::TOPIC)?;
    let mut index: BTreeMap<&str, usize> = BTreeMap::new();
    let mut out: Vec<(String, Track)> = Vec::new();
    for i in 0..poses.len() {
        let child = poses.child_frame(i);
        let slot = *index.entry(child).or_insert_with(|| {
            out.push((
                child.to_owned(),
                Track {
                    parent: poses.parent_frame(i).to_owned(),
                    time_ns: Vec::new(),
                    translation_m: Vec::new(),
                    rotation_xyzw: Vec::new(),
                },
            ));
            out.len() - 1
        });
        let track = &mut out[slot].1;
        track
            .time_ns
            .push(i64::try_from(poses.log_time_ns[i]).unwrap_or(i64::MAX));
        track.translation_m.push(poses.translation_m[i]);
        track.rotation_xyzw.push(poses.rotation_xyzw[i]);
    }
    Ok(out)
}

#[derive(Deserialize)]
struct ShapeHolder {
    shape: Shape,
}

/// Parses a `bodies` metadata value such as `{ kind = "ring", radius_m = 0.085, width_m = 0.012 }`.
pub(crate) fn parse_shape(text: &str) -> Result<Shape, String> {
    toml::from_str::<ShapeHolder>(&format!("shape = {text}"))
        .map(|h| h.shape)
        .map_err(|e| e.message().to_owned())
}

/// Rotor axes and spin signs by body name, from the design TOML in the metadata.
fn rotors(design_toml: &str) -> BTreeMap<String, ([f64; 3], f64)> {
    let mut out = BTreeMap::new();
    let Ok(doc) = design_toml.parse::<toml::Table>() else {
        return out;
    };
    let Some(bodies) = doc.get("body").and_then(toml::Value::as_array) else {
        return out;
    };
    for b in bodies {
        let (Some(name), Some(rotor)) = (
            b.get("name").and_then(toml::Value::as_str),
            b.get("rotor").and_then(toml::Value::as_table),
        ) else {
            continue;
        };
        let num = |v: &toml::Value| v.as_float().or_else(|| v.as_integer().map(|i| i as f64));
        let axis: Vec<f64> = rotor
            .get("axis")
            .and_then(toml::Value::as_array)
            .map(|a| a.iter().filter_map(num).collect())
            .unwrap_or_default();
        let axis = match axis.as_slice() {
            [x, y, z] if (x * x + y * y + z * z).sqrt() > 1e-12 => {
                let n = (x * x + y * y + z * z).sqrt();
                [x / n, y / n, z / n]
            }
            _ => [0.0, 0.0, 1.0],
        };
        let sign = rotor
            .get("spin_rpm")
            .and_then(num)
            .map_or(1.0, |s| if s < 0.0 { -1.0 } else { 1.0 });
        out.insert(name.to_owned(), (axis, sign));
    }
    out
}

/// A rotor's axis and spin sign as the recorder writes them: `<body>.spin_axis = "[x, y, z]"`,
/// `<body>.spin_rad_per_s`.
fn recorded_rotor(entries: &BTreeMap<String, String>, body: &str) -> Option<([f64; 3], f64)> {
    #[derive(Deserialize)]
    struct Axis {
        v: [f64; 3],
    }
    let text = entries.get(&bodies_record::key(body, bodies_record::SPIN_AXIS))?;
    let [x, y, z] = toml::from_str::<Axis>(&format!("v = {text}")).ok()?.v;
    let n = (x * x + y * y + z * z).sqrt();
    if !(n.is_finite() && n > 1e-12) {
        return None;
    }
    let sign = entries
        .get(&bodies_record::key(body, bodies_record::SPIN_RAD_PER_S))
        .and_then(|s| s.trim().parse::<f64>().ok())
        .map_or(1.0, |s| if s < 0.0 { -1.0 } else { 1.0 });
    Some(([x / n, y / n, z / n], sign))
}

fn bodies(
    path: &Path,
    metadata: &BTreeMap<String, BTreeMap<String, String>>,
) -> Result<BTreeMap<String, BodyInfo>, ViewError> {
    let rotors = metadata
        .get(design_record::NAME)
        .and_then(|d| d.get(design_record::TOML))
        .map(|t| rotors(t))
        .unwrap_or_default();
    let mut out = BTreeMap::new();
    if let Some(entries) = metadata.get(bodies_record::NAME) {
        for (key, value) in entries {
            // The contract names a `shape` and a `parent` per body; accept `<body>.shape`,
            // `<body>/shape` and `shape.<body>` spellings of the key.
            let shape_key = bodies_record::SHAPE;
            let Some(body) = key
                .strip_suffix(&format!(".{shape_key}"))
                .or_else(|| key.strip_suffix(&format!("/{shape_key}")))
                .or_else(|| key.strip_prefix(&format!("{shape_key}.")))
            else {
                continue;
            };
            let shape = parse_shape(value).map_err(|detail| ViewError::Metadata {
                path: path.to_path_buf(),
                key: format!("{}/{key}", bodies_record::NAME),
                detail,
            })?;
            let rotor = recorded_rotor(entries, body)
                .or_else(|| rotors.get(body).copied())
                .or(match shape {
                    Shape::Disc { .. } => Some(([0.0, 0.0, 1.0], 1.0)),
                    _ => None,
                });
            out.insert(
                body.to_owned(),
                BodyInfo {
                    shape,
                    rotor,
                    pots: Vec::new(),
                    tanks: Vec::new(),
                    springs: Vec::new(),
                    linkages: Vec::new(),
                },
            );
        }
        for (key, value) in entries {
            let bad = |detail: String| ViewError::Metadata {
                path: path.to_path_buf(),
                key: format!("{}/{key}", bodies_record::NAME),
                detail,
            };
            let part = |what: &str| key.split_once(&format!(".{what}."));
            // A linkage's rod is recorded as a spring's line is; only the list differs.
            let line = part(bodies_record::LINKAGE)
                .map(|p| (p, true))
                .or_else(|| part(bodies_record::SPRING).map(|p| (p, false)));
            if let Some(((body, name), linkage)) = line {
                let drawing = parse_spring(value).map_err(bad)?;
                if let Some(b) = out.get_mut(body) {
                    let list = if linkage {
                        &mut b.linkages
                    } else {
                        &mut b.springs
                    };
                    list.push((name.to_owned(), drawing));
                }
            } else if let Some((body, name)) = part(bodies_record::TANK) {
                let tank = parse_tank(value).map_err(bad)?;
                if let Some(b) = out.get_mut(body) {
                    b.tanks.push((name.to_owned(), tank));
                }
            } else if let Some((body, name)) = part(bodies_record::POTS) {
                let pots = parse_pots(value).map_err(bad)?;
                if let Some(b) = out.get_mut(body) {
                    b.pots.push((name.to_owned(), pots));
                }
            }
        }
    }
    Ok(out)
}

/// Characters allowed in an entity path part; others become `_`.
pub(crate) fn entity_name(s: &str) -> String {
    let mut out: String = s
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '_' || c == '-' {
                c
            } else {
                '_'
            }
        })
        .collect();
    if out.is_empty() {
        out.push('_');
    }
    out
}

impl RunData {
    pub(crate) fn load(path: &Path, name: String) -> Result<RunData, ViewError> {
        let rec = Recording::open(path)?;
        let metadata = rec.metadata().clone();
        Ok(RunData {
            path: path.to_path_buf(),
            name,
            compass: series(&rec, compass_state::TOPIC)?,
            ship: series(&rec, ship_state::TOPIC)?,
            events: events(&rec)?,
            tracks: tracks(&rec)?,
            bodies: bodies(path, &metadata)?,
            metadata,
        })
    }

    pub(crate) fn meta(&self, record: &str, key: &str) -> Option<&str> {
        self.metadata.get(record)?.get(key).map(String::as_str)
    }

    /// How the run ended, read as `gyro_analysis::Run::status` reads it: the `result` record,
    /// else the `run` record (files of earlier builds), else [`status::RECOVERED`].
    pub(crate) fn status(&self) -> &str {
        self.meta(result_record::NAME, result_record::STATUS)
            .or_else(|| self.meta(run_record::NAME, result_record::STATUS))
            .unwrap_or(status::RECOVERED)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shapes_parse_from_metadata_text() {
        assert_eq!(
            parse_shape(r#"{ kind = "ring", radius_m = 0.085, width_m = 0.012 }"#),
            Ok(Shape::Ring {
                radius_m: 0.085,
                width_m: 0.012
            })
        );
        assert_eq!(parse_shape(r#"{ kind = "none" }"#), Ok(Shape::None));
        assert!(parse_shape(r#"{ kind = "teapot" }"#).is_err());
        assert!(parse_shape("]]").is_err());
    }

    #[test]
    fn every_recorded_shape_parses() {
        use gyro_mcap::contract::BodyShape;
        let cases = [
            (
                BodyShape::Ring {
                    radius_m: 0.085,
                    width_m: 0.012,
                },
                Shape::Ring {
                    radius_m: 0.085,
                    width_m: 0.012,
                },
            ),
            (
                BodyShape::Disc {
                    radius_m: 0.06,
                    thickness_m: 0.03,
                },
                Shape::Disc {
                    radius_m: 0.06,
                    thickness_m: 0.03,
                },
            ),
            (
                BodyShape::Box {
                    size_m: [1.0, 0.5, 0.25],
                },
                Shape::Box {
                    size_m: [1.0, 0.5, 0.25],
                },
            ),
            (
                BodyShape::Sphere { radius_m: 0.08 },
                Shape::Sphere { radius_m: 0.08 },
            ),
            (
                BodyShape::Hull {
                    size_m: [120.0, 14.5, 8.0],
                },
                Shape::Hull {
                    size_m: [120.0, 14.5, 8.0],
                },
            ),
            (BodyShape::None, Shape::None),
        ];
        for (recorded, drawn) in cases {
            assert_eq!(parse_shape(&recorded.metadata_value()), Ok(drawn));
        }
    }

    #[test]
    fn rotor_axes_come_from_the_design() {
        let toml = r#"
            [[body]]
            name = "torus"
            rotor = { axis = [0.0, 2.0, 0.0], polar_inertia_kg_m2 = 0.005, spin_rpm = -9000.0, spin = "free" }
            [[body]]
            name = "ring"
        "#;
        let r = rotors(toml);
        assert_eq!(r.get("torus"), Some(&([0.0, 1.0, 0.0], -1.0)));
        assert!(!r.contains_key("ring"));
        assert!(rotors("not toml [").is_empty());
    }

    #[test]
    fn rotor_axes_come_from_the_bodies_record() {
        let entries: BTreeMap<String, String> = [
            ("rotor.spin_axis", "[0.0, 0.0, 2.0]"),
            ("rotor.spin_rad_per_s", "-2000.5"),
            ("bad.spin_axis", "[0.0, 0.0]"),
        ]
        .iter()
        .map(|(k, v)| ((*k).to_owned(), (*v).to_owned()))
        .collect();
        assert_eq!(
            recorded_rotor(&entries, "rotor"),
            Some(([0.0, 0.0, 1.0], -1.0))
        );
        assert_eq!(recorded_rotor(&entries, "bad"), None);
        assert_eq!(recorded_rotor(&entries, "none"), None);
    }

    #[test]
    fn entity_names_are_sanitised() {
        assert_eq!(entity_name("sperry mk/14"), "sperry_mk_14");
        assert_eq!(entity_name(""), "_");
    }
}
