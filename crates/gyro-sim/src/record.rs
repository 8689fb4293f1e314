//! Records a run as an MCAP file, following `docs/recordings.md`: the compass and ship state at
//! every output sample, body poses (decimated), manoeuvre events, solver statistics, metadata and
//! the scene and design files as attachments. Written to `NAME.mcap.partial`, renamed on success;
//! an interrupted run (Ctrl-C) still closes a valid file and records how far it got.

use crate::run::{RunError, RunStats, Simulation};
use crate::scene::Scene;
use crate::solvers::StopReason;
use gyro_mcap::{FieldSpec, Pose, RecordSchema, RecordingWriter, Value, WriterOptions};
use gyro_model::constants::{EARTH_RADIUS_M, schuler_period_s};
use gyro_model::{Root, ShipMotion};
use std::collections::BTreeMap;
use std::ops::ControlFlow;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

/// Program version recorded in every file.
pub const PROGRAM_VERSION: &str = env!("CARGO_PKG_VERSION");

/// Simulated seconds between two progress reports on `/solver/stats` (the first sample at or
/// after each multiple of this, before the end, carries one; the end carries the final one).
pub const SOLVER_STATS_EVERY_S: f64 = 3600.0;

/// Options of a recorded run.
#[derive(Default)]
pub struct RecordOptions<'a> {
    /// Set to true (e.g. by a Ctrl-C handler) to stop at the next sample and close the file.
    pub interrupt: Option<Arc<AtomicBool>>,
    /// Called with the simulated time now and then.
    pub progress: Option<&'a mut dyn FnMut(f64)>,
    pub writer: WriterOptions,
}

/// What a recorded run produced.
#[derive(Clone, Debug)]
pub struct RecordSummary {
    pub path: PathBuf,
    pub bytes: u64,
    pub messages: u64,
    pub stats: RunStats,
    pub rhs_cost_ns: f64,
    pub effects: Vec<&'static str>,
    pub interrupted_at_s: Option<f64>,
    pub wall_time_s: f64,
}

fn ns(t: f64) -> u64 {
    (t * 1e9).round().max(0.0) as u64
}

fn quat_from_matrix(m: &[[f64; 3]; 3]) -> [f64; 4] {
    // Shepperd's method: stable for every rotation.
    let tr = m[0][0] + m[1][1] + m[2][2];
    let (x, y, z, w);
    if tr > 0.0 {
        let s = (tr + 1.0).sqrt() * 2.0;
        w = 0.25 * s;
        x = (m[2][1] - m[1][2]) / s;
        y = (m[0][2] - m[2][0]) / s;
        z = (m[1][0] - m[0][1]) / s;
    } else if m[0][0] > m[1][1] && m[0][0] > m[2][2] {
        let s = (1.0 + m[0][0] - m[1][1] - m[2][2]).sqrt() * 2.0;
        w = (m[2][1] - m[1][2]) / s;
        x = 0.25 * s;
        y = (m[0][1] + m[1][0]) / s;
        z = (m[0][2] + m[2][0]) / s;
    } else if m[1][1] > m[2][2] {
        let s = (1.0 + m[1][1] - m[0][0] - m[2][2]).sqrt() * 2.0;
        w = (m[0][2] - m[2][0]) / s;
        x = (m[0][1] + m[1][0]) / s;
        y = 0.25 * s;
        z = (m[1][2] + m[2][1]) / s;
    } else {
        let s = (1.0 + m[2][2] - m[0][0] - m[1][1]).sqrt() * 2.0;
        w = (m[1][0] - m[0][1]) / s;
        x = (m[0][2] + m[2][0]) / s;
        y = (m[1][2] + m[2][1]) / s;
        z = 0.25 * s;
    }
    [x, y, z, w]
}

fn mat_t_mul(a: &[[f64; 3]; 3], b: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let mut r = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            r[i][j] = (0..3).map(|k| a[k][i] * b[k][j]).sum();
        }
    }
    r
}

