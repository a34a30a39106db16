//! [`distance`]: the exact distance between two meshes (crossing test first, then the
//! branch and bound), its answer [`ExactDistance`] and the O(n·m) reference
//! [`brute_force_distance`].

use super::bnb::{bnb_heap, Best};
use super::containment::contained;
use super::frame::Frame;
use super::mesh::ExactMesh;
use super::overlap::overlap_pairs;
use super::scratch::{ExactScratch, ExactStats};
#[cfg(test)]
use super::tri_tri::triangle_distance;
use super::tri_tri::{self, triangle_distance_hint};
use crate::pose::Pose;
use glam::DVec3;

/// The answer of [`distance`] (points in the world frame).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExactDistance {
    /// Distance between the two solids: the surface distance, or 0 when they intersect.
    pub distance: f64,
    /// Distance between the two surfaces (differs from `distance` only when one body lies
    /// entirely inside the other).
    pub surface_distance: f64,
    /// Closest point on A's surface (a common point when the surfaces cross).
    pub point_a: DVec3,
    /// Closest point on B's surface.
    pub point_b: DVec3,
    /// Index of the triangle of A (in A's mesh) that `point_a` lies on.
    pub tri_a: u32,
    /// Index of the triangle of B that `point_b` lies on.
    pub tri_b: u32,
    /// True when the surfaces cross or touch, or one body lies inside the other.
    pub intersecting: bool,
}

/// Exact distance between A and B at their world poses (see the module docs).
///
/// A non-finite pose gives NaN distances and `intersecting = false`.
/// The distance is the exact minimum over all triangle pairs of
/// `tri_tri::triangle_distance`; when the surfaces cross it is 0 with a common point, and when one
/// body lies entirely inside the other `distance` is 0 and `intersecting` set while
/// `surface_distance` and the points still give the closest surface pair.
pub fn distance(
    a: &ExactMesh,
    pose_a: &Pose,
    b: &ExactMesh,
    pose_b: &Pose,
    scratch: &mut ExactScratch,
) -> ExactDistance {
    let rel = Pose::relative(pose_a, pose_b);
    let (ta, tb) = (a.bvh(), b.bvh());
    let f = Frame::new(&rel, ta, tb);
    let mut best = Best::NONE;
    if !f.is_finite() {
        return ExactDistance {
            distance: f64::NAN,
            surface_distance: f64::NAN,
            point_a: DVec3::NAN,
            point_b: DVec3::NAN,
            tri_a: u32::MAX,
            tri_b: u32::MAX,
            intersecting: false,
        };
    }
    scratch.stats = ExactStats::default();
    // Phase 1: do the surfaces cross? (Exact predicates on every pair of overlapping
    // triangle boxes, stopping at the first crossing.)
    let first = if scratch.warm_start {
        scratch.last_hit
    } else {
        None
    };
    let mut hit = None;
    overlap_pairs(a, b, &f, &mut scratch.stack, first, |sa, sb, x, y, _| {
        if let Some(p) = tri_tri::intersection_point(x, y) {
            hit = Some((sa, sb, p));
            true
        } else {
            false
        }
    });
    if let Some((sa, sb, p)) = hit {
        scratch.last_hit = Some((sa, sb));
        best = Best {
            d2: 0.0,
            pa: p,
            pb: p,
            sa,
            sb,
            intersecting: true,
        };
    } else {
        // Phase 2: no triangle pair crosses; branch and bound on floating-point distances.
        if scratch.warm_start {
            if let Some((sa, sb)) = scratch.last_pair {
                if let (Some(x), Some(y)) = (ta.tris.get(sa as usize), tb.tris.get(sb as usize)) {
                    best.offer(&triangle_distance_hint(x, &f.tri(y), false), sa, sb);
                }
            }
        }
        bnb_heap(a, b, &f, &mut best, &mut scratch.heap, &mut scratch.stats);
    }
    if best.sa != u32::MAX {
        scratch.last_pair = Some((best.sa, best.sb));
    }
    finish(
        a,
        pose_a,
        b,
        &rel,
        &f,
        &best,
        &mut scratch.stats.winding_tests,
    )
}

/// Converts the best pair to the world-frame answer, with the containment test.
fn finish(
    a: &ExactMesh,
    pose_a: &Pose,
    b: &ExactMesh,
    rel: &Pose,
    f: &Frame,
    best: &Best,
    tests: &mut usize,
) -> ExactDistance {
    let surface = best.d2.sqrt();
    let contained = !best.intersecting && contained(a, b, rel, f, tests);
    let tri = |m: &ExactMesh, s: u32| m.bvh().order.get(s as usize).copied().unwrap_or(u32::MAX);
    ExactDistance {
        distance: if best.intersecting || contained {
            0.0
        } else {
            surface
        },
        surface_distance: surface,
        point_a: pose_a.transform_point(best.pa),
        point_b: pose_a.transform_point(best.pb),
        tri_a: tri(a, best.sa),
        tri_b: tri(b, best.sb),
        intersecting: best.intersecting || contained,
    }
}

#[cfg(test)]
/// O(n·m) reference for [`distance`]: every triangle pair, the same containment rule.
pub(crate) fn brute_force_distance(
    a: &ExactMesh,
    pose_a: &Pose,
    b: &ExactMesh,
    pose_b: &Pose,
) -> ExactDistance {
    let rel = Pose::relative(pose_a, pose_b);
    let (ta, tb) = (a.bvh(), b.bvh());
    let f = Frame::new(&rel, ta, tb);
    let mut best = Best::NONE;
    let tbs: Vec<[DVec3; 3]> = tb.tris.iter().map(|t| f.tri(t)).collect();
    'outer: for (i, x) in ta.tris.iter().enumerate() {
        for (j, y) in tbs.iter().enumerate() {
            let r = triangle_distance(x, y);
            best.offer(&r, i as u32, j as u32);
            if r.intersecting {
                break 'outer;
            }
        }
    }
    finish(a, pose_a, b, &rel, &f, &best, &mut 0)
}
