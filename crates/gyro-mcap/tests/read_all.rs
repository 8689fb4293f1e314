//! Reading several channels in one pass (`read_topics`, `read_all`) gives exactly what reading
//! them one by one gives, on a file of many chunks (shared out among threads where there are
//! several cores), and the stream that was written.
#![allow(clippy::unwrap_used)]
use crate::common;

use common::*;
use gyro_mcap::{
    ChannelTable, Column, PoseTable, RecordTable, Recording, RecordingError, WriterOptions,
};

/// A table as bits (NaN payloads compare equal only to themselves, -0.0 differs from 0.0).
fn record_bits(t: &RecordTable) -> Vec<(String, Vec<u64>, Vec<String>)> {
    let mut out = vec![("log_time".to_string(), t.log_time_ns.clone(), Vec::new())];
    for (name, c) in &t.columns {
        out.push(match c {
            Column::F64(v) => (
                name.clone(),
                v.iter().map(|x| x.to_bits()).collect(),
                vec![],
            ),
            Column::U64(v) => (name.clone(), v.clone(), vec![]),
            Column::Str(v) => (name.clone(), vec![], v.clone()),
        });
    }
    out
}

fn pose_bits(t: &PoseTable) -> (Vec<u64>, Vec<String>, Vec<String>, Vec<u64>) {
    let nums = t
        .translation_m
        .iter()
        .flat_map(|a| a.iter())
        .chain(t.rotation_xyzw.iter().flat_map(|a| a.iter()))
        .map(|x| x.to_bits())
        .collect();
    (
        t.log_time_ns.clone(),
        (0..t.len()).map(|i| t.parent_frame(i).to_owned()).collect(),
        (0..t.len()).map(|i| t.child_frame(i).to_owned()).collect(),
        nums,
    )
}

fn many_chunks(name: &str, steps: u64) -> (Recording, std::path::PathBuf) {
    let dir = tmp_dir(name);
    let path = dir.join("run.mcap");
    let opts = WriterOptions {
        chunk_size_bytes: 4 * 1024,
        ..Default::default()
    };
    write_sample(&path, steps, opts);
    (Recording::open(&path).unwrap(), path)
}

#[test]
fn read_all_equals_reading_each_channel_and_the_stream() {
    let steps = 3000;
    let (rec, _) = many_chunks("read_all", steps);
    assert!(rec.block_count() >= 32, "{} chunks", rec.block_count());
    let all = rec.read_all().unwrap();
    assert_eq!(
        all.keys().map(String::as_str).collect::<Vec<_>>(),
        ["/compass", "/events", "/poses", "/solver"]
    );
    for (topic, table) in &all {
        match table {
            ChannelTable::Records(t) => assert!(
                record_bits(t) == record_bits(&rec.read_records(topic).unwrap()),
                "{topic}"
            ),
            ChannelTable::Poses(t) => assert!(
                pose_bits(t) == pose_bits(&rec.read_poses(topic).unwrap()),
                "{topic}"
            ),
        }
    }
    // And both are the stream that was written, bit for bit (NaN payloads included).
    let expected = stream(steps);
    assert_eq!(assert_prefix(&read_back(&rec), &expected), expected.len());
    let n: usize = all.values().map(ChannelTable::len).sum();
    assert_eq!(n, expected.len());
}

#[test]
fn read_topics_keeps_the_order_asked_and_refuses_bad_requests() {
    let (rec, path) = many_chunks("read_topics", 400);
    let got = rec.read_topics(&["/poses", "/compass"]).unwrap();
    assert_eq!(got.len(), 2);
    assert!(pose_bits(got[0].as_poses().unwrap()) == pose_bits(&rec.read_poses("/poses").unwrap()));
    assert!(
        record_bits(got[1].as_records().unwrap())
            == record_bits(&rec.read_records("/compass").unwrap())
    );
    match rec.read_topics(&["/compass", "/nope"]) {
        Err(RecordingError::UnknownTopic { topic, .. }) => assert_eq!(topic, "/nope"),
        other => panic!("expected an unknown-topic error, got {other:?}"),
    }
    let e = rec.read_topics(&["/compass", "/compass"]).unwrap_err();
    assert!(e.to_string().contains("once"), "{e}");
    assert!(e.to_string().contains(&*path.to_string_lossy()), "{e}");
    assert!(rec.read_topics(&[]).unwrap().is_empty());
}

