//! Penetration depth by vertices: the largest distance to the other surface of any vertex of
//! one body that lies inside the other.
//!
//! Which vertices are inside: the exact winding number is constant along a mesh edge that
//! does not cross the other surface, so the vertices split into regions joined by such
//! edges, each entirely inside or outside. Edges that cross (from the exact triangle pair
//! tests) are barriers; the end of a barrier edge that the nearest crossing leaves through
//! the other body's outward face is a candidate inside vertex, and so is one vertex of every
//! connected component that might lie wholly inside the other body. On a closed,
//! consistently wound other surface a region that its crossings call inside, and none call
//! outside, is inside (the inside flips at every crossing); any other candidate region (an
//! open surface, crossings that disagree, a component with no crossing) is decided by one
//! winding-number evaluation. A closed surface that crosses itself is trusted too, so where
//! it wraps twice a region may be counted by its crossings where the winding number would say
//! otherwise. Every vertex of an inside region gets its distance to the other surface from
//! the BVH.
//!
//! Meant for closed, outward-facing meshes (for open meshes it is a best effort).

#![allow(clippy::neg_cmp_op_on_partial_ord)] // `!(x < y)` is deliberate: true for NaN too.

use super::crossings::{barriers, edge_crossings, edge_key, EdgeCrossing, Stamps};
use super::frame::Frame;
use super::mesh::ExactMesh;
use super::overlap::overlap_pairs;
use super::scratch::ExactScratch;
use crate::pose::Pose;
use glam::DVec3;

/// One of the two bodies of a query.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Body {
    /// The first body.
    A,
    /// The second body.
    B,
}

/// The answer of [`penetration`] (points in the world frame).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExactPenetration {
    /// Largest distance from a vertex inside the other body to that body's surface
    /// (0 when no vertex of either body lies inside the other).
    pub depth: f64,
    /// The body the deepest vertex belongs to (`None` when `depth` is 0 for lack of one).
    pub vertex_of: Option<Body>,
    /// The deepest vertex.
    pub vertex: DVec3,
    /// The nearest point to it on the other body's surface.
    pub surface_point: DVec3,
    /// Number of B's vertices inside A.
    pub b_vertices_in_a: usize,
    /// Number of A's vertices inside B.
    pub a_vertices_in_b: usize,
}

/// Scratch memory of [`penetration`].
#[derive(Debug, Clone, Default)]
pub(crate) struct PenScratch {
    cross_a: Vec<EdgeCrossing>,
    cross_b: Vec<EdgeCrossing>,
    /// One triangle pair's crossing points (unused here; the shared recorder writes them).
    points: Vec<DVec3>,
    /// Merged barrier edges: (key, dir at the crossing nearest lo, dir nearest hi).
    pub(super) barrier: Vec<(u64, f64, f64)>,
    stamps: Stamps,
    /// The vertices at an end of a barrier edge: only an edge between two of them can be one.
    ends: Stamps,
    /// The barrier ends whose nearest crossing enters the other body walking away from them:
    /// outside by the crossings.
    outside: Stamps,
    /// One region's vertices, visited once it is known to be inside.
    region: Vec<u32>,
    stack: Vec<u32>,
    candidates: Vec<u32>,
}

/// Sorts the crossings by edge and keeps, per edge, the direction at the crossing nearest
/// each end.
fn merge(cross: &mut [EdgeCrossing], out: &mut Vec<(u64, f64, f64)>) {
    cross.sort_unstable_by(|x, y| x.key.cmp(&y.key).then(x.t.total_cmp(&y.t)));
    barriers(cross, out);
}

/// Calls `visit(v)` once for every vertex `v` of `inner` inside `outer` (see the module
/// docs: regions between the barrier edges `s.barrier`, one winding number per region).
pub(super) fn flood_inside(
    inner: &ExactMesh,
    outer: &ExactMesh,
    to_outer: &Frame,
    s: &mut PenScratch,
    mut visit: impl FnMut(u32),
) {
    let n = inner.mesh.vertices.len();
    s.stamps.begin(n);
    s.ends.begin(n);
    s.outside.begin(n);
    s.candidates.clear();
    for &(key, dir_lo, dir_hi) in &s.barrier {
        let (lo, hi) = ((key >> 32) as u32, key as u32);
        s.ends.mark(lo);
        s.ends.mark(hi);
        // The nearest crossing leaves the other body when walking away from the end: inside.
        if dir_lo > 0.0 {
            s.candidates.push(lo);
        } else {
            s.outside.mark(lo);
        }
        if dir_hi < 0.0 {
            s.candidates.push(hi);
        } else {
            s.outside.mark(hi);
        }
    }
    // Candidates up to here are inside by their crossings; the components' are not known.
    let by_crossings = s.candidates.len();
    s.candidates.extend(inner.maybe_inside(outer, to_outer));
    let (barrier, ends) = (&s.barrier, &s.ends);
    // Most edges of a region have an end no barrier edge touches: no search for those.
    let is_barrier = |u: u32, v: u32| {
        ends.is_marked(u)
            && ends.is_marked(v)
            && barrier
                .binary_search_by_key(&edge_key(u, v), |e| e.0)
                .is_ok()
    };
    let verts = &inner.mesh.vertices;
    for ci in 0..s.candidates.len() {
        let v = s.candidates[ci];
        if !s.stamps.mark(v) {
            continue;
        }
        // The region of `v`: the vertices joined to it by edges that cross nothing.
        s.region.clear();
        s.stack.clear();
        s.stack.push(v);
        let mut disputed = false;
        while let Some(u) = s.stack.pop() {
            s.region.push(u);
            disputed |= s.outside.is_marked(u);
            for &w in inner.neighbours(u) {
                if !s.stamps.is_marked(w) && !is_barrier(u, w) {
                    s.stamps.mark(w);
                    s.stack.push(w);
                }
            }
        }
        // A closed outer surface flips inside at every crossing: a region its crossings call
        // inside, and none outside, is inside. Otherwise (an open or self-crossing surface, a
        // degenerate crossing, a component with no crossing) one winding number decides.
        let trusted = outer.closed && ci < by_crossings && !disputed;
        if trusted || outer.contains_point(to_outer.point(verts[v as usize])) {
            s.region.iter().for_each(|&u| visit(u));
        }
    }
}

