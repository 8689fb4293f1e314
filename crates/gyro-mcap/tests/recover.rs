#![allow(clippy::unwrap_used)]
use crate::common;

use std::time::{Duration, Instant};

use common::*;
use gyro_mcap::{Recording, RecordingError, WriterOptions, partial_path, recover};

#[test]
fn an_abandoned_writer_leaves_a_partial_file_that_recovers_to_its_last_chunk() {
    let dir = tmp_dir("abandoned");
    let path = dir.join("run.mcap");
    let opts = WriterOptions {
        chunk_size_bytes: 1 << 30,
        flush_interval_s: 1e9,
        ..Default::default()
    };
    let (mut w, ch) = start(&path, opts);
    let mut flushed = 0;
    for i in 0..1050 {
        for m in step(i) {
            write(&mut w, &ch, &m);
        }
        if i % 100 == 99 {
            w.flush_chunk().unwrap();
            flushed = stream(i + 1).len();
        }
    }
    // No finish, no Drop: as if the process died here.
    std::mem::forget(w);
    let partial = partial_path(&path);
    assert!(partial.exists());
    assert!(!path.exists(), "the final name appears only after finish");

    let err = Recording::open(&partial)
        .err()
        .expect("an unfinished file does not open");
    assert!(err.to_string().contains("run.mcap.partial"), "{err}");
    assert!(
        err.to_string().contains("recover"),
        "the error points to recover: {err}"
    );

    let out = dir.join("recovered.mcap");
    let report = recover(&partial, &out).unwrap();
    assert_eq!(report.messages as usize, flushed);
    assert_eq!(report.chunks, 10);
    let rec = Recording::open(&out).unwrap();
    assert!(rec.used_index());
    assert_eq!(assert_prefix(&read_back(&rec), &stream(1050)), flushed);
    assert_eq!(rec.metadata(), &metadata());
    assert_eq!(rec.attachments().len(), attachments().len());
}

#[test]
fn dropping_a_writer_keeps_its_open_chunk_for_recovery() {
    let dir = tmp_dir("dropped");
    let path = dir.join("run.mcap");
    let (mut w, ch) = start(&path, WriterOptions::default());
    for i in 0..500 {
        for m in step(i) {
            write(&mut w, &ch, &m);
        }
    }
    drop(w);
    let out = dir.join("recovered.mcap");
    let report = recover(&partial_path(&path), &out).unwrap();
    assert_eq!(report.messages as usize, stream(500).len());
    assert_prefix(&read_back(&Recording::open(&out).unwrap()), &stream(500));
}

#[test]
fn recovering_to_the_default_name_leaves_the_partial_file_as_it_was() {
    // The usual call: `run.mcap.partial` recovered to `run.mcap`, whose own `.partial` name is
    // the input. The recovery must not write over the only copy of the run.
    let dir = tmp_dir("default_name");
    let path = dir.join("run.mcap");
    let (mut w, ch) = start(&path, WriterOptions::default());
    for i in 0..300 {
        for m in step(i) {
            write(&mut w, &ch, &m);
        }
    }
    w.flush_chunk().unwrap();
    std::mem::forget(w);
    let partial = partial_path(&path);
    let before = std::fs::read(&partial).unwrap();
    let report = recover(&partial, &path).unwrap();
    assert_eq!(report.messages as usize, stream(300).len());
    assert_eq!(std::fs::read(&partial).unwrap(), before, "input untouched");
    assert_prefix(&read_back(&Recording::open(&path).unwrap()), &stream(300));
    let left: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .filter(|n| n.contains("recovering"))
        .collect();
    assert!(left.is_empty(), "no temporary file left: {left:?}");

    // A recovery that cannot write its output fails naming it, and leaves the input as it was.
    let e = recover(&partial, &dir.join("no-such-dir").join("run.mcap")).unwrap_err();
    assert!(e.to_string().contains("no-such-dir"), "{e}");
    assert_eq!(std::fs::read(&partial).unwrap(), before);
}

