//! Conversions shared by the classes: library errors to Python exceptions, Python poses to
//! [`Pose`]s, vectors and JSON values to Python objects.

use innersphere::{Error, MatrixOrder, Pose};
use numpy::ndarray::{ArrayViewD, Axis};
use numpy::{AllowTypeChange, IxDyn, PyArray1, PyArrayLike, PyArrayMethods};
use pyo3::exceptions::{PyOSError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyList};
use std::path::{Path, PathBuf};

/// What a pose may be, said in errors.
const POSE_FORMS: &str = "a 4×4 homogeneous matrix or 7 numbers (tx, ty, tz, qw, qx, qy, qz)";

/// A library error as a Python exception: the operating system's errors on a file become
/// `OSError` (its subclass for the errno, e.g. `FileNotFoundError`, with the file name), all
/// others `ValueError`, each with the library's message.
pub(crate) fn error(e: Error) -> PyErr {
    match e {
        Error::Io { path, source } => io_error(&path, &source),
        Error::Output(_) => PyOSError::new_err(e.to_string()),
        other => PyValueError::new_err(other.to_string()),
    }
}

/// `OSError(errno, message, filename)` (which Python turns into the errno's subclass), or a
/// plain `OSError` with the library's message when there is no errno.
pub(crate) fn io_error(path: &Path, source: &std::io::Error) -> PyErr {
    let file = path.display().to_string();
    match source.raw_os_error() {
        Some(errno) => {
            // Rust's message ends in " (os error N)", which the errno already says.
            let text = source.to_string();
            let text = match text.rfind(" (os error ") {
                Some(i) => text[..i].to_string(),
                None => text,
            };
            PyOSError::new_err((errno, text, file))
        }
        None => PyOSError::new_err(format!("{file}: {source}")),
    }
}

/// A path argument: `str`, `bytes` or `os.PathLike` (`bytes` decoded as `os.fsdecode` does).
/// A unit name (`"mm"`, `"cm"`, `"m"`, `"in"`), ValueError otherwise.
pub(crate) fn unit(name: &str) -> PyResult<innersphere::mesh::Unit> {
    name.parse().map_err(error)
}

pub(crate) fn path(obj: &Bound<'_, PyAny>) -> PyResult<PathBuf> {
    let os = obj.py().import("os")?;
    let p = os.call_method1("fspath", (obj,))?;
    if p.is_instance_of::<PyBytes>() {
        return os.call_method1("fsdecode", (p,))?.extract();
    }
    p.extract()
}

/// Any array-like of numbers as an f64 array of any shape, or `ValueError` naming `what`
/// and `expected`.
pub(crate) fn float_array<'py>(
    obj: &Bound<'py, PyAny>,
    what: &str,
    expected: &str,
) -> PyResult<PyArrayLike<'py, f64, IxDyn, AllowTypeChange>> {
    obj.extract::<PyArrayLike<'py, f64, IxDyn, AllowTypeChange>>()
        .map_err(|e| {
            let ty = obj
                .get_type()
                .name()
                .map(|n| n.to_string())
                .unwrap_or_else(|_| "?".into());
            PyValueError::new_err(format!(
                "{what}: expected {expected}, got a {ty} that is not an array of numbers ({e})"
            ))
        })
}

/// One pose from a view of shape (7,) or (4, 4): `Err(message)` when it is no rigid pose.
fn pose_of_view(v: &ArrayViewD<'_, f64>) -> Result<Pose, String> {
    let result = match v.shape() {
        [7] => {
            let mut a = [0.0; 7];
            for (slot, x) in a.iter_mut().zip(v.iter()) {
                *slot = *x;
            }
            Pose::from_array(a)
        }
        [4, 4] => {
            // Row-major as numpy indexes it: m[row, col], the translation in the last column.
            let mut m = [0.0; 16];
            for (slot, x) in m.iter_mut().zip(v.iter()) {
                *slot = *x;
            }
            Pose::from_matrix4(&m, MatrixOrder::RowMajor)
        }
        s => return Err(format!("expected {POSE_FORMS}, got shape {}", shape(s))),
    };
    result.map_err(|e| format!("invalid pose: {e}"))
}

