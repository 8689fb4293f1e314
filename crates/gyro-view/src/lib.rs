//! gyro-view owns how gyrolab recordings look in the Rerun viewer: it reads runs through
//! `gyro-mcap`, logs each design's chain of bodies as shapes posed from `/tf`, the local
//! North–West–Up axes, true and indicated North and the apparent vertical in 3-D, and the
//! reading error, tilt, heading, speed and roll as time series with manoeuvre markers and the
//! fitted settling curve; several runs overlay, each under `/runs/<name>`; a blueprint lays the
//! views out. It knows nothing of physics (it draws what the recording says, with
//! `gyro-model`'s `Shape` only as the vocabulary of body shapes) and nothing of the command
//! line (the `gyrolab view` subcommand calls [`view`]).
//!
//! # Entity paths (per run `<r>`, the file stem made path-safe and unique)
//! - `/runs/<r>/earth/<frame>/…`: one entity per `/tf` frame, nested as the frames are
//!   (`earth/ship/gimbal/…`); `Transform3D` at every kept pose sample; the body's shape at
//!   `…/shape`, the rotor's `…/spin_marker` and `…/spin_axis`, the ship's `…/hull_outline` when
//!   no body is a hull.
//! - `/runs/<r>/overlay/{axes_nwu,true_north,indicated_north,apparent_vertical}`.
//! - `/runs/<r>/series/{reading_error_deg,tilt_deg,heading_deg/compass,heading_deg/true,
//!   speed_m_per_s,roll_deg}`, full rate, angles in degrees; `reading_error_deg/{fit,
//!   envelope_upper,envelope_lower,events}`; `/runs/<r>/events` (text log).
//! - Timeline `sim_time` (a duration: simulated time since the run's start).
//!
//! # Long runs
//! Series go at full rate, each in one `send_columns` call whose values are the recorded column
//! moved into an arrow buffer. Poses are decimated for display ([`ViewOptions::max_pose_rate_hz`],
//! [`ViewOptions::max_pose_samples`]).
//!
//! # Layout
//! [`blueprint`] puts the 3-D view (the manoeuvre log under it) beside the stacked series;
//! [`send_layout`] sends it with every time-series view opening on the whole run (Rerun's own
//! default for a plot over more than a minute is the time cursor ± 30 s).
//!
//! # Small angles
//! [`ViewOptions::tilt_exaggeration`] multiplies every body's tilt from the local vertical (and
//! the apparent vertical's) in the 3-D view, keeping azimuths; the view's title says so.

mod fit;
mod math;
mod run;
mod scene;
mod series;

use std::path::{Path, PathBuf};
use std::time::Instant;

use gyro_mcap::contract::run_record;
use gyro_mcap::partial_path;
use rerun::blueprint::{
    Blueprint, BlueprintPanel, ContainerLike, Horizontal, SelectionPanel, Spatial3DView,
    TextLogView, TimePanel, TimeSeriesView, Vertical,
};
use rerun::{RecordingStream, RecordingStreamBuilder, TimeColumn, Timeline};

pub use fit::{AnalysisFit, DampedSinusoid, NoFit, SettlingFit, default_fit};
pub use math::TILT_SATURATION_RAD;

/// Where the logged data goes.
#[derive(Clone, Debug, PartialEq)]
pub enum Sink {
    /// Write an `.rrd` file.
    Save(PathBuf),
    /// Start a `rerun` viewer (from `PATH`) and stream to it; with none on `PATH`, save an `.rrd`
    /// next to the first run instead and say how to open it.
    Spawn,
    /// Stream to a running viewer, e.g. `rerun+http://127.0.0.1:9876/proxy`.
    Connect(String),
}

/// Settings of [`view`].
#[derive(Clone, Debug, PartialEq)]
pub struct ViewOptions {
    pub sink: Sink,
    /// Multiplies tilts from the local vertical in the 3-D view (1 = true angles; saturates
    /// towards [`TILT_SATURATION_RAD`]). Default 1.
    pub tilt_exaggeration: f64,
    /// Multiplies the reading error in the indicated-North arrow's direction. Default 1.
    pub error_exaggeration: f64,
    /// Poses (and the 3-D arrows) are kept at most this often per simulated second. Default 10 Hz.
    pub max_pose_rate_hz: f64,
    /// …and at most this many per frame over the run (a 24-hour run keeps one pose every ~4 s).
    /// Default 20 000.
    pub max_pose_samples: usize,
    /// Send the layout (3-D beside the time series). Default true.
    pub blueprint: bool,
}

