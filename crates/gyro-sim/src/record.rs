//! Records a run as an MCAP file, following `docs/recordings.md`: the compass and ship state at
//! every output sample, body poses (decimated), manoeuvre events, solver statistics, metadata and
//! the scene and design files as attachments. Written to `NAME.mcap.partial`, renamed on success;
//! an interrupted run (Ctrl-C) still closes a valid file and records how far it got.

use crate::program::ShipProgram;
use crate::run::{ManoeuvreEvent, Progress, RunError, RunObserver, RunProbe, RunStats, Simulation};
use crate::scene::Scene;
use crate::solvers::StopReason;
use gyro_mcap::contract::{
    BodyShape, PotsDrawing, SpringDrawing, TankCompartmentDrawing, TankDrawing, attachments,
    bodies_record, compass_state, design_constants_record, design_record, energy, events,
    result_record, run_record, scene_record, ship_state, solver_stats, status, tf,
};
use gyro_mcap::{ChannelId, Pose, RecordingError, RecordingWriter, Value, WriterOptions};
use gyro_model::constants::{EARTH_RADIUS_M, schuler_period_s};
use gyro_model::{BodyPose, CompiledModel, Root, ShipKinematics, ShipMotion};
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
pub const SOLVER_STATS_EVERY_S: f64 = solver_stats::REPORT_EVERY_S;

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
pub fn record(scene: &Scene, out: &Path, opts: RecordOptions) -> Result<RecordSummary, RunError> {
    let started = Instant::now();
    let sim = Simulation::new(scene)?;
    let rhs_cost_ns = sim.rhs_cost_ns();
    let mut recorder = Recorder::create(&sim, scene, out, rhs_cost_ns, opts)?;
    let result = sim.observe(scene.method, &scene.tolerances, &mut recorder);
    if let Some(e) = recorder.error.take() {
        return Err(rec_err(e));
    }
    // On a solver error the `.partial` file stays for `gyrolab recover`; nothing appears under
    // the final name.
    let stats = result?;
    if let Some(e) = recorder.error.take() {
        return Err(rec_err(e));
    }
    let summary = recorder.writer.finish().map_err(rec_err)?;
    Ok(RecordSummary {
        path: summary.path,
        bytes: summary.bytes,
        messages: summary.messages,
        interrupted_at_s: interrupted_at_s(&stats),
        stats,
        rhs_cost_ns,
        effects: sim.model.effects.names(),
        wall_time_s: started.elapsed().as_secs_f64(),
    })
}

fn rec_err(e: RecordingError) -> RunError {
    RunError::Record(e.to_string())
}

fn interrupted_at_s(stats: &RunStats) -> Option<f64> {
    match stats.stop {
        StopReason::Interrupted { t } => Some(t),
        StopReason::Finished => None,
    }
}

/// The channels of a recording.
struct Channels {
    compass: ChannelId,
    ship: ChannelId,
    events: ChannelId,
    solver_stats: ChannelId,
    tf: ChannelId,
    /// `/compass/energy`, when the scene asks for it.
    energy: Option<ChannelId>,
}

impl Channels {
    fn add(
        w: &mut RecordingWriter,
        coordinates: &[String],
        units: &[&str],
        record_energy: bool,
    ) -> Result<Channels, RecordingError> {
        let with_units: Vec<(&str, &str)> = coordinates
            .iter()
            .zip(units)
            .map(|(c, u)| (c.as_str(), *u))
            .collect();
        Ok(Channels {
            compass: w.add_record_channel(
                compass_state::TOPIC,
                &compass_state::schema_with_units(&with_units),
            )?,
            ship: w.add_record_channel(ship_state::TOPIC, &ship_state::schema())?,
            events: w.add_record_channel(events::TOPIC, &events::schema())?,
            solver_stats: w.add_record_channel(solver_stats::TOPIC, &solver_stats::schema())?,
            tf: w.add_pose_channel(tf::TOPIC)?,
            energy: if record_energy {
                Some(w.add_record_channel(energy::TOPIC, &energy::schema())?)
            } else {
                None
            },
        })
    }
}