fn mat_t_vec(a: &[[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    [0, 1, 2].map(|i| (0..3).map(|k| a[k][i] * v[k]).sum())
}

/// Runs `scene` and records it to `out` (which should end in `.mcap`).
pub fn record(
    scene: &Scene,
    out: &Path,
    mut opts: RecordOptions,
) -> Result<RecordSummary, RunError> {
    let started = Instant::now();
    let sim = Simulation::new(scene)?;
    let model = &sim.model;
    let rhs_cost_ns = sim.rhs_cost_ns();
    let rec_err = |e: gyro_mcap::RecordingError| RunError::Record(e.to_string());
    let mut w = RecordingWriter::create(out, opts.writer).map_err(rec_err)?;

    // Channels.
    let coords: Vec<String> = model
        .design
        .coordinates
        .iter()
        .map(|c| c.name.clone())
        .collect();
    let mut fields = vec![
        FieldSpec::f64("time_s", "s"),
        FieldSpec::f64("reading_error_rad", "rad"),
        FieldSpec::f64("compass_heading_rad", "rad"),
        FieldSpec::f64("true_heading_rad", "rad"),
        FieldSpec::f64("tilt_rad", "rad"),
    ];
    for c in &coords {
        fields.push(FieldSpec::f64(&format!("{c}_rad"), "rad"));
    }
    for c in &coords {
        fields.push(FieldSpec::f64(&format!("{c}_rate_rad_per_s"), "rad/s"));
    }
    let compass_ch = w
        .add_record_channel(
            "/compass/state",
            &RecordSchema {
                full_name: "gyrolab.CompassState".into(),
                fields,
            },
        )
        .map_err(rec_err)?;
    let ship_fields = [
        ("time_s", "s"),
        ("latitude_rad", "rad"),
        ("longitude_rad", "rad"),
        ("heading_rad", "rad"),
        ("speed_m_per_s", "m/s"),
        ("roll_rad", "rad"),
        ("pitch_rad", "rad"),
        ("gravity_north_m_per_s2", "m/s^2"),
        ("gravity_west_m_per_s2", "m/s^2"),
        ("gravity_up_m_per_s2", "m/s^2"),
    ]
    .iter()
    .map(|(n, u)| FieldSpec::f64(n, u))
    .collect();
    let ship_ch = w
        .add_record_channel(
            "/ship/state",
            &RecordSchema {
                full_name: "gyrolab.ShipState".into(),
                fields: ship_fields,
            },
        )
        .map_err(rec_err)?;
    let event_ch = w
        .add_record_channel(
            "/events",
            &RecordSchema {
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
            },
        )
        .map_err(rec_err)?;
    let stats_ch = w
        .add_record_channel(
            "/solver/stats",
            &RecordSchema {
                full_name: "gyrolab.SolverStats".into(),
                fields: vec![
                    FieldSpec::f64("time_s", "s"),
                    FieldSpec::u64("steps"),
                    FieldSpec::u64("rejected_steps"),
                    FieldSpec::u64("rhs_evals"),
                    FieldSpec::u64("jacobian_evals"),
                    FieldSpec::f64("wall_time_s", "s"),
                ],
            },
        )
        .map_err(rec_err)?;
    let tf_ch = w.add_pose_channel("/tf").map_err(rec_err)?;

    // Static metadata first (a recovered file keeps it).
    let mut scene_md = BTreeMap::new();
    scene_md.insert("toml".to_string(), scene.source_text.clone());
    scene_md.insert("path".to_string(), scene.source_path.clone());
    w.write_metadata("scene", &scene_md).map_err(rec_err)?;
    let mut design_md = BTreeMap::new();
    design_md.insert("toml".to_string(), model.design.source_text.clone());
    design_md.insert("path".to_string(), scene.design_path.clone());
    design_md.insert(
        "overrides".to_string(),
        scene
            .design_overrides
            .iter()
            .map(|(k, v)| format!("{k} = {v}"))
            .collect::<Vec<_>>()
            .join("; "),
    );
    w.write_metadata("design", &design_md).map_err(rec_err)?;
    let mut bodies_md = BTreeMap::new();
    for b in &model.design.bodies {
        let parent = match b.parent {
            Some(p) => model.design.bodies[p].name.clone(),
            None => {
                if model.design.root == Root::Ship {
                    "ship".into()
                } else {
                    "earth".into()
                }
            }
        };
        bodies_md.insert(format!("{}.parent", b.name), parent);
        bodies_md.insert(format!("{}.shape", b.name), shape_toml(&b.shape));
        if let Some(r) = &b.rotor {
            bodies_md.insert(format!("{}.spin_axis", b.name), format!("{:?}", r.axis));
            bodies_md.insert(
                format!("{}.spin_rad_per_s", b.name),
                format!("{}", r.spin_rad_per_s),
            );
        }
    }
    w.write_metadata("bodies", &bodies_md).map_err(rec_err)?;
    w.write_metadata("design_constants", &design_constants(&sim, scene))
        .map_err(rec_err)?;
    w.write_metadata("run", &run_metadata(&sim, scene, &coords, rhs_cost_ns))
        .map_err(rec_err)?;
    w.attach(
        "scene.toml",
        "application/toml",
        0,
        scene.source_text.as_bytes(),
    )
    .map_err(rec_err)?;
    w.attach(
        "design.toml",
        "application/toml",
        0,
        model.design.source_text.as_bytes(),
    )
    .map_err(rec_err)?;

    // Events, written when the run passes them (so log times stay ordered).
    let mut events: Vec<(f64, Vec<OwnedValue>)> = Vec::new();
    let segs = &scene.program.segments;
    for (i, s) in segs.iter().enumerate() {
        if s.manoeuvre == "steady" {
            continue;
        }
        let (_, v1, h1) = crate::program::ShipProgram::end_state(s);
        for (phase, t) in [("start", s.start_s), ("end", s.start_s + s.duration_s)] {
            if t > scene.duration_s {
                continue;
            }
            events.push((
                t,
                vec![
                    OwnedValue::F64(t),
                    OwnedValue::Str(phase.into()),
                    OwnedValue::Str(s.manoeuvre.clone()),
                    OwnedValue::U64(i as u64),
                    OwnedValue::Str(s.description.clone()),
                    OwnedValue::F64(s.speed0_m_per_s),
                    OwnedValue::F64(v1),
                    OwnedValue::F64(s.heading0_rad),
                    OwnedValue::F64(h1),
                    OwnedValue::F64(s.duration_s),
                ],
            ));
        }
    }
    let mut next_event = 0;

    let pose_every = pose_every_n_samples(scene);
    let n_compass = 5 + 2 * coords.len();
    let mut compass_vals = vec![0.0; n_compass];
    let mut ship_vals = [0.0; 10];
    let mut longitude = scene.start_longitude_rad;
    let mut last: Option<(f64, f64)> = None; // (t, lon rate)
    let mut sample = 0u64;
    let mut write_error: Option<RunError> = None;
    let mut last_progress = Instant::now();
    let names: Vec<String> = model.design.bodies.iter().map(|b| b.name.clone()).collect();
    let parents: Vec<String> = model
        .design
        .bodies
        .iter()
        .map(|b| match b.parent {
            Some(p) => names[p].clone(),
            None => {
                if model.design.root == Root::Ship {
                    "ship".into()
                } else {
                    "earth".into()
                }
            }
        })
        .collect();
    // One pose message per frame, built once: a sample only updates the numbers (no frame id
    // strings are copied per sample).
    let mut ship_pose = Pose {
        parent_frame: "earth".into(),
        child_frame: "ship".into(),
        translation_m: [0.0; 3],
        rotation_xyzw: [0.0, 0.0, 0.0, 1.0],
    };
    let mut body_pose_msgs: Vec<Pose> = names
        .iter()
        .zip(&parents)
        .map(|(name, parent)| Pose {
            parent_frame: parent.clone(),
            child_frame: name.clone(),
            translation_m: [0.0; 3],
            rotation_xyzw: [0.0, 0.0, 0.0, 1.0],
        })
        .collect();

    let interrupt = opts.interrupt.clone();
    let mut next_stats_s = SOLVER_STATS_EVERY_S;
    let result = sim.run_with_progress(scene.method, &scene.tolerances, |t, x, probe| {
        let mut step = || -> Result<(), gyro_mcap::RecordingError> {
            while next_event < events.len() && events[next_event].0 <= t + 1e-9 {
                let vals: Vec<Value> = events[next_event]
                    .1
                    .iter()
                    .map(OwnedValue::as_value)
                    .collect();
                w.write_record(event_ch, ns(events[next_event].0), &vals)?;
                next_event += 1;
            }
            let r = model.readout(t, x);
            compass_vals[0] = t;
            compass_vals[1] = r.reading_error_rad;
            compass_vals[2] = r.compass_heading_rad;
            compass_vals[3] = r.true_heading_rad;
            compass_vals[4] = r.tilt_rad;
            compass_vals[5..5 + coords.len()].copy_from_slice(&r.q);
            compass_vals[5 + coords.len()..].copy_from_slice(&r.qd);
            w.write_f64_record(compass_ch, ns(t), &compass_vals)?;
            let k = model.motion.kinematics(t);
            let lon_rate =
                k.speed_m_per_s * k.heading_rad.sin() / (EARTH_RADIUS_M * k.latitude_rad.cos());
            if let Some((t0, r0)) = last {
                longitude += 0.5 * (r0 + lon_rate) * (t - t0);
            }
            last = Some((t, lon_rate));
            let g = model.apparent_gravity(t);
            ship_vals = [
                t,
                k.latitude_rad,
                longitude,
                k.heading_rad,
                k.speed_m_per_s,
                k.roll_rad,
                k.pitch_rad,
                g[0],
                g[1],
                g[2],
            ];
            w.write_f64_record(ship_ch, ns(t), &ship_vals)?;
            if sample.is_multiple_of(pose_every) {
                let base = model.world_from_base(t);
                let ship = if model.design.root == Root::Ship {
                    base
                } else {
                    gyro_model::earth::world_from_ship(&k, &model.effects.base).0
                };
                ship_pose.rotation_xyzw = quat_from_matrix(&ship);
                w.write_pose(tf_ch, ns(t), &ship_pose)?;
                let poses = &r.poses;
                for (bi, (rot, pos)) in poses.iter().enumerate() {
                    // parent_from_child = parent_worldᵀ · child_world.
                    let (prot, ppos) = match model.design.bodies[bi].parent {
                        Some(p) => (poses[p].0, poses[p].1),
                        None => (base, [0.0; 3]),
                    };
                    let rel = mat_t_mul(&prot, rot);
                    let d = [pos[0] - ppos[0], pos[1] - ppos[1], pos[2] - ppos[2]];
                    let msg = &mut body_pose_msgs[bi];
                    msg.translation_m = mat_t_vec(&prot, d);
                    msg.rotation_xyzw = quat_from_matrix(&rel);
                    w.write_pose(tf_ch, ns(t), msg)?;
                }
            }
            if t >= next_stats_s && t < scene.duration_s {
                // A progress report: the work so far.
                let p = probe.progress();
                w.write_record(
                    stats_ch,
                    ns(t),
                    &[
                        Value::F64(t),
                        Value::U64(p.steps),
                        Value::U64(p.rejected_steps),
                        Value::U64(p.rhs_evals),
                        Value::U64(p.jacobian_evals),
                        Value::F64(p.wall_time_s),
                    ],
                )?;
                next_stats_s = ((t / SOLVER_STATS_EVERY_S).floor() + 1.0) * SOLVER_STATS_EVERY_S;
            }
            Ok(())
        };
        if let Err(e) = step() {
            write_error = Some(RunError::Record(e.to_string()));
            return ControlFlow::Break(());
        }
        sample += 1;
        if let Some(p) = opts.progress.as_mut()
            && last_progress.elapsed().as_secs_f64() > 0.1
        {
            p(t);
            last_progress = Instant::now();
        }
        if interrupt
            .as_ref()
            .is_some_and(|i| i.load(Ordering::Relaxed))
        {
            return ControlFlow::Break(());
        }
        ControlFlow::Continue(())
    });
    if let Some(e) = write_error {
        return Err(e);
    }
    // On a solver error the `.partial` file stays for `gyrolab recover`; nothing appears under
    // the final name.
    let stats = result?;
    let interrupted_at_s = match stats.stop {
        StopReason::Interrupted { t } => Some(t),
        StopReason::Finished => None,
    };
    let end_t = interrupted_at_s.unwrap_or(scene.duration_s);
    let s = &stats.solver;
    w.write_record(
        stats_ch,
        ns(end_t),
        &[
            Value::F64(end_t),
            Value::U64(s.steps),
            Value::U64(s.rejected_steps),
            Value::U64(s.rhs_evals),
            Value::U64(s.jacobian_evals),
            Value::F64(s.wall_time_s),
        ],
    )
    .map_err(rec_err)?;
    let effects = model.effects.names();
    let status = match interrupted_at_s {
        Some(t) => format!("interrupted at t = {t} s"),
        None => "complete".into(),
    };
    let result_md: BTreeMap<String, String> = [
        ("status", status),
        ("steps", s.steps.to_string()),
        ("rejected_steps", s.rejected_steps.to_string()),
        ("rhs_evals", s.rhs_evals.to_string()),
        ("jacobian_evals", s.jacobian_evals.to_string()),
        ("wall_time_s", format!("{}", s.wall_time_s)),
    ]
    .into_iter()
    .map(|(k, v)| (k.to_string(), v))
    .collect();
    w.write_metadata("result", &result_md).map_err(rec_err)?;
    let summary = w.finish().map_err(rec_err)?;
    Ok(RecordSummary {
        path: summary.path,
        bytes: summary.bytes,
        messages: summary.messages,
        stats,
        rhs_cost_ns,
        effects,
        interrupted_at_s,
        wall_time_s: started.elapsed().as_secs_f64(),
    })
}

/// Poses are written at every this many output samples (`pose_rate_hz` ≤ `output_rate_hz`).
fn pose_every_n_samples(scene: &Scene) -> u64 {
    ((scene.output_rate_hz / scene.pose_rate_hz).round() as u64).max(1)
}

/// The `run` metadata record: what was run and how, all known before the first step, so it is
/// written at the start and a recovered file of a killed run keeps it. How the run ended goes to
/// the `result` record, written at the end.
fn run_metadata(
    sim: &Simulation,
    scene: &Scene,
    coords: &[String],
    rhs_cost_ns: f64,
) -> BTreeMap<String, String> {
    let model = &sim.model;
    [
        ("program_version", PROGRAM_VERSION.to_string()),
        ("scene_name", scene.name.clone()),
        ("design_name", model.design.name.clone()),
        ("design_kind", model.design.kind.clone()),
        ("fidelity", model.fidelity.to_string()),
        ("integrator", scene.method.to_string()),
        ("rtol", format!("{:e}", scene.tolerances.rtol)),
        ("atol", format!("{:e}", scene.tolerances.atol)),
        ("effects", model.effects.names().join(",")),
        ("coordinates", coords.join(",")),
        ("output_rate_hz", format!("{}", scene.output_rate_hz)),
        ("duration_s", format!("{}", scene.duration_s)),
        (
            "latitude_deg",
            format!("{}", scene.start_latitude_rad.to_degrees()),
        ),
        ("rhs_cost_ns", format!("{rhs_cost_ns:.1}")),
        (
            "pose_every_n_samples",
            pose_every_n_samples(scene).to_string(),
        ),
    ]
    .into_iter()
    .map(|(k, v)| (k.to_string(), v))
    .collect()
}

enum OwnedValue {
    F64(f64),
    U64(u64),
    Str(String),
}
impl OwnedValue {
    fn as_value(&self) -> Value<'_> {
        match self {
            OwnedValue::F64(x) => Value::F64(*x),
            OwnedValue::U64(x) => Value::U64(*x),
            OwnedValue::Str(s) => Value::Str(s),
        }
    }
}

fn shape_toml(s: &gyro_model::Shape) -> String {
    use gyro_model::Shape::*;
    match s {
        Ring { radius_m, width_m } => {
            format!("{{ kind = \"ring\", radius_m = {radius_m}, width_m = {width_m} }}")
        }
        Disc {
            radius_m,
            thickness_m,
        } => format!("{{ kind = \"disc\", radius_m = {radius_m}, thickness_m = {thickness_m} }}"),
        Box { size_m } => format!(
            "{{ kind = \"box\", size_m = [{}, {}, {}] }}",
            size_m[0], size_m[1], size_m[2]
        ),
        Sphere { radius_m } => format!("{{ kind = \"sphere\", radius_m = {radius_m} }}"),
        Hull { size_m } => format!(
            "{{ kind = \"hull\", size_m = [{}, {}, {}] }}",
            size_m[0], size_m[1], size_m[2]
        ),
        None => "{ kind = \"none\" }".into(),
    }
}

/// Constants the analysis compares against: from the design's parameters when it names them,
/// and the slow mode of the linearisation at the start.
fn design_constants(sim: &Simulation, scene: &Scene) -> BTreeMap<String, String> {
    let d = &sim.model.design;
    let mut m = BTreeMap::new();
    for (key, param) in [
        ("spin_momentum_n_m_s", "spin_momentum_n_m_s"),
        ("pendulous_moment_n_m", "pendulous_moment_n_m"),
        ("damper_kappa_n_m", "kappa_n_m"),
    ] {
        if let Some(v) = d.parameter(param) {
            m.insert(key.to_string(), format!("{v}"));
        }
    }
    if let (Some(h), Some(ap)) = (
        d.parameter("spin_momentum_n_m_s"),
        d.parameter("pendulous_moment_n_m"),
    ) {
        let th = gyro_model::theory::Anschutz {
            spin_momentum: h,
            pendulous_moment: ap,
            kappa: 0.0,
            inertia_vertical: 0.0,
            inertia_east_west: 0.0,
            latitude_rad: scene.start_latitude_rad,
        };
        m.insert(
            "undamped_period_s".into(),
            format!("{}", th.undamped_period()),
        );
    }
    m.insert("schuler_period_s".into(), format!("{}", schuler_period_s()));
    // Slowest oscillatory mode of the linearisation.
    let modes = sim.model.modes();
    if let Some(slow) = modes
        .iter()
        .filter(|(_, im)| *im > 0.0)
        .min_by(|a, b| a.1.total_cmp(&b.1))
    {
        m.insert(
            "mode_period_s".into(),
            format!("{}", std::f64::consts::TAU / slow.1),
        );
        m.insert("mode_decay_rate_per_s".into(), format!("{}", -slow.0));
    }
    m
}
