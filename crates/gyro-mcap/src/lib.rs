//! gyro-mcap owns gyrolab's recording contract: how a run is written to an MCAP file, how any
//! MCAP file is read back, and how a killed run's `.partial` file is recovered. It knows nothing
//! of physics: it records named channels of flat records and of poses, plus metadata and
//! attachments, and it is the only decoding code the workspace uses.
//!
//! # The file
//! - zstd-compressed chunks (about [`WriterOptions::chunk_size_bytes`] of records each), each
//!   followed by its message indexes; a summary section with schemas, channels, statistics, chunk
//!   indexes, attachment and metadata indexes, and summary offsets; CRCs on chunks, attachments,
//!   the data section and the summary. Any MCAP reader can seek in it.
//! - Record channels carry self-describing protobuf: each [`RecordSchema`] becomes a proto3
//!   message (package = the part of its full name before the last dot, fields numbered 1.. in
//!   order, every field written even when zero so columns are dense) whose FileDescriptorSet is the
//!   MCAP schema (encoding `protobuf`). Units go to the channel metadata as `unit.<field>`.
//! - Pose channels carry `foxglove.FrameTransform` (protobuf; the schema is the FileDescriptorSet
//!   of the shipped `proto/foxglove/*.proto` with `google/protobuf/timestamp.proto`), so Foxglove
//!   and Rerun's MCAP loader show them.
//!
//! # The contract
//! [`contract`] names what a gyrolab run writes (topics, schemas and their fields, metadata
//! records and keys, status strings, frames, body shapes): the recorder and every reader take
//! them from there. The rest of the crate is the container and knows none of them.
//!
//! # Time
//! A message's log time = publish time = the FrameTransform timestamp = **simulation time in
//! nanoseconds since the run's start**: t = 0 s is 0 ns, which tools that show absolute time
//! display as the Unix epoch (1970-01-01T00:00:00Z).
//!
//! # Life of a file
//! [`RecordingWriter::create`] writes `NAME.mcap.partial`. The caller's thread only encodes
//! messages into the open chunk; closed chunks are compressed by worker threads (one per core, up
//! to four) and written in order by a writer thread, which hands each to the operating system
//! as soon as it is written. A chunk is closed at least every [`WriterOptions::flush_interval_s`]
//! of wall time, so a killed process loses at most that much plus the few chunks still queued
//! (milliseconds of work); [`RecordingWriter::flush_chunk`] waits until they are written.
//! [`RecordingWriter::finish`] (callable at any point, e.g. after Ctrl-C) writes the summary,
//! syncs, and renames to `NAME.mcap`. [`recover`] turns a `.partial` file into a valid recording of
//! everything up to its last whole chunk.
//!
//! # Reading untrusted files
//! [`Recording::open`] reads through the summary and indexes when present, else scans the data
//! section. [`Recording::read_topics`] and [`Recording::read_all`] decode several channels in one
//! pass (each chunk decompressed once, chunks shared out among threads); `read_records` and
//! `read_poses` decode one. Truncated, corrupted or foreign files give a [`RecordingError`] that names the file and
//! the byte offset and record kind, never a panic; no allocation is sized by a length field
//! beyond the bytes present (decompression grows with the bytes produced, capped at 256 MiB per
//! chunk). The whole file is held in memory while open.

pub mod contract;
mod decode;
mod error;
mod format;
mod reader;
mod recover;
mod schema;
mod writer;

pub use decode::Column;
pub use error::RecordingError;
pub use reader::{
    AttachmentInfo, ChannelInfo, ChannelKind, ChannelTable, PoseTable, RecordTable, Recording,
};
pub use recover::{RecoverReport, recover};
pub use schema::{FieldKind, FieldSpec, Pose, RecordSchema, Value};
pub use writer::{ChannelId, RecordingWriter, WriteSummary, WriterOptions, partial_path};