/// A shape as Python prints it: `(3,)`, `(4, 4)`.
pub(crate) fn shape(s: &[usize]) -> String {
    match s {
        [n] => format!("({n},)"),
        _ => format!(
            "({})",
            s.iter()
                .map(|n| n.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
}

/// A pose argument: a 4×4 homogeneous matrix (numpy's row-major `m[row, col]`, translation in
/// the last column, last row exactly `0 0 0 1`) or 7 numbers `(tx, ty, tz, qw, qx, qy, qz)`
/// (the quaternion is normalised, as `ist query --pose-b` does). `ValueError` otherwise.
pub(crate) fn pose(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Pose> {
    let arr = float_array(obj, what, POSE_FORMS)?;
    let view = arr.as_array();
    pose_of_view(&view).map_err(|m| PyValueError::new_err(format!("{what}: {m}")))
}

/// An optional pose argument: `None` is the identity (pyo3 passes a Python `None` given
/// explicitly as `None` too).
pub(crate) fn pose_or_identity(obj: Option<&Bound<'_, PyAny>>, what: &str) -> PyResult<Pose> {
    obj.map_or(Ok(Pose::IDENTITY), |o| pose(o, what))
}

/// A batch of poses: an `(N, 7)` or `(N, 4, 4)` array-like. `ValueError` naming the first
/// bad pose otherwise.
pub(crate) fn poses(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<Pose>> {
    const FORMS: &str = "an (N, 7) array of (tx, ty, tz, qw, qx, qy, qz) or an (N, 4, 4) array of homogeneous matrices";
    let arr = float_array(obj, what, FORMS)?;
    let view = arr.as_array();
    let ok = matches!(view.shape(), [_, 7] | [_, 4, 4]);
    if !ok {
        return Err(PyValueError::new_err(format!(
            "{what}: expected {FORMS}, got shape {}",
            shape(view.shape())
        )));
    }
    // The common case, a C-contiguous (N, 7) array, without a view per row.
    if let (Some(flat), [_, 7]) = (view.as_slice(), view.shape()) {
        return flat
            .chunks_exact(7)
            .enumerate()
            .map(|(i, c)| {
                Pose::from_array(c.try_into().expect("7 numbers"))
                    .map_err(|e| PyValueError::new_err(format!("{what}[{i}]: invalid pose: {e}")))
            })
            .collect();
    }
    view.axis_iter(Axis(0))
        .enumerate()
        .map(|(i, row)| {
            pose_of_view(&row).map_err(|m| PyValueError::new_err(format!("{what}[{i}]: {m}")))
        })
        .collect()
}

/// Body A's poses for a batch of `n`: `None` (identity), one pose for all, or `n` poses.
pub(crate) enum PosesA {
    /// The same pose on every frame.
    One(Pose),
    /// One pose per frame.
    Each(Vec<Pose>),
}

impl PosesA {
    /// Reads `pose_a` of a batch of `n` poses.
    pub(crate) fn new(obj: Option<&Bound<'_, PyAny>>, n: usize) -> PyResult<PosesA> {
        let Some(obj) = obj.filter(|o| !o.is_none()) else {
            return Ok(PosesA::One(Pose::IDENTITY));
        };
        let arr = float_array(
            obj,
            "pose_a",
            "one pose (a 4×4 matrix or 7 numbers) or one per pose of the batch",
        )?;
        // (7,) and (4, 4) are one pose; (N, 7) and (N, 4, 4) one per frame.
        let one = matches!(arr.as_array().shape(), [_] | [4, 4]);
        drop(arr);
        if one {
            return Ok(PosesA::One(pose(obj, "pose_a")?));
        }
        let all = poses(obj, "pose_a")?;
        if all.len() != n {
            return Err(PyValueError::new_err(format!(
                "pose_a: {} poses for a batch of {n}",
                all.len()
            )));
        }
        Ok(PosesA::Each(all))
    }

    /// The poses of A as the library's batches take them: one for all, or one per frame.
    pub(crate) fn as_slice(&self) -> &[Pose] {
        match self {
            PosesA::One(p) => std::slice::from_ref(p),
            PosesA::Each(v) => v,
        }
    }
}

/// A pose as a numpy array `(tx, ty, tz, qw, qx, qy, qz)`.
pub(crate) fn pose7<'py>(py: Python<'py>, p: &Pose) -> Bound<'py, PyArray1<f64>> {
    PyArray1::from_slice(py, &p.to_array())
}

/// A pose as a 4×4 numpy matrix (row-major, `m[row, col]`).
pub(crate) fn pose44<'py>(py: Python<'py>, p: &Pose) -> PyResult<Bound<'py, PyAny>> {
    let m = p.to_matrix4(MatrixOrder::RowMajor);
    Ok(PyArray1::from_slice(py, &m).reshape([4, 4])?.into_any())
}

/// A serializable value (an answer, a JSON value) as plain Python objects (dict, list, str,
/// float, int, bool, None): its JSON form, what `ist query --json` prints (vectors as lists,
/// a non-finite number as None, as JSON has it).
pub(crate) fn to_python<'py>(
    py: Python<'py>,
    v: &impl serde::Serialize,
) -> PyResult<Bound<'py, PyAny>> {
    let json = serde_json::to_value(v).map_err(|e| PyValueError::new_err(e.to_string()))?;
    pythonize::pythonize(py, &json).map_err(|e| PyValueError::new_err(e.to_string()))
}

