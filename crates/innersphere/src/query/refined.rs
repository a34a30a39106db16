//! The inner-sphere distance refined to the surfaces (beyond the paper): the exact distance
//! between the meshes' triangles near the closest leaf pair.
//!
//! Inner spheres lie inside their meshes, so the sphere distance is an upper bound of the
//! mesh distance, too large by the two sets' gaps below the surface at the closest points
//! (0.02–0.045 mm at p95 on the jaw preset's 150k spheres per arch; docs/RESULTS.md). Those
//! gaps shrink only slowly with more spheres (p95 0.01 mm needs about 1.4M per arch), but
//! the mesh itself is at hand: the triangles of each mesh within a ball around the sphere
//! pair's closest points hold the surfaces' closest points whenever the spheres' closest
//! pair is near the meshes' (the usual case: the gaps are small against the leaf radii). A
//! bounded local branch and bound over them ([`exact::local`](crate::exact)), pruned by
//! the sphere distance, gives a distance that is still an upper bound of the exact one and
//! never above the spheres'.

use super::distance::Distance;
use crate::exact::local::{local_distance, queue_size, Ball, HeapItem};
use crate::exact::ExactMesh;
use crate::pose::Pose;
use glam::DVec3;

/// Options of [`Pair::refined_distance_with`](crate::Pair::refined_distance_with).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RefineOptions {
    /// Radius of the ball around each closest point whose triangles are searched, as a
    /// multiple of the larger of the two closest leaves' radii (plus [`Self::margin`]).
    pub radius_scale: f64,
    /// Added to the balls' radius, in model units; negative = the larger of the two trees'
    /// voxel sizes (0.1 mm for the jaw preset). With the default scale 0.5 it is what
    /// finds the contacts the spheres miss: on the jaw, scale 0.5 with half a voxel missed
    /// contacts 0.06 mm deep on two of six motions, with one voxel none deeper than 0.025 mm,
    /// at 0.5–0.7× the time of scale 1 with half a voxel (docs/RESULTS.md).
    pub margin: f64,
    /// Most triangle-BVH node pairs the local search visits; past it the answer is the best
    /// found so far (still an upper bound) and `complete` is false. The default 4096 is 3×
    /// the most the jaw preset's trees needed; up to 2¹⁶ the query's queue is reserved
    /// whole (once, when a larger budget than before is first asked for).
    pub max_node_pairs: u64,
    /// Skip the node and triangle pairs that cannot beat the best so far by more than this
    /// fraction of it (as PQP's and FCL's relative tolerance): the answer is within this
    /// fraction above the minimum over the balls. Never hides a crossing (its distance is 0).
    pub rel_tolerance: f64,
}

impl Default for RefineOptions {
    fn default() -> Self {
        RefineOptions {
            radius_scale: 0.5,
            margin: -1.0,
            max_node_pairs: 4096,
            rel_tolerance: 1e-3,
        }
    }
}

impl RefineOptions {
    /// Checks the options: the scale finite and ≥ 0, the margin finite, the relative
    /// tolerance in [0, 1), a budget of at least one node pair.
    pub fn check(&self) -> crate::error::Result<()> {
        let bad = |m: String| Err(crate::error::Error::InvalidOption(m));
        if !(self.radius_scale >= 0.0 && self.radius_scale.is_finite()) {
            return bad(format!(
                "refine radius_scale {} must be finite and ≥ 0",
                crate::error::Num(self.radius_scale)
            ));
        }
        if !self.margin.is_finite() {
            return bad(format!(
                "refine margin {} must be finite (negative: from the trees' voxel sizes)",
                crate::error::Num(self.margin)
            ));
        }
        if !(0.0..1.0).contains(&self.rel_tolerance) {
            return bad(format!(
                "refine rel_tolerance {} must be in [0, 1)",
                crate::error::Num(self.rel_tolerance)
            ));
        }
        if self.max_node_pairs == 0 {
            return bad("refine max_node_pairs must be at least 1".into());
        }
        Ok(())
    }
}

/// Result of [`Pair::refined_distance`](crate::Pair::refined_distance) (points in the world
/// frame).
///
/// Its serde form is the answer every door prints: these fields, `intersecting` as
/// `contact`, `tri_a`/`tri_b` as `triangle_a`/`triangle_b` (null unless refined) and the
/// sphere distance nested as `spheres` (a [`Distance`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct RefinedDistance {
    /// Distance between the meshes as refined: the smallest triangle-pair distance found
    /// near the spheres' closest points, or the sphere distance where none was smaller; 0
    /// when two triangles cross or the sphere packings overlap. Never below the exact mesh
    /// distance, never above `spheres.distance`.
    pub distance: f64,
    /// Closest point on A (on a triangle of A's mesh when `refined`, else the sphere's).
    pub point_a: DVec3,
    /// Closest point on B.
    pub point_b: DVec3,
    /// A's triangle that `point_a` lies on (index in A's mesh), `u32::MAX` unless refined.
    #[serde(rename = "triangle_a", serialize_with = "triangle")]
    pub tri_a: u32,
    /// B's triangle, `u32::MAX` unless refined.
    #[serde(rename = "triangle_b", serialize_with = "triangle")]
    pub tri_b: u32,
    /// True when a triangle pair nearer than the spheres was found.
    pub refined: bool,
    /// True when the bodies touch: two triangles cross, or the sphere packings overlap.
    #[serde(rename = "contact")]
    pub intersecting: bool,
    /// True when the local search ended within its budget (the minimum over every triangle
    /// pair near both points).
    pub complete: bool,
    /// Radius of the balls searched, in model units.
    pub radius: f64,
    /// Triangle-BVH node pairs visited.
    pub node_pairs: u64,
    /// Triangle pairs measured exactly.
    pub triangle_pairs: u64,
    /// The inner-sphere distance that was refined.
    pub spheres: Distance,
}

