//! The one error type of the crate: every variant names the file and the place.

use std::path::PathBuf;

/// What went wrong, where. Every variant carries the file's path; malformed input also says the
/// byte offset and the record kind being read, and what was expected there.
#[derive(Debug, thiserror::Error)]
pub enum RecordingError {
    /// The operating system refused a read, write, rename or sync.
    #[error("{}: {action}: {source}", .path.display())]
    Io {
        path: PathBuf,
        action: &'static str,
        #[source]
        source: std::io::Error,
    },
    /// The bytes are not a well-formed MCAP file (or not the part of one that was expected).
    #[error("{}: at byte {offset} in {record}: expected {expected}", .path.display())]
    Malformed {
        path: PathBuf,
        /// Absolute byte offset in the file (for bytes inside a chunk: the chunk record's offset
        /// plus the offset within its decompressed records, see `expected`).
        offset: u64,
        /// The record kind (e.g. "chunk", "summary section", "footer").
        record: &'static str,
        expected: String,
    },
    /// No channel has this topic.
    #[error("{}: no channel has topic {topic:?} (topics: {available})", .path.display())]
    UnknownTopic {
        path: PathBuf,
        topic: String,
        available: String,
    },
    /// The channel exists but its schema or encoding is not what the call decodes.
    #[error("{}: topic {topic:?}: expected {expected}", .path.display())]
    Schema {
        path: PathBuf,
        topic: String,
        expected: String,
    },
    /// A message's protobuf payload does not match its schema.
    #[error(
        "{}: topic {topic:?}, message at log time {log_time_ns} ns in the chunk at byte {chunk_offset}: expected {expected}",
        .path.display()
    )]
    Message {
        path: PathBuf,
        topic: String,
        chunk_offset: u64,
        log_time_ns: u64,
        expected: String,
    },
    /// The writer was called with arguments that do not fit the channel or schema.
    #[error("{}: {call}: expected {expected}", .path.display())]
    Usage {
        path: PathBuf,
        call: String,
        expected: String,
    },
}

/// A parse failure before it is told which file it belongs to.
#[derive(Debug, Clone)]
pub(crate) struct ParseError {
    pub offset: u64,
    pub record: &'static str,
    pub expected: String,
}

impl ParseError {
    pub(crate) fn new(offset: u64, record: &'static str, expected: impl Into<String>) -> Self {
        Self {
            offset,
            record,
            expected: expected.into(),
        }
    }

    pub(crate) fn in_file(self, path: &std::path::Path) -> RecordingError {
        RecordingError::Malformed {
            path: path.to_path_buf(),
            offset: self.offset,
            record: self.record,
            expected: self.expected,
        }
    }
}

pub(crate) fn io_error(
    path: &std::path::Path,
    action: &'static str,
) -> impl FnOnce(std::io::Error) -> RecordingError {
    let path = path.to_path_buf();
    move |source| RecordingError::Io {
        path,
        action,
        source,
    }
}
