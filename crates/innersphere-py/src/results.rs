//! The result objects of single queries (`DistanceResult`, `PenetrationResult`) and what
//! every result object shares: its attributes are the fields of the answer's serde form (the
//! keys `ist query --json` prints), vectors as float64 arrays; `to_dict()` is that form as
//! plain Python values.

use crate::convert::{answer_dict, to_python};
use innersphere::{Distance, Patch, Penetration};
use pyo3::exceptions::PyAttributeError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

/// Attribute `name` of a result whose dict is `d`: the value under that key, lists of numbers
/// as float64 arrays (recursively in lists and dicts), or `AttributeError`.
pub(crate) fn attribute<'py>(
    d: &Bound<'py, PyDict>,
    class: &str,
    name: &str,
) -> PyResult<Bound<'py, PyAny>> {
    match d.get_item(name)? {
        Some(v) => arrays(v),
        None => Err(PyAttributeError::new_err(format!(
            "'{class}' object has no attribute '{name}'"
        ))),
    }
}

/// The attribute names of a result whose dict is `d`, sorted (for `dir()` and completion).
pub(crate) fn attribute_names(d: &Bound<'_, PyDict>) -> PyResult<Vec<String>> {
    let mut names: Vec<String> = d.keys().extract()?;
    names.extend(["to_dict".to_string()]);
    names.sort();
    Ok(names)
}

/// `v` with every list of numbers turned into a float64 array.
fn arrays(v: Bound<'_, PyAny>) -> PyResult<Bound<'_, PyAny>> {
    let py = v.py();
    if let Ok(list) = v.cast::<PyList>() {
        let numbers = !list.is_empty()
            && list.iter().all(|x| {
                (x.extract::<f64>().is_ok()) && !x.is_instance_of::<pyo3::types::PyBool>()
            });
        if numbers {
            let xs: Vec<f64> = list.extract()?;
            return Ok(numpy::PyArray1::from_vec(py, xs).into_any());
        }
        let out = PyList::empty(py);
        for x in list.iter() {
            out.append(arrays(x)?)?;
        }
        return Ok(out.into_any());
    }
    if let Ok(d) = v.cast::<PyDict>() {
        let out = PyDict::new(py);
        for (k, x) in d.iter() {
            out.set_item(k, arrays(x)?)?;
        }
        return Ok(out.into_any());
    }
    Ok(v)
}

/// The answer of Pair.distance: the exact minimum distance between the two inner-sphere
/// packings, with the closest points (world frame). Attributes: distance, contact,
/// lower_bound, pair_distance, point_a (3,), point_b (3,), normal (3,), leaf_a, leaf_b,
/// visits — the fields of `ist query --json --query distance`.
#[pyclass(module = "innersphere", name = "DistanceResult", frozen)]
pub struct DistanceResult {
    pub(crate) d: Distance,
}

#[pymethods]
impl DistanceResult {
    /// The answer as a dict: its serde form, the keys and values of `ist query --json
    /// --query distance` (vectors as lists).
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        answer_dict(py, &self.d, &[])
    }
    fn __getattr__<'py>(&self, py: Python<'py>, name: &str) -> PyResult<Bound<'py, PyAny>> {
        attribute(&self.to_dict(py)?, "DistanceResult", name)
    }
    fn __dir__(&self, py: Python<'_>) -> PyResult<Vec<String>> {
        attribute_names(&self.to_dict(py)?)
    }
    fn __repr__(&self) -> String {
        format!(
            "DistanceResult(distance={}, contact={}, point_a={:?}, point_b={:?})",
            self.d.distance,
            if self.d.overlapping { "True" } else { "False" },
            self.d.point_a.to_array(),
            self.d.point_b.to_array()
        )
    }
}

/// The answer of Pair.penetration: the penetration volume (the volume of the intersection of
/// the two sphere unions, exact), the penalty force and torques, the contact patches.
/// Attributes: contact, volume, pairs, max_depth, normal (3,), force (3,) on B, torque_a (3,),
/// torque_b (3,), patch_count, area, stiffness, distance, visits, skipped, and patches (a list
/// of dicts: point, normal, depth, volume, pairs) — the fields of `ist query --json --query
/// penetration`.
#[pyclass(module = "innersphere", name = "PenetrationResult", frozen)]
pub struct PenetrationResult {
    pub(crate) p: Penetration,
    pub(crate) patches: Vec<Patch>,
}

#[pymethods]
impl PenetrationResult {
    /// The answer as a dict: its serde form and the patches, the keys and values of `ist
    /// query --json --query penetration` (vectors as lists).
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        answer_dict(py, &self.p, &[("patches", to_python(py, &self.patches)?)])
    }
    fn __getattr__<'py>(&self, py: Python<'py>, name: &str) -> PyResult<Bound<'py, PyAny>> {
        attribute(&self.to_dict(py)?, "PenetrationResult", name)
    }
    fn __dir__(&self, py: Python<'_>) -> PyResult<Vec<String>> {
        attribute_names(&self.to_dict(py)?)
    }
    fn __repr__(&self) -> String {
        format!(
            "PenetrationResult(volume={}, max_depth={}, force={:?}, patches={})",
            self.p.volume,
            self.p.max_depth,
            self.p.force.to_array(),
            self.patches.len()
        )
    }
}
