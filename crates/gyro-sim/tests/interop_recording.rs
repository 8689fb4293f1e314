//! Interop of a shipped scene's recording with the reference tools, through the library API
//! (`gyro_sim::record`, no CLI):
//! - the Python `mcap` library with `mcap-protobuf-support` decodes every message of every channel,
//!   and its counts and values equal what gyro-mcap's reader sees;
//! - `rerun mcap convert` of rerun-sdk 0.36.3 (the Rerun version the workspace builds against)
//!   turns the `/tf` FrameTransforms into transforms of every body, with our numbers.
//!
//! Both use the workspace's pinned interop venv (`gyro_testkit::interop_python`, the one every
//! interop test uses, so a workspace test run downloads Rerun once), made once under the target
//! directory and reused. Where it cannot be had (no python3, pip failing) the tests print a
//! visible `SKIPPED:` line saying why, and fail under `CI=true`.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::process::Command;
use std::sync::OnceLock;

use gyro_mcap::{ChannelKind, Column, PoseTable, RecordTable, Recording};
use gyro_sim::{RecordOptions, Scene, SceneOverrides, record};
use serde_json::Value;

/// turn-90 cut to 4000 s: every channel has messages (the turn starts at 3600 s and lasts
/// 90 s, so both its events fall inside), ~32 k messages.
fn recording() -> &'static (PathBuf, Recording) {
    static REC: OnceLock<(PathBuf, Recording)> = OnceLock::new();
    REC.get_or_init(|| {
        let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("interop-recording");
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("turn-90.mcap");
        let ov = SceneOverrides {
            duration_s: Some(4000.0),
            ..Default::default()
        };
        let scene = Scene::load("turn-90", &ov).unwrap_or_else(|e| panic!("{e}"));
        let summary = record(&scene, &path, RecordOptions::default()).unwrap();
        assert_eq!(summary.path, path);
        let rec = Recording::open(&path).unwrap();
        (path, rec)
    })
}

fn bits(v: &Value) -> u64 {
    v["bits"]
        .as_u64()
        .unwrap_or_else(|| panic!("{{\"bits\": u64}} expected, found {v}"))
}

/// Row `row` of a record table as Python's flattened fields would show it.
fn record_row(t: &RecordTable, row: usize) -> BTreeMap<String, Value> {
    t.columns
        .iter()
        .map(|(name, c)| {
            let v = match c {
                Column::F64(v) => serde_json::json!({ "bits": v[row].to_bits() }),
                Column::U64(v) => Value::from(v[row]),
                Column::Str(v) => Value::from(v[row].clone()),
            };
            (name.clone(), v)
        })
        .collect()
}

