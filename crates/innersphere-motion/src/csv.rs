//! The motion file format: a CSV with the header `t,tx,ty,tz,qw,qx,qy,qz` and one frame per
//! line — time in seconds and the pose of body B in body A's frame, applied to B's model
//! coordinates as `p' = R(q)·p + t`. A final `.gz` in the path means gzip.

use glam::{DQuat, DVec3};
use innersphere::Pose;
use innersphere::{Error, Result};
use std::path::Path;

/// The header line of a motion file.
pub const HEADER: &str = "t,tx,ty,tz,qw,qx,qy,qz";
/// Column names, in file order.
const COLUMNS: [&str; 8] = ["t", "tx", "ty", "tz", "qw", "qx", "qy", "qz"];
/// A quaternion whose norm differs from 1 by more than this is rejected; within it, it is
/// normalized (files written with a few decimals are never exactly unit).
pub const QUAT_NORM_TOLERANCE: f64 = 1e-3;
/// The largest motion file accepted (decompressed), 1 GiB: at 1 kHz, 1.9 hours of frames as
/// [`Motion::to_csv`] writes them (every number in full, about 155 bytes a frame) and 3.5
/// hours at the recorded files' 6 to 9 decimals (84 bytes a frame); a longer recording is
/// split into files. Loading the largest file holds its text and its frames (64 bytes each)
/// at once, at most about 1.9 GB.
pub const MAX_FILE_BYTES: u64 = 1 << 30;

/// A motion file for [`innersphere::input::read_text`].
pub const MOTION_FILE: innersphere::input::TextInput = innersphere::input::TextInput {
    what: "motion file",
    max_bytes: MAX_FILE_BYTES,
};

/// One frame of a motion: a time and the pose of body B in body A's frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame {
    /// Time in seconds (strictly increasing along a motion).
    pub t: f64,
    /// The pose of B in A's frame.
    pub pose: Pose,
}

/// A motion: frames with strictly increasing times (see the [module docs](self)).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Motion {
    /// The frames, in time order.
    pub frames: Vec<Frame>,
}

fn motion_error(path: &Path, line: usize, message: impl Into<String>) -> Error {
    Error::Motion {
        path: path.to_path_buf(),
        line,
        message: message.into(),
    }
}

impl Motion {
    /// Number of frames.
    pub fn len(&self) -> usize {
        self.frames.len()
    }

    /// True when there are no frames.
    pub fn is_empty(&self) -> bool {
        self.frames.is_empty()
    }

    /// Time from the first to the last frame (0 for fewer than two frames).
    pub fn duration(&self) -> f64 {
        match (self.frames.first(), self.frames.last()) {
            (Some(a), Some(b)) => b.t - a.t,
            _ => 0.0,
        }
    }

