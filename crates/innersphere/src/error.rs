//! The one error type of the library: every bad input ends here, never in a panic.

use std::path::PathBuf;

/// Everything that can go wrong while loading, building, reading or querying.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// An operating-system I/O error, with the file it concerns.
    #[error("{path}: {source}")]
    Io {
        /// The file being read or written.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// A mesh file that cannot be parsed (truncated, lying header, bad number, ...).
    #[error("{path}: {format} parse error: {message}")]
    Parse {
        /// The file.
        path: PathBuf,
        /// The format that was tried (stl, obj, ply, off).
        format: &'static str,
        /// What is wrong, with a line number or byte offset where known.
        message: String,
    },
    /// A file whose extension names no supported format.
    #[error("{0}: unsupported mesh format (expected .stl, .obj, .ply or .off, optionally .gz)")]
    UnsupportedFormat(PathBuf),
    /// A mesh that cannot be used as a solid (empty, NaN, no enclosed volume, ...).
    #[error("invalid mesh: {0}")]
    InvalidMesh(String),
    /// An option outside its sane range.
    #[error("invalid option: {0}")]
    InvalidOption(String),
    /// A tree file that is truncated, corrupted or of another version.
    #[error("corrupt tree file: {0}")]
    CorruptTree(String),
    /// An output (a chart, a report) that could not be produced.
    #[error("cannot write output: {0}")]
    Output(String),
    /// Numbers that are no rigid pose (see [`PoseError`](crate::PoseError)).
    #[error("invalid pose: {0}")]
    Pose(#[from] crate::PoseError),
    /// A motion file that cannot be used.
    #[error("{path}:{line}: {message}")]
    Motion {
        /// The file.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        message: String,
    },
}

/// Result with the library's [`Error`].
pub type Result<T> = std::result::Result<T, Error>;

impl Error {
    /// Wraps an I/O error with the path it concerns.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io {
            path: path.into(),
            source,
        }
    }
}
