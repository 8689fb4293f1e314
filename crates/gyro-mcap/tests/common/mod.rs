//! A deterministic sample run shared by the tests: three record channels and a pose channel,
//! whose every message can be regenerated from its step number.
#![allow(dead_code, clippy::unwrap_used)]

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use gyro_mcap::{
    ChannelId, Column, FieldSpec, Pose, RecordSchema, Recording, RecordingWriter, Value,
};

/// Values that must survive bit for bit.
pub const AWKWARD: [f64; 12] = [
    0.0,
    -0.0,
    5e-324,                                // smallest subnormal
    f64::from_bits(0x000f_ffff_ffff_ffff), // largest subnormal
    f64::MIN_POSITIVE,
    f64::MAX,
    -f64::MAX,
    f64::INFINITY,
    f64::NEG_INFINITY,
    f64::EPSILON,
    1e300,
    -std::f64::consts::PI,
];

/// A NaN with a payload (quiet bit set, payload 0xdead_beef).
pub fn nan_payload() -> f64 {
    f64::from_bits(0x7ff8_0000_dead_beef)
}

pub fn compass_schema() -> RecordSchema {
    RecordSchema {
        full_name: "gyrolab.CompassState".into(),
        fields: vec![
            FieldSpec::f64("reading_error_rad", "rad"),
            FieldSpec::f64("heading_rad", "rad"),
            FieldSpec::f64("tilt_rad", "rad"),
            FieldSpec::f64("spin_rad_per_s", "rad/s"),
            FieldSpec::f64("awkward", ""),
        ],
    }
}

pub fn event_schema() -> RecordSchema {
    RecordSchema {
        full_name: "gyrolab.ManoeuvreEvent".into(),
        fields: vec![
            FieldSpec::u64("code"),
            FieldSpec::str("label"),
            FieldSpec::f64("value", "m/s"),
            FieldSpec::u64("big"),
        ],
    }
}

pub fn solver_schema() -> RecordSchema {
    RecordSchema {
        full_name: "gyrolab.solver.SolverStats".into(),
        fields: vec![
            FieldSpec::u64("steps"),
            FieldSpec::u64("rhs_calls"),
            FieldSpec::str("integrator"),
        ],
    }
}

pub const FRAMES: [(&str, &str); 3] = [("earth", "ship"), ("ship", "gimbal"), ("gimbal", "rotor")];

/// One message of the sample stream.
#[derive(Debug, Clone, PartialEq)]
pub enum Msg {
    Compass(u64, [f64; 5]),
    Event(u64, u64, String, f64, u64),
    Solver(u64, u64, u64, String),
    Pose(u64, Pose),
}

impl Msg {
    pub fn topic(&self) -> &'static str {
        match self {
            Msg::Compass(..) => "/compass",
            Msg::Event(..) => "/events",
            Msg::Solver(..) => "/solver",
            Msg::Pose(..) => "/poses",
        }
    }
}

/// The messages of step `i` (10 Hz simulated time).
pub fn step(i: u64) -> Vec<Msg> {
    let t = i * 100_000_000;
    let x = i as f64 * 0.01;
    let mut out = vec![Msg::Compass(
        t,
        [
            x.sin() * 1e-3,
            x,
            -x * 1e-9,
            2.0 * std::f64::consts::PI * 20_000.0 / 60.0,
            if i % 13 == 12 {
                nan_payload()
            } else {
                AWKWARD[(i as usize) % AWKWARD.len()]
            },
        ],
    )];
    for (k, (parent, child)) in FRAMES.iter().enumerate() {
        let a = x * (k as f64 + 1.0);
        out.push(Msg::Pose(
            t,
            Pose {
                parent_frame: (*parent).into(),
                child_frame: (*child).into(),
                translation_m: [k as f64, -0.0, a],
                rotation_xyzw: [0.0, 0.0, (a / 2.0).sin(), (a / 2.0).cos()],
            },
        ));
    }
    if i.is_multiple_of(7) {
        out.push(Msg::Event(
            t,
            i / 7,
            format!("turn {} → port ✓", i / 7),
            if i.is_multiple_of(2) { -0.0 } else { 5e-324 },
            if i.is_multiple_of(3) { u64::MAX - i } else { 0 },
        ));
    }
    if i.is_multiple_of(50) {
        out.push(Msg::Solver(
            t,
            i * 3,
            i * 19,
            if i.is_multiple_of(100) {
                String::new()
            } else {
                "dopri5".into()
            },
        ));
    }
    out
}