/// One pose message per frame, built once: a sample only updates the numbers (no frame id
/// strings are copied per sample).
struct PoseMessages {
    ship: Pose,
    /// By body index.
    bodies: Vec<Pose>,
}

impl PoseMessages {
    fn new(model: &CompiledModel<ShipProgram>) -> PoseMessages {
        let frame = |parent: &str, child: &str| Pose {
            parent_frame: parent.into(),
            child_frame: child.into(),
            translation_m: [0.0; 3],
            rotation_xyzw: [0.0, 0.0, 0.0, 1.0],
        };
        PoseMessages {
            ship: frame(tf::EARTH_FRAME, tf::SHIP_FRAME),
            bodies: (0..model.design.bodies.len())
                .map(|bi| frame(parent_frame(model, bi), &model.design.bodies[bi].name))
                .collect(),
        }
    }
}

/// The frame a body's pose is given in: its parent body, or the ship or the earth for the
/// chain's root.
fn parent_frame(model: &CompiledModel<ShipProgram>, body: usize) -> &str {
    let design = &model.design;
    match design.bodies[body].parent {
        Some(p) => &design.bodies[p].name,
        None if design.root == Root::Ship => tf::SHIP_FRAME,
        None => tf::EARTH_FRAME,
    }
}

/// The longitude, which no physics depends on, integrated along the track for the record (trapezoids
/// between samples).
struct Longitude {
    rad: f64,
    /// The previous sample's time and longitude rate.
    last: Option<(f64, f64)>,
}

impl Longitude {
    fn advance(&mut self, t: f64, k: &ShipKinematics<f64>) -> f64 {
        let rate = k.speed_m_per_s * k.heading_rad.sin() / (EARTH_RADIUS_M * k.latitude_rad.cos());
        if let Some((t0, r0)) = self.last {
            self.rad += 0.5 * (r0 + rate) * (t - t0);
        }
        self.last = Some((t, rate));
        self.rad
    }
}

/// Records one run: the run's observer, writing every event and sample as the run reports them
/// and the final statistics and the `result` record when it ends. Write errors are kept in
/// `error` (the first one stops the run).
struct Recorder<'s, 'p> {
    sim: &'s Simulation,
    scene: &'s Scene,
    writer: RecordingWriter,
    channels: Channels,
    /// The compass record of the sample, reused.
    compass_values: Vec<f64>,
    longitude: Longitude,
    poses: PoseMessages,
    pose_every: u64,
    samples: u64,
    next_stats_s: f64,
    error: Option<RecordingError>,
    interrupt: Option<Arc<AtomicBool>>,
    progress: Option<&'p mut dyn FnMut(f64)>,
    last_progress: Instant,
}

impl<'s, 'p> Recorder<'s, 'p> {
    /// Opens the file with its channels, metadata and attachments (so a recovered file of a run
    /// killed at once keeps them).
    fn create(
        sim: &'s Simulation,
        scene: &'s Scene,
        out: &Path,
        rhs_cost_ns: f64,
        opts: RecordOptions<'p>,
    ) -> Result<Recorder<'s, 'p>, RunError> {
        let model = &sim.model;
        let mut writer = RecordingWriter::create(out, opts.writer).map_err(rec_err)?;
        let coordinates: Vec<String> = model
            .design
            .coordinates
            .iter()
            .map(|c| c.name.clone())
            .collect();
        let units: Vec<&str> = model
            .design
            .coordinates
            .iter()
            .map(|c| c.unit.symbol())
            .collect();
        let channels = Channels::add(&mut writer, &coordinates, &units, scene.record_energy)
            .map_err(rec_err)?;
        write_static_metadata(&mut writer, sim, scene, &coordinates, rhs_cost_ns)
            .map_err(rec_err)?;
        Ok(Recorder {
            sim,
            scene,
            writer,
            channels,
            compass_values: vec![0.0; compass_state::LEADING_FIELDS + 2 * coordinates.len()],
            longitude: Longitude {
                rad: scene.start_longitude_rad,
                last: None,
            },
            poses: PoseMessages::new(model),
            pose_every: pose_every_n_samples(scene),
            samples: 0,
            next_stats_s: SOLVER_STATS_EVERY_S,
            error: None,
            interrupt: opts.interrupt,
            progress: opts.progress,
            last_progress: Instant::now(),
        })
    }

