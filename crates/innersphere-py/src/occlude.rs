//! `innersphere.occlude`: the bite of a jaw pair, as `ist occlude` finds it.

use crate::convert::{error, pose, pose_or_identity, to_python};
use crate::tree::Tree;
use innersphere::glam::DVec3;
use innersphere_dental::{bite, BiteOptions};
use pyo3::prelude::*;

/// B (`tree_b`: the lower jaw, or a free cut segment; built by this version, so that it
/// holds its mass properties) closed onto A (`tree_a`, fixed at the identity) from
/// `from_pose` (B's pose in A's frame, 7 numbers or a 4×4 matrix) under `force` N along
/// `axis` (default the pair's occlusal "up"), with B's temporomandibular joints held where
/// they are with B at `reference` (default the identity: a pair scanned in occlusion), or,
/// with `free=True`, no joints and `starts` closings spread within `spread` mm (yaw: twice
/// that in degrees) from `seed`, the rest poses ranked. Returns `ist occlude --json`'s dict
/// (less its wall time and landmarks): `pose` (7 numbers), `status` (`"converged"` only at
/// rest in contact; `"no_contact"`, `"time_limit"`, `"passed_through"`, `"escaped"`),
/// `converged` (status is converged), `steps`, `seconds`, `volume`, `max_depth`, `patches`,
/// `axis`, `force`, `contact_stiffness`, `contact`, `joints`, `frame`, `candidates`,
/// `closings` (free: the closings per status). `contact="mesh"` rests B on the meshes' own
/// contact (both trees need their meshes: Tree.with_mesh). Options default and are limited as in `ist occlude`; what
/// cannot make a bite (options out of range, arches that do not face each other, a start
/// far open, beside A, beyond it or turned) raises ValueError. Runs with the interpreter
/// released (free: on all cores).
#[pyfunction]
#[pyo3(signature = (tree_a, tree_b, from_pose, *, free=false, axis=None, force=None,
                    contact_stiffness=None, max_seconds=None, reference=None,
                    joint_stiffness=None, starts=None, spread=None, seed=None,
                    contact="spheres"))]
#[allow(clippy::too_many_arguments)]
pub fn occlude<'py>(
    py: Python<'py>,
    tree_a: &Bound<'py, Tree>,
    tree_b: &Bound<'py, Tree>,
    from_pose: &Bound<'py, PyAny>,
    free: bool,
    axis: Option<[f64; 3]>,
    force: Option<f64>,
    contact_stiffness: Option<f64>,
    max_seconds: Option<f64>,
    reference: Option<&Bound<'py, PyAny>>,
    joint_stiffness: Option<f64>,
    starts: Option<usize>,
    spread: Option<f64>,
    seed: Option<u64>,
    contact: &str,
) -> PyResult<Bound<'py, PyAny>> {
    let from = pose(from_pose, "from_pose")?;
    let d = BiteOptions::default();
    let opts = BiteOptions {
        axis: axis.map(DVec3::from_array),
        force: force.unwrap_or(d.force),
        contact_stiffness,
        max_seconds: max_seconds.unwrap_or(d.max_seconds),
        reference: pose_or_identity(reference, "reference")?,
        joint_stiffness: joint_stiffness.unwrap_or(d.joint_stiffness),
        free,
        starts: starts.unwrap_or(d.starts),
        spread: spread.unwrap_or(d.spread),
        seed: seed.unwrap_or(d.seed),
        contact: contact.parse().map_err(error)?,
    };
    let (a, b) = (tree_a.get().shared.clone(), tree_b.get().shared.clone());
    let found = py.detach(|| bite(&a, &b, &from, &opts)).map_err(error)?;
    to_python(py, &found.to_json())
}
