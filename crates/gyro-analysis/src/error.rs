//! The one error type of the crate. Every variant that comes from a recording names the file, and
//! where a channel is involved, the channel (and field).

use std::path::{Path, PathBuf};

use gyro_mcap::RecordingError;

/// What went wrong, where.
#[derive(Debug, thiserror::Error)]
pub enum AnalysisError {
    /// The file could not be read as a recording (truncated, corrupt, not MCAP, unreadable).
    #[error(transparent)]
    Recording(#[from] RecordingError),
    /// The recording lacks a channel the analysis needs.
    #[error("{}: no channel {topic:?} (channels: {available})", .path.display())]
    MissingChannel {
        path: PathBuf,
        topic: String,
        available: String,
    },
    /// The channel lacks a field the analysis needs, or has it with another type.
    #[error("{}: channel {topic:?}: {what} (fields: {available})", .path.display())]
    MissingField {
        path: PathBuf,
        topic: String,
        what: String,
        available: String,
    },
    /// The channel exists but holds no message.
    #[error("{}: channel {topic:?} holds no message (an empty or unfinished recording?)", .path.display())]
    EmptyChannel { path: PathBuf, topic: String },
    /// An argument named no recording (an empty folder, a glob that matched nothing).
    #[error("{input}: {what}")]
    Input { input: String, what: String },
    /// The operating system refused a read or write.
    #[error("{}: {action}: {source}", .path.display())]
    Io {
        path: PathBuf,
        action: &'static str,
        #[source]
        source: std::io::Error,
    },
    /// polars refused an operation (building or writing a frame).
    #[error("{context}: {source}")]
    Polars {
        context: String,
        #[source]
        source: polars::error::PolarsError,
    },
    /// A baseline file that does not parse or does not fit the metrics.
    #[error("{}: {what}", .path.display())]
    Baseline { path: PathBuf, what: String },
}

impl AnalysisError {
    /// An [`AnalysisError::Io`] for `path`, to map an `std::io::Error` with.
    pub fn io(path: &Path, action: &'static str) -> impl FnOnce(std::io::Error) -> Self {
        let path = path.to_path_buf();
        move |source| AnalysisError::Io {
            path,
            action,
            source,
        }
    }

    /// An [`AnalysisError::Polars`] with its context, to map a `PolarsError` with.
    pub fn polars(context: impl Into<String>) -> impl FnOnce(polars::error::PolarsError) -> Self {
        let context = context.into();
        move |source| AnalysisError::Polars { context, source }
    }
}

/// Shorthand used throughout the crate.
pub type Result<T, E = AnalysisError> = std::result::Result<T, E>;
