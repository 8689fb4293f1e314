//! gyro-mcap's writer and reader against the `mcap` crate's (the reference Rust implementation,
//! a dev-dependency), in one run on the same messages: the load of `throughput.rs` (a 20-field
//! f64 record channel and a 6-frame pose channel at 10 Hz), simulated for 6 h by default.
//!
//! `cargo bench -p gyro-mcap --bench vs_mcap` (GYRO_MCAP_BENCH_HOURS changes the length).
//!
//! Both write 1 MiB zstd chunks with message indexes, chunk indexes, statistics and CRCs. The
//! `mcap` writer runs with its own settings: its default level (0, zstd's default 3) and level 1
//! (it takes no negative level), compressing with its default number of zstd worker threads (the
//! physical cores); ours with its default (-4) and at level 3. The `mcap` side encodes each
//! message the way ours does (a template with the values copied in), and the bench checks that
//! both files hold the same message bytes. Reading: ours is `Recording::open` + `read_all` (every
//! channel decoded into columns); the `mcap` crate's is `MessageStream` over the file's bytes,
//! once only iterating (its lower bound) and once decoding each message into the same columns.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::BufWriter;
use std::path::Path;
use std::time::Instant;

use gyro_mcap::{FieldSpec, Pose, RecordSchema, Recording, RecordingWriter, WriterOptions};

/// CPU seconds (user + system) of this process, all threads, from /proc (0 where unavailable).
fn cpu_s() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
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
    (ticks(11) + ticks(12)) / 100.0
}

const FIELDS: usize = 20;
const FRAMES: [&str; 7] = ["earth", "ship", "gimbal", "spider", "case", "rotor", "spin"];

/// The messages, generated the same way for every writer: rotating phasors (a few flops a
/// message), so the loops measure the writers.
struct Load {
    steps: u64,
    phasors: Vec<[f64; 4]>,
    values: [f64; FIELDS],
    poses: Vec<Pose>,
}

impl Load {
    fn new(steps: u64) -> Load {
        let poses: Vec<Pose> = FRAMES
            .windows(2)
            .map(|w| Pose {
                parent_frame: w[0].into(),
                child_frame: w[1].into(),
                translation_m: [0.0; 3],
                rotation_xyzw: [0.0, 0.0, 0.0, 1.0],
            })
            .collect();
        let phasors = (0..FIELDS + poses.len())
            .map(|k| {
                let w = 1e-4 * (k as f64 + 1.0);
                [1.0, 0.0, w.cos(), w.sin()]
            })
            .collect();
        Load {
            steps,
            phasors,
            values: [0.0; FIELDS],
            poses,
        }
    }

    /// Advances to step `i`: the record values and the poses of that instant.
    fn step(&mut self) {
        for p in self.phasors.iter_mut() {
            let [c, s, cw, sw] = *p;
            *p = [c * cw - s * sw, s * cw + c * sw, cw, sw];
        }
        for (k, v) in self.values.iter_mut().enumerate() {
            *v = self.phasors[k][1] * 1e-2 + k as f64;
        }
        for (k, p) in self.poses.iter_mut().enumerate() {
            let [c, s, _, _] = self.phasors[FIELDS + k];
            p.translation_m = [0.1 * k as f64, 0.0, 0.05 * s];
            p.rotation_xyzw = [0.0, 0.0, s, c];
        }
    }
}

fn put_varint(out: &mut Vec<u8>, mut v: u64) {
    while v >= 0x80 {
        out.push((v as u8) | 0x80);
        v >>= 7;
    }
    out.push(v as u8);
}

/// The record message as a template (fields 1..=20, wire type fixed64) and where each value goes.
fn record_template() -> (Vec<u8>, Vec<usize>) {
    let mut bytes = Vec::new();
    let mut at = Vec::new();
    for i in 1..=FIELDS as u64 {
        put_varint(&mut bytes, (i << 3) | 1);
        at.push(bytes.len());
        bytes.extend_from_slice(&[0; 8]);
    }
    (bytes, at)
}

fn put_doubles(out: &mut Vec<u8>, tag: u8, xs: &[f64]) {
    out.push(tag);
    out.push((9 * xs.len()) as u8);
    for (i, x) in xs.iter().enumerate() {
        out.push((((i + 1) << 3) | 1) as u8);
        out.extend_from_slice(&x.to_le_bytes());
    }
}

