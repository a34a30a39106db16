//! Pairs and their queries. Nothing here allocates after a pair's first query of a kind
//! (multipoint: with the same or a smaller k).

use crate::error::{pointer, status, Fail};
use crate::tree::ist_tree;
use crate::types::{
    ist_budgeted_result, ist_contact_point, ist_distance_result, ist_mesh_penetration_result,
    ist_patch, ist_penetration_result, ist_pose, ist_refine_options, ist_refined_distance_result,
};
use crate::{mutable, reference};
use innersphere::query::{Paper, TraversalOptions};
use innersphere::{MultipointOptions, Pair, PenetrationOptions, Pose, RefineOptions};
use std::ffi::c_int;

/// A pair of trees with the temporal coherence of one motion (opaque; one thread at a time).
pub struct ist_pair {
    pub(crate) pair: Pair,
}

/// A new pair of trees `a` (body A) and `b` (body B). NULL on error.
///
/// # Safety
/// `a` and `b` are NULL or live trees.
#[no_mangle]
pub unsafe extern "C" fn ist_pair_new(a: *const ist_tree, b: *const ist_tree) -> *mut ist_pair {
    pointer(|| {
        let a = unsafe { reference(a, "a") }?;
        let b = unsafe { reference(b, "b") }?;
        Ok(Box::new(ist_pair {
            pair: Pair::new(a.tree.clone(), b.tree.clone()),
        }))
    })
}

/// Frees a pair (NULL is accepted).
///
/// # Safety
/// `pair` is NULL or from ist_pair_new, not freed before.
#[no_mangle]
pub unsafe extern "C" fn ist_pair_free(pair: *mut ist_pair) {
    if !pair.is_null() {
        let _ = std::panic::catch_unwind(|| drop(unsafe { Box::from_raw(pair) }));
    }
}

/// Forgets the pair's temporal coherence (call between unrelated motions).
///
/// # Safety
/// `pair` is NULL or a live pair.
#[no_mangle]
pub unsafe extern "C" fn ist_pair_reset(pair: *mut ist_pair) -> c_int {
    status(|| {
        unsafe { mutable(pair, "pair") }?.pair.reset();
        Ok(())
    })
}

unsafe fn args<'a>(
    pair: *mut ist_pair,
    pose_a: *const ist_pose,
    pose_b: *const ist_pose,
) -> Result<(&'a mut Pair, Pose, Pose), Fail> {
    let p = unsafe { mutable(pair, "pair") }?;
    let a = unsafe { reference(pose_a, "pose_a") }?.to_pose()?;
    let b = unsafe { reference(pose_b, "pose_b") }?.to_pose()?;
    Ok((&mut p.pair, a, b))
}

/// Exact distance between the two sphere packings with the closest points (world frame).
///
/// # Safety
/// Every pointer is NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn ist_distance(
    pair: *mut ist_pair,
    pose_a: *const ist_pose,
    pose_b: *const ist_pose,
    out: *mut ist_distance_result,
) -> c_int {
    status(|| {
        let (pair, a, b) = unsafe { args(pair, pose_a, pose_b) }?;
        let out = unsafe { mutable(out, "out") }?;
        let d = pair.distance(&a, &b);
        *out = ist_distance_result {
            distance: d.distance,
            contact: d.overlapping as c_int,
            point_a: d.point_a.to_array(),
            point_b: d.point_b.to_array(),
        };
        Ok(())
    })
}

/// The library's default options of ist_refined_distance.
#[no_mangle]
pub extern "C" fn ist_refine_options_default() -> ist_refine_options {
    let o = RefineOptions::default();
    ist_refine_options {
        radius_scale: o.radius_scale,
        margin: o.margin,
        rel_tolerance: o.rel_tolerance,
        max_node_pairs: o.max_node_pairs,
    }
}

/// The distance between the meshes, refined from the sphere distance by the exact distance
/// of the triangles near its closest points (world frame). Both trees need their meshes
/// (ist_tree_with_mesh): IST_ERR_INVALID_ARGUMENT otherwise. `opts` NULL: the defaults.
///
/// # Safety
/// Every pointer but `opts` is NULL or valid; `opts` is NULL or points to options.
#[no_mangle]
pub unsafe extern "C" fn ist_refined_distance(
    pair: *mut ist_pair,
    pose_a: *const ist_pose,
    pose_b: *const ist_pose,
    opts: *const ist_refine_options,
    out: *mut ist_refined_distance_result,
) -> c_int {
    status(|| {
        let (pair, a, b) = unsafe { args(pair, pose_a, pose_b) }?;
        let out = unsafe { mutable(out, "out") }?;
        let o = unsafe { ist_refine_options::read(opts) };
        *out = ist_refined_distance_result::from(&pair.refined_distance_with(&a, &b, &o)?);
        Ok(())
    })
}

