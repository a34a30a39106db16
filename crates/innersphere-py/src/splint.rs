//! `innersphere.splint`: the occlusal splint between two arches, as `ist splint` makes it.

use crate::convert::{self, error, pose_or_identity, to_python};
use crate::tree::mesh_like;
use innersphere_dental::splint::{make_opened, Opening, SplintOptions};
use numpy::{PyArray1, PyArray2, PyArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

/// Vertices (n, 3), faces (m, 3) and the measurements.
type SplintOut<'py> = (
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<u32>>,
    Bound<'py, PyAny>,
);

/// The occlusal splint (surgical wafer) between arch `a` (upper, fixed) and arch `b` at
/// `pose_b` (default the identity), each a file path, a `(vertices, faces)` pair or a
/// `trimesh.Trimesh`: the vertices and faces of its closed, outward-facing surface in A's
/// frame and a dict of its measurements (the JSON of `ist splint`, with `opened` and
/// `pose`). `open`: an incisal opening about the hinge (mm) applied after the pose, or
/// "auto" for the least that leaves room for the wafer. Options default as in `ist splint`
/// (`max_triangles`: simplified down to it; 0 for as extracted).
/// `unit`: the meshes' unit (mm, cm, m, in), converted to mm; the wafer is in mm.
/// A wafer that fails one of its guarantees (the report's `checks`) raises ValueError
/// unless `keep_unfit` (then it is returned, and written, with `fit` false).
/// `out`: also write it there, as binary STL (`.stl`), OBJ (`.obj`; either compressed when the
/// name ends in `.gz`) or 3MF (`.3mf`); another name is refused before the work. Runs on all cores with the interpreter
/// released.
#[pyfunction]
#[pyo3(signature = (a, b, pose_b=None, open=None, clearance=None, coverage=None,
                    min_thickness=None, rim=None, voxel=None, max_triangles=None, out=None,
                    keep_unfit=false,
                    unit="mm"))]
#[allow(clippy::too_many_arguments)]
pub fn splint<'py>(
    py: Python<'py>,
    a: &Bound<'py, PyAny>,
    b: &Bound<'py, PyAny>,
    pose_b: Option<&Bound<'py, PyAny>>,
    open: Option<&Bound<'py, PyAny>>,
    clearance: Option<f64>,
    coverage: Option<f64>,
    min_thickness: Option<f64>,
    rim: Option<f64>,
    voxel: Option<f64>,
    max_triangles: Option<usize>,
    out: Option<&Bound<'py, PyAny>>,
    keep_unfit: bool,
    unit: &str,
) -> PyResult<SplintOut<'py>> {
    let pose = pose_or_identity(pose_b, "pose_b")?;
    let d = SplintOptions::default();
    let opts = SplintOptions {
        clearance: clearance.unwrap_or(d.clearance),
        coverage: coverage.unwrap_or(d.coverage),
        min_thickness: min_thickness.unwrap_or(d.min_thickness),
        rim: rim.unwrap_or(d.rim),
        voxel: voxel.unwrap_or(d.voxel),
        max_triangles: max_triangles.unwrap_or(d.max_triangles),
    };
    opts.validate().map_err(error)?;
    let opening = match open {
        None => Opening::By(0.0),
        Some(o) if o.extract::<String>().is_ok_and(|s| s == "auto") => Opening::Auto,
        Some(o) => Opening::By(o.extract::<f64>().map_err(|_| {
            PyValueError::new_err("open: expected a number of millimetres or \"auto\"")
        })?),
    };
    let out = out.map(convert::path).transpose()?;
    if let Some(p) = &out {
        // Before the work: a name that promises another format, or a folder that is missing.
        innersphere_dental::splint::threemf::WAFER_FILE
            .check(p)
            .map_err(error)?;
        innersphere::output::ensure_folder_writable(p).map_err(error)?;
    }
    let ma = mesh_like(py, a, "a", false, unit)?;
    let mb = mesh_like(py, b, "b", false, unit)?;
    let s = py
        .detach(|| -> innersphere::Result<_> {
            let s = make_opened(&ma, &mb, &pose, opening, &opts)?;
            if let Some(p) = out.as_ref().filter(|_| s.report.fit || keep_unfit) {
                innersphere_dental::splint::threemf::save_wafer(&s.mesh, p)?;
            }
            Ok(s)
        })
        .map_err(error)?;
    if !(s.report.fit || keep_unfit) {
        let failed: Vec<String> = s
            .report
            .checks
            .iter()
            .filter(|c| !c.ok)
            .map(|c| format!("{}: {}", c.name, c.detail))
            .collect();
        return Err(PyValueError::new_err(format!(
            "the wafer is not fit to print ({}); keep_unfit=True returns it for inspection",
            failed.join("; ")
        )));
    }
    let report =
        serde_json::to_value(&s.report).map_err(|e| PyValueError::new_err(e.to_string()))?;
    let n = s.mesh.vertices.len();
    let m = s.mesh.triangles.len();
    let v: Vec<f64> = s.mesh.vertices.iter().flat_map(|p| p.to_array()).collect();
    let f: Vec<u32> = s.mesh.triangles.iter().flatten().copied().collect();
    Ok((
        PyArray1::from_vec(py, v).reshape([n, 3])?,
        PyArray1::from_vec(py, f).reshape([m, 3])?,
        to_python(py, &report)?,
    ))
}
