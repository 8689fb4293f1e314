//! Synthetic recordings on the contract of docs/recordings.md, written with gyro-mcap's writer.
#![allow(dead_code, clippy::unwrap_used)]

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use gyro_mcap::{FieldSpec, RecordSchema, RecordingWriter, Value, WriterOptions};

pub fn compass_schema() -> RecordSchema {
    let mut fields = vec![FieldSpec::f64("time_s", "s")];
    for f in [
        "reading_error_rad",
        "compass_heading_rad",
        "true_heading_rad",
        "tilt_rad",
        "zeta_rad",
        "theta_rad",
    ] {
        fields.push(FieldSpec::f64(f, "rad"));
    }
    fields.push(FieldSpec::f64("zeta_rate_rad_per_s", "rad/s"));
    fields.push(FieldSpec::f64("theta_rate_rad_per_s", "rad/s"));
    RecordSchema {
        full_name: "gyrolab.CompassState".into(),
        fields,
    }
}

pub fn ship_schema() -> RecordSchema {
    let mut fields = vec![FieldSpec::f64("time_s", "s")];
    for f in [
        "latitude_rad",
        "longitude_rad",
        "heading_rad",
        "speed_m_per_s",
        "roll_rad",
        "pitch_rad",
        "gravity_north_m_per_s2",
        "gravity_west_m_per_s2",
        "gravity_up_m_per_s2",
    ] {
        fields.push(FieldSpec::f64(f, ""));
    }
    RecordSchema {
        full_name: "gyrolab.ShipState".into(),
        fields,
    }
}

pub fn event_schema() -> RecordSchema {
    RecordSchema {
        full_name: "gyrolab.ManoeuvreEvent".into(),
        fields: vec![
            FieldSpec::f64("time_s", "s"),
            FieldSpec::str("phase"),
            FieldSpec::str("manoeuvre"),
            FieldSpec::u64("segment"),
            FieldSpec::str("description"),
            FieldSpec::f64("speed_before_m_per_s", "m/s"),
            FieldSpec::f64("speed_after_m_per_s", "m/s"),
            FieldSpec::f64("heading_before_rad", "rad"),
            FieldSpec::f64("heading_after_rad", "rad"),
            FieldSpec::f64("duration_s", "s"),
        ],
    }
}

pub fn solver_schema() -> RecordSchema {
    RecordSchema {
        full_name: "gyrolab.SolverStats".into(),
        fields: vec![
            FieldSpec::f64("time_s", "s"),
            FieldSpec::u64("steps"),
            FieldSpec::u64("rejected_steps"),
            FieldSpec::u64("rhs_evals"),
            FieldSpec::u64("jacobian_evals"),
            FieldSpec::f64("wall_time_s", "s"),
        ],
    }
}

/// A manoeuvre event pair: (start, end, segment, speed before/after, heading before/after).
#[derive(Clone, Copy, Debug)]
pub struct Manoeuvre {
    pub start_s: f64,
    pub end_s: f64,
    pub segment: u64,
    pub speed_before: f64,
    pub speed_after: f64,
    pub heading_before: f64,
    pub heading_after: f64,
}

/// What a synthetic run holds.
pub struct Spec {
    pub duration_s: f64,
    pub rate_hz: f64,
    pub error: Box<dyn Fn(f64) -> f64 + Sync>,
    pub tilt: Box<dyn Fn(f64) -> f64 + Sync>,
    pub roll: Box<dyn Fn(f64) -> f64 + Sync>,
    pub latitude_deg: f64,
    pub manoeuvres: Vec<Manoeuvre>,
    pub compass: bool,
    pub ship: bool,
    pub design: String,
    pub scene: String,
    pub undamped_period_s: Option<f64>,
}

impl Default for Spec {
    fn default() -> Self {
        Self {
            duration_s: 6.0 * 3600.0,
            rate_hz: 1.0,
            error: Box::new(|_| 0.0),
            tilt: Box::new(|_| 0.0),
            roll: Box::new(|_| 0.0),
            latitude_deg: 50.0,
            manoeuvres: Vec::new(),
            compass: true,
            ship: true,
            design: "synthetic".into(),
            scene: "calm".into(),
            undamped_period_s: None,
        }
    }
}