/// First contact: `*in_contact` = 1 when the packings overlap, else 0.
///
/// # Safety
/// Every pointer is NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn ist_contact(
    pair: *mut ist_pair,
    pose_a: *const ist_pose,
    pose_b: *const ist_pose,
    in_contact: *mut c_int,
) -> c_int {
    status(|| {
        let (pair, a, b) = unsafe { args(pair, pose_a, pose_b) }?;
        let out = unsafe { mutable(in_contact, "in_contact") }?;
        *out = pair.contact(&a, &b).contact.is_some() as c_int;
        Ok(())
    })
}

/// The paper's distance traversal (its first-contact baseline): `*in_contact` = 1 when the
/// packings overlap, else 0 (the same answer as ist_contact).
///
/// # Safety
/// Every pointer is NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn ist_distance_traversal(
    pair: *mut ist_pair,
    pose_a: *const ist_pose,
    pose_b: *const ist_pose,
    in_contact: *mut c_int,
) -> c_int {
    unsafe {
        traversal(pair, pose_a, pose_b, in_contact, |p, a, b, o| {
            p.distance_traversal(a, b, o)
        })
    }
}

/// The paper's backtracking traversal (from the pair's previous contact; on a new or reset
/// pair the distance traversal): `*in_contact` = 1 when the packings overlap, else 0.
///
/// # Safety
/// Every pointer is NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn ist_backtracking(
    pair: *mut ist_pair,
    pose_a: *const ist_pose,
    pose_b: *const ist_pose,
    in_contact: *mut c_int,
) -> c_int {
    unsafe {
        traversal(pair, pose_a, pose_b, in_contact, |p, a, b, o| {
            p.backtracking(a, b, o)
        })
    }
}

/// A paper traversal `run` on the pair: `*in_contact` = 1 when the packings overlap.
///
/// # Safety
/// Every pointer is NULL or valid.
unsafe fn traversal(
    pair: *mut ist_pair,
    pose_a: *const ist_pose,
    pose_b: *const ist_pose,
    in_contact: *mut c_int,
    run: impl FnOnce(&mut Paper<'_>, &Pose, &Pose, &TraversalOptions) -> innersphere::ContactResult,
) -> c_int {
    status(move || {
        let (pair, a, b) = unsafe { args(pair, pose_a, pose_b) }?;
        let out = unsafe { mutable(in_contact, "in_contact") }?;
        let opts = TraversalOptions::default();
        *out = run(&mut pair.paper(), &a, &b, &opts).in_contact() as c_int;
        Ok(())
    })
}

/// Time-critical penetration volume: refines the largest overlaps first for at most
/// `budget` node-pair tests (about 75 ns each), answering the volume found and a proved
/// upper bound on the rest; `stiffness` as ist_penetration_with_stiffness.
///
/// # Safety
/// Every pointer is NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn ist_penetration_within(
    pair: *mut ist_pair,
    pose_a: *const ist_pose,
    pose_b: *const ist_pose,
    budget: u64,
    stiffness: f64,
    out: *mut ist_budgeted_result,
) -> c_int {
    status(|| {
        let (pair, a, b) = unsafe { args(pair, pose_a, pose_b) }?;
        let out = unsafe { mutable(out, "out") }?;
        let opts = PenetrationOptions {
            stiffness,
            ..Default::default()
        };
        opts.check()?;
        let w = pair.penetration_within_with(&a, &b, budget, &opts);
        *out = ist_budgeted_result {
            volume: w.volume,
            upper_bound: w.upper_bound,
            complete: w.complete as c_int,
            max_depth: w.max_depth,
            normal: w.normal.to_array(),
            force: w.force.to_array(),
            torque_b: w.torque_b.to_array(),
            visits: w.visits,
        };
        Ok(())
    })
}

/// Penetration volume, normal, force (volume along the normal: stiffness 1), torques and
/// contact patches (read them with ist_penetration_patch).
///
/// # Safety
/// Every pointer is NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn ist_penetration(
    pair: *mut ist_pair,
    pose_a: *const ist_pose,
    pose_b: *const ist_pose,
    out: *mut ist_penetration_result,
) -> c_int {
    unsafe { ist_penetration_with_stiffness(pair, pose_a, pose_b, 1.0, out) }
}

/// ist_penetration with a penalty stiffness: force per unit volume (e.g. N/mm³), from 0 to
/// 1e30 (else IST_ERR_INVALID_ARGUMENT).
///
/// # Safety
/// Every pointer is NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn ist_penetration_with_stiffness(
    pair: *mut ist_pair,
    pose_a: *const ist_pose,
    pose_b: *const ist_pose,
    stiffness: f64,
    out: *mut ist_penetration_result,
) -> c_int {
    status(|| {
        let (pair, a, b) = unsafe { args(pair, pose_a, pose_b) }?;
        let out = unsafe { mutable(out, "out") }?;
        let opts = PenetrationOptions {
            stiffness,
            ..Default::default()
        };
        opts.check()?;
        let p = pair.penetration_with(&a, &b, &opts);
        *out = ist_penetration_result::from(&p);
        Ok(())
    })
}

