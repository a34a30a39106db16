//! [`intersects`]: whether two meshes intersect (a crossing or one inside the other), and
//! its O(n·m) reference [`brute_force_intersects`].

use super::containment::contained;
#[cfg(test)]
use super::distance::brute_force_distance;
use super::frame::Frame;
use super::mesh::ExactMesh;
use super::overlap::overlap_pairs;
use super::scratch::{ExactScratch, ExactStats};
use super::tri_tri;
use crate::pose::Pose;

/// True when A and B at their world poses intersect: some triangle pair crosses or touches
/// (exact predicates), or one body lies entirely inside the other. False for a non-finite
/// pose.
pub fn intersects(
    a: &ExactMesh,
    pose_a: &Pose,
    b: &ExactMesh,
    pose_b: &Pose,
    scratch: &mut ExactScratch,
) -> bool {
    let rel = Pose::relative(pose_a, pose_b);
    let f = Frame::new(&rel, a.bvh(), b.bvh());
    if !f.is_finite() {
        return false;
    }
    scratch.stats = ExactStats::default();
    let first = if scratch.warm_start {
        scratch.last_hit
    } else {
        None
    };
    let mut hit = None;
    let crossing = overlap_pairs(a, b, &f, &mut scratch.stack, first, |sa, sb, x, y, _| {
        let h = tri_tri::intersection_point(x, y).is_some();
        if h {
            hit = Some((sa, sb));
        }
        h
    });
    if crossing {
        scratch.last_hit = hit;
        return true;
    }
    contained(a, b, &rel, &f, &mut scratch.stats.winding_tests)
}

#[cfg(test)]
/// O(n·m) reference for [`intersects`].
pub(crate) fn brute_force_intersects(
    a: &ExactMesh,
    pose_a: &Pose,
    b: &ExactMesh,
    pose_b: &Pose,
) -> bool {
    brute_force_distance(a, pose_a, b, pose_b).intersecting
}
