//! Untrusted input: whatever the bytes, opening and reading give a value or an error that names
//! the file, never a panic.
#![allow(clippy::unwrap_used)]
// The counting allocator below needs `unsafe impl GlobalAlloc`; it only forwards to the system.
#![allow(unsafe_code)]
mod common;

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

/// Records the largest single allocation request, to prove length fields do not size allocations.
struct LargestRequest;
static LARGEST: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for LargestRequest {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        LARGEST.fetch_max(layout.size(), Ordering::Relaxed);
        // SAFETY: forwarded unchanged to the system allocator.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: forwarded unchanged to the system allocator.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        LARGEST.fetch_max(new_size, Ordering::Relaxed);
        // SAFETY: forwarded unchanged to the system allocator.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static ALLOCATOR: LargestRequest = LargestRequest;

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::Path;

use common::*;
use gyro_mcap::{ChannelKind, Recording, RecordingError, WriterOptions};

/// Opens `bytes` as `name` and reads every channel; panics are caught and reported as failures.
/// Returns the first error, if any.
fn open_and_read_all(name: &str, bytes: Vec<u8>) -> Result<(), RecordingError> {
    let path = Path::new(name);
    let outcome = catch_unwind(AssertUnwindSafe(|| -> Result<(), RecordingError> {
        let rec = Recording::from_bytes(path, bytes)?;
        let _ = rec.metadata();
        let _ = rec.attachments();
        for ch in rec.channels() {
            match ch.kind {
                ChannelKind::Pose => {
                    rec.read_poses(&ch.topic)?;
                }
                _ => {
                    rec.read_records(&ch.topic)?;
                }
            }
        }
        Ok(())
    }));
    match outcome {
        Ok(r) => {
            if let Err(e) = &r {
                assert!(
                    e.to_string().contains(name),
                    "error does not name the file: {e}"
                );
            }
            r
        }
        Err(_) => panic!("{name}: the reader panicked"),
    }
}

fn sample_bytes(name: &str, steps: u64) -> Vec<u8> {
    let dir = tmp_dir(name);
    let path = dir.join("sample.mcap");
    let opts = WriterOptions {
        chunk_size_bytes: 8 * 1024,
        ..Default::default()
    };
    write_sample(&path, steps, opts);
    std::fs::read(&path).unwrap()
}

#[test]
fn truncation_at_any_offset_is_an_error_not_a_panic() {
    let bytes = sample_bytes("truncate", 150);
    assert!(open_and_read_all("whole.mcap", bytes.clone()).is_ok());
    let mut errors = 0;
    for cut in 0..bytes.len() {
        if open_and_read_all("truncated.mcap", bytes[..cut].to_vec()).is_err() {
            errors += 1;
        }
    }
    // Every proper prefix lacks the closing magic.
    assert_eq!(errors, bytes.len());
}

#[test]
fn flipped_bits_give_errors_or_values_never_panics() {
    let bytes = sample_bytes("bitflip", 150);
    let mut errors = 0;
    let mut seed = 0x9E37_79B9_7F4A_7C15u64;
    let flips = 4000;
    for k in 0..flips {
        let mut b = bytes.clone();
        // Every byte of the head and tail (headers, summary, footer) plus random bytes elsewhere.
        let at = if k < 1500 {
            if k < 750 { k } else { b.len() - 1 - (k - 750) }
        } else {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed % b.len() as u64) as usize
        };
        b[at] ^= 1 << (k % 8);
        if open_and_read_all("flipped.mcap", b).is_err() {
            errors += 1;
        }
    }
    // CRCs catch most flips; some land on values (e.g. a channel's metadata) that stay valid.
    assert!(
        errors > flips / 2,
        "only {errors} of {flips} flips were noticed"
    );
}

#[test]
fn garbage_and_empty_files_are_errors_naming_the_file() {
    for (name, bytes) in [
        ("empty.mcap", Vec::new()),
        ("text.mcap", b"hello, world".to_vec()),
        ("magic_only.mcap", b"\x89MCAP0\r\n".to_vec()),
        ("two_magics.mcap", b"\x89MCAP0\r\n\x89MCAP0\r\n".to_vec()),
        ("zeros.mcap", vec![0; 4096]),
    ] {
        let e = open_and_read_all(name, bytes).unwrap_err();
        assert!(matches!(e, RecordingError::Malformed { .. }), "{name}: {e}");
    }
}

