//! Bad input gives clear messages naming the file and channel, never a panic.
#![allow(clippy::unwrap_used)]

use crate::common;

use common::{Spec, damped, temp_dir, write_run};
use gyro_analysis::{AnalysisError, AnalysisOptions, Quality, analyze_run, analyze_runs};
use gyro_mcap::{FieldSpec, RecordSchema, RecordingWriter, WriterOptions};

fn message(r: gyro_analysis::Result<impl std::fmt::Debug>) -> String {
    match r {
        Ok(v) => panic!("expected an error, got {v:?}"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn a_missing_compass_channel_names_file_and_channel() {
    let dir = temp_dir("missing");
    let spec = Spec {
        compass: false,
        duration_s: 600.0,
        ..Spec::default()
    };
    let path = write_run(&dir.join("nocompass.mcap"), &spec);
    let msg = message(analyze_run(&path, &AnalysisOptions::default()));
    assert!(msg.contains("nocompass.mcap"), "{msg}");
    assert!(msg.contains("/compass/state"), "{msg}");
    assert!(msg.contains("/ship/state"), "lists what is there: {msg}");
}

#[test]
fn a_missing_field_names_the_field() {
    let dir = temp_dir("field");
    let path = dir.join("nofield.mcap");
    let mut w = RecordingWriter::create(&path, WriterOptions::default()).unwrap();
    let schema = RecordSchema {
        full_name: "gyrolab.CompassState".into(),
        fields: vec![
            FieldSpec::f64("time_s", "s"),
            FieldSpec::f64("tilt_rad", "rad"),
        ],
    };
    let ch = w.add_record_channel("/compass/state", &schema).unwrap();
    for i in 0..100u64 {
        w.write_f64_record(ch, i * 1_000_000_000, &[i as f64, 0.0])
            .unwrap();
    }
    w.finish().unwrap();
    let msg = message(analyze_run(&path, &AnalysisOptions::default()));
    assert!(
        msg.contains("nofield.mcap")
            && msg.contains("/compass/state")
            && msg.contains("reading_error_rad"),
        "{msg}"
    );
}

#[test]
fn an_empty_channel_and_an_empty_recording() {
    let dir = temp_dir("empty");
    let path = dir.join("empty.mcap");
    let mut w = RecordingWriter::create(&path, WriterOptions::default()).unwrap();
    w.add_record_channel("/compass/state", &common::compass_schema())
        .unwrap();
    w.finish().unwrap();
    let msg = message(analyze_run(&path, &AnalysisOptions::default()));
    assert!(
        msg.contains("empty.mcap") && msg.contains("/compass/state"),
        "{msg}"
    );
    assert!(msg.contains("no message"), "{msg}");

    let zero = dir.join("zero.mcap");
    std::fs::write(&zero, b"").unwrap();
    let msg = message(analyze_run(&zero, &AnalysisOptions::default()));
    assert!(msg.contains("zero.mcap"), "{msg}");

    let text = dir.join("text.mcap");
    std::fs::write(&text, b"not a recording at all, just some text\n").unwrap();
    let msg = message(analyze_run(&text, &AnalysisOptions::default()));
    assert!(msg.contains("text.mcap"), "{msg}");
}

#[test]
fn a_truncated_recording_never_panics() {
    let dir = temp_dir("truncated");
    let spec = Spec {
        duration_s: 3.0 * 3600.0,
        error: Box::new(damped(0.0, 0.0, 0.05, 1e-5, 3600.0, 0.0)),
        ..Spec::default()
    };
    let path = write_run(&dir.join("whole.mcap"), &spec);
    let bytes = std::fs::read(&path).unwrap();
    for frac in [0.0, 0.01, 0.3, 0.5, 0.9, 0.999] {
        let cut = dir.join(format!("cut{}.mcap", (frac * 1000.0) as u32));
        std::fs::write(&cut, &bytes[..(bytes.len() as f64 * frac) as usize]).unwrap();
        // Either a clear error naming the file, or (data section scanned) an analysis.
        if let Err(e) = analyze_run(&cut, &AnalysisOptions::default()) {
            let msg = e.to_string();
            assert!(
                msg.contains(cut.file_name().unwrap().to_str().unwrap()),
                "{msg}"
            );
        }
    }
}

#[test]
fn a_run_too_short_to_fit_is_flagged_not_failed() {
    let dir = temp_dir("short");
    let spec = Spec {
        duration_s: 12.0,
        error: Box::new(|t| 1e-3 * t),
        ..Spec::default()
    };
    let path = write_run(&dir.join("short.mcap"), &spec);
    let a = analyze_run(&path, &AnalysisOptions::default()).unwrap();
    assert_eq!(a.azimuth.quality, Quality::TooShort);
    assert_eq!(a.metrics.azimuth_quality, "too_short");
    assert!(a.metrics.period_s.is_none());
    let note = a.notes.iter().find(|n| n.contains("period")).unwrap();
    assert!(
        note.contains("short.mcap") && note.contains("/compass/state"),
        "{note}"
    );
    // One sample only.
    let spec = Spec {
        duration_s: 0.0,
        ..Spec::default()
    };
    let path = write_run(&dir.join("one.mcap"), &spec);
    let a = analyze_run(&path, &AnalysisOptions::default()).unwrap();
    assert_eq!(a.azimuth.quality, Quality::TooShort);
    assert!(a.steady.value.is_none());
}

#[test]
fn arguments_that_name_no_recording() {
    let dir = temp_dir("args");
    let msg = message(analyze_runs(&[dir.join("*.mcap")]));
    assert!(msg.contains("names no recording"), "{msg}");
    let msg = message(analyze_runs(std::slice::from_ref(&dir)));
    assert!(msg.contains("names no recording"), "{msg}");
    let missing = dir.join("absent.mcap");
    let err = analyze_runs(&[missing]).unwrap_err();
    assert!(matches!(err, AnalysisError::Recording(_)), "{err:?}");
    assert!(err.to_string().contains("absent.mcap"));
}
