//! Throughput of the recording contract on a realistic load: a 20-field f64 record channel and
//! a 6-frame pose channel at 10 Hz for a simulated 24 h (864 000 records + 5 184 000 poses).
//! `cargo bench -p gyro-mcap --bench throughput` (set GYRO_MCAP_BENCH_HOURS to change the length,
//! GYRO_MCAP_BENCH_ZSTD_LEVEL the level; GYRO_MCAP_BENCH_WRITE_ONLY skips the reads,
//! GYRO_MCAP_BENCH_KEEP=PATH keeps the file there).
//! `benches/python/peer_throughput.py` does the same load with the reference Python libraries,
//! to compare the two at the same moment on a shared machine.

use std::time::Instant;

use gyro_mcap::{FieldSpec, Pose, RecordSchema, Recording, RecordingWriter, WriterOptions};

/// CPU seconds (user + system) this process has used, all threads, from /proc (0 where
/// unavailable): on a shared machine, rates per CPU second say more than rates per wall second.
fn cpu_s() -> f64 {
    cpu_s_of("/proc/self/stat")
}

/// CPU seconds of the calling thread only (the one that encodes; compression runs on others).
fn thread_cpu_s() -> f64 {
    cpu_s_of("/proc/thread-self/stat")
}

fn cpu_s_of(file: &str) -> f64 {
    let stat = std::fs::read_to_string(file).unwrap_or_default();
    let fields: Vec<&str> = stat
        .rsplit_once(')')
        .map_or("", |(_, rest)| rest)
        .split_whitespace()
        .collect();
    let ticks = |i: usize| {
        fields
            .get(i)
            .and_then(|f| f.parse::<f64>().ok())
            .unwrap_or(0.0)
    };
    // utime and stime are fields 14 and 15 of stat(5); 11 and 12 after the command name.
    (ticks(11) + ticks(12)) / 100.0
}

fn varint_len(v: u64) -> usize {
    (64 - (v | 1).leading_zeros() as usize).div_ceil(7)
}

