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
    Pose(#[from] crate::pose::PoseError),
    /// A text input that cannot be used: a teeth-axes JSON (or landmarks) file that is too
    /// large, not text, malformed, or does not fit the arch it labels
    /// ([`input`](crate::input), the teeth files of `innersphere-dental`).
    #[error("{path}: {message}")]
    Input {
        /// The file.
        path: PathBuf,
        /// What is wrong, naming the limit or the check that failed.
        message: String,
    },
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

/// A number as a message writes it: plain decimals from 1e-4 to 1e9, else exponent notation
/// (`1e300`, `2.5e-7`); never hundreds of digits, never a debug dump.
#[derive(Debug, Clone, Copy)]
pub struct Num(pub f64);

impl std::fmt::Display for Num {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let x = self.0;
        if !x.is_finite() || x == 0.0 || (1e-4..1e9).contains(&x.abs()) {
            write!(f, "{x}")
        } else {
            write!(f, "{x:e}")
        }
    }
}

/// [`Num`] of `x`.
pub fn num(x: f64) -> Num {
    Num(x)
}

/// A vector as a message writes it: `(x, y, z)` in [`Num`]s.
pub fn vec3(v: glam::DVec3) -> String {
    format!("({}, {}, {})", num(v.x), num(v.y), num(v.z))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_in_messages_are_plain() {
        assert_eq!(num(1e300).to_string(), "1e300");
        assert_eq!(num(-2.5e-7).to_string(), "-2.5e-7");
        assert_eq!(num(0.006).to_string(), "0.006");
        assert_eq!(num(12.0).to_string(), "12");
        assert_eq!(num(0.0).to_string(), "0");
        assert_eq!(num(f64::NAN).to_string(), "NaN");
        assert_eq!(num(1e9).to_string(), "1e9");
    }
}
