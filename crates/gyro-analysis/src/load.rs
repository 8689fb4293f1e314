//! Loading recordings: each channel becomes a polars [`DataFrame`] with `time_s` first, one column
//! per field, and `run_id` last; many runs load in parallel, and the channels of one run too.
//!
//! Only the channels asked for are decoded (by default every record channel, and no poses: a day
//! of poses is millions of rows the fits never read), so opening a recording for one channel
//! costs one channel. [`stack_channel`] stacks one channel of many runs into one frame, aligned by
//! field name, for queries across runs.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use gyro_mcap::contract::{TIME_S, result_record, run_record, status};
use gyro_mcap::{
    ChannelKind, ChannelTable, Column as McapColumn, PoseTable, RecordTable, Recording,
};
use polars::prelude::*;
use rayon::prelude::*;

use crate::error::{AnalysisError, Result};

/// The compass state channel (see `docs/recordings.md`; the topics are `gyro_mcap::contract`'s).
pub use gyro_mcap::contract::compass_state::TOPIC as COMPASS_TOPIC;
/// Manoeuvre start and end events.
pub use gyro_mcap::contract::events::TOPIC as EVENTS_TOPIC;
/// The ship state channel.
pub use gyro_mcap::contract::ship_state::TOPIC as SHIP_TOPIC;
/// Solver statistics.
pub use gyro_mcap::contract::solver_stats::TOPIC as SOLVER_TOPIC;
/// Poses (`foxglove.FrameTransform`).
pub use gyro_mcap::contract::tf::TOPIC as TF_TOPIC;

/// Which channels to decode.
#[derive(Debug, Clone, Default)]
pub struct LoadOptions {
    /// Record channels to decode; `None`: every record channel of the file. A topic listed here
    /// that the file lacks is an error naming the file and the topic.
    pub topics: Option<Vec<String>>,
    /// Also decode pose channels (one row per frame per sample: large).
    pub poses: bool,
}

impl LoadOptions {
    /// Exactly these topics (record or pose channels).
    pub fn topics(topics: &[&str]) -> Self {
        Self {
            topics: Some(topics.iter().map(|t| (*t).to_owned()).collect()),
            poses: true,
        }
    }
}

/// One recording, loaded: its metadata records and one frame per decoded channel.
#[derive(Debug, Clone)]
pub struct Run {
    pub path: PathBuf,
    /// The file name without `.mcap`; also the `run_id` column of every frame.
    pub run_id: String,
    /// Metadata records by name (`run`, `design_constants`, `scene`, …), as written.
    pub metadata: BTreeMap<String, BTreeMap<String, String>>,
    /// Frames by topic.
    pub frames: BTreeMap<String, DataFrame>,
}

impl Run {
    /// The frame of `topic`; the error names the file and the channels it has.
    pub fn frame(&self, topic: &str) -> Result<&DataFrame> {
        self.frames
            .get(topic)
            .ok_or_else(|| AnalysisError::MissingChannel {
                path: self.path.clone(),
                topic: topic.to_owned(),
                available: quoted(self.frames.keys().map(String::as_str)),
            })
    }

    /// A float column of a channel as a slice (frames built here are contiguous and null-free).
    pub fn f64_field(&self, topic: &str, field: &str) -> Result<&[f64]> {
        let frame = self.frame(topic)?;
        let missing = |what: String| AnalysisError::MissingField {
            path: self.path.clone(),
            topic: topic.to_owned(),
            what,
            available: quoted(frame.get_column_names().iter().map(|s| s.as_str())),
        };
        let column = frame
            .column(field)
            .map_err(|_| missing(format!("no field {field:?}")))?;
        let ca = column
            .f64()
            .map_err(|_| missing(format!("field {field:?} is {}, not f64", column.dtype())))?;
        ca.cont_slice()
            .map_err(|_| missing(format!("field {field:?} has nulls or several chunks")))
    }

    /// A string column of a channel.
    pub fn str_field(&self, topic: &str, field: &str) -> Result<Vec<String>> {
        let frame = self.frame(topic)?;
        let missing = |what: String| AnalysisError::MissingField {
            path: self.path.clone(),
            topic: topic.to_owned(),
            what,
            available: quoted(frame.get_column_names().iter().map(|s| s.as_str())),
        };
        let column = frame
            .column(field)
            .map_err(|_| missing(format!("no field {field:?}")))?;
        let ca = column.str().map_err(|_| {
            missing(format!(
                "field {field:?} is {}, not a string",
                column.dtype()
            ))
        })?;
        Ok(ca
            .iter()
            .map(|s| s.unwrap_or_default().to_owned())
            .collect())
    }

    /// A metadata value (`record`, `key`), e.g. (`run`, `design_name`).
    pub fn meta(&self, record: &str, key: &str) -> Option<&str> {
        self.metadata
            .get(record)
            .and_then(|r| r.get(key))
            .map(String::as_str)
    }