    fn write_event(&mut self, event: &ManoeuvreEvent) -> Result<(), RecordingError> {
        let s = event.segment;
        let phase = if event.is_start {
            events::START
        } else {
            events::END
        };
        self.writer.write_record(
            self.channels.events,
            ns(event.time_s),
            &[
                Value::F64(event.time_s),
                Value::Str(phase),
                Value::Str(&s.manoeuvre),
                Value::U64(event.segment_index as u64),
                Value::Str(&s.description),
                Value::F64(s.speed0_m_per_s),
                Value::F64(event.speed_after_m_per_s),
                Value::F64(s.heading0_rad),
                Value::F64(event.heading_after_rad),
                Value::F64(s.duration_s),
            ],
        )
    }

    fn write_sample(&mut self, t: f64, x: &[f64], probe: &RunProbe) -> Result<(), RecordingError> {
        let model = &self.sim.model;
        let r = model.readout(t, x);
        let n = r.q.len();
        let c = &mut self.compass_values;
        c[..compass_state::LEADING_FIELDS].copy_from_slice(&[
            t,
            r.reading_error_rad,
            r.compass_heading_rad,
            r.true_heading_rad,
            r.tilt_rad,
        ]);
        c[compass_state::LEADING_FIELDS..compass_state::LEADING_FIELDS + n].copy_from_slice(&r.q);
        c[compass_state::LEADING_FIELDS + n..].copy_from_slice(&r.qd);
        self.writer
            .write_f64_record(self.channels.compass, ns(t), &self.compass_values)?;
        if let Some(ch) = self.channels.energy {
            // A singular state (never seen in a run that got here) records NaN, not a gap.
            let e = model.energetics(t, x).unwrap_or(gyro_model::Energetics {
                energy_j: f64::NAN,
                ..Default::default()
            });
            let values = [
                t,
                e.energy_j,
                e.kinetic_j,
                e.frame_kinetic_j,
                e.potential_j,
                e.servo_power_w,
                e.damper_power_w,
                e.applied_power_w,
            ];
            self.writer.write_f64_record(ch, ns(t), &values)?;
        }
        let k = model.motion.kinematics(t);
        let longitude = self.longitude.advance(t, &k);
        let g = model.apparent_gravity(t);
        let ship = [
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
        self.writer
            .write_f64_record(self.channels.ship, ns(t), &ship)?;
        if self.samples.is_multiple_of(self.pose_every) {
            self.write_poses(t, &k, &r.poses)?;
        }
        if t >= self.next_stats_s && t < self.scene.duration_s {
            // A progress report: the work so far.
            self.write_solver_stats(t, &probe.progress())?;
            self.next_stats_s = ((t / SOLVER_STATS_EVERY_S).floor() + 1.0) * SOLVER_STATS_EVERY_S;
        }
        Ok(())
    }

    /// The ship in the earth frame, then every body in its parent frame.
    fn write_poses(
        &mut self,
        t: f64,
        k: &ShipKinematics<f64>,
        poses: &[BodyPose],
    ) -> Result<(), RecordingError> {
        let model = &self.sim.model;
        let base = model.world_from_base(t);
        let ship = if model.design.root == Root::Ship {
            base
        } else {
            gyro_model::earth::world_from_ship(k, &model.effects.base).0
        };
        self.poses.ship.rotation_xyzw = quat_from_matrix(&ship);
        self.writer
            .write_pose(self.channels.tf, ns(t), &self.poses.ship)?;
        for (bi, pose) in poses.iter().enumerate() {
            let (rot, pos) = (&pose.world_from_body, &pose.origin_m);
            // parent_from_child = parent_worldᵀ · child_world.
            let (prot, ppos) = match model.design.bodies[bi].parent {
                Some(p) => (poses[p].world_from_body, poses[p].origin_m),
                None => (base, [0.0; 3]),
            };
            let rel = mat_t_mul(&prot, rot);
            let d = [pos[0] - ppos[0], pos[1] - ppos[1], pos[2] - ppos[2]];
            let msg = &mut self.poses.bodies[bi];
            msg.translation_m = mat_t_vec(&prot, d);
            msg.rotation_xyzw = quat_from_matrix(&rel);
            self.writer.write_pose(self.channels.tf, ns(t), msg)?;
        }
        Ok(())
    }

    fn write_solver_stats(&mut self, t: f64, p: &Progress) -> Result<(), RecordingError> {
        self.writer.write_record(
            self.channels.solver_stats,
            ns(t),
            &[
                Value::F64(t),
                Value::U64(p.steps),
                Value::U64(p.rejected_steps),
                Value::U64(p.rhs_evals),
                Value::U64(p.jacobian_evals),
                Value::F64(p.wall_time_s),
            ],
        )
    }

    /// The final statistics at the end (or where the run stopped) and the `result` record.
    fn write_end(&mut self, stats: &RunStats) -> Result<(), RecordingError> {
        let interrupted_at_s = interrupted_at_s(stats);
        let end_t = interrupted_at_s.unwrap_or(self.scene.duration_s);
        let s = &stats.solver;
        let final_stats = Progress {
            steps: s.steps,
            rejected_steps: s.rejected_steps,
            rhs_evals: s.rhs_evals,
            jacobian_evals: s.jacobian_evals,
            wall_time_s: s.wall_time_s,
        };
        self.write_solver_stats(end_t, &final_stats)?;
        let status = match interrupted_at_s {
            Some(t) => status::interrupted_at(t),
            None => status::COMPLETE.into(),
        };
        let result: BTreeMap<String, String> = [
            (result_record::STATUS, status),
            (result_record::STEPS, s.steps.to_string()),
            (result_record::REJECTED_STEPS, s.rejected_steps.to_string()),
            (result_record::RHS_EVALS, s.rhs_evals.to_string()),
            (result_record::JACOBIAN_EVALS, s.jacobian_evals.to_string()),
            (result_record::WALL_TIME_S, format!("{}", s.wall_time_s)),
        ]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v))
        .collect();
        self.writer.write_metadata(result_record::NAME, &result)
    }
}

