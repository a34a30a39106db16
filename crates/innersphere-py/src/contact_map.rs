//! `innersphere.contact_map`: the signed gap of every vertex of two meshes to the other.

use crate::convert::{error, pose_or_identity};
use crate::tree::mesh_like;
use innersphere::exact::ExactMesh;
use innersphere_dental::contact_map::ContactMap;
use numpy::PyArray1;
use pyo3::prelude::*;

/// Both meshes' per-vertex gaps (N_a,), (N_b,).
type Gaps<'py> = (Bound<'py, PyArray1<f64>>, Bound<'py, PyArray1<f64>>);

/// The contact map of meshes `a` and `b` (each a file path, a `(vertices, faces)` pair or a
/// `trimesh.Trimesh`) at `pose_b` (and `pose_a`, default the identity): per vertex of each,
/// its exact f64 distance to the other's surface, negative inside the other (as `ist
/// occlusion-map` writes in its PLYs' `gap`). Arrays keep their vertex order (not welded);
/// a file's vertices are the loader's (welded, the order of `ist occlusion-map`'s PLY).
/// `unit`: the meshes' unit (mm, cm, m, in), converted to mm; the gaps are in mm. Runs on
/// all cores with the interpreter released.
#[pyfunction]
#[pyo3(signature = (a, b, pose_b=None, pose_a=None, unit="mm"))]
pub fn contact_map<'py>(
    py: Python<'py>,
    a: &Bound<'py, PyAny>,
    b: &Bound<'py, PyAny>,
    pose_b: Option<&Bound<'py, PyAny>>,
    pose_a: Option<&Bound<'py, PyAny>>,
    unit: &str,
) -> PyResult<Gaps<'py>> {
    let pose_b = pose_or_identity(pose_b, "pose_b")?;
    let pose_a = pose_or_identity(pose_a, "pose_a")?;
    let ma = mesh_like(py, a, "a", false, unit)?;
    let mb = mesh_like(py, b, "b", false, unit)?;
    let map = py
        .detach(|| {
            let ea = ExactMesh::new(&ma)?;
            let eb = ExactMesh::new(&mb)?;
            ContactMap::new(&ea, &pose_a, &eb, &pose_b, f64::INFINITY)
        })
        .map_err(error)?;
    Ok((
        PyArray1::from_vec(py, map.gaps_a),
        PyArray1::from_vec(py, map.gaps_b),
    ))
}