    /// The poses, in order.
    pub fn poses(&self) -> impl Iterator<Item = Pose> + '_ {
        self.frames.iter().map(|f| f.pose)
    }

    /// Reads a motion file (gzip-compressed when the path ends in `.gz`).
    pub fn load(path: impl AsRef<Path>) -> Result<Motion> {
        let path = path.as_ref();
        Motion::parse(&read_text(path)?, path)
    }

    /// [`load`](Self::load), with each frame's eight numbers as the file writes them (the
    /// quaternion before it is normalised): for callers that hand the file's own numbers on
    /// (the Python module), from the same parser.
    pub fn load_with_rows(path: impl AsRef<Path>) -> Result<(Motion, Vec<[f64; 8]>)> {
        let path = path.as_ref();
        Motion::parse_with_rows(&read_text(path)?, path)
    }

    /// The pose at time `t`: translation interpolated linearly and rotation by slerp between
    /// the frames around `t`, held at the ends (as a device driver's last reading would be).
    /// Allocates nothing (a binary search). The motion must have a frame.
    pub fn pose_at(&self, t: f64) -> Pose {
        let f = &self.frames;
        let i = f.partition_point(|x| x.t <= t);
        if i == 0 {
            return f[0].pose;
        }
        if i >= f.len() {
            return f[f.len() - 1].pose;
        }
        let (a, b) = (&f[i - 1], &f[i]);
        let s = ((t - a.t) / (b.t - a.t)).clamp(0.0, 1.0);
        Pose {
            rotation: a.pose.rotation.slerp(b.pose.rotation, s).normalize(),
            translation: a.pose.translation.lerp(b.pose.translation, s),
        }
    }

    /// Parses the text of a motion file; `path` only names the file in errors.
    ///
    /// Accepts `\n` or `\r\n` line ends, a UTF-8 byte-order mark, blank lines and spaces
    /// around values. Rejects, with the 1-based line number: a missing or wrong header,
    /// missing or extra columns, values that are not numbers or not finite, quaternions
    /// whose norm is off 1 by more than [`QUAT_NORM_TOLERANCE`] (nearly unit ones are
    /// normalized), times that do not increase, and a file without frames. Never panics.
    pub fn parse(text: &str, path: impl AsRef<Path>) -> Result<Motion> {
        Motion::parse_with_rows(text, path).map(|(m, _)| m)
    }

    /// [`parse`](Self::parse), with each frame's eight numbers as written.
    pub fn parse_with_rows(text: &str, path: impl AsRef<Path>) -> Result<(Motion, Vec<[f64; 8]>)> {
        let path = path.as_ref();
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        let mut rows: Vec<[f64; 8]> = Vec::new();
        let mut lines = text.lines().enumerate().map(|(i, l)| (i + 1, l));
        // The header: the first non-blank line.
        let header = lines.by_ref().find(|(_, l)| !l.trim().is_empty());
        let Some((hline, header)) = header else {
            return Err(motion_error(
                path,
                1,
                format!("empty file: expected the header \"{HEADER}\""),
            ));
        };
        let names: Vec<&str> = header.split(',').map(str::trim).collect();
        if names != COLUMNS {
            return Err(motion_error(
                path,
                hline,
                format!(
                    "expected the header \"{HEADER}\", found \"{}\"",
                    truncate(header.trim(), 80)
                ),
            ));
        }
        let mut frames: Vec<Frame> = Vec::new();
        let mut last_line = hline;
        for (line, text) in lines {
            last_line = line;
            if text.trim().is_empty() {
                continue;
            }
            let mut v = [0.0f64; 8];
            let mut n = 0usize;
            for field in text.split(',') {
                if n == 8 {
                    return Err(motion_error(
                        path,
                        line,
                        format!(
                            "extra columns: expected 8 values ({HEADER}), found {}",
                            text.split(',').count()
                        ),
                    ));
                }
                let f = field.trim();
                let x: f64 = f.parse().map_err(|_| {
                    motion_error(
                        path,
                        line,
                        format!("{}: \"{}\" is not a number", COLUMNS[n], truncate(f, 40)),
                    )
                })?;
                if !x.is_finite() {
                    return Err(motion_error(
                        path,
                        line,
                        format!("{}: \"{}\" is not finite", COLUMNS[n], truncate(f, 40)),
                    ));
                }
                v[n] = x;
                n += 1;
            }
            if n < 8 {
                return Err(motion_error(
                    path,
                    line,
                    format!(
                        "missing columns: expected 8 values ({HEADER}), found {n} (no {})",
                        COLUMNS[n..].join(", ")
                    ),
                ));
            }
            let q = DQuat::from_xyzw(v[5], v[6], v[7], v[4]);
            // The sum of squares of finite values may overflow; length() of huge values is
            // inf, which fails the tolerance check below.
            let norm = q.length();
            if !unit_norm(norm) {
                return Err(motion_error(
                    path,
                    line,
                    format!(
                        "the quaternion (qw,qx,qy,qz) has norm {norm}, not 1 (tolerance {QUAT_NORM_TOLERANCE})"
                    ),
                ));
            }
            let t = v[0];
            if let Some(prev) = frames.last() {
                if t <= prev.t {
                    return Err(motion_error(
                        path,
                        line,
                        format!(
                            "time {t} does not increase (the previous frame is at {})",
                            prev.t
                        ),
                    ));
                }
            }
            let pose = Pose::new(DVec3::new(v[1], v[2], v[3]), q)
                .map_err(|e| motion_error(path, line, format!("not a valid rigid pose: {e}")))?;
            frames.push(Frame { t, pose });
            rows.push(v);
        }
        if frames.is_empty() {
            return Err(motion_error(
                path,
                last_line + 1,
                "no frames after the header",
            ));
        }
        Ok((Motion { frames }, rows))
    }

    /// Checks what [`parse`](Self::parse) would check of a file written from this motion:
    /// at least one frame, finite values, unit quaternions, increasing times. Errors name
    /// the line the frame would be on (`path` only names the file).
    pub fn validate(&self, path: impl AsRef<Path>) -> Result<()> {
        let path = path.as_ref();
        if self.frames.is_empty() {
            return Err(motion_error(path, 2, "no frames"));
        }
        for (i, f) in self.frames.iter().enumerate() {
            let line = i + 2;
            let [tx, ty, tz, qw, qx, qy, qz] = f.pose.to_array();
            if ![f.t, tx, ty, tz, qw, qx, qy, qz]
                .iter()
                .all(|x| x.is_finite())
            {
                return Err(motion_error(path, line, "a value is not finite"));
            }
            let norm = f.pose.rotation.length();
            if !unit_norm(norm) {
                return Err(motion_error(
                    path,
                    line,
                    format!("the quaternion has norm {norm}, not 1"),
                ));
            }
            if i > 0 && f.t <= self.frames[i - 1].t {
                return Err(motion_error(path, line, "time does not increase"));
            }
        }
        Ok(())
    }

    /// The text of the motion file: the header, then one line per frame with every value
    /// in the shortest form that reads back to the same `f64`.
    pub fn to_csv(&self) -> String {
        use std::fmt::Write as _;
        let mut s = String::with_capacity(16 + self.frames.len() * 150);
        s.push_str(HEADER);
        s.push('\n');
        for f in &self.frames {
            let [tx, ty, tz, qw, qx, qy, qz] = f.pose.to_array();
            // Writing into a String cannot fail.
            let _ = writeln!(s, "{},{tx},{ty},{tz},{qw},{qx},{qy},{qz}", f.t);
        }
        s
    }

    /// Writes the motion file ([`to_csv`](Self::to_csv)), gzip-compressed when the path ends
    /// in `.gz`, through a temporary file renamed into place
    /// ([`innersphere::output::write_file`]: a failed write leaves no partial file). Refuses a
    /// motion that [`validate`](Self::validate) rejects, so that every written file loads
    /// again.
    pub fn save(&self, path: impl AsRef<Path>) -> Result<()> {
        let path = path.as_ref();
        self.validate(path)?;
        innersphere::output::write_file(path, self.to_csv().as_bytes())
    }
}

/// The text of a motion file, decompressed when the path ends in `.gz`, at most
/// [`MAX_FILE_BYTES`], through the library's bounded reader ([`innersphere::input`]: a
/// device or binary data is refused at its first NUL byte).
fn read_text(path: &Path) -> Result<String> {
    innersphere::input::read_text(path, MOTION_FILE)
}

/// True when a quaternion norm is within [`QUAT_NORM_TOLERANCE`] of 1 (false for NaN).
fn unit_norm(norm: f64) -> bool {
    (norm - 1.0).abs() <= QUAT_NORM_TOLERANCE
}

/// At most `n` characters of `s`, with an ellipsis when cut.
fn truncate(s: &str, n: usize) -> String {
    if s.chars().count() <= n {
        s.to_string()
    } else {
        let mut out: String = s.chars().take(n).collect();
        out.push('…');
        out
    }
}