impl RunObserver for Recorder<'_, '_> {
    fn event(&mut self, event: &ManoeuvreEvent) -> ControlFlow<()> {
        match self.write_event(event) {
            Ok(()) => ControlFlow::Continue(()),
            Err(e) => {
                self.error = Some(e);
                ControlFlow::Break(())
            }
        }
    }

    fn sample(&mut self, t: f64, x: &[f64], probe: &RunProbe) -> ControlFlow<()> {
        if let Err(e) = self.write_sample(t, x, probe) {
            self.error = Some(e);
            return ControlFlow::Break(());
        }
        self.samples += 1;
        if let Some(p) = self.progress.as_mut()
            && self.last_progress.elapsed().as_secs_f64() > 0.1
        {
            p(t);
            self.last_progress = Instant::now();
        }
        if self
            .interrupt
            .as_ref()
            .is_some_and(|i| i.load(Ordering::Relaxed))
        {
            return ControlFlow::Break(());
        }
        ControlFlow::Continue(())
    }

    fn finish(&mut self, stats: &RunStats) {
        if self.error.is_none()
            && let Err(e) = self.write_end(stats)
        {
            self.error = Some(e);
        }
    }
}

/// The metadata records known before the first step, and the attachments.
fn write_static_metadata(
    w: &mut RecordingWriter,
    sim: &Simulation,
    scene: &Scene,
    coordinates: &[String],
    rhs_cost_ns: f64,
) -> Result<(), RecordingError> {
    let model = &sim.model;
    let record = |pairs: &[(&str, String)]| -> BTreeMap<String, String> {
        pairs
            .iter()
            .map(|(k, v)| (k.to_string(), v.clone()))
            .collect()
    };
    let overrides: Vec<String> = scene
        .design_overrides
        .iter()
        .map(|(k, v)| format!("{k} = {v}"))
        .collect();
    w.write_metadata(
        scene_record::NAME,
        &record(&[
            (scene_record::TOML, scene.source_text.clone()),
            (scene_record::PATH, scene.source_path.clone()),
        ]),
    )?;
    w.write_metadata(
        design_record::NAME,
        &record(&[
            (design_record::TOML, model.design.source_text.clone()),
            (design_record::PATH, scene.design_path.clone()),
            (design_record::OVERRIDES, overrides.join("; ")),
        ]),
    )?;
    w.write_metadata(bodies_record::NAME, &bodies_metadata(model))?;
    w.write_metadata(design_constants_record::NAME, &design_constants(sim, scene))?;
    w.write_metadata(
        run_record::NAME,
        &run_metadata(sim, scene, coordinates, rhs_cost_ns),
    )?;
    w.attach(
        attachments::SCENE_TOML,
        attachments::TOML_MEDIA_TYPE,
        0,
        scene.source_text.as_bytes(),
    )?;
    w.attach(
        attachments::DESIGN_TOML,
        attachments::TOML_MEDIA_TYPE,
        0,
        model.design.source_text.as_bytes(),
    )
}

