//! A synthetic recording that follows docs/recordings.md: a small chain
//! earth → ship → gimbal (ring) → float (sphere) → rotor (disc), compass and ship state,
//! manoeuvre events, metadata with body shapes. Known values so the viewer's output can be checked.
#![allow(dead_code)]

use std::collections::BTreeMap;
use std::path::Path;

use gyro_mcap::contract::{
    BodyShape, PotsDrawing, SpringDrawing, TankCompartmentDrawing, TankDrawing, bodies_record,
    compass_state, design_record, events, result_record, run_record, ship_state, status, tf,
};
use gyro_mcap::{Pose, RecordingWriter, Value, WriterOptions};

pub const FRAMES: [(&str, &str); 4] = [
    (tf::SHIP_FRAME, tf::EARTH_FRAME),
    ("gimbal", tf::SHIP_FRAME),
    ("float", "gimbal"),
    ("rotor", "float"),
];

/// The synthetic reading error: a damped sinusoid (radians) — also what the test's fit returns.
pub const ERR_OFFSET: f64 = 0.002;
pub const ERR_AMP: f64 = 0.02;
pub const ERR_DECAY: f64 = 1.0 / 1500.0;
pub const ERR_PERIOD: f64 = 600.0;

pub fn reading_error(t: f64) -> f64 {
    ERR_OFFSET + ERR_AMP * (-ERR_DECAY * t).exp() * (std::f64::consts::TAU * t / ERR_PERIOD).cos()
}
pub fn tilt(t: f64) -> f64 {
    0.0005 * (std::f64::consts::TAU * t / ERR_PERIOD).sin()
}
pub fn roll(t: f64) -> f64 {
    0.05 * (std::f64::consts::TAU * t / 9.0).sin()
}
pub fn speed(t: f64) -> f64 {
    if t < 300.0 { 5.0 } else { 10.0 }
}

fn quat_x(a: f64) -> [f64; 4] {
    [(0.5 * a).sin(), 0.0, 0.0, (0.5 * a).cos()]
}
fn quat_y(a: f64) -> [f64; 4] {
    [0.0, (0.5 * a).sin(), 0.0, (0.5 * a).cos()]
}

/// Pose of each frame at time t: (translation, rotation) in its parent.
pub fn pose(frame: &str, t: f64) -> ([f64; 3], [f64; 4]) {
    match frame {
        tf::SHIP_FRAME => ([0.0, 0.0, -0.5], quat_x(roll(t))),
        // The gimbal's hinge undoes the roll; the float carries the tilt.
        "gimbal" => ([0.0, 0.0, 0.5], quat_x(-roll(t))),
        "float" => ([0.0, 0.0, 0.0], quat_y(tilt(t))),
        _ => ([0.0, 0.0, 0.01], [0.0, 0.0, 0.0, 1.0]),
    }
}

const DESIGN_TOML: &str = r#"
name = "synthetic"
kind = "gyrocompass"
root = "ship"
[[body]]
name = "rotor"
parent = "float"
rotor = { axis = [1.0, 0.0, 0.0], polar_inertia_kg_m2 = 0.01, spin_rpm = 6000.0, spin = "held" }
shape = { kind = "disc", radius_m = 0.06, thickness_m = 0.03 }
"#;

/// The synthetic mercury level of [`write_recording_with_pots`], m.
pub fn mercury_level(t: f64) -> f64 {
    0.004 * (std::f64::consts::TAU * t / 30.0).sin()
}

/// The pots [`write_recording_with_pots`] puts on the float.
pub fn pots() -> PotsDrawing {
    PotsDrawing {
        level_field: "u_m".into(),
        first_base_m: [0.1, 0.0, -0.02],
        second_base_m: [-0.1, 0.0, -0.02],
        axis: [0.0, 0.0, 1.0],
        radius_m: 0.01,
        rest_level_m: 0.03,
        tube_path_m: vec![[-0.1, 0.0, -0.02], [0.1, 0.0, -0.02]],
    }
}

/// The two-compartment tank [`write_recording_with_pots`] also puts on the float: its levels
/// are ±u (the second compartment's follows from the first's, as a tank's last one does).
pub fn tank() -> TankDrawing {
    let compartment = |x: f64, a: f64| TankCompartmentDrawing {
        centroid_m: [x, 0.05],
        radius_m: 0.02,
        level_fields: vec!["u_m".into()],
        level_coefficients: vec![a],
    };
    TankDrawing {
        rest_depth_m: 0.01,
        floor_height_m: -0.07,
        compartments: vec![compartment(0.05, 1.0), compartment(-0.05, -1.0)],
    }
}

/// The spring [`write_recording_with_pots`] also puts between the gimbal and the float.
pub fn spring() -> SpringDrawing {
    SpringDrawing {
        other_body: "float".into(),
        point_m: [0.1, 0.0, 0.0],
        other_point_m: [0.0, 0.05, -0.02],
    }
}

/// The linkage's rod [`write_recording_with_pots`] also puts between the float and the gimbal.
pub fn linkage() -> SpringDrawing {
    SpringDrawing {
        other_body: "gimbal".into(),
        point_m: [0.0, -0.05, 0.07],
        other_point_m: [0.02, 0.05, 0.0],
    }
}

/// Writes `n` samples at `rate_hz` to `path`.
pub fn write_recording(path: &Path, n: usize, rate_hz: f64) {
    write(path, n, rate_hz, false);
}

