//! A run killed with SIGKILL, as a user would meet it: `gyrolab run` dies mid-way, `gyrolab
//! recover` salvages its `.partial` file, and what comes back is a valid recording whose every
//! message equals, byte for byte, the same message of an uninterrupted run of the same scene.

use crate::common;
use common::{gyrolab, succeed};

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Stdio;
use std::time::{Duration, Instant};

use gyro_mcap::{Column, Recording};

fn tmp(name: &str) -> PathBuf {
    common::tmp("kill", name)
}

/// Every message of a file, per topic, as the reference `mcap` reader gives it (it checks every
/// CRC on the way): (sequence, log time, publish time, payload bytes).
type Raw = (u32, u64, u64, Vec<u8>);

fn raw_messages(path: &Path) -> BTreeMap<String, Vec<Raw>> {
    let bytes = std::fs::read(path).expect("read");
    let mut out: BTreeMap<String, Vec<Raw>> = BTreeMap::new();
    for m in mcap::MessageStream::new(&bytes).expect("an MCAP file") {
        let m = m.expect("a valid message");
        out.entry(m.channel.topic.clone()).or_default().push((
            m.sequence,
            m.log_time,
            m.publish_time,
            m.data.into_owned(),
        ));
    }
    out
}

fn u64s(rec: &Recording, topic: &str, field: &str) -> Vec<u64> {
    match rec.read_records(topic).expect("records").column(field) {
        Some(Column::U64(v)) => v.clone(),
        other => panic!("{topic} {field}: {other:?}"),
    }
}

#[test]
fn a_run_killed_with_sigkill_recovers_to_a_prefix_of_the_uninterrupted_run() {
    let d = tmp("run");
    let killed = d.join("killed.mcap");
    let partial = PathBuf::from(format!("{}.partial", killed.display()));
    // Rolling at sea, 2 Hz output: about 4000 simulated seconds and 3.5 MB per wall second here,
    // so 6 MB is a simulated hour or two and a dozen chunks.
    let mut child = gyrolab()
        .args([
            "run",
            "rolling-intercardinal",
            "--quiet",
            "--duration-s",
            "864000",
            "-o",
        ])
        .arg(&killed)
        .stdout(Stdio::null())
        .spawn()
        .expect("spawn");
    let deadline = Instant::now() + Duration::from_secs(300);
    while std::fs::metadata(&partial).map_or(0, |m| m.len()) < 6_000_000 {
        assert!(Instant::now() < deadline, "the run wrote too little");
        assert!(
            child.try_wait().expect("try_wait").is_none(),
            "the run ended by itself"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    child.kill().expect("SIGKILL");
    child.wait().expect("wait");
    assert!(!killed.exists(), "nothing under the final name");

    let out = succeed(gyrolab().args(["recover", "--json"]).arg(&partial));
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).expect("json");
    assert!(report["chunks"].as_u64().expect("chunks") >= 2, "{report}");
    assert!(partial.exists(), "the .partial file is left as it was");

    // A valid file through both readers, with the run's description (written at the start) and
    // no result (the run never ended).
    let rec = Recording::open(&killed).expect("the recovered file opens");
    assert!(rec.used_index());
    let md = rec.metadata();
    for (record, key) in [
        ("run", "fidelity"),
        ("run", "integrator"),
        ("run", "rtol"),
        ("run", "effects"),
        ("run", "program_version"),
        ("scene", "toml"),
        ("design", "toml"),
    ] {
        assert!(
            md.get(record).and_then(|r| r.get(key)).is_some(),
            "{record}.{key} missing from the recovered file"
        );
    }
    assert!(!md.contains_key("result"));
    assert_eq!(rec.attachments().len(), 2);
    let got = raw_messages(&killed);
    let n: usize = got.values().map(Vec::len).sum();
    assert_eq!(n as u64, report["messages"].as_u64().expect("messages"));
    let t_last_ns = got["/compass/state"].last().expect("samples").1;
    assert!(t_last_ns > 3_600_000_000_000, "at least a simulated hour");

    // The same scene, uninterrupted, a little longer than what was recovered.
    let reference = d.join("reference.mcap");
    let duration_s = (t_last_ns / 1_000_000_000 + 600).to_string();
    let status = gyrolab()
        .args([
            "run",
            "rolling-intercardinal",
            "--quiet",
            "--duration-s",
            &duration_s,
            "-o",
        ])
        .arg(&reference)
        .stdout(Stdio::null())
        .status()
        .expect("reference run");
    assert!(status.success());
    let want = raw_messages(&reference);
    assert_eq!(
        got.keys().collect::<Vec<_>>(),
        want.keys().collect::<Vec<_>>()
    );
    for (topic, msgs) in &got {
        if topic == "/solver/stats" {
            continue; // progress reports carry wall time: compared field by field below
        }
        let w = &want[topic];
        assert!(msgs.len() <= w.len(), "{topic}: more than the full run");
        if let Some(i) = msgs.iter().zip(w).position(|(a, b)| a != b) {
            panic!("{topic}: message {i} differs from the uninterrupted run's");
        }
    }
    // Progress reports: the counters equal the full run's at the same simulated hours.
    let full = Recording::open(&reference).expect("reference");
    let hours = got.get("/solver/stats").map_or(0, Vec::len);
    assert!(hours >= 1, "an hourly progress report was recovered");
    for field in ["steps", "rejected_steps", "rhs_evals", "jacobian_evals"] {
        let a = u64s(&rec, "/solver/stats", field);
        let b = u64s(&full, "/solver/stats", field);
        assert_eq!(a[..], b[..a.len()], "/solver/stats {field}");
    }

    // The analysis reads the salvaged run and says what it is.
    let out = succeed(gyrolab().args(["analyze", "--json"]).arg(&killed));
    let said = String::from_utf8_lossy(&out.stdout);
    assert!(said.contains("recovered from a killed run"), "{said}");
    eprintln!(
        "SIGKILL at {:.0} simulated s: recovered {n} messages in {} chunks, {} bytes dropped",
        t_last_ns as f64 * 1e-9,
        report["chunks"],
        report["bytes_dropped"]
    );
}
