//! Time and file size to view a 24-hour run: writes a synthetic day-long recording (the chain
//! earth → ship → gimbal → float → rotor, every body posed at every sample) and times
//! `gyro_view::view` saving an `.rrd`. Prints its figures; no criterion (one long run measures
//! better than many short ones here).
//!
//! `cargo bench -p gyro-view --bench day [-- RATE_HZ]` (default 1 Hz, the shipped scenes' rate).

#[path = "../tests/common/mod.rs"]
mod common;

use std::path::PathBuf;
use std::time::Instant;

use gyro_view::{Output, Sink, ViewOptions, view};

fn main() {
    let rate_hz: f64 = std::env::args()
        .skip(1)
        .find_map(|a| a.parse().ok())
        .unwrap_or(1.0);
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("gyro-view-bench");
    let _ = std::fs::create_dir_all(&dir);
    let run = dir.join(format!("day-{rate_hz}hz.mcap"));
    let n = (86_400.0 * rate_hz) as usize;
    let t = Instant::now();
    common::write_recording(&run, n, rate_hz);
    let mcap_bytes = std::fs::metadata(&run).map(|m| m.len()).unwrap_or(0);
    println!(
        "wrote {} ({} samples, 4 frames; {:.1} MB) in {:.2} s",
        run.display(),
        n,
        mcap_bytes as f64 / 1e6,
        t.elapsed().as_secs_f64()
    );
    let rrd = dir.join(format!("day-{rate_hz}hz.rrd"));
    let opts = ViewOptions {
        sink: Sink::Save(rrd.clone()),
        ..Default::default()
    };
    let cpu = Instant::now();
    let report = match view(&[run], &opts) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("view failed: {e}");
            std::process::exit(1);
        }
    };
    let bytes = match report.output {
        Output::Saved { bytes, .. } => bytes,
        _ => 0,
    };
    println!(
        "view → {}: {:.2} s wall, {:.1} MB; series {} samples each, {} poses per frame",
        rrd.display(),
        cpu.elapsed().as_secs_f64(),
        bytes as f64 / 1e6,
        report.runs.first().map_or(0, |r| r.samples),
        report.runs.first().map_or(0, |r| r.poses_per_frame),
    );
}