impl Default for ViewOptions {
    fn default() -> Self {
        Self {
            sink: Sink::Spawn,
            tilt_exaggeration: 1.0,
            error_exaggeration: 1.0,
            max_pose_rate_hz: 10.0,
            max_pose_samples: 20_000,
            blueprint: true,
        }
    }
}

/// Where the data went.
#[derive(Clone, Debug, PartialEq)]
pub enum Output {
    Saved { path: PathBuf, bytes: u64 },
    Spawned,
    Connected { url: String },
}

/// What was logged for one run.
#[derive(Clone, Debug, PartialEq)]
pub struct RunSummary {
    pub path: PathBuf,
    /// Its entity root, `/runs/<name>`.
    pub entity: String,
    /// `/compass/state` samples sent per series.
    pub samples: usize,
    /// Poses sent per frame (after decimation).
    pub poses_per_frame: usize,
    /// The `/tf` frames drawn.
    pub frames: Vec<String>,
    pub fit: Option<DampedSinusoid>,
}

#[derive(Clone, Debug, PartialEq)]
pub struct ViewReport {
    pub output: Output,
    pub runs: Vec<RunSummary>,
    /// Things the user should know (e.g. no viewer found, the file saved and how to open it).
    pub notes: Vec<String>,
    pub elapsed_s: f64,
}