#[test]
fn huge_length_fields_do_not_allocate() {
    // magic, a header record claiming 2^63 bytes, then a footer and closing magic.
    let mut b = b"\x89MCAP0\r\n".to_vec();
    b.push(0x01);
    b.extend_from_slice(&(1u64 << 63).to_le_bytes());
    b.extend_from_slice(&[0; 8]);
    b.push(0x02);
    b.extend_from_slice(&20u64.to_le_bytes());
    b.extend_from_slice(&[0; 20]);
    b.extend_from_slice(b"\x89MCAP0\r\n");
    let e = open_and_read_all("huge_header.mcap", b).unwrap_err();
    assert!(e.to_string().contains("at byte 9"), "{e}");

    // A valid file whose first chunk claims a 2^62-byte uncompressed size.
    let mut bytes = sample_bytes("huge_chunk", 50);
    let chunk_at = find_first_chunk(&bytes);
    // chunk body: start(8) end(8) uncompressed_size(8)
    let size_at = chunk_at + 9 + 16;
    bytes[size_at..size_at + 8].copy_from_slice(&(1u64 << 62).to_le_bytes());
    let e = open_and_read_all("huge_chunk.mcap", bytes.clone()).unwrap_err();
    assert!(e.to_string().contains("uncompressed size"), "{e}");

    // Just under the 256 MiB cap: accepted as a size, but the buffer grows only with the bytes
    // that zstd actually produces (then the size mismatch is an error).
    let size_at = find_first_chunk(&bytes) + 9 + 16;
    bytes[size_at..size_at + 8].copy_from_slice(&(255u64 << 20).to_le_bytes());
    LARGEST.store(0, Ordering::Relaxed);
    let e = open_and_read_all("big_chunk.mcap", bytes).unwrap_err();
    assert!(e.to_string().contains("after decompression"), "{e}");
    let largest = LARGEST.load(Ordering::Relaxed);
    assert!(largest < 8 << 20, "largest allocation {largest} bytes");
}

fn find_first_chunk(bytes: &[u8]) -> usize {
    let mut at = 8;
    loop {
        if bytes[at] == 0x06 {
            return at;
        }
        let len = u64::from_le_bytes(bytes[at + 1..at + 9].try_into().unwrap()) as usize;
        at += 9 + len;
    }
}

#[test]
fn a_json_channel_is_listed_but_not_decoded_as_protobuf() {
    use std::borrow::Cow;
    use std::sync::Arc;
    let dir = tmp_dir("json");
    let path = dir.join("json.mcap");
    let mut w = mcap::Writer::new(std::io::BufWriter::new(
        std::fs::File::create(&path).unwrap(),
    ))
    .unwrap();
    let schema = Arc::new(mcap::Schema {
        id: 1,
        name: "Point".into(),
        encoding: "jsonschema".into(),
        data: Cow::Borrowed(br#"{"type":"object"}"#),
    });
    let channel = Arc::new(mcap::Channel {
        id: 0,
        topic: "/json".into(),
        schema: Some(schema),
        message_encoding: "json".into(),
        metadata: Default::default(),
    });
    for i in 0..10u64 {
        w.write(&mcap::Message {
            channel: channel.clone(),
            sequence: i as u32,
            log_time: i,
            publish_time: i,
            data: Cow::Owned(format!(r#"{{"x": {i}}}"#).into_bytes()),
        })
        .unwrap();
    }
    w.finish().unwrap();
    drop(w);
    let rec = Recording::open(&path).unwrap();
    let chans = rec.channels();
    assert_eq!(chans.len(), 1);
    assert_eq!(chans[0].kind, ChannelKind::Other);
    assert_eq!(chans[0].message_encoding, "json");
    assert_eq!(chans[0].message_count, 10);
    let e = rec.read_records("/json").unwrap_err();
    assert!(matches!(e, RecordingError::Schema { .. }), "{e}");
    assert!(
        e.to_string().contains("json.mcap") && e.to_string().contains("/json"),
        "{e}"
    );
    let e = rec.read_poses("/json").unwrap_err();
    assert!(e.to_string().contains("json.mcap"), "{e}");
    let e = rec.read_records("/nope").unwrap_err();
    assert!(matches!(e, RecordingError::UnknownTopic { .. }), "{e}");
}

#[test]
fn a_missing_file_is_an_io_error_naming_it() {
    let e = Recording::open(Path::new("/nonexistent/dir/run.mcap"))
        .err()
        .unwrap();
    assert!(matches!(e, RecordingError::Io { .. }));
    assert!(e.to_string().contains("/nonexistent/dir/run.mcap"), "{e}");
}
