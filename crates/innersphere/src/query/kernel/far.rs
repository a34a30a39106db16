//! Far poses: where the f32 rounding of B's transform approaches the finest scale of the
//! trees, the f32 traversals lose their pruning (every node pair lies within the rounding
//! slack, and a search becomes exhaustive) and, beyond about 10¹⁹, their squared distances
//! overflow. There the queries answer in f64 from the root spheres, to a tolerance that
//! grows with the distance.
//!
//! A pose is *far* when the rounding slack of its f32 transform, `s = 16·ε₃₂·(e_A + e_B +
//! |t|)` (the pruning slack of every query, [`pruning_slack`](super::geometry::pruning_slack)),
//! exceeds [`NEAR_SLACK`] of the smaller median leaf radius of the two trees (the scale the
//! traversals resolve; a few tiny leaves do not make a pose far), and the root spheres
//! (the balls of radius ρ about the root centres that hold every leaf) are apart by more than
//! `2s` in f64. Then the sphere sets are separated by at least that root separation, which
//! is what the contact kinds answer, and the distance query answers within
//! [`FAR_TOLERANCE_SLACKS`]`·s` of the exact distance. On the jaw trees a pose is far
//! beyond several metres; nothing nearer changes.

use super::info::TreeInfo;
use crate::pose::Pose;
use glam::DVec3;

/// A pose is near while the f32 rounding slack stays below this fraction of the median leaf
/// radius: the pruning then works as designed.
pub(crate) const NEAR_SLACK: f64 = 1.0 / 8.0;

/// The distance query's absolute tolerance at a far pose, in rounding slacks: large enough
/// that the search prunes at the scale of the leaves.
pub(crate) const FAR_TOLERANCE_SLACKS: f64 = 64.0;

/// Below this |t| the f32 transform and its squared distances are finite with a wide margin
/// (f32 squares overflow at 1.8·10¹⁹).
const F32_SAFE: f64 = 1e15;

/// How to answer at a far pose.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Far {
    /// Separation of the root spheres in f64: a proved lower bound on the distance of the
    /// sphere sets (finite: clamped to `f64::MAX`).
    pub separation: f64,
    /// The distance query's absolute tolerance at this pose.
    pub tolerance: f64,
    /// True when the tolerance exceeds the trees' size, or f32 cannot hold the transform:
    /// the distance is answered from the roots alone.
    pub roots_only: bool,
}

/// Length of `v` without overflow or underflow of the squares.
pub(crate) fn norm(v: DVec3) -> f64 {
    let m = v.abs().max_element();
    if m == 0.0 || !m.is_finite() {
        return m;
    }
    m * (v / m).length()
}

/// `Some` when `rel` (B in A's frame) is a far pose for trees `ia`, `ib` (see the module
/// docs); `None` for every other pose, which the f32 queries answer as always.
pub(crate) fn far(ia: &TreeInfo, ib: &TreeInfo, rel: &Pose) -> Option<Far> {
    let tlen = norm(rel.translation);
    let slack = (16.0 * f32::EPSILON as f64 * (ia.extent as f64 + ib.extent as f64 + tlen))
        .min(f64::MAX / 4.0);
    if slack <= NEAR_SLACK * ia.median_leaf_radius.min(ib.median_leaf_radius) {
        return None;
    }
    let cb = rel.transform_point(ib.root_center);
    let separation = (norm(cb - ia.root_center) - ia.radius - ib.radius).min(f64::MAX);
    // Roots that overlap, or nearly, are the f32 queries' case whatever the slack (trees
    // whose own size is large against their leaves).
    if separation.is_nan() || separation <= 2.0 * slack {
        return None;
    }
    let tolerance = (FAR_TOLERANCE_SLACKS * slack).min(f64::MAX);
    Some(Far {
        separation,
        tolerance,
        roots_only: tlen.is_nan() || tlen >= F32_SAFE || tolerance >= 2.0 * (ia.radius + ib.radius),
    })
}