/// foxglove.FrameTransform as gyro-mcap encodes it (every field written).
fn encode_pose(out: &mut Vec<u8>, t_ns: u64, p: &Pose) {
    out.clear();
    let (s, n) = (t_ns / 1_000_000_000, t_ns % 1_000_000_000);
    let mut ts = Vec::with_capacity(12);
    ts.push(0x08);
    put_varint(&mut ts, s);
    ts.push(0x10);
    put_varint(&mut ts, n);
    out.push(0x0A);
    put_varint(out, ts.len() as u64);
    out.extend_from_slice(&ts);
    for (tag, f) in [(0x12, &p.parent_frame), (0x1A, &p.child_frame)] {
        out.push(tag);
        put_varint(out, f.len() as u64);
        out.extend_from_slice(f.as_bytes());
    }
    put_doubles(out, 0x22, &p.translation_m);
    put_doubles(out, 0x2A, &p.rotation_xyzw);
}

struct Written {
    wall_s: f64,
    cpu_s: f64,
    bytes: u64,
    messages: u64,
}

fn write_ours(
    path: &Path,
    steps: u64,
    zstd_level: i32,
) -> Result<Written, Box<dyn std::error::Error>> {
    let schema = RecordSchema {
        full_name: "gyrolab.CompassState".into(),
        fields: (0..FIELDS)
            .map(|i| FieldSpec::f64(&format!("q{i}"), "rad"))
            .collect(),
    };
    let mut load = Load::new(steps);
    let (started, cpu0) = (Instant::now(), cpu_s());
    let opts = WriterOptions {
        zstd_level,
        ..WriterOptions::default()
    };
    let mut w = RecordingWriter::create(path, opts)?;
    let rec_ch = w.add_record_channel("/compass", &schema)?;
    let pose_ch = w.add_pose_channel("/poses")?;
    for i in 0..load.steps {
        let t_ns = i * 100_000_000;
        load.step();
        w.write_f64_record(rec_ch, t_ns, &load.values)?;
        for p in &load.poses {
            w.write_pose(pose_ch, t_ns, p)?;
        }
    }
    let summary = w.finish()?;
    Ok(Written {
        wall_s: started.elapsed().as_secs_f64(),
        cpu_s: cpu_s() - cpu0,
        bytes: summary.bytes,
        messages: summary.messages,
    })
}

/// Writes the same messages with the `mcap` crate, with the schemas and channel metadata read
/// from `like` (a file ours wrote).
fn write_mcap(
    like: &[u8],
    path: &Path,
    steps: u64,
    level: Option<u32>,
) -> Result<Written, Box<dyn std::error::Error>> {
    let summary = mcap::Summary::read(like)?.ok_or("no summary")?;
    let mut by_topic = BTreeMap::new();
    for ch in summary.channels.values() {
        by_topic.insert(ch.topic.clone(), ch.clone());
    }
    let (template, value_at) = record_template();
    let mut load = Load::new(steps);
    let (started, cpu0) = (Instant::now(), cpu_s());
    let mut opts = mcap::WriteOptions::new()
        .compression(Some(mcap::Compression::Zstd))
        .chunk_size(Some(1 << 20));
    if let Some(l) = level {
        opts = opts.compression_level(l);
    }
    let mut w = opts.create(BufWriter::new(File::create(path)?))?;
    let mut ids = BTreeMap::new();
    for (topic, ch) in &by_topic {
        let s = ch.schema.as_ref().ok_or("channel without schema")?;
        let sid = w.add_schema(&s.name, &s.encoding, &s.data)?;
        let cid = w.add_channel(sid, topic, &ch.message_encoding, &ch.metadata)?;
        ids.insert(topic.as_str(), cid);
    }
    let (rec_ch, pose_ch) = (ids["/compass"], ids["/poses"]);
    let mut rec = template.clone();
    let mut pose = Vec::with_capacity(128);
    let mut sequence = [0u32; 2];
    for i in 0..load.steps {
        let t_ns = i * 100_000_000;
        load.step();
        for (&at, v) in value_at.iter().zip(&load.values) {
            rec[at..at + 8].copy_from_slice(&v.to_le_bytes());
        }
        let header = |channel_id, sequence| mcap::records::MessageHeader {
            channel_id,
            sequence,
            log_time: t_ns,
            publish_time: t_ns,
        };
        w.write_to_known_channel(&header(rec_ch, sequence[0]), &rec)?;
        sequence[0] += 1;
        for p in &load.poses {
            encode_pose(&mut pose, t_ns, p);
            w.write_to_known_channel(&header(pose_ch, sequence[1]), &pose)?;
            sequence[1] += 1;
        }
    }
    let s = w.finish()?;
    drop(w);
    Ok(Written {
        wall_s: started.elapsed().as_secs_f64(),
        cpu_s: cpu_s() - cpu0,
        bytes: std::fs::metadata(path)?.len(),
        messages: s.stats.map_or(0, |st| st.message_count),
    })
}

