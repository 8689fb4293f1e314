//! A write that fails on the writer thread (here: a full disk) reaches the caller: the next
//! call that hands work to the threads, `flush_chunk`, or `finish` returns the I/O error naming
//! the file, and no call panics or hangs.
#![allow(clippy::unwrap_used)]
#![cfg(target_os = "linux")]
use crate::common;

use common::*;
use gyro_mcap::{RecordingError, WriterOptions, partial_path};

#[test]
fn a_full_disk_is_reported_to_the_caller() {
    let full = std::path::Path::new("/dev/full");
    if !full.exists() {
        gyro_testkit::unavailable("no /dev/full here: a full disk was not tried");
        return;
    }
    let dir = tmp_dir("full_disk");
    let path = dir.join("run.mcap");
    // The `.partial` file the writer creates is /dev/full: every write to it fails (ENOSPC).
    std::os::unix::fs::symlink(full, partial_path(&path)).unwrap();
    let opts = WriterOptions {
        chunk_size_bytes: 16 * 1024,
        ..Default::default()
    };
    let (mut w, ch) = start(&path, opts);
    let mut first_error = None;
    'outer: for i in 0..20_000 {
        for m in step(i) {
            let r = match &m {
                Msg::Compass(t, v) => w.write_f64_record(ch.compass, *t, v),
                Msg::Pose(t, p) => w.write_pose(ch.poses, *t, p),
                _ => continue,
            };
            if let Err(e) = r {
                first_error = Some(e);
                break 'outer;
            }
        }
    }
    let e = match first_error {
        Some(e) => e,
        // Small enough to stay in buffers until now: the flush must fail.
        None => w.flush_chunk().unwrap_err(),
    };
    match &e {
        RecordingError::Io {
            path: p, source, ..
        } => {
            assert_eq!(p, &partial_path(&path));
            assert_eq!(source.raw_os_error(), Some(28), "ENOSPC: {source}");
        }
        other => panic!("an I/O error, got {other}"),
    }
    assert!(e.to_string().contains("run.mcap.partial"), "{e}");
    // Later calls keep failing (no panic, no hang), and so does finish.
    assert!(w.flush_chunk().is_err());
    let e = w.finish().unwrap_err();
    assert!(e.to_string().contains("run.mcap.partial"), "{e}");
    assert!(!path.exists(), "nothing appears under the final name");
}
