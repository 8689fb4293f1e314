//! Interop: the reference Python MCAP libraries decode every channel of our recordings.
//! Uses the workspace's pinned interop venv (`gyro_testkit::interop_python`), made once under
//! the target dir; without python3 it prints SKIPPED, and fails under `CI=true`.
#![allow(clippy::unwrap_used)]
use crate::common;

use std::collections::HashMap;
use std::process::Command;

use common::*;
use gyro_mcap::WriterOptions;

#[test]
fn python_mcap_decodes_every_channel() {
    let Some(python) = gyro_testkit::interop_python() else {
        return; // SKIPPED (outside CI): the Python mcap library did not decode our recording
    };
    let dir = tmp_dir("python");
    let path = dir.join("run.mcap");
    let steps = 700;
    let opts = WriterOptions {
        chunk_size_bytes: 32 * 1024,
        ..Default::default()
    };
    write_sample(&path, steps, opts);
    let script = gyro_testkit::manifest_dir!().join("tests/python/decode_recording.py");
    let out = Command::new(&python)
        .arg(&script)
        .arg(&path)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "python failed:\n{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let got: HashMap<&str, &str> = stdout.lines().filter_map(|l| l.split_once('=')).collect();
    let key = |k: &str| {
        *got.get(k)
            .unwrap_or_else(|| panic!("{k} missing from:\n{stdout}"))
    };

    let all = stream(steps);
    let of = |topic: &str| {
        all.iter()
            .filter(|m| m.topic() == topic)
            .cloned()
            .collect::<Vec<_>>()
    };
    assert_eq!(key("statistics.message_count"), all.len().to_string());
    assert_eq!(key("statistics.chunk_count"), key("chunk_indexes"));
    for (topic, schema) in [
        ("/compass", "gyrolab.CompassState"),
        ("/events", "gyrolab.ManoeuvreEvent"),
        ("/solver", "gyrolab.solver.SolverStats"),
        ("/poses", "foxglove.FrameTransform"),
    ] {
        assert_eq!(
            key(&format!("count.{topic}")),
            of(topic).len().to_string(),
            "{topic}"
        );
        assert_eq!(key(&format!("schema.{topic}")), schema);
    }
    let Msg::Compass(t, v) = &of("/compass")[10] else {
        unreachable!()
    };
    assert_eq!(key("compass.10.log_time"), t.to_string());
    assert_eq!(
        key("compass.10.heading_rad.bits"),
        v[1].to_bits().to_string()
    );
    assert_eq!(key("compass.10.awkward.bits"), v[4].to_bits().to_string());
    let Msg::Event(_, code, label, _, big) = &of("/events")[3] else {
        unreachable!()
    };
    assert_eq!(key("events.3.code"), code.to_string());
    assert_eq!(key("events.3.label"), label);
    assert_eq!(key("events.3.big"), big.to_string());
    let Msg::Solver(_, _, calls, name) = &of("/solver")[1] else {
        unreachable!()
    };
    assert_eq!(key("solver.1.integrator"), name);
    assert_eq!(key("solver.1.rhs_calls"), calls.to_string());
    let Msg::Pose(t, p) = &of("/poses")[5] else {
        unreachable!()
    };
    assert_eq!(key("poses.5.timestamp_ns"), t.to_string());
    assert_eq!(key("poses.5.parent"), p.parent_frame);
    assert_eq!(key("poses.5.child"), p.child_frame);
    assert_eq!(
        key("poses.5.translation_z.bits"),
        p.translation_m[2].to_bits().to_string()
    );
    assert_eq!(
        key("poses.5.rotation_w.bits"),
        p.rotation_xyzw[3].to_bits().to_string()
    );
    for (name, entries) in metadata() {
        assert_eq!(key(&format!("metadata.{name}")), entries.len().to_string());
    }
    for (name, _, _, data) in attachments() {
        assert_eq!(key(&format!("attachment.{name}")), data.len().to_string());
    }
}