/// Vertices of `inner` inside `outer`: (depth, deepest vertex and its nearest surface point
/// in `outer`'s frame, count).
fn side(
    inner: &ExactMesh,
    outer: &ExactMesh,
    to_outer: &Frame,
    s: &mut PenScratch,
) -> (f64, DVec3, DVec3, usize) {
    let mut depth_sq = 0.0f64;
    let mut deepest = (DVec3::ZERO, DVec3::ZERO);
    let mut count = 0usize;
    let mut hint = u32::MAX;
    let verts = &inner.mesh.vertices;
    flood_inside(inner, outer, to_outer, s, |u| {
        count += 1;
        let p = to_outer.point(verts[u as usize]);
        if let Some(c) = outer.bvh().closest_point_from(p, hint) {
            hint = c.slot;
            if c.dist_sq > depth_sq {
                depth_sq = c.dist_sq;
                deepest = (p, c.point);
            }
        }
    });
    (depth_sq.sqrt(), deepest.0, deepest.1, count)
}

/// Penetration depth of A and B at their world poses by vertices (see the module docs):
/// the largest distance from a vertex of either body inside the other to the other's
/// surface, with where it is and how many vertices are inside. A non-finite pose gives
/// depth 0.
pub fn penetration(
    a: &ExactMesh,
    pose_a: &Pose,
    b: &ExactMesh,
    pose_b: &Pose,
    scratch: &mut ExactScratch,
) -> ExactPenetration {
    let rel = Pose::relative(pose_a, pose_b);
    let f = Frame::new(&rel, a.bvh(), b.bvh());
    let g = Frame::new(&rel.inverse(), b.bvh(), a.bvh());
    if !(f.is_finite() && g.is_finite()) {
        return ExactPenetration {
            depth: 0.0,
            vertex_of: None,
            vertex: DVec3::ZERO,
            surface_point: DVec3::ZERO,
            b_vertices_in_a: 0,
            a_vertices_in_b: 0,
        };
    }
    let s = &mut scratch.pen;
    // Triangle pairs with overlapping boxes; crossings of each body's edges with the other.
    s.cross_a.clear();
    s.cross_b.clear();
    {
        let (cross_a, cross_b, points) = (&mut s.cross_a, &mut s.cross_b, &mut s.points);
        overlap_pairs(a, b, &f, &mut scratch.stack, None, |sa, sb, x, y, sides| {
            points.clear();
            // Coincidences decide per crossing here (a vertex's depth, not a closed boundary).
            edge_crossings(
                b.slot_vertices(sb),
                y,
                sa,
                x,
                &sides.b_on_a,
                cross_b,
                points,
            );
            edge_crossings(
                a.slot_vertices(sa),
                x,
                sb,
                y,
                &sides.a_on_b,
                cross_a,
                points,
            );
            false
        });
    }
    let mut cross = std::mem::take(&mut s.cross_b);
    merge(&mut cross, &mut s.barrier);
    s.cross_b = cross;
    let (db, vb, sb, nb) = side(b, a, &f, s);
    let mut cross = std::mem::take(&mut s.cross_a);
    merge(&mut cross, &mut s.barrier);
    s.cross_a = cross;
    let (da, va, sa, na) = side(a, b, &g, s);
    let (depth, vertex_of, vertex, surface_point) = if db >= da && db > 0.0 {
        (
            db,
            Some(Body::B),
            pose_a.transform_point(vb),
            pose_a.transform_point(sb),
        )
    } else if da > 0.0 {
        (
            da,
            Some(Body::A),
            pose_b.transform_point(va),
            pose_b.transform_point(sa),
        )
    } else {
        (0.0, None, DVec3::ZERO, DVec3::ZERO)
    };
    ExactPenetration {
        depth,
        vertex_of,
        vertex,
        surface_point,
        b_vertices_in_a: nb,
        a_vertices_in_b: na,
    }
}

/// [`penetration`]'s depth alone: 0 when no vertex of either body lies inside the other.
pub fn penetration_depth(
    a: &ExactMesh,
    pose_a: &Pose,
    b: &ExactMesh,
    pose_b: &Pose,
    scratch: &mut ExactScratch,
) -> f64 {
    penetration(a, pose_a, b, pose_b, scratch).depth
}