#[derive(Debug, thiserror::Error)]
pub enum ViewError {
    #[error(transparent)]
    Recording(#[from] gyro_mcap::RecordingError),
    #[error("{path}: metadata {key}: {detail}")]
    Metadata {
        path: PathBuf,
        key: String,
        detail: String,
    },
    #[error("{path}: /tf: {detail}")]
    Poses { path: PathBuf, detail: String },
    #[error("option {name}: {detail}")]
    Option { name: &'static str, detail: String },
    #[error("no runs given")]
    NoRuns,
    #[error("rerun: {0}")]
    Rerun(String),
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
}

macro_rules! rerun_error {
    ($($t:ty),*) => {$(
        impl From<$t> for ViewError {
            fn from(e: $t) -> Self {
                ViewError::Rerun(e.to_string())
            }
        }
    )*};
}
rerun_error!(
    rerun::RecordingStreamError,
    rerun::SerializationError,
    rerun::sink::FileSinkError,
    rerun::sink::SinkFlushError
);

/// The application id of every stream gyro-view opens.
const APPLICATION_ID: &str = "gyrolab";

/// The timeline every entity is logged on.
pub const TIMELINE: &str = "sim_time";

pub(crate) fn sim_time(time_ns: Vec<i64>) -> TimeColumn {
    let sorted = time_ns.windows(2).all(|w| w[0] <= w[1]);
    TimeColumn::new(
        Some(sorted),
        Timeline::new_duration(TIMELINE),
        time_ns.into(),
    )
}

/// Indices of the samples kept for display: at most one per `1 / max_pose_rate_hz` and at most
/// about `max_pose_samples` over the span; the first and last are always kept.
pub(crate) fn decimate(time_ns: &[i64], opts: &ViewOptions) -> Vec<usize> {
    let (Some(&first), Some(&last)) = (time_ns.first(), time_ns.last()) else {
        return Vec::new();
    };
    let by_rate = if opts.max_pose_rate_hz > 0.0 {
        1e9 / opts.max_pose_rate_hz
    } else {
        0.0
    };
    let span = (last.saturating_sub(first)) as f64;
    let by_count = span / opts.max_pose_samples.max(2) as f64;
    let interval = by_rate.max(by_count).min(i64::MAX as f64) as i64;
    let mut kept =
        Vec::with_capacity(((span / interval.max(1) as f64) as usize + 2).min(time_ns.len()));
    let mut next = first;
    for (i, &t) in time_ns.iter().enumerate() {
        if t >= next {
            kept.push(i);
            next = t.saturating_add(interval.max(1));
        }
    }
    let n = time_ns.len() - 1;
    if kept.last() != Some(&n) {
        kept.push(n);
    }
    kept
}

fn check(opts: &ViewOptions) -> Result<(), ViewError> {
    let bad = |name, v: f64| ViewError::Option {
        name,
        detail: format!("{v} is not a positive finite number"),
    };
    if !(opts.tilt_exaggeration.is_finite() && opts.tilt_exaggeration > 0.0) {
        return Err(bad("tilt_exaggeration", opts.tilt_exaggeration));
    }
    if !opts.error_exaggeration.is_finite() || opts.error_exaggeration <= 0.0 {
        return Err(bad("error_exaggeration", opts.error_exaggeration));
    }
    if !(opts.max_pose_rate_hz.is_finite() && opts.max_pose_rate_hz > 0.0) {
        return Err(bad("max_pose_rate_hz", opts.max_pose_rate_hz));
    }
    Ok(())
}

/// Unique, path-safe run names from file stems.
fn run_names(runs: &[PathBuf]) -> Vec<String> {
    let mut names: Vec<String> = Vec::with_capacity(runs.len());
    for p in runs {
        let stem = p
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        let base = run::entity_name(&stem);
        let mut name = base.clone();
        let mut k = 2;
        while names.contains(&name) {
            name = format!("{base}_{k}");
            k += 1;
        }
        names.push(name);
    }
    names
}

/// Logs the runs into `rec` (any sink) and returns what was logged; [`view`] wraps this with
/// the sink and the blueprint.
pub fn log_runs(
    rec: &RecordingStream,
    runs: &[PathBuf],
    opts: &ViewOptions,
    fit: &dyn SettlingFit,
) -> Result<Vec<RunSummary>, ViewError> {
    check(opts)?;
    rec.log_static("/", &rerun::ViewCoordinates::RIGHT_HAND_Z_UP())?;
    let mut out = Vec::with_capacity(runs.len());
    for (i, (path, name)) in runs.iter().zip(run_names(runs)).enumerate() {
        let mut data = run::RunData::load(path, name)?;
        let root = format!("/runs/{}", data.name);
        let scene = scene::log_scene(rec, &data, i, &root, opts)?;
        let series = series::log_series(rec, &mut data, i, &root, fit)?;
        log_about(rec, &data, &root, opts)?;
        out.push(RunSummary {
            path: path.clone(),
            entity: root,
            samples: series.samples,
            poses_per_frame: scene.poses_per_frame,
            frames: scene.bodies,
            fit: series.fit,
        });
    }
    Ok(out)
}

fn log_about(
    rec: &RecordingStream,
    run: &run::RunData,
    root: &str,
    opts: &ViewOptions,
) -> Result<(), ViewError> {
    let m = |r: &str, k: &str| run.meta(r, k).unwrap_or("?").to_owned();
    let text = format!(
        "# {}\n\nfile: `{}`\n\nscene **{}**, design **{}** ({}), fidelity {}, integrator {} (rtol {}), \
         {} s at {} Hz, status: {}\n\neffects: {}\n\n3-D: tilts ×{} (saturating at 80°), \
         reading error in the indicated-North arrow ×{}; poses at most {} Hz / {} per frame.",
        run.name,
        run.path.display(),
        m(run_record::NAME, run_record::SCENE_NAME),
        m(run_record::NAME, run_record::DESIGN_NAME),
        m(run_record::NAME, run_record::DESIGN_KIND),
        m(run_record::NAME, run_record::FIDELITY),
        m(run_record::NAME, run_record::INTEGRATOR),
        m(run_record::NAME, run_record::RTOL),
        m(run_record::NAME, run_record::DURATION_S),
        m(run_record::NAME, run_record::OUTPUT_RATE_HZ),
        run.status(),
        m(run_record::NAME, run_record::EFFECTS),
        opts.tilt_exaggeration,
        opts.error_exaggeration,
        opts.max_pose_rate_hz,
        opts.max_pose_samples,
    );
    rec.log_static(
        format!("{root}/about"),
        &rerun::TextDocument::from_markdown(text),
    )?;
    Ok(())
}

/// What [`blueprint`] lays out: the blueprint, and the blueprint paths of its time-series views
/// (each opens on the whole run when the layout is sent, see [`send_layout`]).
pub struct Layout {
    pub blueprint: Blueprint,
    /// `view/<id>` of every time-series view.
    pub time_series_views: Vec<String>,
}

/// The layout: the 3-D view (with the events log under it) beside the stacked time series.
pub fn blueprint(run_roots: &[String], opts: &ViewOptions) -> Layout {
    let each = |suffix: &str| -> Vec<String> {
        run_roots
            .iter()
            .map(|r| format!("+ {r}/{suffix}/**"))
            .collect()
    };
    let title = if (opts.tilt_exaggeration - 1.0).abs() < 1e-12 {
        "3-D".to_owned()
    } else {
        format!("3-D (tilts exaggerated ×{})", opts.tilt_exaggeration)
    };
    let mut contents = each("earth");
    contents.extend(each("overlay"));
    let left = Vertical::new([
        Spatial3DView::new(title)
            .with_origin("/")
            .with_contents(contents)
            .into(),
        TextLogView::new("manoeuvres")
            .with_contents(run_roots.iter().map(|r| format!("+ {r}/events")))
            .into(),
    ])
    .with_row_shares([4.0, 1.0]);
    let mut time_series_views = Vec::with_capacity(series::SERIES_VIEWS.len());
    let series: Vec<ContainerLike> = series::SERIES_VIEWS
        .iter()
        .map(|(name, leaf)| {
            let view: ContainerLike = TimeSeriesView::new(*name)
                .with_contents(each(&format!("series/{leaf}")))
                .with_origin("/")
                .into();
            if let ContainerLike::View(v) = &view {
                time_series_views.push(v.blueprint_path().to_string());
            }
            view
        })
        .collect();
    let right = Vertical::new(series);
    use rerun::blueprint::components::{PanelState, PlayState};
    let blueprint =
        Blueprint::new(Horizontal::new([left.into(), right.into()]).with_column_shares([1.1, 1.0]))
            .with_blueprint_panel(BlueprintPanel::new().with_state(PanelState::Collapsed))
            .with_selection_panel(SelectionPanel::new().with_state(PanelState::Collapsed))
            .with_time_panel(
                TimePanel::new()
                    .with_state(PanelState::Collapsed)
                    .with_timeline(TIMELINE)
                    .with_play_state(PlayState::Following),
            );
    Layout {
        blueprint,
        time_series_views,
    }
}

/// Sends the layout to `rec`, every time-series view opening on the whole run.
///
/// Why not the plain `Blueprint::send`: without a `TimeAxis.view_range`, Rerun 0.36 shows a plot
/// whose data span more than a minute as the time cursor ± 30 s (the view's fallback, chosen for
/// hours-long robot logs), so a five-hour settling curve opens as a flat line at its end. The
/// Rust blueprint builder has no setter for a time-series view's properties, so the blueprint is
/// rendered into memory, a `TimeAxis` over everything is added to the same blueprint store for
/// each series view, and the whole is sent with the blueprint's own activation command.
pub fn send_layout(rec: &RecordingStream, layout: &Layout) -> Result<(), ViewError> {
    use rerun::external::re_log_types::LogMsg;
    use rerun::external::re_sdk_types::blueprint::archetypes::TimeAxis;
    use rerun::external::re_sdk_types::datatypes::TimeRange;
    let (capture, storage) = RecordingStreamBuilder::new(APPLICATION_ID)
        .default_enabled(true)
        .memory()?;
    layout
        .blueprint
        .send(&capture, rerun::blueprint::BlueprintActivation::default())?;
    let mut msgs = Vec::new();
    let mut activation = None;
    for msg in storage.take() {
        match msg {
            LogMsg::BlueprintActivationCommand(cmd) => activation = Some(cmd),
            msg if msg.store_id().is_blueprint() => msgs.push(msg),
            _ => {}
        }
    }
    let activation = activation
        .ok_or_else(|| ViewError::Rerun("the blueprint came without activation".into()))?;
    let (props, props_storage) = RecordingStreamBuilder::new(APPLICATION_ID)
        .default_enabled(true)
        .recording_id(activation.blueprint_id.recording_id().clone())
        .blueprint()
        .memory()?;
    props.set_time_sequence("blueprint", 0);
    for view in &layout.time_series_views {
        props.log(
            format!("{view}/TimeAxis"),
            &TimeAxis::new().with_view_range(TimeRange::EVERYTHING),
        )?;
    }
    msgs.extend(
        props_storage
            .take()
            .into_iter()
            .filter(|m| matches!(m, LogMsg::ArrowMsg(..))),
    );
    rec.send_blueprint(msgs, activation);
    Ok(())
}

/// The first `rerun` executable on `PATH`.
pub fn find_viewer() -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .map(|d| d.join("rerun"))
        .find(|p| p.is_file())
}

/// `<dir of the first run>/<its stem>.rrd`.
fn fallback_rrd(first: &Path) -> PathBuf {
    first.with_extension("rrd")
}

/// Views recordings: logs them with [`default_fit`] and sends them to `opts.sink`.
pub fn view(runs: &[PathBuf], opts: &ViewOptions) -> Result<ViewReport, ViewError> {
    view_with_fit(runs, opts, default_fit())
}

/// [`view`] with a chosen settling fit.
pub fn view_with_fit(
    runs: &[PathBuf],
    opts: &ViewOptions,
    fit: &dyn SettlingFit,
) -> Result<ViewReport, ViewError> {
    let start = Instant::now();
    check(opts)?;
    let first = runs.first().ok_or(ViewError::NoRuns)?;
    let mut notes = Vec::new();
    let builder = RecordingStreamBuilder::new(APPLICATION_ID).default_enabled(true);
    // A saved file is written under `<name>.partial` (the recorder's convention) and renamed
    // when whole: a run that fails half-way (an unreadable recording, a full disk) leaves no
    // `.rrd` under the final name.
    let (rec, output) = match &opts.sink {
        Sink::Save(path) => (
            builder.save(partial_path(path))?,
            Output::Saved {
                path: path.clone(),
                bytes: 0,
            },
        ),
        Sink::Connect(url) => (
            builder.connect_grpc_opts(url.clone())?,
            Output::Connected { url: url.clone() },
        ),
        Sink::Spawn => {
            if let Some(viewer) = find_viewer() {
                let spawn = rerun::SpawnOptions {
                    executable_path: Some(viewer.to_string_lossy().into_owned()),
                    ..Default::default()
                };
                (builder.spawn_opts(&spawn)?, Output::Spawned)
            } else {
                let path = fallback_rrd(first);
                notes.push(format!(
                    "no `rerun` viewer on PATH: saved {}; open it with `rerun {}` \
                     (the viewer comes with `pip install rerun-sdk==0.36.3`)",
                    path.display(),
                    path.display()
                ));
                (
                    builder.save(partial_path(&path))?,
                    Output::Saved { path, bytes: 0 },
                )
            }
        }
    };
    let logged = (|| -> Result<_, ViewError> {
        let summaries = log_runs(&rec, runs, opts, fit)?;
        if opts.blueprint {
            let roots: Vec<String> = summaries.iter().map(|s| s.entity.clone()).collect();
            send_layout(&rec, &blueprint(&roots, opts))?;
        }
        rec.flush_blocking()?;
        Ok(summaries)
    })();
    drop(rec);
    let summaries = match logged {
        Ok(s) => s,
        Err(e) => {
            if let Output::Saved { path, .. } = &output {
                let _ = std::fs::remove_file(partial_path(path));
            }
            return Err(e);
        }
    };
    let output = match output {
        Output::Saved { path, .. } => {
            let tmp = partial_path(&path);
            let bytes = std::fs::rename(&tmp, &path)
                .and_then(|()| std::fs::metadata(&path))
                .map_err(|source| ViewError::Io {
                    path: path.clone(),
                    source,
                })?
                .len();
            Output::Saved { path, bytes }
        }
        o => o,
    };
    Ok(ViewReport {
        output,
        runs: summaries,
        notes,
        elapsed_s: start.elapsed().as_secs_f64(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decimation_keeps_rate_count_and_ends() {
        let t: Vec<i64> = (0..=1000).map(|i| i * 10_000_000).collect(); // 100 Hz for 10 s
        let opts = ViewOptions {
            max_pose_rate_hz: 10.0,
            ..Default::default()
        };
        let k = decimate(&t, &opts);
        assert_eq!(k.len(), 101);
        assert_eq!(k.first(), Some(&0));
        assert_eq!(k.last(), Some(&1000));
        let opts = ViewOptions {
            max_pose_rate_hz: 1e6,
            max_pose_samples: 50,
            ..Default::default()
        };
        assert_eq!(decimate(&t, &opts).len(), 51);
        assert!(decimate(&[], &opts).is_empty());
        assert_eq!(decimate(&[5], &opts), vec![0]);
    }

    #[test]
    fn run_names_are_unique() {
        let runs = [
            PathBuf::from("a/x.mcap"),
            PathBuf::from("b/x.mcap"),
            PathBuf::from("c d.mcap"),
        ];
        assert_eq!(run_names(&runs), vec!["x", "x_2", "c_d"]);
    }

    #[test]
    fn bad_options_are_refused() {
        let opts = ViewOptions {
            tilt_exaggeration: f64::NAN,
            ..Default::default()
        };
        assert!(matches!(
            check(&opts),
            Err(ViewError::Option {
                name: "tilt_exaggeration",
                ..
            })
        ));
    }
}