/// A triangle index as serialized: null for `u32::MAX` (none).
fn triangle<S: serde::Serializer>(t: &u32, s: S) -> Result<S::Ok, S::Error> {
    serde::Serialize::serialize(&(*t != u32::MAX).then_some(*t), s)
}

/// The largest budget whose queue is reserved whole: a larger one (a search without a
/// practical limit) lets the queue grow as the search needs.
const MAX_RESERVED_BUDGET: u64 = 1 << 16;

/// The refined query's memory: the local search's queue.
#[derive(Debug)]
pub(crate) struct RefineScratch {
    heap: std::collections::BinaryHeap<HeapItem>,
    /// BVH slots of the last answer's triangle pair (the next query's first bound).
    last: Option<(u32, u32)>,
}

impl RefineScratch {
    /// Room for the local search with the default budget.
    pub(crate) fn new() -> RefineScratch {
        let budget = RefineOptions::default().max_node_pairs;
        RefineScratch {
            heap: std::collections::BinaryHeap::with_capacity(queue_size(budget)),
            last: None,
        }
    }

    /// Forgets the last answer's triangle pair.
    pub(crate) fn reset(&mut self) {
        self.last = None;
    }
}

/// The two meshes and what the refinement needs of each tree: the closest leaves' radii and
/// the margin's default.
pub(crate) struct Surfaces<'m> {
    pub a: &'m ExactMesh,
    pub b: &'m ExactMesh,
    /// Radii of the closest leaf of A and of B.
    pub leaf_radii: (f64, f64),
    /// The larger voxel size of the two trees.
    pub default_margin: f64,
}

/// The error of a refined distance asked of trees without their meshes.
pub(crate) fn missing_meshes(query: &str) -> crate::error::Error {
    crate::error::Error::InvalidOption(format!(
        "{query} needs the meshes of both trees (SharedTree::with_mesh)"
    ))
}

/// Refines `spheres` (the sphere distance at world poses `pose_a`, `pose_b`) to the
/// surfaces of `m` (see the module doc).
pub(crate) fn refine(
    spheres: Distance,
    m: &Surfaces,
    pose_a: &Pose,
    pose_b: &Pose,
    opts: &RefineOptions,
    s: &mut RefineScratch,
) -> RefinedDistance {
    let margin = if opts.margin < 0.0 {
        m.default_margin
    } else {
        opts.margin
    };
    let radius = opts.radius_scale * m.leaf_radii.0.max(m.leaf_radii.1) + margin;
    let mut out = RefinedDistance {
        distance: spheres.distance.max(0.0),
        point_a: spheres.point_a,
        point_b: spheres.point_b,
        tri_a: u32::MAX,
        tri_b: u32::MAX,
        refined: false,
        intersecting: false,
        complete: true,
        radius,
        node_pairs: 0,
        triangle_pairs: 0,
        spheres,
    };
    let positive = spheres.distance > 0.0;
    if spheres.overlapping || !positive {
        // Overlapping inner spheres lie inside both bodies: they touch.
        out.intersecting = spheres.overlapping || spheres.distance == 0.0;
        out.complete = !spheres.distance.is_nan();
        return out;
    }
    let room = queue_size(opts.max_node_pairs.min(MAX_RESERVED_BUDGET));
    if s.heap.capacity() < room {
        // A budget above the default: the queue grows once, to its bound.
        s.heap.reserve(room - s.heap.len());
    }
    let rel = Pose::relative(pose_a, pose_b);
    let ball_a = Ball {
        centre: pose_a.inverse().transform_point(spheres.point_a),
        radius,
    };
    let ball_b = Ball {
        centre: pose_b.inverse().transform_point(spheres.point_b),
        radius,
    };
    let l = local_distance(
        m.a,
        m.b,
        &rel,
        ball_a,
        ball_b,
        spheres.distance,
        s.last,
        opts.rel_tolerance,
        opts.max_node_pairs,
        &mut s.heap,
    );
    if l.slots.is_some() {
        s.last = l.slots;
    }
    out.complete = l.complete;
    out.node_pairs = l.node_pairs;
    out.triangle_pairs = l.triangle_pairs;
    if l.found {
        let world = |p: DVec3| pose_a.transform_point(p);
        out.distance = l.distance;
        out.point_a = world(l.point_a);
        out.point_b = world(l.point_b);
        out.tri_a = l.tri_a;
        out.tri_b = l.tri_b;
        out.refined = true;
        out.intersecting = l.intersecting;
    }
    out
}
