//! `innersphere.Pair` and its results: every query kind, single and batched.

use crate::convert::{
    answer_dict, columns, error, non_negative, pose, pose_or_identity, poses, to_python, PosesA,
};
use crate::results::{DistanceResult, PenetrationResult};
use crate::tree::Tree;
use innersphere::query::{BatchOptions, Paper, TraversalOptions};
use innersphere::{
    ContactResult, DistanceOptions, MultipointOptions, Penetration, PenetrationOptions, Pose,
    RefineOptions, RefinedDistance, SharedTree,
};
use numpy::{PyArray1, PyArray2, PyArrayMethods};
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::sync::{Mutex, MutexGuard, TryLockError};

/// Two trees and all per-pair state of their queries (temporal coherence, scratch memory).
///
/// Pair(tree_a, tree_b). Every query takes B's pose (pose_b) and optionally A's (pose_a=,
/// default the identity), each a 4×4 homogeneous matrix (numpy, row-major, translation in
/// the last column) or 7 numbers (tx, ty, tz, qw, qx, qy, qz), applied to the tree's model
/// coordinates (p' = R p + t); answers are in the world frame.
///
/// The pair remembers what the last queries found and starts the next from it (as a haptic
/// loop wants: consecutive poses of a motion are fast). The answers do not depend on it,
/// except that a far pair may be answered within the library's far-field tolerance; call
/// reset() (or use a new Pair) for a query from scratch, which is what `ist query` runs.
/// One thread at a time per pair (another thread's query raises RuntimeError); trees are
/// shared freely.
#[pyclass(module = "innersphere", name = "Pair", frozen)]
pub struct Pair {
    inner: Mutex<innersphere::Pair>,
    a: Py<Tree>,
    b: Py<Tree>,
}

impl Pair {
    /// A new Rust pair of the same trees.
    pub(crate) fn fresh(&self) -> innersphere::Pair {
        innersphere::Pair::new(self.a.get().shared.clone(), self.b.get().shared.clone())
    }

    /// A paper traversal `run` at the poses, the interpreter released: whether the packings
    /// overlap.
    fn traversal(
        &self,
        py: Python<'_>,
        pose_b: &Bound<'_, PyAny>,
        pose_a: Option<&Bound<'_, PyAny>>,
        run: impl FnOnce(&mut Paper<'_>, &Pose, &Pose, &TraversalOptions) -> ContactResult + Send,
    ) -> PyResult<bool> {
        let pb = pose(pose_b, "pose_b")?;
        let pa = pose_or_identity(pose_a, "pose_a")?;
        let mut guard = self.lock()?;
        let inner: &mut innersphere::Pair = &mut guard;
        let opts = TraversalOptions::default();
        Ok(py.detach(|| run(&mut inner.paper(), &pa, &pb, &opts).in_contact()))
    }

    /// The Rust pair, or a clear error while another thread's query holds it.
    fn lock(&self) -> PyResult<MutexGuard<'_, innersphere::Pair>> {
        match self.inner.try_lock() {
            Ok(g) => Ok(g),
            Err(TryLockError::Poisoned(p)) => Ok(p.into_inner()),
            Err(TryLockError::WouldBlock) => Err(PyRuntimeError::new_err(
                "this Pair is answering a query in another thread: a Pair keeps one query's \
                 state at a time; make one Pair per thread (Pairs of the same Trees share them)",
            )),
        }
    }
}

/// The stiffness argument, checked by the library as `ist query --stiffness` is.
fn stiffness_arg(stiffness: f64) -> PyResult<f64> {
    PenetrationOptions {
        stiffness,
        ..Default::default()
    }
    .check()
    .map_err(error)?;
    Ok(stiffness)
}

/// What a batch runs: the poses of B and of A, both shared trees, and the batch options of
/// `threads` (None: all cores) and `chunk`.
struct Batch {
    pb: Vec<Pose>,
    pa: PosesA,
    a: SharedTree,
    b: SharedTree,
    o: BatchOptions,
}

