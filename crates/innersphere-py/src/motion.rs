//! `innersphere.load_motion`: a motion file as numpy arrays.

use crate::convert::error;
use innersphere::Pose;
use innersphere_eval::motion::Motion;
use numpy::{PyArray1, PyArray2, PyArrayMethods};
use pyo3::prelude::*;
use std::io::Read;
use std::path::Path;

/// The numbers of each frame line of a motion file's text, as written (`t, tx, ty, tz, qw,
/// qx, qy, qz`), read the way `Motion::parse` reads them; `None` when the text is not what
/// it parsed.
fn raw_rows(text: &str) -> Option<Vec<[f64; 8]>> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut lines = text.lines().filter(|l| !l.trim().is_empty());
    lines.next()?; // the header
    lines
        .map(|l| {
            let mut v = [0.0; 8];
            let mut n = 0;
            for field in l.split(',') {
                *v.get_mut(n)? = field.trim().parse().ok()?;
                n += 1;
            }
            (n == 8).then_some(v)
        })
        .collect()
}

/// The file's text, decompressed when its name ends in `.gz`.
fn read_text(path: &Path) -> Option<String> {
    let bytes = std::fs::read(path).ok()?;
    if innersphere::mesh::io::is_gzip(path) {
        let mut out = String::new();
        flate2::read::MultiGzDecoder::new(&bytes[..])
            .read_to_string(&mut out)
            .ok()?;
        Some(out)
    } else {
        String::from_utf8(bytes).ok()
    }
}

/// The poses of a parsed motion, as the file's own numbers when they give exactly the
/// motion's poses (so that the queries on them, which normalise each quaternion as the
/// motion reader did, see bit for bit the poses `ist replay` sees), else as the normalised
/// poses.
fn pose_rows(motion: &Motion, path: &Path) -> Vec<[f64; 7]> {
    let normalised = || motion.frames.iter().map(|f| f.pose.to_array()).collect();
    let Some(rows) = read_text(path).and_then(|t| raw_rows(&t)) else {
        return normalised();
    };
    let same = rows.len() == motion.frames.len()
        && rows.iter().zip(&motion.frames).all(|(r, f)| {
            let p: [f64; 7] = r[1..].try_into().expect("7 numbers");
            r[0] == f.t && Pose::from_array(p) == Ok(f.pose)
        });
    if same {
        rows.iter()
            .map(|r| r[1..].try_into().expect("7 numbers"))
            .collect()
    } else {
        normalised()
    }
}

/// A motion's times (N,) and poses (N, 7).
type TimesAndPoses<'py> = (Bound<'py, PyArray1<f64>>, Bound<'py, PyArray2<f64>>);

/// Reads a motion file (CSV `t,tx,ty,tz,qw,qx,qy,qz`, optionally .gz): the pose of body B in
/// body A's frame per frame, as `ist replay --motion` reads it. Returns (t, poses): the times
/// (N,) in seconds and the poses (N, 7) as (tx, ty, tz, qw, qx, qy, qz), the file's own
/// numbers (each quaternion is within 1e-3 of unit; the queries normalise it exactly as the
/// motion reader does, so pair.distance_many(poses) on a new pair gives `ist replay`'s
/// distances). Raises OSError when the file cannot be read, ValueError (with the line) when
/// it is not a valid motion.
#[pyfunction]
pub fn load_motion<'py>(py: Python<'py>, path: &Bound<'py, PyAny>) -> PyResult<TimesAndPoses<'py>> {
    let path = crate::convert::path(path)?;
    let (t, rows) = py
        .detach(|| {
            let motion = Motion::load(&path)?;
            let t: Vec<f64> = motion.frames.iter().map(|f| f.t).collect();
            Ok::<_, innersphere::Error>((t, pose_rows(&motion, &path)))
        })
        .map_err(error)?;
    let n = rows.len();
    let flat: Vec<f64> = rows.into_iter().flatten().collect();
    Ok((
        PyArray1::from_vec(py, t),
        PyArray1::from_vec(py, flat).reshape([n, 7])?,
    ))
}