pub struct Channels {
    pub compass: ChannelId,
    pub events: ChannelId,
    pub solver: ChannelId,
    pub poses: ChannelId,
}

pub fn metadata() -> BTreeMap<String, BTreeMap<String, String>> {
    let mut m = BTreeMap::new();
    m.insert(
        "scene".to_string(),
        BTreeMap::from([
            (
                "toml".to_string(),
                "latitude_deg = 45.0\n[ship]\nspeed_kn = 12\n".to_string(),
            ),
            ("fidelity".to_string(), "full".to_string()),
        ]),
    );
    m.insert(
        "program".to_string(),
        BTreeMap::from([
            ("version".to_string(), "0.1.0".to_string()),
            ("empty".to_string(), String::new()),
        ]),
    );
    m
}

pub fn attachments() -> Vec<(String, String, u64, Vec<u8>)> {
    vec![
        (
            "scene.toml".into(),
            "application/toml".into(),
            0,
            b"latitude_deg = 45.0\n".to_vec(),
        ),
        (
            "blob.bin".into(),
            "application/octet-stream".into(),
            7,
            (0..=255u8).cycle().take(10_000).collect(),
        ),
        ("empty".into(), "text/plain".into(), u64::MAX, Vec::new()),
    ]
}

pub fn start(path: &Path, opts: gyro_mcap::WriterOptions) -> (RecordingWriter, Channels) {
    let mut w = RecordingWriter::create(path, opts).unwrap();
    let ch = Channels {
        compass: w.add_record_channel("/compass", &compass_schema()).unwrap(),
        events: w.add_record_channel("/events", &event_schema()).unwrap(),
        solver: w.add_record_channel("/solver", &solver_schema()).unwrap(),
        poses: w.add_pose_channel("/poses").unwrap(),
    };
    for (name, entries) in metadata() {
        w.write_metadata(&name, &entries).unwrap();
    }
    for (name, media, t, data) in attachments() {
        w.attach(&name, &media, t, &data).unwrap();
    }
    (w, ch)
}

pub fn write(w: &mut RecordingWriter, ch: &Channels, msg: &Msg) {
    match msg {
        Msg::Compass(t, v) => w.write_f64_record(ch.compass, *t, v).unwrap(),
        Msg::Event(t, code, label, value, big) => w
            .write_record(
                ch.events,
                *t,
                &[
                    Value::U64(*code),
                    Value::Str(label),
                    Value::F64(*value),
                    Value::U64(*big),
                ],
            )
            .unwrap(),
        Msg::Solver(t, steps, calls, name) => w
            .write_record(
                ch.solver,
                *t,
                &[Value::U64(*steps), Value::U64(*calls), Value::Str(name)],
            )
            .unwrap(),
        Msg::Pose(t, p) => w.write_pose(ch.poses, *t, p).unwrap(),
    }
}

/// A finished sample recording of `steps` steps.
pub fn write_sample(
    path: &Path,
    steps: u64,
    opts: gyro_mcap::WriterOptions,
) -> gyro_mcap::WriteSummary {
    let (mut w, ch) = start(path, opts);
    for i in 0..steps {
        for m in step(i) {
            write(&mut w, &ch, &m);
        }
    }
    w.finish().unwrap()
}