/// The penetration of the meshes themselves: the exact volume of the intersection of the two
/// solids, with the force (stiffness × volume along the direction that loses overlap
/// fastest; stiffness from 0 to 1e30, else IST_ERR_INVALID_ARGUMENT) and torques from its
/// exact gradient, and its connected pieces (read the 8 largest with
/// ist_penetration_patch). Both trees need their meshes (ist_tree_with_mesh), else
/// IST_ERR_INVALID_ARGUMENT.
///
/// # Safety
/// Every pointer is NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn ist_mesh_penetration(
    pair: *mut ist_pair,
    pose_a: *const ist_pose,
    pose_b: *const ist_pose,
    stiffness: f64,
    out: *mut ist_mesh_penetration_result,
) -> c_int {
    status(|| {
        let (pair, a, b) = unsafe { args(pair, pose_a, pose_b) }?;
        let out = unsafe { mutable(out, "out") }?;
        let opts = PenetrationOptions {
            stiffness,
            ..Default::default()
        };
        *out = ist_mesh_penetration_result::from(&pair.mesh_penetration_with(&a, &b, &opts)?);
        Ok(())
    })
}

/// Patch `i` (< the patches kept: patch_count, at most 8) of the pair's last
/// ist_penetration or ist_mesh_penetration.
///
/// # Safety
/// Every pointer is NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn ist_penetration_patch(
    pair: *const ist_pair,
    i: usize,
    out: *mut ist_patch,
) -> c_int {
    status(|| {
        let p = unsafe { reference(pair, "pair") }?;
        let out = unsafe { mutable(out, "out") }?;
        let patches = p.pair.patches();
        let Some(x) = patches.get(i) else {
            return Err(Fail::arg(format!(
                "patch {i} does not exist (the last penetration has {})",
                patches.len()
            )));
        };
        *out = ist_patch {
            point: x.point.to_array(),
            normal: x.normal.to_array(),
            depth: x.depth,
            volume: x.volume,
            pairs: x.pairs,
        };
        Ok(())
    })
}

/// Up to `k` contacts (one per pair of nodes at split depth 4), written to `out[0..*count]`;
/// `out` has room for `k`. k must be at least 1. The contacts still valid from the pair's
/// last multipoint come first; when more than k exist, which are kept depends on the
/// traversal and the pair's history (ist_pair_reset first for an answer from the pose
/// alone).
///
/// # Safety
/// Every pointer is NULL or valid; `out` points to at least `k` elements.
#[no_mangle]
pub unsafe extern "C" fn ist_multipoint(
    pair: *mut ist_pair,
    pose_a: *const ist_pose,
    pose_b: *const ist_pose,
    k: usize,
    out: *mut ist_contact_point,
    count: *mut usize,
) -> c_int {
    status(|| {
        let (pair, a, b) = unsafe { args(pair, pose_a, pose_b) }?;
        let count = unsafe { mutable(count, "count") }?;
        if out.is_null() {
            return Err(Fail::null("out"));
        }
        if k == 0 {
            return Err(Fail::arg("k must be at least 1"));
        }
        let opts = MultipointOptions {
            k,
            ..Default::default()
        };
        pair.multipoint(&a, &b, &opts);
        let contacts = pair.contacts();
        let n = contacts.len().min(k);
        // SAFETY: the caller gives room for k elements.
        let slots = unsafe { std::slice::from_raw_parts_mut(out, n) };
        for (s, c) in slots.iter_mut().zip(contacts) {
            *s = ist_contact_point {
                point: c.point.to_array(),
                normal: c.normal.to_array(),
                depth: c.depth,
                leaf_a: c.leaf_a,
                leaf_b: c.leaf_b,
            };
        }
        *count = n;
        Ok(())
    })
}

/// Fills `*out` from a 4×4 homogeneous matrix (OpenGL / OpenHaptics / CHAI3D), column-major
/// when `column_major` is non-zero, else row-major.
///
/// # Safety
/// `m` is NULL or points to 16 doubles; `out` NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn ist_pose_from_matrix(
    m: *const f64,
    column_major: c_int,
    out: *mut ist_pose,
) -> c_int {
    status(|| {
        if m.is_null() {
            return Err(Fail::null("m"));
        }
        let out = unsafe { mutable(out, "out") }?;
        let mut a = [0.0f64; 16];
        // SAFETY: the caller gives 16 doubles.
        a.copy_from_slice(unsafe { std::slice::from_raw_parts(m, 16) });
        let order = if column_major != 0 {
            innersphere::MatrixOrder::ColumnMajor
        } else {
            innersphere::MatrixOrder::RowMajor
        };
        let p = Pose::from_matrix4(&a, order)
            .map_err(|e| Fail(crate::error::IST_ERR_POSE, format!("bad matrix: {e}")))?;
        *out = ist_pose::from_pose(&p);
        Ok(())
    })
}

/// The identity pose.
#[no_mangle]
pub extern "C" fn ist_pose_identity() -> ist_pose {
    ist_pose::from_pose(&Pose::IDENTITY)
}
