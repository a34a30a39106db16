//! Batches: many poses of B in one call, on all cores (`innersphere::query::batch`). They
//! allocate (a pair per worker thread) and are meant for sweeps and data sets, not for a
//! servo loop.

use crate::error::{status, Fail};
use crate::reference;
use crate::tree::ist_tree;
use crate::types::{
    ist_mesh_penetration_result, ist_penetration_result, ist_pose, ist_refine_options,
    ist_refined_distance_result,
};
use innersphere::query::batch::{self, BatchOptions};
use innersphere::{PenetrationOptions, Pose, SharedTree};
use std::ffi::c_int;

/// Poses of a batch as the library takes them: `n` poses of B, and `n_a` (1 or `n`) of A.
type Batch<'t> = (&'t SharedTree, &'t SharedTree, Vec<Pose>, Vec<Pose>);

/// Reads a batch's arguments; `out` must hold `n` results.
unsafe fn batch_args<'t, T>(
    a: *const ist_tree,
    b: *const ist_tree,
    poses_a: *const ist_pose,
    n_a: usize,
    poses_b: *const ist_pose,
    n: usize,
    out: *mut T,
) -> Result<(Batch<'t>, &'t mut [T]), Fail> {
    let ta = &unsafe { reference(a, "a") }?.tree;
    let tb = &unsafe { reference(b, "b") }?.tree;
    if n_a != 1 && n_a != n {
        return Err(Fail::arg(format!(
            "n_a is {n_a}: give one pose of A, or one per pose of B ({n})"
        )));
    }
    let poses = |p: *const ist_pose, len: usize, what: &str| -> Result<Vec<Pose>, Fail> {
        if len == 0 {
            return Ok(Vec::new());
        }
        if p.is_null() {
            return Err(Fail::null(what));
        }
        unsafe { std::slice::from_raw_parts(p, len) }
            .iter()
            .map(|x| x.to_pose())
            .collect()
    };
    let pa = poses(poses_a, n_a, "poses_a")?;
    let pb = poses(poses_b, n, "poses_b")?;
    let out: &mut [T] = if n == 0 {
        &mut []
    } else if out.is_null() {
        return Err(Fail::null("out"));
    } else {
        unsafe { std::slice::from_raw_parts_mut(out, n) }
    };
    Ok(((ta, tb, pa, pb), out))
}

/// ist_distance for `n` poses of B (`poses_b`), A at `poses_a` (`n_a` = 1: one pose for all;
/// `n_a` = `n`: one each), on `threads` threads (0: all cores) in chunks of `chunk` poses
/// that each start from a fresh state (1: every pose as a new pair answers it, right for
/// scattered poses; a motion gains from long chunks). The answers never depend on
/// `threads`. `out[i]` = the distance (0 where the packings overlap). Allocates.
///
/// # Safety
/// Every pointer is NULL or valid for its count.
#[no_mangle]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn ist_distance_many(
    a: *const ist_tree,
    b: *const ist_tree,
    poses_a: *const ist_pose,
    n_a: usize,
    poses_b: *const ist_pose,
    n: usize,
    threads: usize,
    chunk: usize,
    out: *mut f64,
) -> c_int {
    status(|| {
        let ((ta, tb, pa, pb), out) = unsafe { batch_args(a, b, poses_a, n_a, poses_b, n, out) }?;
        let o = BatchOptions { threads, chunk };
        for (o, d) in out
            .iter_mut()
            .zip(batch::distance_many(ta, tb, &pa, &pb, &o)?)
        {
            *o = d.distance;
        }
        Ok(())
    })
}

