//! Writes small valid recordings to seed the fuzzer's corpus:
//! `cargo run --release -p gyro-mcap --example fuzz_seeds -- fuzz/corpus/recording_open`

use std::collections::BTreeMap;
use std::path::PathBuf;

use gyro_mcap::{FieldSpec, Pose, RecordSchema, RecordingWriter, Value, WriterOptions};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = PathBuf::from(std::env::args().nth(1).unwrap_or_else(|| "seeds".into()));
    std::fs::create_dir_all(&dir)?;
    for (n, steps) in [(0, 0u64), (1, 3), (2, 40)] {
        let path = dir.join(format!("seed-{n}.mcap"));
        let opts = WriterOptions {
            chunk_size_bytes: 512,
            ..Default::default()
        };
        let mut w = RecordingWriter::create(&path, opts)?;
        let rec = w.add_record_channel(
            "/state",
            &RecordSchema {
                full_name: "gyrolab.State".into(),
                fields: vec![
                    FieldSpec::f64("x", "m"),
                    FieldSpec::u64("n"),
                    FieldSpec::str("s"),
                ],
            },
        )?;
        let pose = w.add_pose_channel("/poses")?;
        w.write_metadata(
            "scene",
            &BTreeMap::from([("toml".to_string(), "a = 1".to_string())]),
        )?;
        w.attach("scene.toml", "application/toml", 0, b"a = 1")?;
        for i in 0..steps {
            w.write_record(
                rec,
                i,
                &[Value::F64(i as f64), Value::U64(i), Value::Str("ok")],
            )?;
            w.write_pose(
                pose,
                i,
                &Pose {
                    parent_frame: "a".into(),
                    child_frame: "b".into(),
                    translation_m: [i as f64, 0.0, 0.0],
                    rotation_xyzw: [0.0, 0.0, 0.0, 1.0],
                },
            )?;
        }
        w.finish()?;
    }
    Ok(())
}