#[test]
fn a_partial_file_cut_anywhere_recovers_to_a_prefix_of_whole_chunks() {
    let dir = tmp_dir("cut");
    let path = dir.join("run.mcap");
    let opts = WriterOptions {
        chunk_size_bytes: 16 * 1024,
        ..Default::default()
    };
    write_sample(&path, 600, opts);
    let bytes = std::fs::read(&path).unwrap();
    let all = stream(600);
    let mut last = 0;
    let cut_path = dir.join("cut.mcap.partial");
    let out = dir.join("out.mcap");
    for cut in (0..bytes.len())
        .step_by(bytes.len() / 97)
        .chain([bytes.len() - 1, bytes.len()])
    {
        std::fs::write(&cut_path, &bytes[..cut]).unwrap();
        match recover(&cut_path, &out) {
            Ok(report) => {
                let rec = Recording::open(&out).unwrap();
                let n = assert_prefix(&read_back(&rec), &all);
                assert_eq!(n as u64, report.messages);
                assert!(n >= last, "a longer cut never recovers fewer messages");
                last = n;
                assert!(report.bytes_dropped <= cut as u64);
            }
            Err(e) => {
                assert!(
                    cut < 30,
                    "only a cut inside the magic or header fails, not at {cut}: {e}"
                );
                assert!(e.to_string().contains("cut.mcap.partial"), "{e}");
            }
        }
    }
    assert_eq!(last, all.len(), "the whole file recovers everything");
}

#[test]
fn recovering_a_non_mcap_file_is_an_error_naming_it() {
    let dir = tmp_dir("recover_garbage");
    let p = dir.join("garbage.partial");
    std::fs::write(&p, b"definitely not an mcap file").unwrap();
    let e = recover(&p, &dir.join("o.mcap")).unwrap_err();
    assert!(
        matches!(e, RecordingError::Malformed { offset: 0, .. }),
        "{e}"
    );
    assert!(e.to_string().contains("garbage.partial"), "{e}");
}

const CHILD_ENV: &str = "GYRO_MCAP_SIGKILL_CHILD";

/// In the child process (re-executed by the test below): write the sample stream forever with a
/// short flush interval, until killed.
#[test]
fn sigkill_child() {
    let Ok(path) = std::env::var(CHILD_ENV) else {
        return; // the ordinary test run: nothing to do
    };
    let opts = WriterOptions {
        flush_interval_s: 0.02,
        ..Default::default()
    };
    let (mut w, ch) = start(std::path::Path::new(&path), opts);
    for i in 0.. {
        for m in step(i) {
            write(&mut w, &ch, &m);
        }
        if i % 64 == 0 {
            std::thread::sleep(Duration::from_millis(1));
        }
    }
}

#[test]
fn a_writer_killed_with_sigkill_recovers_to_a_prefix() {
    let dir = tmp_dir("sigkill");
    let path = dir.join("killed.mcap");
    let partial = partial_path(&path);
    // libtest names a test by its path inside the binary, without the binary's crate name.
    let child_test = match module_path!().split_once("::") {
        Some((_, module)) => format!("{module}::sigkill_child"),
        None => "sigkill_child".to_owned(),
    };
    let mut child = std::process::Command::new(std::env::current_exe().unwrap())
        .args([
            "--exact",
            child_test.as_str(),
            "--nocapture",
            "--test-threads=1",
        ])
        .env(CHILD_ENV, &path)
        .stdout(std::process::Stdio::null())
        .spawn()
        .unwrap();
    // Let it write several flushes' worth.
    let deadline = Instant::now() + Duration::from_secs(60);
    while std::fs::metadata(&partial).map_or(0, |m| m.len()) < 300_000 {
        assert!(Instant::now() < deadline, "the child wrote too little");
        assert!(
            child.try_wait().unwrap().is_none(),
            "the child exited by itself"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    child.kill().unwrap(); // SIGKILL on Unix
    child.wait().unwrap();
    assert!(!path.exists());

    let out = dir.join("recovered.mcap");
    let report = recover(&partial, &out).unwrap();
    assert!(report.chunks >= 2, "{report:?}");
    let rec = Recording::open(&out).unwrap();
    let got = read_back(&rec);
    let n = got.values().map(Vec::len).sum::<usize>();
    // Enough of the stream to cover what was recovered.
    let steps = (n / 4 + 10) as u64;
    assert_eq!(assert_prefix(&got, &stream(steps)), n);
    assert_eq!(n as u64, report.messages);
    eprintln!(
        "SIGKILL: recovered {n} messages in {} chunks, dropped {} bytes",
        report.chunks, report.bytes_dropped
    );
}