/// ist_refined_distance for `n` poses of B, as ist_distance_many, with `opts` (NULL: the
/// defaults): `out[i]`. Both trees need their meshes (ist_tree_with_mesh); without them, or
/// with bad options, IST_ERR_INVALID_ARGUMENT before any query. Allocates.
///
/// # Safety
/// Every pointer but `opts` is NULL or valid for its count; `opts` is NULL or points to
/// options.
#[no_mangle]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn ist_refined_distance_many(
    a: *const ist_tree,
    b: *const ist_tree,
    poses_a: *const ist_pose,
    n_a: usize,
    poses_b: *const ist_pose,
    n: usize,
    opts: *const ist_refine_options,
    threads: usize,
    chunk: usize,
    out: *mut ist_refined_distance_result,
) -> c_int {
    status(|| {
        let ((ta, tb, pa, pb), out) = unsafe { batch_args(a, b, poses_a, n_a, poses_b, n, out) }?;
        let q = unsafe { ist_refine_options::read(opts) };
        let o = BatchOptions { threads, chunk };
        for (o, r) in out
            .iter_mut()
            .zip(batch::refined_distance_many(ta, tb, &pa, &pb, &q, &o)?)
        {
            *o = ist_refined_distance_result::from(&r);
        }
        Ok(())
    })
}

/// ist_contact for `n` poses of B, as ist_distance_many: `out[i]` = 1 where the packings
/// overlap, else 0. Allocates.
///
/// # Safety
/// Every pointer is NULL or valid for its count.
#[no_mangle]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn ist_contact_many(
    a: *const ist_tree,
    b: *const ist_tree,
    poses_a: *const ist_pose,
    n_a: usize,
    poses_b: *const ist_pose,
    n: usize,
    threads: usize,
    chunk: usize,
    out: *mut c_int,
) -> c_int {
    status(|| {
        let ((ta, tb, pa, pb), out) = unsafe { batch_args(a, b, poses_a, n_a, poses_b, n, out) }?;
        let o = BatchOptions { threads, chunk };
        for (o, c) in out
            .iter_mut()
            .zip(batch::contact_many(ta, tb, &pa, &pb, &o)?)
        {
            *o = c.in_contact() as c_int;
        }
        Ok(())
    })
}

/// ist_penetration_with_stiffness for `n` poses of B, as ist_distance_many: `out[i]` (its
/// patch_count is given; the patches of a batch are not kept). Allocates.
///
/// # Safety
/// Every pointer is NULL or valid for its count.
#[no_mangle]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn ist_penetration_many(
    a: *const ist_tree,
    b: *const ist_tree,
    poses_a: *const ist_pose,
    n_a: usize,
    poses_b: *const ist_pose,
    n: usize,
    stiffness: f64,
    threads: usize,
    chunk: usize,
    out: *mut ist_penetration_result,
) -> c_int {
    status(|| {
        let ((ta, tb, pa, pb), out) = unsafe { batch_args(a, b, poses_a, n_a, poses_b, n, out) }?;
        let q = PenetrationOptions {
            stiffness,
            ..Default::default()
        };
        q.check()?;
        let o = BatchOptions { threads, chunk };
        for (o, p) in out
            .iter_mut()
            .zip(batch::penetration_many(ta, tb, &pa, &pb, &q, &o)?)
        {
            *o = ist_penetration_result::from(&p);
        }
        Ok(())
    })
}

/// ist_mesh_penetration for `n` poses of B, as ist_distance_many: `out[i]` (its patch_count
/// is given; the patches of a batch are not kept). Both trees need their meshes
/// (ist_tree_with_mesh); without them, or with a bad stiffness, IST_ERR_INVALID_ARGUMENT
/// before any query. Allocates.
///
/// # Safety
/// Every pointer is NULL or valid for its count.
#[no_mangle]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn ist_mesh_penetration_many(
    a: *const ist_tree,
    b: *const ist_tree,
    poses_a: *const ist_pose,
    n_a: usize,
    poses_b: *const ist_pose,
    n: usize,
    stiffness: f64,
    threads: usize,
    chunk: usize,
    out: *mut ist_mesh_penetration_result,
) -> c_int {
    status(|| {
        let ((ta, tb, pa, pb), out) = unsafe { batch_args(a, b, poses_a, n_a, poses_b, n, out) }?;
        let q = PenetrationOptions {
            stiffness,
            ..Default::default()
        };
        let o = BatchOptions { threads, chunk };
        for (o, m) in out
            .iter_mut()
            .zip(batch::mesh_penetration_many(ta, tb, &pa, &pb, &q, &o)?)
        {
            *o = ist_mesh_penetration_result::from(&m);
        }
        Ok(())
    })
}
