//! Synthetic recordings on the contract of docs/recordings.md, written with gyro-mcap's writer.
#![allow(dead_code, clippy::unwrap_used)]

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use gyro_mcap::contract::{
    compass_state, design_constants_record, events, result_record, run_record, ship_state,
    solver_stats, status,
};
use gyro_mcap::{RecordSchema, RecordingWriter, Value, WriterOptions};

pub fn compass_schema() -> RecordSchema {
    compass_state::schema(&["zeta", "theta"])
}

pub fn ship_schema() -> RecordSchema {
    ship_state::schema()
}

pub fn event_schema() -> RecordSchema {
    events::schema()
}

pub fn solver_schema() -> RecordSchema {
    solver_stats::schema()
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
        w.add_record_channel(compass_state::TOPIC, &compass_schema())
            .unwrap()
    });
    let ship = spec.ship.then(|| {
        w.add_record_channel(ship_state::TOPIC, &ship_schema())
            .unwrap()
    });
    let events = w
        .add_record_channel(events::TOPIC, &event_schema())
        .unwrap();
    let solver = w
        .add_record_channel(solver_stats::TOPIC, &solver_schema())
        .unwrap();
    let mut run = BTreeMap::new();
    for (k, v) in [
        (run_record::PROGRAM_VERSION, "test"),
        (run_record::SCENE_NAME, spec.scene.as_str()),
        (run_record::DESIGN_NAME, spec.design.as_str()),
        (run_record::DESIGN_KIND, "synthetic"),
        (run_record::FIDELITY, "full"),
        (run_record::INTEGRATOR, "dopri5"),
        (run_record::RTOL, "1e-8"),
        (run_record::ATOL, "1e-10"),
        (run_record::EFFECTS, "earth_rotation"),
        // A file of an earlier build: how the run ended is in `run`.
        (result_record::STATUS, status::COMPLETE),
    ] {
        run.insert(k.to_owned(), v.to_owned());
    }
    run.insert(
        run_record::LATITUDE_DEG.into(),
        spec.latitude_deg.to_string(),
    );
    run.insert(run_record::DURATION_S.into(), spec.duration_s.to_string());
    w.write_metadata(run_record::NAME, &run).unwrap();
    let mut constants = BTreeMap::new();
    constants.insert(
        design_constants_record::SCHULER_PERIOD_S.to_owned(),
        "5064.3".to_owned(),
    );
    if let Some(p) = spec.undamped_period_s {
        constants.insert(
            design_constants_record::UNDAMPED_PERIOD_S.to_owned(),
            p.to_string(),
        );
    }
    w.write_metadata(design_constants_record::NAME, &constants)
        .unwrap();

    let n = (spec.duration_s * spec.rate_hz).round() as u64;
    let lat = spec.latitude_deg.to_radians();
    let mut pending: Vec<(f64, &str, Manoeuvre)> = spec
        .manoeuvres
        .iter()
        .flat_map(|m| [(m.start_s, events::START, *m), (m.end_s, events::END, *m)])
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