/// The `bodies` record: every body's parent frame and shape, and its rotor's axis and spin.
fn bodies_metadata(model: &CompiledModel<ShipProgram>) -> BTreeMap<String, String> {
    let mut m = BTreeMap::new();
    for (bi, b) in model.design.bodies.iter().enumerate() {
        let key = |what| bodies_record::key(&b.name, what);
        m.insert(
            key(bodies_record::PARENT),
            parent_frame(model, bi).to_owned(),
        );
        m.insert(
            key(bodies_record::SHAPE),
            body_shape(&b.shape).metadata_value(),
        );
        if let Some(r) = &b.rotor {
            m.insert(key(bodies_record::SPIN_AXIS), format!("{:?}", r.axis));
            m.insert(
                key(bodies_record::SPIN_RAD_PER_S),
                format!("{}", r.spin_rad_per_s),
            );
        }
    }
    for p in &model.design.pots {
        let level = &model.design.coordinates[p.level];
        let drawing = PotsDrawing {
            level_field: compass_state::coordinate_field(&level.name, level.unit.symbol()),
            first_base_m: p.bases_m[0],
            second_base_m: p.bases_m[1],
            axis: p.axis,
            radius_m: (p.section_m2 / std::f64::consts::PI).sqrt(),
            rest_level_m: p.rest_level_m,
            tube_path_m: p.tube_path_m.clone(),
        };
        m.insert(
            bodies_record::pots_key(&model.design.bodies[p.body].name, &p.name),
            drawing.metadata_value(),
        );
    }
    for f in &model.design.forces {
        if let gyro_model::Force::LinkSpring {
            name,
            bodies,
            points,
            ..
        } = f
        {
            let drawing = SpringDrawing {
                other_body: model.design.bodies[bodies[1]].name.clone(),
                point_m: points[0],
                other_point_m: points[1],
            };
            m.insert(
                bodies_record::spring_key(&model.design.bodies[bodies[0]].name, name),
                drawing.metadata_value(),
            );
        }
    }
    for l in &model.design.linkages {
        let drawing = SpringDrawing {
            other_body: model.design.bodies[l.bodies[1]].name.clone(),
            point_m: l.points_m[0],
            other_point_m: l.points_m[1],
        };
        m.insert(
            bodies_record::linkage_key(&model.design.bodies[l.bodies[0]].name, &l.name),
            drawing.metadata_value(),
        );
    }
    for t in &model.design.tanks {
        let fields: Vec<String> = t
            .levels
            .iter()
            .map(|&l| {
                let c = &model.design.coordinates[l];
                compass_state::coordinate_field(&c.name, c.unit.symbol())
            })
            .collect();
        let compartments = (0..t.compartments.len())
            .map(|i| {
                let c = &t.compartments[i];
                let (level_fields, level_coefficients) = fields
                    .iter()
                    .zip(t.level_coefficients(i).iter().copied())
                    .filter(|(_, a)| *a != 0.0)
                    .map(|(f, a)| (f.clone(), a))
                    .unzip();
                TankCompartmentDrawing {
                    centroid_m: c.centroid_m,
                    radius_m: (c.area_m2 / std::f64::consts::PI).sqrt(),
                    level_fields,
                    level_coefficients,
                }
            })
            .collect();
        let drawing = TankDrawing {
            rest_depth_m: t.rest_depth_m,
            floor_height_m: t.floor_height_m,
            compartments,
        };
        m.insert(
            bodies_record::tank_key(&model.design.bodies[t.body].name, &t.name),
            drawing.metadata_value(),
        );
    }
    m
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
        (run_record::PROGRAM_VERSION, PROGRAM_VERSION.to_string()),
        (run_record::SCENE_NAME, scene.name.clone()),
        (run_record::DESIGN_NAME, model.design.name.clone()),
        (run_record::DESIGN_KIND, model.design.kind.clone()),
        (run_record::FIDELITY, model.fidelity.to_string()),
        (run_record::INTEGRATOR, scene.method.to_string()),
        (run_record::RTOL, format!("{:e}", scene.tolerances.rtol)),
        (run_record::ATOL, format!("{:e}", scene.tolerances.atol)),
        (
            run_record::JACOBIAN_REUSE_CONTRACTION,
            format!("{:e}", scene.tolerances.jacobian_reuse_contraction),
        ),
        (run_record::EFFECTS, model.effects.names().join(",")),
        (run_record::COORDINATES, coords.join(",")),
        (
            run_record::OUTPUT_RATE_HZ,
            format!("{}", scene.output_rate_hz),
        ),
        (run_record::DURATION_S, format!("{}", scene.duration_s)),
        (
            run_record::LATITUDE_DEG,
            format!("{}", scene.start_latitude_rad.to_degrees()),
        ),
        (run_record::RHS_COST_NS, format!("{rhs_cost_ns:.1}")),
        (
            run_record::POSE_EVERY_N_SAMPLES,
            pose_every_n_samples(scene).to_string(),
        ),
    ]
    .into_iter()
    .chain(
        sim.keep_jacobi_integral
            .then(|| (run_record::KEEP_JACOBI_INTEGRAL, "true".to_string())),
    )
    .map(|(k, v)| (k.to_string(), v))
    .collect()
}

