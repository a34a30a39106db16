//! [`local_distance`]: the exact distance between the parts of two meshes near given points,
//! under an upper bound, in bounded work: what refines an inner-sphere distance to the
//! surfaces ([`Pair::refined_distance`](crate::Pair::refined_distance)).
//!
//! A best-first branch and bound over node pairs (by the bounds of
//! [`bound::lower_bound_sq`](super::bound::lower_bound_sq)), restricted to the nodes whose
//! boxes reach a ball around each point (A's in A's frame, B's in B's own), pruned by the
//! best triangle pair so far, which starts at the given upper bound. Triangle pairs whose
//! boxes touch are tested for crossing first. Its answer is the minimum over a subset of
//! the triangle pairs, so it is never below the exact mesh distance; it stops after a
//! budget of node pairs and allocates nothing when its queue has room for that budget
//! ([`queue_size`]).

#![allow(clippy::neg_cmp_op_on_partial_ord)] // `!(x < y)` is deliberate: true for NaN too.

use super::bnb::{leaf_distance, Best};
use super::frame::{size_sq, Frame};
use super::mesh::ExactMesh;
use super::scratch::ExactStats;
pub(crate) use super::scratch::HeapItem;
use super::tri_tri::triangle_distance_hint;
use crate::mesh::bvh::BvhNode;
use crate::pose::Pose;
use glam::DVec3;
use std::collections::BinaryHeap;

/// A ball in one mesh's local frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Ball {
    /// Centre (the mesh's local frame).
    pub centre: DVec3,
    /// Radius (≥ 0).
    pub radius: f64,
}

/// The answer of [`local_distance`] (points in A's local frame).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct LocalDistance {
    /// The smallest triangle-pair distance found below the upper bound (the upper bound
    /// itself when none was below it; 0 when two triangles cross).
    pub distance: f64,
    /// Closest point on A's triangle (A's frame); meaningless when `found` is false.
    pub point_a: DVec3,
    /// Closest point on B's triangle, in A's frame.
    pub point_b: DVec3,
    /// A's triangle (index in A's mesh), `u32::MAX` when none was below the bound.
    pub tri_a: u32,
    /// B's triangle (index in B's mesh), `u32::MAX` when none was below the bound.
    pub tri_b: u32,
    /// True when a triangle pair below the bound was found.
    pub found: bool,
    /// True when the two triangles cross (then `distance` is 0).
    pub intersecting: bool,
    /// True when the search ended within its budget: `distance` is then the minimum over
    /// every triangle pair whose nodes reach both balls.
    pub complete: bool,
    /// Node pairs taken from the stack.
    pub node_pairs: u64,
    /// Triangle pairs measured exactly.
    pub triangle_pairs: u64,
    /// BVH slots of the best pair (A's, B's), for the next query's `hint`.
    pub slots: Option<(u32, u32)>,
}

/// The queue [`local_distance`] needs for a budget of `budget` node pairs: each pair taken
/// queues at most two.
pub(crate) fn queue_size(budget: u64) -> usize {
    (budget as usize).saturating_mul(2).saturating_add(2)
}

