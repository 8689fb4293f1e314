#![allow(clippy::unwrap_used)]
use crate::common;

use common::*;
use gyro_mcap::{ChannelKind, Recording, WriterOptions};

const STEPS: u64 = 3000;

#[test]
fn every_value_reads_back_bit_identical() {
    let dir = tmp_dir("round_trip");
    let path = dir.join("run.mcap");
    // Small chunks so the file has many of them.
    let opts = WriterOptions {
        chunk_size_bytes: 64 * 1024,
        ..Default::default()
    };
    let summary = write_sample(&path, STEPS, opts);
    let all = stream(STEPS);
    assert_eq!(summary.messages, all.len() as u64);
    assert_eq!(summary.bytes, std::fs::metadata(&path).unwrap().len());
    assert!(
        !gyro_mcap::partial_path(&path).exists(),
        "finish renames the .partial file"
    );

    let rec = Recording::open(&path).unwrap();
    assert!(
        rec.used_index(),
        "a finished file is read through its summary"
    );
    assert!(
        rec.block_count() > 5,
        "expected many chunks, found {}",
        rec.block_count()
    );
    let got = read_back(&rec);
    for topic in ["/compass", "/events", "/solver", "/poses"] {
        let want: Vec<&Msg> = all.iter().filter(|m| m.topic() == topic).collect();
        let have = &got[topic];
        assert_eq!(have.len(), want.len(), "{topic}");
        for (h, w) in have.iter().zip(&want) {
            assert!(same_bits(h, w), "{topic}: wrote {w:?}, read {h:?}");
        }
    }
    assert_eq!(rec.metadata(), &metadata());
    let att: Vec<_> = rec
        .attachments()
        .into_iter()
        .map(|a| (a.name, a.media_type, a.log_time_ns, a.data))
        .collect();
    assert_eq!(att, attachments());

    let channels = rec.channels();
    let by_topic = |t: &str| channels.iter().find(|c| c.topic == t).unwrap();
    let compass = by_topic("/compass");
    assert_eq!(compass.kind, ChannelKind::Record);
    assert_eq!(compass.schema_name, "gyrolab.CompassState");
    assert_eq!(compass.message_encoding, "protobuf");
    assert_eq!(compass.message_count, STEPS);
    assert_eq!(compass.first_log_time_ns, Some(0));
    assert_eq!(compass.last_log_time_ns, Some((STEPS - 1) * 100_000_000));
    assert_eq!(
        compass.field_names,
        [
            "reading_error_rad",
            "heading_rad",
            "tilt_rad",
            "spin_rad_per_s",
            "awkward"
        ]
    );
    assert_eq!(
        compass
            .metadata
            .get("unit.spin_rad_per_s")
            .map(String::as_str),
        Some("rad/s")
    );
    assert_eq!(
        by_topic("/solver").schema_name,
        "gyrolab.solver.SolverStats"
    );
    let poses = by_topic("/poses");
    assert_eq!(poses.kind, ChannelKind::Pose);
    assert_eq!(poses.schema_name, "foxglove.FrameTransform");
    assert_eq!(poses.message_count, 3 * STEPS);
}

#[test]
fn writeback_while_writing_leaves_the_same_file() {
    // A writeback requested after every chunk (the default asks every 32 MiB), and none: the
    // bytes on disk are the same, and every message reads back.
    let dir = tmp_dir("writeback");
    let mut files = Vec::new();
    for (name, sync_every_bytes) in [("often.mcap", 1), ("never.mcap", 0)] {
        let path = dir.join(name);
        let opts = WriterOptions {
            chunk_size_bytes: 16 * 1024,
            sync_every_bytes,
            // Chunks cut by size alone, so the two files can be compared byte for byte.
            flush_interval_s: 1e9,
            ..Default::default()
        };
        write_sample(&path, STEPS, opts);
        files.push(std::fs::read(&path).unwrap());
        let rec = Recording::open(&path).unwrap();
        assert_eq!(
            assert_prefix(&read_back(&rec), &stream(STEPS)),
            stream(STEPS).len()
        );
    }
    assert!(files[0] == files[1], "the two files differ");
}