/// All messages of a recording as `Msg`s, per topic in log-time order.
/// Channels missing from the file (a recovered prefix may lack late ones) read as empty.
pub fn read_back(rec: &Recording) -> BTreeMap<&'static str, Vec<Msg>> {
    let mut out = BTreeMap::new();
    let topics: Vec<String> = rec.channels().into_iter().map(|c| c.topic).collect();
    for topic in ["/compass", "/events", "/solver", "/poses"] {
        if !topics.iter().any(|t| t == topic) {
            out.insert(topic, Vec::new());
        }
    }
    let Ok(c) = rec.read_records("/compass") else {
        return out;
    };
    let cols: Vec<&[f64]> = c
        .columns
        .iter()
        .map(|(_, col)| col.as_f64().unwrap())
        .collect();
    out.insert(
        "/compass",
        (0..c.len())
            .map(|r| {
                Msg::Compass(
                    c.log_time_ns[r],
                    [cols[0][r], cols[1][r], cols[2][r], cols[3][r], cols[4][r]],
                )
            })
            .collect(),
    );
    let Ok(e) = rec.read_records("/events") else {
        return out;
    };
    let (code, label, value, big) = match &e.columns[..] {
        [
            (_, Column::U64(a)),
            (_, Column::Str(b)),
            (_, Column::F64(c)),
            (_, Column::U64(d)),
        ] => (a, b, c, d),
        other => panic!("unexpected event columns {other:?}"),
    };
    out.insert(
        "/events",
        (0..e.len())
            .map(|r| {
                Msg::Event(
                    e.log_time_ns[r],
                    code[r],
                    label[r].clone(),
                    value[r],
                    big[r],
                )
            })
            .collect(),
    );
    let Ok(s) = rec.read_records("/solver") else {
        return out;
    };
    let (steps, calls, name) = match &s.columns[..] {
        [
            (_, Column::U64(a)),
            (_, Column::U64(b)),
            (_, Column::Str(c)),
        ] => (a, b, c),
        other => panic!("unexpected solver columns {other:?}"),
    };
    out.insert(
        "/solver",
        (0..s.len())
            .map(|r| Msg::Solver(s.log_time_ns[r], steps[r], calls[r], name[r].clone()))
            .collect(),
    );
    let Ok(p) = rec.read_poses("/poses") else {
        return out;
    };
    out.insert(
        "/poses",
        (0..p.len())
            .map(|r| {
                Msg::Pose(
                    p.log_time_ns[r],
                    Pose {
                        parent_frame: p.parent_frame(r).to_owned(),
                        child_frame: p.child_frame(r).to_owned(),
                        translation_m: p.translation_m[r],
                        rotation_xyzw: p.rotation_xyzw[r],
                    },
                )
            })
            .collect(),
    );
    out
}

/// Bit-exact comparison (f64 by bits, so NaN payloads and -0.0 count).
pub fn same_bits(a: &Msg, b: &Msg) -> bool {
    fn bits(v: &[f64]) -> Vec<u64> {
        v.iter().map(|x| x.to_bits()).collect()
    }
    match (a, b) {
        (Msg::Compass(t1, v1), Msg::Compass(t2, v2)) => t1 == t2 && bits(v1) == bits(v2),
        (Msg::Event(t1, c1, l1, v1, b1), Msg::Event(t2, c2, l2, v2, b2)) => {
            t1 == t2 && c1 == c2 && l1 == l2 && v1.to_bits() == v2.to_bits() && b1 == b2
        }
        (Msg::Solver(..), Msg::Solver(..)) => a == b,
        (Msg::Pose(t1, p1), Msg::Pose(t2, p2)) => {
            t1 == t2
                && p1.parent_frame == p2.parent_frame
                && p1.child_frame == p2.child_frame
                && bits(&p1.translation_m) == bits(&p2.translation_m)
                && bits(&p1.rotation_xyzw) == bits(&p2.rotation_xyzw)
        }
        _ => false,
    }
}

/// The sample stream of steps `0..steps` in write order.
pub fn stream(steps: u64) -> Vec<Msg> {
    (0..steps).flat_map(step).collect()
}

/// Asserts that `got` (per topic) is exactly a prefix of the write-order stream `all`, and
/// returns its length.
pub fn assert_prefix(got: &BTreeMap<&'static str, Vec<Msg>>, all: &[Msg]) -> usize {
    let total: usize = got.values().map(Vec::len).sum();
    let mut seen: BTreeMap<&str, usize> = BTreeMap::new();
    for (k, m) in all[..total.min(all.len())].iter().enumerate() {
        let i = seen.entry(m.topic()).or_default();
        let have = got.get(m.topic()).and_then(|v| v.get(*i));
        assert!(
            have.is_some_and(|h| same_bits(h, m)),
            "message {k} of the stream ({m:?}) is not message {i} of {} in the recovered file (found {have:?})",
            m.topic()
        );
        *i += 1;
    }
    assert!(
        total <= all.len(),
        "recovered more messages ({total}) than written ({})",
        all.len()
    );
    total
}

pub fn tmp_dir(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
        .join("gyro-mcap")
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}