impl Pair {
    /// The [`Batch`] of `poses_b` (an (N, 7) or (N, 4, 4) array) and `pose_a` (None, one
    /// pose, or N) on this pair's trees.
    fn batch(
        &self,
        poses_b: &Bound<'_, PyAny>,
        pose_a: Option<&Bound<'_, PyAny>>,
        threads: Option<usize>,
        chunk: usize,
    ) -> PyResult<Batch> {
        let pb = poses(poses_b, "poses")?;
        let pa = PosesA::new(pose_a, pb.len())?;
        Ok(Batch {
            pb,
            pa,
            a: self.a.get().shared.clone(),
            b: self.b.get().shared.clone(),
            o: BatchOptions {
                threads: threads.unwrap_or(0),
                chunk,
            },
        })
    }
}

/// `n` rows of 3 as an (n, 3) float64 array.
fn rows3(py: Python<'_>, v: Vec<[f64; 3]>) -> PyResult<Bound<'_, PyArray2<f64>>> {
    let n = v.len();
    let flat: Vec<f64> = v.into_iter().flatten().collect();
    PyArray1::from_vec(py, flat).reshape([n, 3])
}

#[pymethods]
impl Pair {
    #[new]
    fn new(tree_a: Py<Tree>, tree_b: Py<Tree>) -> Pair {
        let inner =
            innersphere::Pair::new(tree_a.get().shared.clone(), tree_b.get().shared.clone());
        Pair {
            inner: Mutex::new(inner),
            a: tree_a,
            b: tree_b,
        }
    }

    /// Tree A.
    #[getter]
    fn tree_a(&self, py: Python<'_>) -> Py<Tree> {
        self.a.clone_ref(py)
    }

    /// Tree B.
    #[getter]
    fn tree_b(&self, py: Python<'_>) -> Py<Tree> {
        self.b.clone_ref(py)
    }

    /// Exact minimum distance between the two inner-sphere packings, with the closest
    /// points, as a DistanceResult (.distance, .contact, .point_a, .point_b, .normal, ...).
    /// signed=True reports minus the deepest leaf overlap instead of 0 when they overlap
    /// (slower); abs_tol / rel_tol stop once the answer is proved within that absolute /
    /// relative error.
    #[pyo3(signature = (pose_b, *, pose_a=None, signed=false, abs_tol=0.0, rel_tol=0.0))]
    fn distance(
        &self,
        py: Python<'_>,
        pose_b: &Bound<'_, PyAny>,
        pose_a: Option<&Bound<'_, PyAny>>,
        signed: bool,
        abs_tol: f64,
        rel_tol: f64,
    ) -> PyResult<DistanceResult> {
        let pb = pose(pose_b, "pose_b")?;
        let pa = pose_or_identity(pose_a, "pose_a")?;
        let opts = DistanceOptions {
            abs_tolerance: non_negative(abs_tol, "abs_tol")?,
            rel_tolerance: non_negative(rel_tol, "rel_tol")?,
            signed,
            ..Default::default()
        };
        let mut guard = self.lock()?;
        let inner: &mut innersphere::Pair = &mut guard;
        let d = py.detach(|| inner.distance_with(&pa, &pb, &opts));
        Ok(DistanceResult { d })
    }

    /// Whether the two packings overlap (first contact, from the kinetic front).
    #[pyo3(signature = (pose_b, *, pose_a=None))]
    fn contact(
        &self,
        py: Python<'_>,
        pose_b: &Bound<'_, PyAny>,
        pose_a: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<bool> {
        let pb = pose(pose_b, "pose_b")?;
        let pa = pose_or_identity(pose_a, "pose_a")?;
        let mut guard = self.lock()?;
        let inner: &mut innersphere::Pair = &mut guard;
        Ok(py.detach(|| inner.contact(&pa, &pb).in_contact()))
    }

    /// Up to k contact points (world), at most one below each pair of nodes at split_depth:
    /// a float64 array of shape (count, 3), empty when the bodies are apart. Their depths,
    /// normals and leaves are in pair.contacts until the next multipoint query.
    #[pyo3(signature = (pose_b, k=16, *, pose_a=None, split_depth=4))]
    fn multipoint<'py>(
        &self,
        py: Python<'py>,
        pose_b: &Bound<'py, PyAny>,
        k: i64,
        pose_a: Option<&Bound<'py, PyAny>>,
        split_depth: i64,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let pb = pose(pose_b, "pose_b")?;
        let pa = pose_or_identity(pose_a, "pose_a")?;
        if k < 1 {
            return Err(PyValueError::new_err(format!(
                "k must be at least 1 (the most contacts multipoint reports), not {k}"
            )));
        }
        let split_depth = u32::try_from(split_depth).map_err(|_| {
            PyValueError::new_err(format!("split_depth must be ≥ 0, not {split_depth}"))
        })?;
        let opts = MultipointOptions {
            k: k as usize,
            split_depth,
            ..Default::default()
        };
        let mut guard = self.lock()?;
        let inner: &mut innersphere::Pair = &mut guard;
        py.detach(|| inner.multipoint(&pa, &pb, &opts));
        let points = inner
            .contacts()
            .iter()
            .map(|c| c.point.to_array())
            .collect();
        rows3(py, points)
    }

    /// The contacts of the last multipoint query as a dict of arrays: point (n, 3),
    /// normal (n, 3) (from A's sphere centre to B's), depth (n,), leaf_a (n,), leaf_b (n,).
    #[getter]
    fn contacts<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let guard = self.lock()?;
        let c = guard.contacts();
        let d = PyDict::new(py);
        d.set_item(
            "point",
            rows3(py, c.iter().map(|c| c.point.to_array()).collect())?,
        )?;
        d.set_item(
            "normal",
            rows3(py, c.iter().map(|c| c.normal.to_array()).collect())?,
        )?;
        d.set_item("depth", PyArray1::from_iter(py, c.iter().map(|c| c.depth)))?;
        d.set_item(
            "leaf_a",
            PyArray1::from_iter(py, c.iter().map(|c| c.leaf_a)),
        )?;
        d.set_item(
            "leaf_b",
            PyArray1::from_iter(py, c.iter().map(|c| c.leaf_b)),
        )?;
        Ok(d)
    }

    /// Penetration volume with the contact normal, the penalty force (stiffness × volume, on
    /// B), the torques about both centres of mass and up to max_patches contact patches, as
    /// a PenetrationResult (.volume, .max_depth, .normal, .force, .torque_a, .torque_b,
    /// .patches, ...).
    #[pyo3(signature = (pose_b, stiffness=1.0, *, pose_a=None, max_patches=8))]
    fn penetration(
        &self,
        py: Python<'_>,
        pose_b: &Bound<'_, PyAny>,
        stiffness: f64,
        pose_a: Option<&Bound<'_, PyAny>>,
        max_patches: i64,
    ) -> PyResult<PenetrationResult> {
        let pb = pose(pose_b, "pose_b")?;
        let pa = pose_or_identity(pose_a, "pose_a")?;
        let max_patches = usize::try_from(max_patches).map_err(|_| {
            PyValueError::new_err(format!("max_patches must be ≥ 0, not {max_patches}"))
        })?;
        let opts = PenetrationOptions {
            stiffness: stiffness_arg(stiffness)?,
            max_patches,
            ..Default::default()
        };
        let mut guard = self.lock()?;
        let inner: &mut innersphere::Pair = &mut guard;
        let p = py.detach(|| inner.penetration_with(&pa, &pb, &opts));
        Ok(PenetrationResult {
            p,
            patches: inner.patches().to_vec(),
        })
    }

    /// Time-critical penetration volume: refines the largest overlaps first for at most
    /// budget node-pair tests (about 75 ns each). Returns the answer's serde form as a dict
    /// (`ist query --json --query penetration-within` without its budget): volume (found),
    /// upper_bound (proved), complete (the volume is exact), max_depth, normal, force and
    /// torque_b on B (of the pairs found and, when the budget ran out, the unrefined node
    /// pairs as their bounds), area, stiffness, visits.
    #[pyo3(signature = (pose_b, budget=8000, stiffness=1.0, *, pose_a=None))]
    fn penetration_within<'py>(
        &self,
        py: Python<'py>,
        pose_b: &Bound<'py, PyAny>,
        budget: u64,
        stiffness: f64,
        pose_a: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let pb = pose(pose_b, "pose_b")?;
        let pa = pose_or_identity(pose_a, "pose_a")?;
        let opts = PenetrationOptions {
            stiffness: stiffness_arg(stiffness)?,
            ..Default::default()
        };
        let mut guard = self.lock()?;
        let inner: &mut innersphere::Pair = &mut guard;
        let w = py.detach(|| inner.penetration_within_with(&pa, &pb, budget, &opts));
        answer_dict(py, &w, &[])
    }

    /// The distance between the meshes: the sphere distance refined by the exact distance of
    /// the triangles near its closest points (never below the exact mesh distance, never
    /// above the sphere distance). Both trees need their meshes (Tree.with_mesh): ValueError
    /// otherwise. Returns the answer's serde form as a dict (`ist query --json
    /// --query refined-distance`): distance, contact, refined, complete, point_a, point_b,
    /// triangle_a, triangle_b (None unless refined), radius, node_pairs, triangle_pairs and
    /// spheres (the sphere distance, as DistanceResult.to_dict()).
    #[pyo3(signature = (pose_b, *, pose_a=None, radius_scale=0.5, rel_tol=1e-3, max_node_pairs=4096))]
    fn refined_distance<'py>(
        &self,
        py: Python<'py>,
        pose_b: &Bound<'py, PyAny>,
        pose_a: Option<&Bound<'py, PyAny>>,
        radius_scale: f64,
        rel_tol: f64,
        max_node_pairs: u64,
    ) -> PyResult<Bound<'py, PyDict>> {
        let pb = pose(pose_b, "pose_b")?;
        let pa = pose_or_identity(pose_a, "pose_a")?;
        let opts = RefineOptions {
            radius_scale,
            rel_tolerance: rel_tol,
            max_node_pairs,
            ..Default::default()
        };
        let mut guard = self.lock()?;
        let inner: &mut innersphere::Pair = &mut guard;
        let r = py
            .detach(|| inner.refined_distance_with(&pa, &pb, &opts))
            .map_err(error)?;
        answer_dict(py, &r, &[])
    }

    /// The penetration of the meshes themselves: the exact volume of the intersection of the
    /// two solids, with the penalty force (stiffness × volume along the direction that loses
    /// overlap fastest) and the torques from its exact gradient. Both trees need their
    /// meshes (Tree.with_mesh): ValueError otherwise. Returns the answer's serde form as a
    /// dict (`ist query --json --query mesh-penetration`): contact, volume, normal, force,
    /// torque_a, torque_b, gradient, rotation_gradient, area, max_depth, patch_count,
    /// stiffness, crossing_pairs, and the max_patches largest patches (the intersection's
    /// connected pieces: point, normal, depth, volume, pairs) as patches.
    #[pyo3(signature = (pose_b, *, pose_a=None, stiffness=1.0, max_patches=8))]
    fn mesh_penetration<'py>(
        &self,
        py: Python<'py>,
        pose_b: &Bound<'py, PyAny>,
        pose_a: Option<&Bound<'py, PyAny>>,
        stiffness: f64,
        max_patches: i64,
    ) -> PyResult<Bound<'py, PyDict>> {
        let pb = pose(pose_b, "pose_b")?;
        let pa = pose_or_identity(pose_a, "pose_a")?;
        let max_patches = usize::try_from(max_patches).map_err(|_| {
            PyValueError::new_err(format!("max_patches must be ≥ 0, not {max_patches}"))
        })?;
        let opts = PenetrationOptions {
            stiffness: stiffness_arg(stiffness)?,
            max_patches,
            ..Default::default()
        };
        let mut guard = self.lock()?;
        let inner: &mut innersphere::Pair = &mut guard;
        let m = py
            .detach(|| inner.mesh_penetration_with(&pa, &pb, &opts))
            .map_err(error)?;
        let patches = to_python(py, &inner.patches())?;
        answer_dict(py, &m, &[("patches", patches)])
    }

    /// The paper's distance traversal (its first-contact baseline): whether the packings
    /// overlap, as contact() answers.
    #[pyo3(signature = (pose_b, *, pose_a=None))]
    fn distance_traversal(
        &self,
        py: Python<'_>,
        pose_b: &Bound<'_, PyAny>,
        pose_a: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<bool> {
        self.traversal(py, pose_b, pose_a, |p, a, b, o| {
            p.distance_traversal(a, b, o)
        })
    }

    /// The paper's backtracking traversal (from this pair's previous contact; on a new or
    /// reset pair the distance traversal): whether the packings overlap.
    #[pyo3(signature = (pose_b, *, pose_a=None))]
    fn backtracking(
        &self,
        py: Python<'_>,
        pose_b: &Bound<'_, PyAny>,
        pose_a: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<bool> {
        self.traversal(py, pose_b, pose_a, |p, a, b, o| p.backtracking(a, b, o))
    }

    /// Forgets all temporal coherence (last contacts, closest pair, proved separation,
    /// fronts): the next query starts from scratch, as `ist query` does. Keeps the memory.
    fn reset(&self) -> PyResult<()> {
        self.lock()?.reset();
        Ok(())
    }

    /// Pair.distance for each pose of B in poses, an (N, 7) or (N, 4, 4) array, in order, on
    /// `threads` threads (None: all cores). The poses are cut into chunks of `chunk`; each
    /// chunk starts from a fresh state and carries it from pose to pose (as `ist replay`
    /// does), so the answers never depend on `threads` (on a new pair and a batch of at most
    /// `chunk` poses they are `distance` pose after pose). This pair's own state is neither
    /// used nor changed. pose_a: None (identity), one pose, or N poses. Returns the (N,)
    /// float64 distances (0 where the packings overlap). The interpreter is released.
    #[pyo3(signature = (poses, *, pose_a=None, threads=None, chunk=1024))]
    fn distance_many<'py>(
        &self,
        py: Python<'py>,
        poses: &Bound<'py, PyAny>,
        pose_a: Option<&Bound<'py, PyAny>>,
        threads: Option<usize>,
        chunk: usize,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let Batch { pb, pa, a, b, o } = self.batch(poses, pose_a, threads, chunk)?;
        let out = py
            .detach(|| innersphere::query::batch::distance_many(&a, &b, pa.as_slice(), &pb, &o))
            .map_err(error)?;
        Ok(PyArray1::from_iter(py, out.iter().map(|d| d.distance)))
    }

    /// Pair.refined_distance for each pose of B (an (N, 7) or (N, 4, 4) array), in order,
    /// on `threads` threads in chunks of `chunk` as distance_many. Both trees need their
    /// meshes (Tree.with_mesh): ValueError otherwise, or for bad options, before any query.
    /// Returns the keys of refined_distance as numpy columns over the poses (convert::columns:
    /// triangle_a and triangle_b int64, −1 unless refined; spheres a dict of columns).
    /// Interpreter released.
    #[pyo3(signature = (poses, *, pose_a=None, threads=None, chunk=1024, radius_scale=0.5, rel_tol=1e-3, max_node_pairs=4096))]
    #[allow(clippy::too_many_arguments)]
    fn refined_distance_many<'py>(
        &self,
        py: Python<'py>,
        poses: &Bound<'py, PyAny>,
        pose_a: Option<&Bound<'py, PyAny>>,
        threads: Option<usize>,
        chunk: usize,
        radius_scale: f64,
        rel_tol: f64,
        max_node_pairs: u64,
    ) -> PyResult<Bound<'py, PyDict>> {
        let Batch { pb, pa, a, b, o } = self.batch(poses, pose_a, threads, chunk)?;
        let query = RefineOptions {
            radius_scale,
            rel_tolerance: rel_tol,
            max_node_pairs,
            ..Default::default()
        };
        let out: Vec<RefinedDistance> = py
            .detach(|| {
                innersphere::query::batch::refined_distance_many(
                    &a,
                    &b,
                    pa.as_slice(),
                    &pb,
                    &query,
                    &o,
                )
            })
            .map_err(error)?;
        columns(py, &out, &Default::default())
    }

    /// Pair.contact for each pose of B (an (N, 7) or (N, 4, 4) array), in order, on
    /// `threads` threads in chunks of `chunk` as distance_many: an (N,) bool array.
    #[pyo3(signature = (poses, *, pose_a=None, threads=None, chunk=1024))]
    fn contact_many<'py>(
        &self,
        py: Python<'py>,
        poses: &Bound<'py, PyAny>,
        pose_a: Option<&Bound<'py, PyAny>>,
        threads: Option<usize>,
        chunk: usize,
    ) -> PyResult<Bound<'py, PyArray1<bool>>> {
        let Batch { pb, pa, a, b, o } = self.batch(poses, pose_a, threads, chunk)?;
        let out = py
            .detach(|| innersphere::query::batch::contact_many(&a, &b, pa.as_slice(), &pb, &o))
            .map_err(error)?;
        Ok(PyArray1::from_iter(py, out.iter().map(|c| c.in_contact())))
    }

    /// Pair.penetration for each pose of B (an (N, 7) or (N, 4, 4) array), in order, on
    /// `threads` threads in chunks of `chunk` as distance_many (on a new pair and a batch of
    /// at most `chunk` poses the volumes equal `ist replay --query penetration`'s). Returns the
    /// keys of PenetrationResult.to_dict() but the patches as numpy columns over the poses
    /// (convert::columns: vectors (N, 3), pairs int64, contact bool). Interpreter released.
    #[pyo3(signature = (poses, stiffness=1.0, *, pose_a=None, threads=None, chunk=1024))]
    fn penetration_many<'py>(
        &self,
        py: Python<'py>,
        poses: &Bound<'py, PyAny>,
        stiffness: f64,
        pose_a: Option<&Bound<'py, PyAny>>,
        threads: Option<usize>,
        chunk: usize,
    ) -> PyResult<Bound<'py, PyDict>> {
        let Batch { pb, pa, a, b, o } = self.batch(poses, pose_a, threads, chunk)?;
        let query = PenetrationOptions {
            stiffness: stiffness_arg(stiffness)?,
            ..Default::default()
        };
        let out: Vec<Penetration> = py
            .detach(|| {
                innersphere::query::batch::penetration_many(&a, &b, pa.as_slice(), &pb, &query, &o)
            })
            .map_err(error)?;
        columns(py, &out, &Default::default())
    }

    /// Pair.mesh_penetration for each pose of B (an (N, 7) or (N, 4, 4) array), in order, on
    /// `threads` threads in chunks of `chunk` as distance_many. Both trees need their meshes
    /// (Tree.with_mesh): ValueError otherwise, or for a bad stiffness, before any query.
    /// Returns the keys of mesh_penetration but the patches as numpy columns over the poses
    /// (convert::columns). Interpreter released.
    #[pyo3(signature = (poses, stiffness=1.0, *, pose_a=None, threads=None, chunk=1024))]
    fn mesh_penetration_many<'py>(
        &self,
        py: Python<'py>,
        poses: &Bound<'py, PyAny>,
        stiffness: f64,
        pose_a: Option<&Bound<'py, PyAny>>,
        threads: Option<usize>,
        chunk: usize,
    ) -> PyResult<Bound<'py, PyDict>> {
        let Batch { pb, pa, a, b, o } = self.batch(poses, pose_a, threads, chunk)?;
        let query = PenetrationOptions {
            stiffness: stiffness_arg(stiffness)?,
            ..Default::default()
        };
        let out: Vec<innersphere::MeshPenetration> = py
            .detach(|| {
                innersphere::query::batch::mesh_penetration_many(
                    &a,
                    &b,
                    pa.as_slice(),
                    &pb,
                    &query,
                    &o,
                )
            })
            .map_err(error)?;
        columns(py, &out, &Default::default())
    }

    fn __repr__(&self, py: Python<'_>) -> String {
        let (a, b) = (self.a.bind(py).get(), self.b.bind(py).get());
        format!(
            "Pair(tree_a=Tree(node_count={}), tree_b=Tree(node_count={}))",
            a.shared.len(),
            b.shared.len()
        )
    }
}