/// Columns as ours decodes them: per record channel the log times and one Vec<f64> per field;
/// per pose channel log times, interned frame ids, translations and rotations.
#[derive(Default)]
struct Columns {
    record_t: Vec<u64>,
    record: Vec<Vec<f64>>,
    pose_t: Vec<u64>,
    frames: Vec<String>,
    parent: Vec<u32>,
    child: Vec<u32>,
    translation: Vec<[f64; 3]>,
    rotation: Vec<[f64; 4]>,
}

fn varint(b: &[u8], at: &mut usize) -> u64 {
    let mut v = 0u64;
    let mut shift = 0;
    while let Some(&x) = b.get(*at) {
        *at += 1;
        v |= u64::from(x & 0x7F) << shift;
        if x < 0x80 {
            break;
        }
        shift += 7;
    }
    v
}

fn f64_at(b: &[u8], at: usize) -> f64 {
    let mut a = [0u8; 8];
    a.copy_from_slice(&b[at..at + 8]);
    f64::from_le_bytes(a)
}

/// Doubles 1..=N of a nested Vector3/Quaternion message.
fn doubles<const N: usize>(b: &[u8]) -> [f64; N] {
    let mut out = [0.0; N];
    let mut at = 0;
    while at < b.len() {
        let tag = varint(b, &mut at);
        let f = (tag >> 3) as usize;
        if (1..=N).contains(&f) {
            out[f - 1] = f64_at(b, at);
        }
        at += 8;
    }
    out
}

impl Columns {
    fn record(&mut self, t: u64, b: &[u8]) {
        self.record_t.push(t);
        let mut at = 0;
        while at < b.len() {
            let tag = varint(b, &mut at);
            let f = (tag >> 3) as usize;
            if f == 0 || tag & 7 != 1 {
                return;
            }
            if self.record.len() < f {
                self.record.resize_with(f, Vec::new);
            }
            self.record[f - 1].push(f64_at(b, at));
            at += 8;
        }
    }

    fn frame(&mut self, s: &[u8]) -> u32 {
        match self.frames.iter().position(|f| f.as_bytes() == s) {
            Some(i) => i as u32,
            None => {
                self.frames.push(String::from_utf8_lossy(s).into_owned());
                self.frames.len() as u32 - 1
            }
        }
    }

    fn pose(&mut self, t: u64, b: &[u8]) {
        self.pose_t.push(t);
        let (mut parent, mut child) = (0, 0);
        let (mut tr, mut rot) = ([0.0; 3], [0.0, 0.0, 0.0, 1.0]);
        let mut at = 0;
        while at < b.len() {
            let tag = varint(b, &mut at);
            let len = varint(b, &mut at) as usize;
            let body = &b[at..(at + len).min(b.len())];
            match tag >> 3 {
                2 => parent = self.frame(body),
                3 => child = self.frame(body),
                4 => tr = doubles::<3>(body),
                5 => rot = doubles::<4>(body),
                _ => {}
            }
            at += len;
        }
        self.parent.push(parent);
        self.child.push(child);
        self.translation.push(tr);
        self.rotation.push(rot);
    }
}

struct Read {
    wall_s: f64,
    cpu_s: f64,
    messages: usize,
}

fn read_ours(path: &Path) -> Result<Read, Box<dyn std::error::Error>> {
    let (started, cpu0) = (Instant::now(), cpu_s());
    let rec = Recording::open(path)?;
    let all = rec.read_all()?;
    let messages = all.values().map(|t| t.len()).sum();
    Ok(Read {
        wall_s: started.elapsed().as_secs_f64(),
        cpu_s: cpu_s() - cpu0,
        messages,
    })
}

/// The `mcap` crate's reader: the file read into memory, then `MessageStream`; with `decode`,
/// each message decoded into columns as ours does.
fn read_mcap(path: &Path, decode: bool) -> Result<Read, Box<dyn std::error::Error>> {
    let (started, cpu0) = (Instant::now(), cpu_s());
    let bytes = std::fs::read(path)?;
    let mut cols = Columns::default();
    let mut messages = 0;
    for m in mcap::MessageStream::new(&bytes)? {
        let m = m?;
        messages += 1;
        if decode {
            match m.channel.topic.as_str() {
                "/compass" => cols.record(m.log_time, &m.data),
                _ => cols.pose(m.log_time, &m.data),
            }
        } else {
            std::hint::black_box(&m.data);
        }
    }
    std::hint::black_box(&cols);
    if decode {
        assert_eq!(cols.record_t.len() + cols.pose_t.len(), messages);
        assert_eq!(cols.record.len(), FIELDS);
        assert_eq!(cols.frames.len(), FRAMES.len());
        assert!(
            cols.parent.len() == cols.child.len() && cols.rotation.len() == cols.translation.len()
        );
    }
    Ok(Read {
        wall_s: started.elapsed().as_secs_f64(),
        cpu_s: cpu_s() - cpu0,
        messages,
    })
}