#[test]
fn python_mcap_decodes_every_channel_of_a_shipped_scene() {
    let Some(python) = gyro_testkit::interop_python() else {
        return; // SKIPPED (outside CI): the recording was not decoded by the Python mcap library
    };
    let (path, rec) = recording();
    let channels = rec.channels();
    let tf_rows = channels
        .iter()
        .find(|c| c.topic == "/tf")
        .unwrap()
        .message_count;
    let mid = tf_rows / 2;
    let script =
        gyro_testkit::manifest_dir!().join("../gyro-mcap/tests/python/decode_recording.py");
    let out = Command::new(&python)
        .arg(&script)
        .arg(path)
        .args(["--json", "--rows", &format!("0,1,2,{mid}")])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "python failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let py: Value = serde_json::from_slice(&out.stdout).unwrap();

    // The same channels, each fully decoded, with the same counts.
    let topics = py["topics"].as_object().unwrap();
    let ours: Vec<&str> = channels.iter().map(|c| c.topic.as_str()).collect();
    assert_eq!(
        topics.keys().map(String::as_str).collect::<Vec<_>>(),
        {
            let mut t = ours.clone();
            t.sort();
            t
        },
        "topics"
    );
    let mut total = 0;
    for ch in &channels {
        let t = &topics[&ch.topic];
        assert_eq!(t["schema"], ch.schema_name.as_str(), "{}", ch.topic);
        assert_eq!(t["encoding"], "protobuf", "{}", ch.topic);
        assert_eq!(t["count"], ch.message_count, "{}", ch.topic);
        assert!(ch.message_count > 0, "{} is empty", ch.topic);
        total += ch.message_count;
    }
    assert_eq!(py["message_count"], total);
    for topic in [
        "/compass/state",
        "/ship/state",
        "/events",
        "/solver/stats",
        "/tf",
    ] {
        assert!(topics.contains_key(topic), "{topic} missing");
    }

    // Values: first rows and the last of every record channel, bit for bit, every field.
    for ch in channels.iter().filter(|c| c.kind == ChannelKind::Record) {
        let table = rec.read_records(&ch.topic).unwrap();
        let rows = &topics[&ch.topic]["rows"];
        let mut checked = 0;
        for (key, row) in [("0", 0), ("1", 1), ("last", table.len() - 1)] {
            if row >= table.len() {
                continue;
            }
            let got = &rows[key];
            assert_eq!(
                got["log_time"], table.log_time_ns[row],
                "{} row {key}",
                ch.topic
            );
            let fields: BTreeMap<String, Value> =
                serde_json::from_value(got["fields"].clone()).unwrap();
            assert_eq!(fields, record_row(&table, row), "{} row {key}", ch.topic);
            checked += 1;
        }
        assert!(checked >= 1, "{}", ch.topic);
    }
    // The compass moved: the values compared are not all zero.
    let compass = rec.read_records("/compass/state").unwrap();
    let err = compass
        .column("reading_error_rad")
        .unwrap()
        .as_f64()
        .unwrap();
    assert!(err.iter().any(|e| e.abs() > 1e-4));

    // Poses: frame ids, timestamp, translation and rotation of rows 0, 1, 2, the middle and
    // the last.
    let poses = rec.read_poses("/tf").unwrap();
    let rows = &topics["/tf"]["rows"];
    for (key, row) in [
        ("0".to_string(), 0usize),
        ("1".into(), 1),
        ("2".into(), 2),
        (mid.to_string(), mid as usize),
        ("last".into(), poses.len() - 1),
    ] {
        let f = &rows[&key]["fields"];
        let t = poses.log_time_ns[row];
        assert_eq!(rows[&key]["log_time"], t);
        assert_eq!(
            f["timestamp.seconds"].as_u64().unwrap() * 1_000_000_000
                + f["timestamp.nanos"].as_u64().unwrap(),
            t
        );
        assert_eq!(f["parent_frame_id"], poses.parent_frame(row));
        assert_eq!(f["child_frame_id"], poses.child_frame(row));
        for (k, axis) in ["x", "y", "z"].iter().enumerate() {
            assert_eq!(
                bits(&f[format!("translation.{axis}")]),
                poses.translation_m[row][k].to_bits()
            );
        }
        for (k, axis) in ["x", "y", "z", "w"].iter().enumerate() {
            assert_eq!(
                bits(&f[format!("rotation.{axis}")]),
                poses.rotation_xyzw[row][k].to_bits()
            );
        }
    }

    // Metadata and attachments as the reader sees them.
    let md = py["metadata"].as_object().unwrap();
    assert_eq!(md.len(), rec.metadata().len());
    for (name, entries) in rec.metadata() {
        let theirs: BTreeMap<String, String> = serde_json::from_value(md[name].clone()).unwrap();
        assert_eq!(&theirs, entries, "metadata {name}");
    }
    // The run's solver settings, RADAU5's Jacobian-reuse threshold among them (the default).
    let run = &rec.metadata()["run"];
    assert_eq!(run["jacobian_reuse_contraction"], "1e-3", "{run:?}");
    for a in rec.attachments() {
        assert_eq!(py["attachments"][&a.name], a.data.len(), "{}", a.name);
    }
}