/// The shape a body is drawn with, in the recording's vocabulary.
fn body_shape(s: &gyro_model::Shape) -> BodyShape {
    use gyro_model::Shape;
    match *s {
        Shape::Ring { radius_m, width_m } => BodyShape::Ring { radius_m, width_m },
        Shape::Disc {
            radius_m,
            thickness_m,
        } => BodyShape::Disc {
            radius_m,
            thickness_m,
        },
        Shape::Box { size_m } => BodyShape::Box { size_m },
        Shape::Sphere { radius_m } => BodyShape::Sphere { radius_m },
        Shape::Hull { size_m } => BodyShape::Hull { size_m },
        Shape::None => BodyShape::None,
    }
}

/// Constants the analysis compares against: from the design's parameters when it names them,
/// and the slow mode of the linearisation at the start.
fn design_constants(sim: &Simulation, scene: &Scene) -> BTreeMap<String, String> {
    let d = &sim.model.design;
    let mut m = BTreeMap::new();
    for (key, param) in [
        (
            design_constants_record::SPIN_MOMENTUM_N_M_S,
            "spin_momentum_n_m_s",
        ),
        (
            design_constants_record::PENDULOUS_MOMENT_N_M,
            "pendulous_moment_n_m",
        ),
        (design_constants_record::DAMPER_KAPPA_N_M, "kappa_n_m"),
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
            design_constants_record::UNDAMPED_PERIOD_S.into(),
            format!("{}", th.undamped_period()),
        );
    }
    m.insert(
        design_constants_record::SCHULER_PERIOD_S.into(),
        format!("{}", schuler_period_s()),
    );
    // Slowest oscillatory mode of the linearisation.
    let modes = sim.model.modes();
    if let Some(slow) = modes
        .iter()
        .filter(|(_, im)| *im > 0.0)
        .min_by(|a, b| a.1.total_cmp(&b.1))
    {
        m.insert(
            design_constants_record::MODE_PERIOD_S.into(),
            format!("{}", std::f64::consts::TAU / slow.1),
        );
        m.insert(
            design_constants_record::MODE_DECAY_RATE_PER_S.into(),
            format!("{}", -slow.0),
        );
    }
    m
}