/// The exact distance between A's triangles near `ball_a` and B's near `ball_b` (B at
/// `rel`: its pose in A's frame), at most `upper` (see the module doc). `hint` (BVH slots,
/// the last answer's `slots`) is measured first: any triangle pair bounds the search from
/// the start. At most `budget` node pairs; `heap` needs room for [`queue_size`] of it to
/// allocate nothing. `rel_tolerance`: node and triangle pairs that cannot beat the best by
/// more than this fraction of it are skipped.
// Kept whole (over 120 lines): one branch and bound whose queue, budget and best pair are
// the loop's locals on the refined distance's hot path.
#[allow(clippy::too_many_arguments)]
pub(crate) fn local_distance(
    a: &ExactMesh,
    b: &ExactMesh,
    rel: &Pose,
    ball_a: Ball,
    ball_b: Ball,
    upper: f64,
    hint: Option<(u32, u32)>,
    rel_tolerance: f64,
    budget: u64,
    heap: &mut BinaryHeap<HeapItem>,
) -> LocalDistance {
    let (ta, tb) = (a.bvh(), b.bvh());
    let f = Frame::new(rel, ta, tb);
    let mut best = Best::NONE;
    best.d2 = upper * upper;
    let mut out = LocalDistance {
        distance: upper,
        point_a: DVec3::NAN,
        point_b: DVec3::NAN,
        tri_a: u32::MAX,
        tri_b: u32::MAX,
        found: false,
        intersecting: false,
        complete: true,
        node_pairs: 0,
        triangle_pairs: 0,
        slots: None,
    };
    let usable = |m: &ExactMesh| {
        let t = m.bvh();
        !t.nodes.is_empty() && m.shapes.len() == t.nodes.len()
    };
    if !f.is_finite()
        || !(upper >= 0.0)
        || !(ball_a.radius >= 0.0)
        || !(ball_b.radius >= 0.0)
        || !ball_a.centre.is_finite()
        || !ball_b.centre.is_finite()
        || !usable(a)
        || !usable(b)
    {
        out.complete = upper.is_finite() && upper >= 0.0 && f.is_finite();
        return out;
    }
    let mut stats = ExactStats::default();
    if let Some((sa, sb)) = hint {
        if let (Some(x), Some(y)) = (ta.tris.get(sa as usize), tb.tris.get(sb as usize)) {
            stats.triangle_pairs += 1;
            best.offer(&triangle_distance_hint(x, &f.tri(y), true), sa, sb);
        }
    }
    // A pair is worth a look while its lower bound is below the best less the tolerance.
    let keep = (1.0 - rel_tolerance.clamp(0.0, 1.0)).powi(2);
    let cut = |b: &Best| b.d2 * keep;
    let (ra2, rb2) = (ball_a.radius * ball_a.radius, ball_b.radius * ball_b.radius);
    let reaches_a = |n: &BvhNode| n.dist_sq(ball_a.centre) <= ra2;
    let reaches_b = |n: &BvhNode| n.dist_sq(ball_b.centre) <= rb2;
    heap.clear();
    if !best.intersecting && reaches_a(&ta.nodes[0]) && reaches_b(&tb.nodes[0]) {
        heap.push(HeapItem(f.lower_bound_sq(&a.shapes[0], &b.shapes[0]), 0, 0));
    }
    while let Some(HeapItem(lb, ia, ib)) = heap.pop() {
        if !(lb < cut(&best)) {
            // Everything still queued is at least as far.
            break;
        }
        if out.node_pairs >= budget {
            out.complete = false;
            break;
        }
        out.node_pairs += 1;
        let na = &ta.nodes[ia as usize];
        let nb = &tb.nodes[ib as usize];
        if na.is_leaf() && nb.is_leaf() {
            leaf_distance(a, b, na, nb, &f, &mut best, &mut stats, keep, true);
            if best.intersecting {
                break;
            }
            continue;
        }
        // Split the larger node (as the full branch and bound does); queue the children
        // that reach their ball and may beat the best.
        let split_a = !na.is_leaf() && (nb.is_leaf() || size_sq(na) >= size_sq(nb));
        if split_a {
            let sb = f.shape(&b.shapes[ib as usize]);
            for x in [ia + 1, na.start] {
                if reaches_a(&ta.nodes[x as usize]) {
                    let d = sb.lower_bound_sq(&a.shapes[x as usize], f.pad);
                    if d < cut(&best) {
                        heap.push(HeapItem(d, x, ib));
                    }
                }
            }
        } else {
            let sa = &a.shapes[ia as usize];
            for y in [ib + 1, nb.start] {
                if reaches_b(&tb.nodes[y as usize]) {
                    let d = f.lower_bound_sq(sa, &b.shapes[y as usize]);
                    if d < cut(&best) {
                        heap.push(HeapItem(d, ia, y));
                    }
                }
            }
        }
    }
    heap.clear();
    out.triangle_pairs = stats.triangle_pairs as u64;
    if best.sa != u32::MAX {
        let tri =
            |m: &ExactMesh, s: u32| m.bvh().order.get(s as usize).copied().unwrap_or(u32::MAX);
        out.distance = best.d2.sqrt();
        out.point_a = best.pa;
        out.point_b = best.pb;
        out.tri_a = tri(a, best.sa);
        out.tri_b = tri(b, best.sb);
        out.found = true;
        out.slots = Some((best.sa, best.sb));
        out.intersecting = best.intersecting;
        if best.intersecting {
            out.distance = 0.0;
        }
    }
    out
}