/// A corrupt message late in the file is reported at its own chunk even when the chunks are
/// decoded by several threads (the first error in file order wins).
#[test]
fn a_bad_message_is_reported_at_its_chunk() {
    let (rec, path) = many_chunks("read_all_bad", 3000);
    drop(rec);
    let mut bytes = std::fs::read(&path).unwrap();
    // Rewrite the file with one chunk's records damaged: find the last chunk through the
    // reference reader's summary and flip its compression to an unsupported one.
    let summary = mcap::read::Summary::read(&bytes).unwrap().unwrap();
    let last = summary.chunk_indexes.last().unwrap();
    let start = last.chunk_start_offset as usize;
    // opcode(1) len(8) start(8) end(8) size(8) crc(4) then the compression string.
    let at = start + 1 + 8 + 8 + 8 + 8 + 4 + 4;
    assert_eq!(&bytes[at..at + 4], b"zstd");
    bytes[at..at + 4].copy_from_slice(b"zstx");
    let rec = Recording::from_bytes(&path, bytes).unwrap();
    let e = rec.read_all().unwrap_err().to_string();
    assert!(e.contains(&format!("at byte {start}")), "{e}");
    assert!(e.contains("zstx"), "{e}");
}

/// Frame ids are stored once per distinct id: with more ids than the decoder scans (so the
/// hash map takes over), ids that first appear late in the file (in another thread's share of
/// the chunks, which numbers them differently), non-ASCII ids and rows out of time order, every
/// row still reads back its own parent and child.
#[test]
fn pose_frames_are_stored_once_and_read_back_per_row() {
    let dir = tmp_dir("pose_frames");
    let path = dir.join("frames.mcap");
    let opts = WriterOptions {
        chunk_size_bytes: 2 * 1024,
        ..Default::default()
    };
    let mut w = gyro_mcap::RecordingWriter::create(&path, opts).unwrap();
    let ch = w.add_pose_channel("/tf").unwrap();
    let rows = 4000u64;
    let name = |k: u64| format!("body-{k}-ü");
    let mut expected = Vec::new();
    for i in 0..rows {
        // Ids 0..8 throughout; ids 8..48 only in the second half of the file.
        let k = if i < rows / 2 { i % 8 } else { 8 + i % 40 };
        // Log times shuffled within runs of 16 rows: the reader sorts rows by time.
        let t = ((i / 16) * 16 + (i * 7) % 16) * 1_000_000;
        let pose = gyro_mcap::Pose {
            parent_frame: name(k / 2),
            child_frame: name(k),
            translation_m: [i as f64, 0.0, -0.0],
            rotation_xyzw: [0.0, 0.0, 0.0, 1.0],
        };
        w.write_pose(ch, t, &pose).unwrap();
        expected.push((t, name(k / 2), name(k), i as f64));
    }
    w.finish().unwrap();
    expected.sort_by_key(|e| e.0);
    let rec = Recording::open(&path).unwrap();
    assert!(rec.block_count() >= 16, "{} chunks", rec.block_count());
    for t in [
        rec.read_poses("/tf").unwrap(),
        rec.read_all().unwrap()["/tf"].as_poses().unwrap().clone(),
    ] {
        assert_eq!(t.len(), rows as usize);
        let mut sorted = t.frames.clone();
        sorted.sort();
        sorted.dedup();
        assert_eq!(sorted.len(), t.frames.len(), "each id once");
        assert_eq!(t.frames.len(), 48);
        assert_eq!(t.frames[0], name(0), "in order of first appearance");
        let got: Vec<_> = (0..t.len())
            .map(|r| {
                (
                    t.log_time_ns[r],
                    t.parent_frame(r).to_owned(),
                    t.child_frame(r).to_owned(),
                    t.translation_m[r][0],
                )
            })
            .collect();
        assert_eq!(got, expected);
    }
}
