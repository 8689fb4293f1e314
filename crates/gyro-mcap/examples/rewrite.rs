//! The writer on a real recording's messages: writes the F64 record channels and the pose
//! channels of FILE again (in log-time order, metadata left out) with the current writer, at one
//! or several zstd levels in turn, and prints the best of `REPS` (default 3) rates per level
//! (per wall second and per CPU second of the process: on a shared machine the minimum of
//! several runs, levels interleaved, is what compares).
//!
//! `LEVELS=-1,-4 REPS=6 cargo run --release -p gyro-mcap --example rewrite -- FILE.mcap`
//! (`KEEP=out.mcap` keeps the last file written).

use gyro_mcap::{
    ChannelTable, Column, FieldSpec, Pose, RecordSchema, Recording, RecordingWriter, WriterOptions,
};
use std::time::Instant;

/// CPU seconds (user + system) of this process, all threads (0 where /proc is missing).
fn cpu_s() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let f: Vec<&str> = stat
        .rsplit_once(')')
        .map_or("", |(_, r)| r)
        .split_whitespace()
        .collect();
    let ticks = |i: usize| f.get(i).and_then(|x| x.parse::<f64>().ok()).unwrap_or(0.0);
    (ticks(11) + ticks(12)) / 100.0
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::args()
        .nth(1)
        .ok_or("usage: rewrite FILE.mcap (env LEVELS, REPS, KEEP)")?;
    let rec = Recording::open(std::path::Path::new(&path))?;
    let all = rec.read_all()?;
    let mut opts = WriterOptions::default();
    // (time, channel index, row)
    let mut order: Vec<(u64, usize, usize)> = Vec::new();
    let mut tables = Vec::new();
    for (topic, t) in &all {
        let keep = match t {
            ChannelTable::Records(r) => r.columns.iter().all(|(_, c)| matches!(c, Column::F64(_))),
            ChannelTable::Poses(_) => true,
        };
        if !keep || t.is_empty() {
            continue;
        }
        let i = tables.len();
        order.extend(
            t.log_time_ns()
                .iter()
                .enumerate()
                .map(|(row, &ts)| (ts, i, row)),
        );
        tables.push((topic.clone(), t));
    }
    order.sort();
    let out = std::env::temp_dir().join(format!("gyro-mcap-rewrite-{}.mcap", std::process::id()));
    let mut pose = Pose {
        parent_frame: String::new(),
        child_frame: String::new(),
        translation_m: [0.0; 3],
        rotation_xyzw: [0.0; 4],
    };
    let reps: usize = std::env::var("REPS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(3);
    let levels: Vec<i32> = std::env::var("LEVELS")
        .ok()
        .map(|s| s.split(',').filter_map(|x| x.parse().ok()).collect())
        .unwrap_or_else(|| vec![opts.zstd_level]);
    let mut bests = vec![(f64::INFINITY, f64::INFINITY, 0u64, 0u64); levels.len()];
    for _ in 0..reps {
        for (li, &level) in levels.iter().enumerate() {
            opts.zstd_level = level;
            let best = &mut bests[li];
            let t0 = Instant::now();
            let c0 = cpu_s();
            let mut w = RecordingWriter::create(&out, opts)?;
            let mut chans = Vec::new();
            for (topic, t) in &tables {
                chans.push(match t {
                    ChannelTable::Records(r) => w.add_record_channel(
                        topic,
                        &RecordSchema {
                            full_name: format!("x.{}", topic.replace('/', "_")),
                            fields: r
                                .columns
                                .iter()
                                .map(|(n, _)| FieldSpec::f64(n, ""))
                                .collect(),
                        },
                    )?,
                    ChannelTable::Poses(_) => w.add_pose_channel(topic)?,
                });
            }
            let mut vals = Vec::new();
            for &(ts, i, row) in &order {
                match tables[i].1 {
                    ChannelTable::Records(r) => {
                        vals.clear();
                        vals.extend(
                            r.columns
                                .iter()
                                .map(|(_, c)| c.as_f64().map_or(0.0, |v| v[row])),
                        );
                        w.write_f64_record(chans[i], ts, &vals)?;
                    }
                    ChannelTable::Poses(p) => {
                        pose.parent_frame.clear();
                        pose.parent_frame.push_str(p.parent_frame(row));
                        pose.child_frame.clear();
                        pose.child_frame.push_str(p.child_frame(row));
                        pose.translation_m = p.translation_m[row];
                        pose.rotation_xyzw = p.rotation_xyzw[row];
                        w.write_pose(chans[i], ts, &pose)?;
                    }
                }
            }
            let s = w.finish()?;
            let wall = t0.elapsed().as_secs_f64();
            let cpu = cpu_s() - c0;
            *best = (best.0.min(wall), best.1.min(cpu), s.bytes, s.messages);
        }
    }
    for (&level, &(wall, cpu, bytes, n)) in levels.iter().zip(&bests) {
        opts.zstd_level = level;
        println!(
            "level {:>3}: {:.2} M msgs/s wall, {:.2} M msgs/CPU s, {:.1} MB ({:.1} B/msg)",
            opts.zstd_level,
            n as f64 / wall / 1e6,
            n as f64 / cpu / 1e6,
            bytes as f64 / 1e6,
            bytes as f64 / n as f64
        );
    }
    if let Ok(keep) = std::env::var("KEEP") {
        std::fs::rename(&out, keep)?;
    } else {
        std::fs::remove_file(&out)?;
    }
    Ok(())
}