pub fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("gyro-analysis-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Writes the run to `path` (finished: summary, indexes, renamed from .partial).
pub fn write_run(path: &Path, spec: &Spec) -> PathBuf {
    let mut w = RecordingWriter::create(path, WriterOptions::default()).unwrap();
    let compass = spec.compass.then(|| {
        w.add_record_channel("/compass/state", &compass_schema())
            .unwrap()
    });
    let ship = spec
        .ship
        .then(|| w.add_record_channel("/ship/state", &ship_schema()).unwrap());
    let events = w.add_record_channel("/events", &event_schema()).unwrap();
    let solver = w
        .add_record_channel("/solver/stats", &solver_schema())
        .unwrap();
    let mut run = BTreeMap::new();
    for (k, v) in [
        ("program_version", "test"),
        ("scene_name", spec.scene.as_str()),
        ("design_name", spec.design.as_str()),
        ("design_kind", "synthetic"),
        ("fidelity", "full"),
        ("integrator", "dopri5"),
        ("rtol", "1e-8"),
        ("atol", "1e-10"),
        ("effects", "earth_rotation"),
        ("status", "complete"),
    ] {
        run.insert(k.to_owned(), v.to_owned());
    }
    run.insert("latitude_deg".into(), spec.latitude_deg.to_string());
    run.insert("duration_s".into(), spec.duration_s.to_string());
    w.write_metadata("run", &run).unwrap();
    let mut constants = BTreeMap::new();
    constants.insert("schuler_period_s".to_owned(), "5064.3".to_owned());
    if let Some(p) = spec.undamped_period_s {
        constants.insert("undamped_period_s".to_owned(), p.to_string());
    }
    w.write_metadata("design_constants", &constants).unwrap();

    let n = (spec.duration_s * spec.rate_hz).round() as u64;
    let lat = spec.latitude_deg.to_radians();
    let mut pending: Vec<(f64, &str, Manoeuvre)> = spec
        .manoeuvres
        .iter()
        .flat_map(|m| [(m.start_s, "start", *m), (m.end_s, "end", *m)])
        .collect();
    pending.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut next_event = 0;
    for i in 0..=n {
        let t = i as f64 / spec.rate_hz;
        let ns = (t * 1e9).round() as u64;
        while next_event < pending.len() && pending[next_event].0 <= t {
            let (te, phase, m) = pending[next_event];
            w.write_record(
                events,
                (te * 1e9).round() as u64,
                &[
                    Value::F64(te),
                    Value::Str(phase),
                    Value::Str("speed_change"),
                    Value::U64(m.segment),
                    Value::Str("synthetic manoeuvre"),
                    Value::F64(m.speed_before),
                    Value::F64(m.speed_after),
                    Value::F64(m.heading_before),
                    Value::F64(m.heading_after),
                    Value::F64(m.end_s - m.start_s),
                ],
            )
            .unwrap();
            next_event += 1;
        }
        if let Some(ch) = compass {
            let e = (spec.error)(t);
            let tilt = (spec.tilt)(t);
            w.write_f64_record(ch, ns, &[t, e, e, 0.0, tilt, e, tilt, 0.0, 0.0])
                .unwrap();
        }
        if let Some(ch) = ship {
            w.write_f64_record(
                ch,
                ns,
                &[t, lat, 0.0, 0.0, 0.0, (spec.roll)(t), 0.0, 0.0, 0.0, -9.81],
            )
            .unwrap();
        }
        if i % 3600 == 0 || i == n {
            w.write_record(
                solver,
                ns,
                &[
                    Value::F64(t),
                    Value::U64(i / 10),
                    Value::U64(1),
                    Value::U64(i * 6 / 10),
                    Value::U64(0),
                    Value::F64(t * 1e-5),
                ],
            )
            .unwrap();
        }
    }
    w.finish().unwrap();
    path.to_path_buf()
}

/// x(t) = c + d t + A e^{−σt} cos(2πt/T + φ).
pub fn damped(c: f64, d: f64, a: f64, sigma: f64, period: f64, phi: f64) -> impl Fn(f64) -> f64 {
    move |t| {
        c + d * t + a * (-sigma * t).exp() * (2.0 * std::f64::consts::PI * t / period + phi).cos()
    }
}

/// A deterministic Gaussian noise source (xorshift + Box–Muller), so tests repeat exactly.
pub struct Noise(u64);

impl Noise {
    pub fn new(seed: u64) -> Self {
        Self(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1)
    }
    fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        ((self.0 >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }
    pub fn gauss(&mut self) -> f64 {
        let (u, v) = (self.uniform(), self.uniform());
        (-2.0 * u.ln()).sqrt() * (2.0 * std::f64::consts::PI * v).cos()
    }
}