/// An answer's serde form as a dict, with `more` (what the pair keeps beside it: patches)
/// under its own keys.
pub(crate) fn answer_dict<'py>(
    py: Python<'py>,
    answer: &impl serde::Serialize,
    more: &[(&str, Bound<'py, PyAny>)],
) -> PyResult<Bound<'py, PyDict>> {
    let d = to_python(py, answer)?.cast_into::<PyDict>()?;
    for (k, v) in more {
        d.set_item(k, v)?;
    }
    Ok(d)
}

/// Many answers of one type as columns: a dict with the keys of their serde form, each a
/// numpy array over the answers — bools as bool, integers as int64 (null as −1), other
/// numbers as float64 (null as NaN), fixed-length lists of numbers as (N, m) float64, records
/// as dicts of such columns. `zero` (any answer of the type) gives the keys and kinds when
/// there are no answers. Written here, not with pythonize, because numpy columns are what a
/// batch of thousands wants (one array per key, not a dict per answer).
pub(crate) fn columns<'py, T: serde::Serialize>(
    py: Python<'py>,
    answers: &[T],
    zero: &T,
) -> PyResult<Bound<'py, PyDict>> {
    let value = |a: &T| serde_json::to_value(a).map_err(|e| PyValueError::new_err(e.to_string()));
    let rows: Vec<serde_json::Value> = answers.iter().map(value).collect::<PyResult<_>>()?;
    let template = value(zero)?;
    let refs: Vec<&serde_json::Value> = rows.iter().collect();
    column_record(py, &refs, &template)
}

/// The columns of records (all of one type's form, `template` one of them).
fn column_record<'py>(
    py: Python<'py>,
    rows: &[&serde_json::Value],
    template: &serde_json::Value,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let Some(fields) = template.as_object() else {
        return Ok(d);
    };
    for (key, t) in fields {
        let col: Vec<&serde_json::Value> = rows
            .iter()
            .map(|r| r.get(key).unwrap_or(&serde_json::Value::Null))
            .collect();
        d.set_item(key, column(py, &col, t)?)?;
    }
    Ok(d)
}

/// One column (see [`columns`]); its kind from its values, or from `template` when empty.
fn column<'py>(
    py: Python<'py>,
    col: &[&serde_json::Value],
    template: &serde_json::Value,
) -> PyResult<Bound<'py, PyAny>> {
    use serde_json::Value;
    let n = col.len();
    let kind: Vec<&Value> = if col.is_empty() {
        vec![template]
    } else {
        col.to_vec()
    };
    let all = |f: &dyn Fn(&Value) -> bool| kind.iter().all(|v| f(v));
    if all(&Value::is_boolean) {
        let v = col.iter().map(|v| v.as_bool() == Some(true));
        return Ok(PyArray1::from_iter(py, v).into_any());
    }
    if all(&|v| v.is_i64() || v.is_u64() || v.is_null()) && !all(&Value::is_null) {
        let v = col.iter().map(|v| v.as_i64().unwrap_or(-1));
        return Ok(PyArray1::from_iter(py, v).into_any());
    }
    if all(&|v| v.is_number() || v.is_null()) {
        let v = col.iter().map(|v| v.as_f64().unwrap_or(f64::NAN));
        return Ok(PyArray1::from_iter(py, v).into_any());
    }
    let m = kind[0].as_array().map_or(0, Vec::len);
    let numbers = |v: &Value| {
        v.as_array()
            .is_some_and(|a| a.len() == m && a.iter().all(|x| x.is_number() || x.is_null()))
    };
    if m > 0 && all(&numbers) {
        let flat: Vec<f64> = col
            .iter()
            .flat_map(|v| v.as_array().into_iter().flatten())
            .map(|x| x.as_f64().unwrap_or(f64::NAN))
            .collect();
        return Ok(PyArray1::from_vec(py, flat).reshape([n, m])?.into_any());
    }
    if all(&Value::is_object) {
        return Ok(column_record(py, col, kind[0])?.into_any());
    }
    let list = PyList::empty(py);
    for v in col {
        list.append(to_python(py, v)?)?;
    }
    Ok(list.into_any())
}

/// A finite, non-negative number argument, or `ValueError`.
pub(crate) fn non_negative(x: f64, what: &str) -> PyResult<f64> {
    if x.is_finite() && x >= 0.0 {
        Ok(x)
    } else {
        Err(PyValueError::new_err(format!(
            "{what} must be a finite number ≥ 0, not {x}"
        )))
    }
}