    /// A metadata value parsed as a number (absent or unparsable: `None`).
    pub fn meta_f64(&self, record: &str, key: &str) -> Option<f64> {
        self.meta(record, key)
            .and_then(|s| s.trim().parse::<f64>().ok())
            .filter(|v| v.is_finite())
    }

    /// A value of how the run ended (`status`, `steps`, `wall_time_s`, …): the `result` record,
    /// written when the run closes its file, or the `run` record of files written before the two
    /// were split. `None` in a file recovered from a killed run.
    pub fn result(&self, key: &str) -> Option<&str> {
        self.meta(result_record::NAME, key)
            .or_else(|| self.meta(run_record::NAME, key))
    }

    /// How the run ended: `complete`, `interrupted at t = … s`, or [`status::RECOVERED`] when
    /// the file has no result (its writer was killed and `gyrolab recover` salvaged it).
    pub fn status(&self) -> &str {
        self.result(result_record::STATUS)
            .unwrap_or(status::RECOVERED)
    }
}

pub(crate) fn quoted<'a>(names: impl Iterator<Item = &'a str>) -> String {
    let v: Vec<String> = names.map(|n| format!("{n:?}")).collect();
    if v.is_empty() {
        "none".to_owned()
    } else {
        v.join(", ")
    }
}

/// Turns arguments into recording paths: a file is taken as given; a folder gives its `*.mcap`
/// files (sorted, not recursive); anything with `*`, `?` or `[` is a glob. An argument that
/// names no recording is an error.
pub fn expand_inputs<P: AsRef<Path>>(inputs: &[P]) -> Result<Vec<PathBuf>> {
    let mut out = Vec::new();
    for input in inputs {
        let input = input.as_ref();
        let text = input.to_string_lossy();
        let before = out.len();
        if input.is_dir() {
            let entries = std::fs::read_dir(input).map_err(AnalysisError::io(input, "listing"))?;
            let mut found: Vec<PathBuf> = entries
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.is_file() && p.extension().is_some_and(|x| x == "mcap"))
                .collect();
            found.sort();
            out.extend(found);
        } else if text.contains(['*', '?', '[']) {
            let paths = glob::glob(&text).map_err(|e| AnalysisError::Input {
                input: text.to_string(),
                what: format!("not a valid glob pattern: {e}"),
            })?;
            let mut found: Vec<PathBuf> = paths.filter_map(|p| p.ok()).collect();
            found.sort();
            out.extend(found);
        } else {
            out.push(input.to_path_buf());
        }
        if out.len() == before {
            return Err(AnalysisError::Input {
                input: text.to_string(),
                what: "names no recording (no *.mcap file there)".to_owned(),
            });
        }
    }
    Ok(out)
}

/// The run id of a path: its file name less `.mcap`.
pub fn run_id_of(path: &Path) -> String {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    name.strip_suffix(".mcap").unwrap_or(&name).to_owned()
}

/// Opens one recording and decodes the channels `opts` asks for.
pub fn load_run(path: &Path, opts: &LoadOptions) -> Result<Run> {
    let recording = Recording::open(path)?;
    let run_id = run_id_of(path);
    let channels = recording.channels();
    let available = || quoted(channels.iter().map(|c| c.topic.as_str()));
    let wanted: Vec<&gyro_mcap::ChannelInfo> = match &opts.topics {
        Some(topics) => {
            let mut v = Vec::with_capacity(topics.len());
            for topic in topics {
                let ch = channels.iter().find(|c| &c.topic == topic).ok_or_else(|| {
                    AnalysisError::MissingChannel {
                        path: path.to_path_buf(),
                        topic: topic.clone(),
                        available: available(),
                    }
                })?;
                v.push(ch);
            }
            v
        }
        None => channels
            .iter()
            .filter(|c| {
                c.kind == ChannelKind::Record || (opts.poses && c.kind == ChannelKind::Pose)
            })
            .collect(),
    };
    // One pass over the file decompresses each chunk once for every channel asked for (the
    // reader shares chunks among threads); the tables then become frames one per core.
    let topics: Vec<&str> = wanted.iter().map(|c| c.topic.as_str()).collect();
    let tables = recording.read_topics(&topics)?;
    let frames = tables
        .into_par_iter()
        .zip(topics.par_iter())
        .map(|(table, topic)| {
            let frame = match table {
                ChannelTable::Poses(p) => pose_frame(&recording, p, topic, &run_id)?,
                ChannelTable::Records(r) => record_frame(&recording, r, topic, &run_id)?,
            };
            Ok((topic.to_string(), frame))
        })
        .collect::<Result<BTreeMap<String, DataFrame>>>()?;
    Ok(Run {
        path: path.to_path_buf(),
        run_id,
        metadata: recording.metadata().clone(),
        frames,
    })
}

/// Loads every recording the arguments name (see [`expand_inputs`]), in parallel; the first
/// failure (in argument order) is returned.
pub fn load_runs<P: AsRef<Path> + Sync>(inputs: &[P], opts: &LoadOptions) -> Result<Vec<Run>> {
    let paths = expand_inputs(inputs)?;
    paths.par_iter().map(|p| load_run(p, opts)).collect()
}