/// Encoded bytes of a FrameTransform as the writer encodes it (every field written).
fn pose_len(t_ns: u64, p: &Pose) -> usize {
    let ts = 2 + varint_len(t_ns / 1_000_000_000) + varint_len(t_ns % 1_000_000_000);
    (2 + ts) + (2 + p.parent_frame.len()) + (2 + p.child_frame.len()) + (2 + 27) + (2 + 36)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let hours: f64 = std::env::var("GYRO_MCAP_BENCH_HOURS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(24.0);
    let steps = (hours * 3600.0 * 10.0) as u64;
    let dir = std::env::temp_dir().join("gyro-mcap-bench");
    std::fs::create_dir_all(&dir)?;
    let path = dir.join("day.mcap");

    let schema = RecordSchema {
        full_name: "gyrolab.CompassState".into(),
        fields: (0..20)
            .map(|i| FieldSpec::f64(&format!("q{i}"), "rad"))
            .collect(),
    };
    let frames = ["earth", "ship", "gimbal", "spider", "case", "rotor", "spin"];
    let mut poses: Vec<Pose> = frames
        .windows(2)
        .map(|w| Pose {
            parent_frame: w[0].into(),
            child_frame: w[1].into(),
            translation_m: [0.0; 3],
            rotation_xyzw: [0.0, 0.0, 0.0, 1.0],
        })
        .collect();

    let mut opts = WriterOptions::default();
    if let Some(level) = std::env::var("GYRO_MCAP_BENCH_ZSTD_LEVEL")
        .ok()
        .and_then(|s| s.parse().ok())
    {
        opts.zstd_level = level;
    }
    // Signals advance by rotating phasors (a few flops), so the loop measures the writer, not sin().
    let mut phasors: Vec<[f64; 4]> = (0..20 + poses.len())
        .map(|k| {
            let w = 1e-4 * (k as f64 + 1.0);
            [1.0, 0.0, w.cos(), w.sin()]
        })
        .collect();
    let started = Instant::now();
    let cpu0 = cpu_s();
    let thread_cpu0 = thread_cpu_s();
    let mut w = RecordingWriter::create(&path, opts)?;
    let rec_ch = w.add_record_channel("/compass", &schema)?;
    let pose_ch = w.add_pose_channel("/poses")?;
    let mut values = [0.0f64; 20];
    let mut payload_bytes = 0u64;
    for i in 0..steps {
        let t_ns = i * 100_000_000;
        for p in phasors.iter_mut() {
            let [c, s, cw, sw] = *p;
            *p = [c * cw - s * sw, s * cw + c * sw, cw, sw];
        }
        for (k, v) in values.iter_mut().enumerate() {
            *v = phasors[k][1] * 1e-2 + k as f64;
        }
        w.write_f64_record(rec_ch, t_ns, &values)?;
        // 15 fields with one-byte tags, 5 (numbers 16..20) with two.
        payload_bytes += 15 * 9 + 5 * 10;
        for (k, p) in poses.iter_mut().enumerate() {
            let [c, s, _, _] = phasors[20 + k];
            p.translation_m = [0.1 * k as f64, 0.0, 0.05 * s];
            p.rotation_xyzw = [0.0, 0.0, s, c];
            w.write_pose(pose_ch, t_ns, p)?;
            payload_bytes += pose_len(t_ns, p) as u64;
        }
    }
    let encode_thread_cpu_s = thread_cpu_s() - thread_cpu0;
    let summary = w.finish()?;
    let write_s = started.elapsed().as_secs_f64();
    let write_cpu_s = cpu_s() - cpu0;
    let messages = summary.messages as f64;
    println!(
        "simulated: {hours} h at 10 Hz, {} messages",
        summary.messages
    );
    println!(
        "write: {:.2} s, {:.2} M msgs/s, {:.0} MB/s of payload, {:.0} MB/s to disk",
        write_s,
        messages / write_s / 1e6,
        payload_bytes as f64 / write_s / 1e6,
        summary.bytes as f64 / write_s / 1e6
    );
    println!(
        "write per CPU second: {:.2} M msgs/s ({write_cpu_s:.2} CPU s in all threads; the calling \
         thread {encode_thread_cpu_s:.2} CPU s, {:.2} M msgs/s)",
        messages / write_cpu_s / 1e6,
        messages / encode_thread_cpu_s / 1e6
    );
    println!(
        "file: {:.1} MB, {:.2} MB per simulated hour ({:.1} bytes/message)",
        summary.bytes as f64 / 1e6,
        summary.bytes as f64 / 1e6 / hours,
        summary.bytes as f64 / messages
    );

    if std::env::var_os("GYRO_MCAP_BENCH_WRITE_ONLY").is_some() {
        return finish_with(&path);
    }

    let started = Instant::now();
    let cpu0 = cpu_s();
    let rec = Recording::open(&path)?;
    let open_s = started.elapsed().as_secs_f64();
    let records = rec.read_records("/compass")?;
    let records_s = started.elapsed().as_secs_f64() - open_s;
    let poses_table = rec.read_poses("/poses")?;
    let read_s = started.elapsed().as_secs_f64();
    let read_cpu_s = cpu_s() - cpu0;
    assert_eq!(records.len() + poses_table.len(), summary.messages as usize);
    println!(
        "read: {:.2} s ({:.2} M msgs/s; open {:.3} s, records {:.2} M msgs/s, poses {:.2} M msgs/s)",
        read_s,
        messages / read_s / 1e6,
        open_s,
        records.len() as f64 / records_s / 1e6,
        poses_table.len() as f64 / (read_s - open_s - records_s) / 1e6
    );
    println!(
        "read per CPU second: {:.2} M msgs/s ({read_cpu_s:.2} CPU s)",
        messages / read_cpu_s / 1e6
    );

    // Every channel in one pass (each chunk decompressed once), as a loader of whole runs does.
    let started = Instant::now();
    let cpu0 = cpu_s();
    let rec = Recording::open(&path)?;
    let open_s = started.elapsed().as_secs_f64();
    let all = rec.read_all()?;
    let read_s = started.elapsed().as_secs_f64();
    let read_cpu_s = cpu_s() - cpu0;
    let n: usize = all.values().map(|t| t.len()).sum();
    assert_eq!(n, summary.messages as usize);
    println!(
        "read_all: {:.2} s ({:.2} M msgs/s, {:.0} MB/s of file; open {:.3} s, decode {:.2} M msgs/s)",
        read_s,
        messages / read_s / 1e6,
        summary.bytes as f64 / read_s / 1e6,
        open_s,
        messages / (read_s - open_s) / 1e6
    );
    println!(
        "read_all per CPU second: {:.2} M msgs/s ({read_cpu_s:.2} CPU s)",
        messages / read_cpu_s / 1e6
    );
    finish_with(&path)
}

/// Removes the bench's file, or moves it to `GYRO_MCAP_BENCH_KEEP` (to look at its chunks).
fn finish_with(path: &std::path::Path) -> Result<(), Box<dyn std::error::Error>> {
    match std::env::var_os("GYRO_MCAP_BENCH_KEEP") {
        Some(keep) => std::fs::rename(path, keep)?,
        None => std::fs::remove_file(path)?,
    }
    Ok(())
}