#[test]
fn the_reference_mcap_reader_sees_statistics_indexes_and_every_message() {
    let dir = tmp_dir("reference_reader");
    let path = dir.join("run.mcap");
    let opts = WriterOptions {
        chunk_size_bytes: 32 * 1024,
        ..Default::default()
    };
    write_sample(&path, 1000, opts);
    let bytes = std::fs::read(&path).unwrap();
    let summary = mcap::Summary::read(&bytes)
        .unwrap()
        .expect("a summary section");
    let stats = summary.stats.as_ref().expect("statistics");
    let all = stream(1000);
    assert_eq!(stats.message_count, all.len() as u64);
    assert_eq!(stats.channel_count, 4);
    assert_eq!(stats.attachment_count, 3);
    assert_eq!(stats.metadata_count, 2);
    assert!(summary.chunk_indexes.len() > 3);
    assert_eq!(stats.chunk_count as usize, summary.chunk_indexes.len());
    assert_eq!(summary.attachment_indexes.len(), 3);
    assert_eq!(summary.metadata_indexes.len(), 2);
    // Message indexes are found through the chunk indexes.
    let mut indexed = 0;
    for ci in &summary.chunk_indexes {
        let idx = summary.read_message_indexes(&bytes, ci).unwrap();
        indexed += idx.values().map(Vec::len).sum::<usize>();
    }
    assert_eq!(indexed, all.len());
    // Every message, in order, with our encoding (the linear reader also checks every CRC).
    let msgs: Vec<_> = mcap::MessageStream::new(&bytes)
        .unwrap()
        .map(|m| m.unwrap())
        .collect();
    assert_eq!(msgs.len(), all.len());
    for (m, want) in msgs.iter().zip(&all) {
        assert_eq!(m.channel.topic, want.topic());
        assert_eq!(m.channel.message_encoding, "protobuf");
        let schema = m.channel.schema.as_ref().unwrap();
        assert_eq!(schema.encoding, "protobuf");
    }
    for ai in &summary.attachment_indexes {
        let a = mcap::read::attachment(&bytes, ai).unwrap();
        assert!(
            attachments()
                .iter()
                .any(|(n, _, _, d)| *n == a.name && d[..] == a.data[..])
        );
    }
}

#[test]
fn a_file_written_by_the_reference_writer_reads_here() {
    use std::borrow::Cow;
    use std::sync::Arc;
    let dir = tmp_dir("reference_writer");
    // Chunked (zstd) and unchunked files: the second has no chunk indexes, so it is scanned.
    for (name, chunked) in [("chunked.mcap", true), ("loose.mcap", false)] {
        let path = dir.join(name);
        let file = std::io::BufWriter::new(std::fs::File::create(&path).unwrap());
        let mut w = mcap::WriteOptions::new()
            .use_chunks(chunked)
            .create(file)
            .unwrap();
        // Our own schema bytes, written by the reference writer.
        let tmp = dir.join(format!("{name}.ours.mcap"));
        write_sample(&tmp, 1, WriterOptions::default());
        let ours = std::fs::read(&tmp).unwrap();
        let s = mcap::Summary::read(&ours).unwrap().unwrap();
        let schema = s
            .channels
            .values()
            .find(|c| c.topic == "/compass")
            .unwrap()
            .schema
            .clone()
            .unwrap();
        let channel = Arc::new(mcap::Channel {
            id: 0,
            topic: "/compass".into(),
            schema: Some(schema),
            message_encoding: "protobuf".into(),
            metadata: Default::default(),
        });
        let all: Vec<Msg> = stream(500)
            .into_iter()
            .filter(|m| m.topic() == "/compass")
            .collect();
        for (seq, m) in all.iter().enumerate() {
            let Msg::Compass(t, v) = m else {
                unreachable!()
            };
            // Encode with the fields in reverse order and zeros omitted, as other encoders may.
            let mut data = Vec::new();
            for (i, x) in v.iter().enumerate().rev() {
                if x.to_bits() != 0 {
                    data.push((((i + 1) << 3) | 1) as u8);
                    data.extend_from_slice(&x.to_le_bytes());
                }
            }
            w.write(&mcap::Message {
                channel: channel.clone(),
                sequence: seq as u32,
                log_time: *t,
                publish_time: *t,
                data: Cow::Owned(data),
            })
            .unwrap();
        }
        w.finish().unwrap();
        drop(w);
        let rec = Recording::open(&path).unwrap();
        assert_eq!(rec.used_index(), chunked, "{name}");
        let got = read_back_compass(&rec);
        assert_eq!(got.len(), all.len(), "{name}");
        for (h, w) in got.iter().zip(&all) {
            assert!(same_bits(h, w), "{name}: wrote {w:?}, read {h:?}");
        }
    }
}