fn record_frame(
    recording: &Recording,
    table: RecordTable,
    topic: &str,
    run_id: &str,
) -> Result<DataFrame> {
    let n = table.len();
    let ctx = || format!("{}: channel {topic:?}", recording.path().display());
    // Time: the record's own `time_s` field (exact) where present, else the log time.
    let mut columns: Vec<Column> = Vec::with_capacity(table.columns.len() + 2);
    let has_time_field = matches!(table.column(TIME_S), Some(McapColumn::F64(_)));
    if !has_time_field {
        let t: Vec<f64> = table
            .log_time_ns
            .iter()
            .map(|&ns| ns as f64 * 1e-9)
            .collect();
        columns.push(Float64Chunked::from_vec(TIME_S.into(), t).into_column());
    }
    let mut time_first = None;
    for (name, col) in table.columns {
        let column = match col {
            McapColumn::F64(v) => Float64Chunked::from_vec(name.as_str().into(), v).into_column(),
            McapColumn::U64(v) => UInt64Chunked::from_vec(name.as_str().into(), v).into_column(),
            McapColumn::Str(v) => Column::new(name.as_str().into(), v),
        };
        if name == TIME_S && has_time_field {
            time_first = Some(column);
        } else {
            columns.push(column);
        }
    }
    if let Some(t) = time_first {
        columns.insert(0, t);
    }
    columns.push(Column::new_scalar(
        "run_id".into(),
        Scalar::from(PlSmallStr::from(run_id)),
        n,
    ));
    DataFrame::new(n, columns).map_err(AnalysisError::polars(ctx()))
}

fn pose_frame(recording: &Recording, p: PoseTable, topic: &str, run_id: &str) -> Result<DataFrame> {
    let n = p.len();
    let ctx = || format!("{}: channel {topic:?}", recording.path().display());
    let t: Vec<f64> = p.log_time_ns.iter().map(|&ns| ns as f64 * 1e-9).collect();
    let mut columns = vec![
        Float64Chunked::from_vec("time_s".into(), t).into_column(),
        Column::new(
            "parent_frame".into(),
            (0..n).map(|i| p.parent_frame(i)).collect::<Vec<&str>>(),
        ),
        Column::new(
            "child_frame".into(),
            (0..n).map(|i| p.child_frame(i)).collect::<Vec<&str>>(),
        ),
    ];
    for (k, name) in ["x_m", "y_m", "z_m"].iter().enumerate() {
        let v: Vec<f64> = p.translation_m.iter().map(|a| a[k]).collect();
        columns.push(Float64Chunked::from_vec((*name).into(), v).into_column());
    }
    for (k, name) in ["qx", "qy", "qz", "qw"].iter().enumerate() {
        let v: Vec<f64> = p.rotation_xyzw.iter().map(|a| a[k]).collect();
        columns.push(Float64Chunked::from_vec((*name).into(), v).into_column());
    }
    columns.push(Column::new_scalar(
        "run_id".into(),
        Scalar::from(PlSmallStr::from(run_id)),
        n,
    ));
    DataFrame::new(n, columns).map_err(AnalysisError::polars(ctx()))
}

/// One channel of many runs stacked into one frame (rows of each run in time order, runs in the
/// given order, told apart by `run_id`). Runs whose channel has other fields are aligned by name
/// (missing fields are null). Buffers are shared with the runs' frames, not copied; call
/// `.lazy()` on the result for query plans if your crate enables polars' `lazy` feature (this
/// one does not: it would add six polars crates, about six minutes of cold build, for one call).
pub fn stack_channel(runs: &[Run], topic: &str) -> Result<DataFrame> {
    // The union of the runs' columns, in first-seen order (designs differ in coordinates).
    let mut union: Vec<(PlSmallStr, DataType)> = Vec::new();
    for run in runs {
        for (name, dtype) in run.frame(topic)?.schema().iter() {
            if !union.iter().any(|(n, _)| n == name) {
                union.push((name.clone(), dtype.clone()));
            }
        }
    }
    let ctx = || format!("stacking channel {topic:?}");
    let mut stacked: Option<DataFrame> = None;
    for run in runs {
        let frame = run.frame(topic)?;
        let height = frame.height();
        let columns: Vec<Column> = union
            .iter()
            .map(|(name, dtype)| match frame.column(name) {
                Ok(c) => c.clone(),
                Err(_) => Column::full_null(name.clone(), height, dtype),
            })
            .collect();
        let aligned = DataFrame::new(height, columns).map_err(AnalysisError::polars(ctx()))?;
        match stacked.as_mut() {
            None => stacked = Some(aligned),
            Some(s) => {
                s.vstack_mut_owned(aligned)
                    .map_err(AnalysisError::polars(ctx()))?;
            }
        }
    }
    Ok(stacked.unwrap_or_default())
}