/// The frames of a pose table: child → parent.
fn frames(p: &PoseTable) -> BTreeMap<String, String> {
    (0..p.len())
        .map(|i| (p.child_frame(i).to_owned(), p.parent_frame(i).to_owned()))
        .collect()
}

#[test]
fn rerun_mcap_convert_turns_the_poses_into_transforms_of_every_body() {
    let Some(python) = gyro_testkit::interop_python() else {
        return; // SKIPPED (outside CI): `rerun mcap convert` (rerun-sdk 0.36.3) was not tried
    };
    let (path, rec) = recording();
    let rerun = python.parent().unwrap().join("rerun");
    let rrd = path.with_extension("rrd");
    let _ = std::fs::remove_file(&rrd);
    let out = Command::new(&rerun)
        .args(["mcap", "convert"])
        .arg(path)
        .arg("-o")
        .arg(&rrd)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "rerun mcap convert failed:\n{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(rrd.exists());

    let script = gyro_testkit::manifest_dir!().join("tests/rrd_transforms.py");
    let out = Command::new(&python)
        .arg(&script)
        .arg(&rrd)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "rrd_transforms.py failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let got: Value = serde_json::from_slice(&out.stdout).unwrap();
    let transforms = got["transforms"].as_object().unwrap();
    assert!(
        got["timelines"]
            .as_array()
            .unwrap()
            .contains(&Value::from("message_log_time")),
        "timelines: {}",
        got["timelines"]
    );

    // Every frame of the recording (ship and each body of the chain) is a transform, under its
    // own child frame name, parented as in /tf, at every pose time, with our numbers.
    let poses = rec.read_poses("/tf").unwrap();
    let want = frames(&poses);
    let bodies: Vec<String> = rec.metadata()["bodies"]
        .keys()
        .filter_map(|k| k.strip_suffix(".parent").map(str::to_owned))
        .collect();
    assert!(bodies.len() >= 4, "{bodies:?}");
    for b in bodies.iter().chain(std::iter::once(&"ship".to_string())) {
        assert!(want.contains_key(b), "/tf lacks {b}");
    }
    assert_eq!(
        transforms.keys().cloned().collect::<Vec<_>>(),
        want.keys().cloned().collect::<Vec<_>>(),
        "child frames with transforms"
    );
    for (child, parent) in &want {
        let t = &transforms[child];
        assert_eq!(t["parent_frame"], parent.as_str(), "{child}");
        let rows: Vec<usize> = (0..poses.len())
            .filter(|&i| poses.child_frame(i) == child)
            .collect();
        assert_eq!(t["count"], rows.len(), "{child}: one transform per pose");
        // The last pose of the frame, exactly (Rerun keeps f64 translations and quaternions
        // as f32 or f64; compare to f32 precision).
        let last = *rows.last().unwrap();
        assert_eq!(t["last_time_ns"], poses.log_time_ns[last], "{child}");
        let close = |a: &Value, b: f64| (a.as_f64().unwrap() - b).abs() <= 1e-6 * (1.0 + b.abs());
        for k in 0..3 {
            assert!(
                close(&t["last_translation"][k], poses.translation_m[last][k]),
                "{child} translation {k}: {} vs {}",
                t["last_translation"][k],
                poses.translation_m[last][k]
            );
        }
        for k in 0..4 {
            assert!(
                close(&t["last_quaternion_xyzw"][k], poses.rotation_xyzw[last][k]),
                "{child} rotation {k}: {} vs {}",
                t["last_quaternion_xyzw"][k],
                poses.rotation_xyzw[last][k]
            );
        }
    }
    // The timeline is simulation time from the epoch: the last pose is at 4000 s.
    let end = transforms
        .values()
        .filter_map(|t| t["last_time_ns"].as_u64())
        .max();
    assert_eq!(end, Some(4_000_000_000_000));
}
