//! Separation records: a proved lower bound on the distance of the two sphere sets at one
//! relative pose, and the bound it still guarantees after a motion (the safe-motion skip of
//! the contact queries).

use super::geometry::{pruning_slack, Rel32};
use super::info::TreeInfo;
use super::Ctx;
use crate::pose::Pose;
use glam::DVec3;

/// A lower bound on the separation of the two sphere sets, proved by a query at a relative
/// pose (B in A's frame).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct SeparationRecord {
    /// The sphere sets were at least this far apart.
    pub lower: f64,
    /// Pose of B in A's frame when it was measured.
    pub relative: Pose,
}

/// Upper bound on the displacement of any point of B between two relative poses.
pub(crate) fn motion_bound(ib: &TreeInfo, from: &Pose, to: &Pose) -> f64 {
    let c = ib.root_center;
    let dc = (to.transform_point(c) - from.transform_point(c)).length();
    let dq = to.rotation * from.rotation.conjugate();
    let v = DVec3::new(dq.x, dq.y, dq.z).length();
    let angle = 2.0 * v.atan2(dq.w.abs());
    (dc + angle * ib.radius) * (1.0 + 1e-9)
}

/// See [`Pair::safe_separation`](crate::Pair::safe_separation).
pub(crate) fn safe_separation(
    ia: &TreeInfo,
    ib: &TreeInfo,
    rec: Option<SeparationRecord>,
    rel: &Pose,
) -> Option<f64> {
    let rec = rec?;
    let moved = motion_bound(ib, &rec.relative, rel);
    // The rounding slack of the query asking (its f32 transform differs from the one that
    // measured the record).
    let slack = pruning_slack(ia.extent, ib.extent, &Rel32::new(rel)) as f64;
    Some(rec.lower - moved - slack)
}

/// Records that the sphere sets are at least `lower` apart at the query's pose (or forgets
/// the record when `lower` is not positive).
pub(crate) fn record(sep: &mut Option<SeparationRecord>, ctx: &Ctx, lower: f64) {
    *sep = (lower > 0.0).then_some(SeparationRecord {
        lower,
        relative: ctx.rel,
    });
}

/// The safe-motion answer, when enabled and positive.
pub(crate) fn safe_skip(
    ia: &TreeInfo,
    ib: &TreeInfo,
    sep: Option<SeparationRecord>,
    ctx: &Ctx,
    on: bool,
) -> Option<f64> {
    if !on {
        return None;
    }
    safe_separation(ia, ib, sep, &ctx.rel).filter(|&d| d > 0.0)
}