fn read_back_compass(rec: &Recording) -> Vec<Msg> {
    let c = rec.read_records("/compass").unwrap();
    let cols: Vec<&[f64]> = c
        .columns
        .iter()
        .map(|(_, col)| col.as_f64().unwrap())
        .collect();
    (0..c.len())
        .map(|r| {
            Msg::Compass(
                c.log_time_ns[r],
                [cols[0][r], cols[1][r], cols[2][r], cols[3][r], cols[4][r]],
            )
        })
        .collect()
}

#[test]
fn an_older_schema_version_reads_with_defaults_for_missing_fields() {
    // Version 1 had two fields; version 2 (what a newer reader expects) has three. The reader
    // decodes through the schema stored in the file, so the v1 file gives v1's columns.
    let dir = tmp_dir("schema_versions");
    let path = dir.join("v1.mcap");
    let mut w = gyro_mcap::RecordingWriter::create(&path, WriterOptions::default()).unwrap();
    let v1 = gyro_mcap::RecordSchema {
        full_name: "gyrolab.ShipState".into(),
        fields: vec![
            gyro_mcap::FieldSpec::f64("speed_m_per_s", "m/s"),
            gyro_mcap::FieldSpec::f64("heading_rad", "rad"),
        ],
    };
    let ch = w.add_record_channel("/ship", &v1).unwrap();
    w.write_f64_record(ch, 0, &[1.5, 0.25]).unwrap();
    w.finish().unwrap();
    let rec = Recording::open(&path).unwrap();
    let t = rec.read_records("/ship").unwrap();
    assert_eq!(t.columns.len(), 2);
    assert_eq!(
        t.column("heading_rad").and_then(|c| c.as_f64()),
        Some(&[0.25][..])
    );
}

#[test]
fn writer_misuse_gives_errors_naming_the_file() {
    let dir = tmp_dir("misuse");
    let path = dir.join("m.mcap");
    let mut w = gyro_mcap::RecordingWriter::create(&path, WriterOptions::default()).unwrap();
    let ch = w.add_record_channel("/c", &compass_schema()).unwrap();
    let ev = w.add_record_channel("/e", &event_schema()).unwrap();
    let p = w.add_pose_channel("/p").unwrap();
    let errs = [
        w.write_f64_record(ch, 0, &[1.0]).unwrap_err(),
        w.write_f64_record(ev, 0, &[1.0, 2.0, 3.0, 4.0])
            .unwrap_err(),
        w.write_f64_record(p, 0, &[]).unwrap_err(),
        w.write_record(ev, 0, &[gyro_mcap::Value::F64(1.0); 4])
            .unwrap_err(),
        w.add_record_channel("/c", &compass_schema()).unwrap_err(),
        w.add_record_channel(
            "/bad",
            &gyro_mcap::RecordSchema {
                full_name: "has space".into(),
                fields: vec![],
            },
        )
        .unwrap_err(),
    ];
    for e in errs {
        assert!(e.to_string().contains("m.mcap.partial"), "{e}");
    }
    w.finish().unwrap();
}
