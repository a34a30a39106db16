//! `innersphere.arch_pair`: the library's generated dental arch pairs, so that a script (and
//! the tests) can try the planning tools on arches with roots or with bone without scans.

use numpy::{PyArray1, PyArray2, PyArrayMethods};
use pyo3::prelude::*;

/// One mesh as (vertices (n, 3), faces (m, 3)).
type Arrays<'py> = (Bound<'py, PyArray2<f64>>, Bound<'py, PyArray2<u32>>);

fn arrays<'py>(py: Python<'py>, m: &innersphere::Mesh) -> PyResult<Arrays<'py>> {
    let v: Vec<f64> = m.vertices.iter().flat_map(|p| p.to_array()).collect();
    let f: Vec<u32> = m.triangles.iter().flatten().copied().collect();
    Ok((
        PyArray1::from_vec(py, v).reshape([m.vertices.len(), 3])?,
        PyArray1::from_vec(py, f).reshape([m.triangles.len(), 3])?,
    ))
}

/// A generated arch pair in mm, (upper, lower), each (vertices, faces): `teeth` molar-like
/// teeth per arch (2..=16) with roots, interlocking at the identity like a bite
/// (`innersphere::shapes::arch_pair`); with `bone`, the same teeth standing in a solid
/// horseshoe of bone, each arch one closed surface (`shapes::arch_pair_with_bone`, about
/// 0.5 M triangles per arch).
#[pyfunction]
#[pyo3(signature = (teeth=12, bone=false))]
pub fn arch_pair<'py>(
    py: Python<'py>,
    teeth: usize,
    bone: bool,
) -> PyResult<(Arrays<'py>, Arrays<'py>)> {
    let teeth = teeth.clamp(2, 16);
    let (a, b) = py.detach(|| {
        if bone {
            innersphere::shapes::arch_pair_with_bone(3, teeth)
        } else {
            innersphere::shapes::arch_pair(3, teeth)
        }
    });
    Ok((arrays(py, &a)?, arrays(py, &b)?))
}
