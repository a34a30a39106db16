//! `innersphere.plan`: one case file run from the scans to the wafers and a report, as
//! `ist plan` runs it.

use crate::convert::{self, error, to_python};
use innersphere::build::BuildCache;
use innersphere::progress::Silent;
use innersphere_dental::case::{self, Case, PlanEnv};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

/// Runs the case file `case` (JSON, docs/PLAN.md; paths relative to it) into the folder
/// `out` (new, empty or a previous plan's): the contact map's PLYs, each fit wafer's STL and 3MF,
/// `report.html` and `case.json`, the same files as `ist plan` writes. Returns the plan as
/// a dict (the JSON of `ist plan --json`). `cache`: the build cache's folder (default the
/// platform's, as `ist`; `False` for none). Runs on all cores with the interpreter released.
/// Raises OSError for unreadable or unwritable files and ValueError for a case that cannot
/// be planned (with the reason); a wafer that fails a guarantee is in the dict with `fit`
/// false and no file, one that cannot be made with `report` None and its `error`.
#[pyfunction]
#[pyo3(signature = (case, out, cache=None))]
pub fn plan<'py>(
    py: Python<'py>,
    case: &Bound<'py, PyAny>,
    out: &Bound<'py, PyAny>,
    cache: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyAny>> {
    let case_path = convert::path(case)?;
    let out = convert::path(out)?;
    let cache = match cache {
        Some(c) if c.extract::<bool>().is_ok_and(|b| !b) => None,
        Some(c) => Some(convert::path(c)?),
        None => BuildCache::default_dir(),
    }
    .map(|d| BuildCache::new(d, innersphere::build::cache::DEFAULT_MAX_BYTES))
    .filter(|c| c.prepare().is_ok());
    let case = Case::load(&case_path).map_err(error)?;
    case::check_folder(&out).map_err(error)?;
    let planned = py
        .detach(|| -> innersphere::Result<_> {
            let planned = case::run(&case, &PlanEnv { cache }, &Silent)?;
            case::write(&planned, &out, &case::utc_stamp())?;
            Ok(planned)
        })
        .map_err(error)?;
    let value =
        serde_json::to_value(&planned.plan).map_err(|e| PyValueError::new_err(e.to_string()))?;
    to_python(py, &value)
}