/// Every message of `a` and `b`, in order: (topic, log time, bytes) equal.
fn same_messages(a: &[u8], b: &[u8]) -> Result<u64, Box<dyn std::error::Error>> {
    let mut sa = mcap::MessageStream::new(a)?;
    let mut sb = mcap::MessageStream::new(b)?;
    let mut n = 0;
    loop {
        match (sa.next(), sb.next()) {
            (None, None) => return Ok(n),
            (Some(x), Some(y)) => {
                let (x, y) = (x?, y?);
                if x.channel.topic != y.channel.topic
                    || x.log_time != y.log_time
                    || x.data != y.data
                {
                    return Err(format!("message {n} differs").into());
                }
                n += 1;
            }
            _ => return Err(format!("the files differ in length after {n} messages").into()),
        }
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let hours: f64 = std::env::var("GYRO_MCAP_BENCH_HOURS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(6.0);
    let steps = (hours * 3600.0 * 10.0) as u64;
    let dir = std::env::temp_dir().join("gyro-mcap-bench-vs");
    std::fs::create_dir_all(&dir)?;
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    println!(
        "{hours} h at 10 Hz: {} messages, {threads} hardware threads",
        steps * FRAMES.len() as u64 // one record and six poses a step
    );
    println!(
        "{:<34} {:>8} {:>8} {:>10} {:>14} {:>9}",
        "write", "wall s", "CPU s", "M msgs/s", "M msgs/CPU s", "MB"
    );
    let show_w = |name: &str, w: &Written| {
        println!(
            "{name:<34} {:>8.2} {:>8.2} {:>10.2} {:>14.2} {:>9.1}",
            w.wall_s,
            w.cpu_s,
            w.messages as f64 / w.wall_s / 1e6,
            w.messages as f64 / w.cpu_s / 1e6,
            w.bytes as f64 / 1e6
        )
    };
    let ours = dir.join("ours.mcap");
    let w = write_ours(&ours, steps, WriterOptions::default().zstd_level)?;
    show_w("gyro-mcap, level -4 (default)", &w);
    let ours3 = dir.join("ours3.mcap");
    let w = write_ours(&ours3, steps, 3)?;
    show_w("gyro-mcap, level 3", &w);
    let ours_bytes = std::fs::read(&ours)?;
    let theirs = dir.join("theirs.mcap");
    let w = write_mcap(&ours_bytes, &theirs, steps, None)?;
    show_w("mcap crate, level 0 (default: 3)", &w);
    let theirs1 = dir.join("theirs1.mcap");
    let w = write_mcap(&ours_bytes, &theirs1, steps, Some(1))?;
    show_w("mcap crate, level 1", &w);
    let n = same_messages(&ours_bytes, &std::fs::read(&theirs)?)?;
    println!("the files hold the same {n} messages");

    println!(
        "{:<34} {:>8} {:>8} {:>10} {:>14}",
        "read (every message)", "wall s", "CPU s", "M msgs/s", "M msgs/CPU s"
    );
    let show_r = |name: &str, r: &Read| {
        println!(
            "{name:<34} {:>8.2} {:>8.2} {:>10.2} {:>14.2}",
            r.wall_s,
            r.cpu_s,
            r.messages as f64 / r.wall_s / 1e6,
            r.messages as f64 / r.cpu_s / 1e6
        )
    };
    for (label, file) in [
        ("ours", &ours),
        ("level 3, ours", &ours3),
        ("mcap's", &theirs),
    ] {
        show_r(
            &format!("gyro-mcap read_all, {label} file"),
            &read_ours(file)?,
        );
        show_r(
            &format!("mcap decode to columns, {label}"),
            &read_mcap(file, true)?,
        );
        show_r(
            &format!("mcap iterate only, {label}"),
            &read_mcap(file, false)?,
        );
    }
    for f in [ours, ours3, theirs, theirs1] {
        std::fs::remove_file(f)?;
    }
    Ok(())
}