/// The same run with communicating pots on the float, their level a coordinate `u` in metres.
pub fn write_recording_with_pots(path: &Path, n: usize, rate_hz: f64) {
    write(path, n, rate_hz, true);
}

/// One compass-state sample: the leading fields, θ (and u), then their rates (zero).
fn compass_values(t: f64, heading: f64, with_pots: bool) -> Vec<f64> {
    let err = reading_error(t);
    let mut v = vec![t, err, heading + err, heading, tilt(t), tilt(t)];
    if with_pots {
        v.extend([mercury_level(t), 0.0, 0.0]);
    } else {
        v.push(0.0);
    }
    v
}

fn write(path: &Path, n: usize, rate_hz: f64, with_pots: bool) {
    let mut w = RecordingWriter::create(path, WriterOptions::default()).expect("create");
    let coordinates: &[(&str, &str)] = if with_pots {
        &[("theta", "rad"), ("u", "m")]
    } else {
        &[("theta", "rad")]
    };
    let c = w
        .add_record_channel(
            compass_state::TOPIC,
            &compass_state::schema_with_units(coordinates),
        )
        .expect("channel");
    let s = w
        .add_record_channel(ship_state::TOPIC, &ship_state::schema())
        .expect("channel");
    let e = w
        .add_record_channel(events::TOPIC, &events::schema())
        .expect("channel");
    let tf = w.add_pose_channel(tf::TOPIC).expect("channel");
    let heading = 0.3_f64;
    for i in 0..n {
        let t = i as f64 / rate_hz;
        let ns = (t * 1e9).round() as u64;
        w.write_f64_record(c, ns, &compass_values(t, heading, with_pots))
            .expect("compass");
        let accel = if (300.0..320.0).contains(&t) {
            0.25
        } else {
            0.0
        };
        w.write_f64_record(
            s,
            ns,
            &[
                t,
                0.8,
                0.1,
                heading,
                speed(t),
                roll(t),
                0.0,
                -accel,
                0.0,
                -9.81,
            ],
        )
        .expect("ship");
        for (frame, parent) in FRAMES {
            let (tr, q) = pose(frame, t);
            w.write_pose(
                tf,
                ns,
                &Pose {
                    parent_frame: parent.into(),
                    child_frame: frame.into(),
                    translation_m: tr,
                    rotation_xyzw: q,
                },
            )
            .expect("pose");
        }
    }
    for (t, phase) in [(300.0, events::START), (320.0, events::END)] {
        w.write_record(
            e,
            (t * 1e9) as u64,
            &[
                Value::F64(t),
                Value::Str(phase),
                Value::Str("speed_change"),
                Value::U64(1),
                Value::Str("5 → 10 m/s"),
                Value::F64(5.0),
                Value::F64(10.0),
                Value::F64(heading),
                Value::F64(heading),
                Value::F64(20.0),
            ],
        )
        .expect("event");
    }
    let meta = |pairs: &[(&str, &str)]| -> BTreeMap<String, String> {
        pairs
            .iter()
            .map(|(k, v)| ((*k).into(), (*v).into()))
            .collect()
    };
    w.write_metadata(
        run_record::NAME,
        &meta(&[
            (run_record::SCENE_NAME, "synthetic-speed-change"),
            (run_record::DESIGN_NAME, "synthetic"),
            (run_record::DESIGN_KIND, "gyrocompass"),
            (run_record::OUTPUT_RATE_HZ, &rate_hz.to_string()),
            (run_record::DURATION_S, &(n as f64 / rate_hz).to_string()),
            (result_record::STATUS, status::COMPLETE),
            (run_record::POSE_EVERY_N_SAMPLES, "1"),
        ]),
    )
    .expect("meta");
    let bodies = bodies_metadata(with_pots);
    w.write_metadata(bodies_record::NAME, &bodies)
        .expect("meta");
    w.write_metadata(
        design_record::NAME,
        &meta(&[
            (design_record::TOML, DESIGN_TOML),
            (design_record::PATH, "synthetic.toml"),
        ]),
    )
    .expect("meta");
    w.finish().expect("finish");
}

/// The `bodies` record: the synthetic chain's shapes and parents, and with `with_pots` the
/// pots, the tank and the spring on them.
fn bodies_metadata(with_pots: bool) -> BTreeMap<String, String> {
    let mut bodies = BTreeMap::new();
    for (body, parent, shape) in [
        (
            "gimbal",
            tf::SHIP_FRAME,
            BodyShape::Ring {
                radius_m: 0.12,
                width_m: 0.015,
            },
        ),
        ("float", "gimbal", BodyShape::Sphere { radius_m: 0.08 }),
        (
            "rotor",
            "float",
            BodyShape::Disc {
                radius_m: 0.06,
                thickness_m: 0.03,
            },
        ),
    ] {
        bodies.insert(
            bodies_record::key(body, bodies_record::SHAPE),
            shape.metadata_value(),
        );
        bodies.insert(
            bodies_record::key(body, bodies_record::PARENT),
            parent.to_owned(),
        );
    }
    if with_pots {
        bodies.insert(
            bodies_record::pots_key("float", "mercury"),
            pots().metadata_value(),
        );
        bodies.insert(
            bodies_record::tank_key("float", "oil"),
            tank().metadata_value(),
        );
        bodies.insert(
            bodies_record::spring_key("gimbal", "hh"),
            spring().metadata_value(),
        );
        bodies.insert(
            bodies_record::linkage_key("float", "rod"),
            linkage().metadata_value(),
        );
    }
    bodies
}
