//! Any bytes, opened as a recording and every channel decoded, one at a time and all in one
//! pass (`read_all` has its own fast paths and shares chunks among threads): must give values or
//! `RecordingError`s, never a panic, hang or huge allocation.
#![no_main]

use gyro_mcap::{ChannelKind, Recording};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let path = std::path::Path::new("fuzz-input.mcap");
    if let Ok(rec) = Recording::from_bytes(path, data.to_vec()) {
        let _ = rec.metadata();
        let _ = rec.attachments();
        for ch in rec.channels() {
            match ch.kind {
                ChannelKind::Pose => {
                    let _ = rec.read_poses(&ch.topic);
                }
                _ => {
                    let _ = rec.read_records(&ch.topic);
                }
            }
        }
        let _ = rec.read_all();
    }
});
