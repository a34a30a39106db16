//! `innersphere.load_motion`: a motion file as numpy arrays.

use crate::convert::error;
use innersphere_motion::Motion;
use numpy::{PyArray1, PyArray2, PyArrayMethods};
use pyo3::prelude::*;

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
            // The file's own numbers (the queries normalise each quaternion as the motion
            // reader does), from the one motion parser.
            let (motion, rows) = Motion::load_with_rows(&path)?;
            let t: Vec<f64> = motion.frames.iter().map(|f| f.t).collect();
            let poses: Vec<[f64; 7]> = rows
                .iter()
                .map(|r| [r[1], r[2], r[3], r[4], r[5], r[6], r[7]])
                .collect();
            Ok::<_, innersphere::Error>((t, poses))
        })
        .map_err(error)?;
    let n = rows.len();
    let flat: Vec<f64> = rows.into_iter().flatten().collect();
    Ok((
        PyArray1::from_vec(py, t),
        PyArray1::from_vec(py, flat).reshape([n, 7])?,
    ))
}
