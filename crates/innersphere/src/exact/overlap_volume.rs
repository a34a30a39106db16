//! The exact intersection volume of two closed meshes and its gradient with respect to B's
//! pose: the contact of the scanned surfaces themselves (ours, beyond the paper).
//!
//! By the divergence theorem `V = ⅓ ∮ x·n dS` over the surface of `A ∩ B`, which is the part
//! of A's surface inside B and the part of B's surface inside A. On a triangle of either
//! surface `x·n` is constant (its plane's offset), so each triangle adds `⅓ (n·p₀) · area`
//! of its part inside the other body, and each such area is a boundary integral (Green's
//! theorem, a fan of signed triangles from `p₀`) over the part's boundary: the stretches of
//! the triangle's own edges that lie inside the other body, and the segments where it
//! crosses the other body's triangles, oriented so that the inside lies to their left
//! (`n_T × n_U` on `T`, the reverse on `U`). The boundary need not be assembled into loops:
//! the integrals are sums over its oriented segments, in any order.
//!
//! Moving B by `δ` changes `V` by the flux of `δ` through B's surface inside A, so the
//! gradient with respect to B's translation is that surface part's vector area `∫ n dS`, and
//! with respect to a rotation of B about a point `c` its moment `∫ (x − c) × n dS`: both are
//! sums over the same parts, exact, with no finite differences.
//!
//! Which stretches of an edge lie inside: the exact triangle pair tests give where each edge
//! crosses the other surface; the inside state flips at each crossing, starting from its
//! first vertex's state, which the penetration query's flood fill gives (regions of vertices
//! joined by edges that do not cross, decided by their crossings on a closed surface, by one
//! winding number each otherwise). Meant for closed,
//! outward-facing meshes: on an open mesh the winding number still decides which vertices are
//! inside, but the volume is that of a solid the surface does not close. A crossing decided at
//! a coincidence (an edge through another edge or vertex, coplanar faces) makes the query
//! answer at B nudged by [`NUDGE`] of the bodies' size (see [`intersection_volume`]).

use super::crossings::{barriers, edge_crossings, edge_key, EdgeCrossing, EdgeRuns, Stamps};
use super::frame::Frame;
use super::mesh::ExactMesh;
use super::overlap_patches::{AreaMoments, Grouping, PartRec};
use super::penetration::flood_inside;
use super::scratch::ExactScratch;
use crate::pose::Pose;
use glam::DVec3;

/// The answer of [`intersection_volume`] (vectors in the world frame).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct MeshOverlap {
    /// Volume of the intersection of the two solids (model units³).
    pub volume: f64,
    /// Gradient of the volume with respect to B's translation (world): the vector area of
    /// B's surface inside A. The volume grows fastest moving B along it.
    pub gradient: DVec3,
    /// Gradient of the volume with respect to a rotation of B about `center_b` (world; the
    /// rotation vector's components, per radian): the moment of the same surface.
    pub rotation_gradient: DVec3,
    /// Area of B's surface inside A (of A's inside B in `area_a`).
    pub area_b: f64,
    /// Area of A's surface inside B.
    pub area_a: f64,
    /// Triangle pairs that cross.
    pub crossing_pairs: usize,
    /// The largest mean thickness of a connected piece of the intersection along the
    /// direction it pushes B ([`OverlapPatch::depth`](super::OverlapPatch::depth)).
    pub max_depth: f64,
    /// Connected pieces of the intersection (the patches; read them with
    /// [`ExactScratch::patches`]).
    pub patch_count: usize,
    /// Area moments of B's surface inside A (world), about `center_b`: the linearised
    /// penalty wrench per unit stiffness.
    pub moments: AreaMoments,
}

/// A segment where triangle `slot_a` of A and `slot_b` of B cross (A's frame), from `p` to
/// `q` along `n_A × n_B`: the inside of B to its left on A's triangle.
#[derive(Debug, Clone, Copy)]
struct PairSegment {
    slot_a: u32,
    slot_b: u32,
    p: DVec3,
    q: DVec3,
}

/// Scratch memory of [`intersection_volume`].
#[derive(Debug, Clone, Default)]
pub(crate) struct VolumeScratch {
    cross_a: Vec<EdgeCrossing>,
    cross_b: Vec<EdgeCrossing>,
    /// Each edge's run in `cross_a`, `cross_b`.
    runs_a: EdgeRuns,
    runs_b: EdgeRuns,
    segments: Vec<PairSegment>,
    /// One triangle pair's crossing points.
    points: Vec<DVec3>,
    /// Segment indices sorted by A's slot, by B's slot.
    by_a: Vec<u32>,
    by_b: Vec<u32>,
    inside: Vec<bool>,
    inside_list: Vec<u32>,
    touched: Vec<u32>,
    slots: Stamps,
    /// The parts, grouped into patches.
    pub(super) group: Grouping,
}

/// Sorts the crossings by edge, then along it, and drops the duplicates: the same edge and
/// triangle found from both triangles of the edge, and an edge through the shared edge of two
/// triangles (the same point and direction twice).
fn settle(cross: &mut Vec<EdgeCrossing>) {
    cross.sort_unstable_by(|x, y| x.key.cmp(&y.key).then(x.other.cmp(&y.other)));
    cross.dedup_by(|x, y| x.key == y.key && x.other == y.other);
    cross.sort_unstable_by(|x, y| x.key.cmp(&y.key).then(x.t.total_cmp(&y.t)));
    cross.dedup_by(|x, y| {
        x.key == y.key && (x.dir < 0.0) == (y.dir < 0.0) && (x.t - y.t).abs() <= 1e-12
    });
}

/// What one triangle's part inside the other body adds: its area, and its first moment
/// `∫ x dS` (both from the fan of the boundary's oriented segments from `p0`).
#[derive(Debug, Clone, Copy, Default)]
struct Part {
    area: f64,
    moment: DVec3,
}

impl Part {
    /// Adds the oriented boundary segment `p → q` of a part in the plane through `p0` with
    /// unit normal `n`.
    #[inline]
    fn add(&mut self, p0: DVec3, n: DVec3, p: DVec3, q: DVec3) {
        let a = 0.5 * n.dot((p - p0).cross(q - p0));
        self.area += a;
        self.moment += a * (p0 + p + q) / 3.0;
    }
}

/// A triangle's unit normal from its winding; `None` when it is degenerate.
#[inline]
fn unit_normal(tri: &[DVec3; 3]) -> Option<DVec3> {
    let nn = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
    let len = nn.length();
    (len > 0.0).then(|| nn / len)
}

/// A whole triangle as a part: its unit normal, first corner, area and first moment (what
/// [`part`] gives when every edge lies inside, by the same fan from the first corner).
fn whole(tri: &[DVec3; 3]) -> Option<(DVec3, DVec3, Part)> {
    let n = unit_normal(tri)?;
    let mut part = Part::default();
    for k in 0..3 {
        part.add(tri[0], n, tri[k], tri[(k + 1) % 3]);
    }
    Some((n, tri[0], part))
}

/// The part inside the other body of the triangle with vertex ids `ids` and corners `tri`
/// (A's frame): the inside stretches of its edges (`inside`: its mesh's vertices' states;
/// `cross`: its mesh's edge crossings, indexed by `runs`) and its crossing segments `segs`,
/// oriented. Returns
/// its unit normal, first corner and part; `None` for a degenerate triangle.
fn part(
    ids: [u32; 3],
    tri: &[DVec3; 3],
    inside: &[bool],
    cross: &[EdgeCrossing],
    runs: &EdgeRuns,
    segs: impl Iterator<Item = (DVec3, DVec3)>,
) -> Option<(DVec3, DVec3, Part)> {
    let n = unit_normal(tri)?;
    let p0 = tri[0];
    let mut part = Part::default();
    for k in 0..3 {
        let (u, v) = (ids[k], ids[(k + 1) % 3]);
        let (pu, pv) = (tri[k], tri[(k + 1) % 3]);
        let (lo, hi, plo, phi) = if u < v {
            (u, v, pu, pv)
        } else {
            (v, u, pv, pu)
        };
        let on = runs.of(cross, edge_key(lo, hi));
        let mut state = inside.get(lo as usize).copied().unwrap_or(false);
        let mut from = 0.0;
        let at = |t: f64| plo + (phi - plo) * t;
        // The stretches inside, lo → hi; added in the triangle's own direction u → v.
        let mut add = |a: f64, b: f64| {
            let (p, q) = (at(a), at(b));
            if u < v {
                part.add(p0, n, p, q);
            } else {
                part.add(p0, n, q, p);
            }
        };
        for c in on {
            if state {
                add(from, c.t);
            }
            // Walking lo → hi against the crossed face's outward normal: into the body.
            state = c.dir < 0.0;
            from = c.t;
        }
        if state {
            add(from, 1.0);
        }
    }
    for (p, q) in segs {
        part.add(p0, n, p, q);
    }
    Some((n, p0, part))
}

/// Exact volume of the intersection of the solids of `a` at `pose_a` and `b` at `pose_b`
/// (world poses), with its gradient with respect to B's translation and to B's rotation
/// about `center_b` (a point in B's own frame, e.g. its centre of mass). See the module
/// docs. A non-finite pose gives zero.
///
/// Where a crossing is decided at a coincidence (a corner on the other surface, an edge
/// through another's edge or corner, coplanar faces: common in CAD models and generated
/// grids, rare in scans), the boundary built from it need not close and the volume could err
/// by the area it touches. The query then answers at B moved by [`NUDGE`] of the bodies'
/// size along a fixed generic direction (up to three directions): the exact answer of a pose
/// that close, instead of an inexact one at the pose itself.
pub fn intersection_volume(
    a: &ExactMesh,
    pose_a: &Pose,
    b: &ExactMesh,
    pose_b: &Pose,
    center_b: DVec3,
    scratch: &mut ExactScratch,
) -> MeshOverlap {
    let (answer, coincident) = volume_at(a, pose_a, b, pose_b, center_b, scratch);
    if !coincident {
        return answer;
    }
    let size = match (a.bvh().bounds(), b.bvh().bounds()) {
        (Some((la, ha)), Some((lb, hb))) => (ha - la).length().max((hb - lb).length()),
        _ => return answer,
    };
    for d in NUDGE_DIRECTIONS {
        let moved = Pose {
            translation: pose_b.translation + DVec3::from_array(d).normalize() * (NUDGE * size),
            rotation: pose_b.rotation,
        };
        let (nudged, coincident) = volume_at(a, pose_a, b, &moved, center_b, scratch);
        if !coincident {
            return nudged;
        }
    }
    answer
}

/// How far a query that met a coincidence moves B, as a fraction of the larger body's
/// bounding-box diagonal: 1e-12, 6e-11 mm on a 60 mm jaw arch, far below any mesh's own
/// precision and still thousands of rounding steps of its coordinates. (A pose that puts the
/// bodies a million sizes from the origin rounds the nudge away; the query then answers at
/// the pose itself.)
pub const NUDGE: f64 = 1e-12;

/// The directions of the nudge, tried in turn: generic (no two components in a simple ratio),
/// so that no grid, axis or face of a model is along them.
const NUDGE_DIRECTIONS: [[f64; 3]; 3] = [
    [0.5773502691896258, 0.6180339887498949, 0.5303300858899107],
    [-0.7, 0.3819660112501051, 0.6004673596133295],
    [0.2679491924311228, -0.8660254037844387, 0.4142135623730951],
];

/// [`intersection_volume`] at exactly these poses, and whether a crossing was decided at a
/// coincidence.
fn volume_at(
    a: &ExactMesh,
    pose_a: &Pose,
    b: &ExactMesh,
    pose_b: &Pose,
    center_b: DVec3,
    scratch: &mut ExactScratch,
) -> (MeshOverlap, bool) {
    let rel = Pose::relative(pose_a, pose_b);
    let f = Frame::new(&rel, a.bvh(), b.bvh());
    let g = Frame::new(&rel.inverse(), b.bvh(), a.bvh());
    if !(f.is_finite() && g.is_finite()) {
        return (MeshOverlap::default(), false);
    }
    let s = &mut scratch.vol;
    let mut coincident = false;
    s.cross_a.clear();
    s.cross_b.clear();
    s.segments.clear();
    let mut pairs = 0usize;
    {
        let (cross_a, cross_b, segments, points) = (
            &mut s.cross_a,
            &mut s.cross_b,
            &mut s.segments,
            &mut s.points,
        );
        let warm = scratch.warm_start;
        scratch
            .front
            .overlap_pairs(a, b, &rel, &f, warm, |sa, sb, x, y, sides| {
                points.clear();
                coincident |= edge_crossings(
                    a.slot_vertices(sa),
                    x,
                    sb,
                    y,
                    &sides.a_on_b,
                    cross_a,
                    points,
                );
                coincident |= edge_crossings(
                    b.slot_vertices(sb),
                    y,
                    sa,
                    x,
                    &sides.b_on_a,
                    cross_b,
                    points,
                );
                if points.len() >= 2 {
                    // The two points farthest apart (two, unless the contact is degenerate).
                    let (mut p, mut q, mut best) = (points[0], points[1], -1.0);
                    for i in 0..points.len() {
                        for j in i + 1..points.len() {
                            let d = points[i].distance_squared(points[j]);
                            if d > best {
                                (p, q, best) = (points[i], points[j], d);
                            }
                        }
                    }
                    let na = (x[1] - x[0]).cross(x[2] - x[0]);
                    let nb = (y[1] - y[0]).cross(y[2] - y[0]);
                    let dir = na.cross(nb);
                    let (p, q) = if (q - p).dot(dir) >= 0.0 {
                        (p, q)
                    } else {
                        (q, p)
                    };
                    if best > 0.0 {
                        pairs += 1;
                        segments.push(PairSegment {
                            slot_a: sa,
                            slot_b: sb,
                            p,
                            q,
                        });
                    }
                }
            });
    }
    settle(&mut s.cross_a);
    settle(&mut s.cross_b);
    s.runs_a.index(&s.cross_a);
    s.runs_b.index(&s.cross_b);
    s.by_a.clear();
    s.by_a.extend(0..s.segments.len() as u32);
    s.by_a
        .sort_unstable_by_key(|&i| s.segments[i as usize].slot_a);
    s.by_b.clear();
    s.by_b.extend(0..s.segments.len() as u32);
    s.by_b
        .sort_unstable_by_key(|&i| s.segments[i as usize].slot_b);

    let c = f.point(center_b);
    s.group.clear();
    // A's surface inside B, then B's inside A (both in A's frame).
    let area_a = side_parts(a, b, &g, None, s, &mut scratch.pen);
    let area_b = side_parts(b, a, &f, Some(&f), s, &mut scratch.pen);
    let (mut volume, mut grad, mut rot) = (0.0, DVec3::ZERO, DVec3::ZERO);
    let mut moments = AreaMoments::default();
    for r in &s.group.parts {
        volume += r.n.dot(r.p0) * r.area;
        if r.of_b {
            grad += r.n * r.area;
            rot += (r.moment - c * r.area).cross(r.n);
            if r.area > 0.0 {
                moments.add(r.area, r.n, r.moment / r.area, c);
            }
        }
    }
    for seg in &s.segments {
        s.group.join_crossing(seg.slot_a, seg.slot_b);
    }
    let max_depth = s
        .group
        .group(s.segments.iter().map(|seg| (seg.slot_a, seg.slot_b)));
    let r = glam::DMat3::from_quat(pose_a.rotation);
    let answer = MeshOverlap {
        volume: (volume / 3.0).max(0.0),
        gradient: pose_a.transform_vector(grad),
        rotation_gradient: pose_a.transform_vector(rot),
        area_a,
        area_b,
        crossing_pairs: pairs,
        max_depth,
        patch_count: s.group.patches.len(),
        moments: moments.rotated(r),
    };
    (answer, coincident)
}

/// Records the part inside `outer` of every triangle of `inner` in `s.group` (A's frame;
/// `to_a`: `inner`'s frame to A's, `None` when `inner` is A), joins the parts around each
/// inside vertex, and returns the parts' summed area. `to_outer` maps `inner`'s points into
/// `outer`'s frame (for the inside test).
fn side_parts(
    inner: &ExactMesh,
    outer: &ExactMesh,
    to_outer: &Frame,
    to_a: Option<&Frame>,
    s: &mut VolumeScratch,
    pen: &mut super::penetration::PenScratch,
) -> f64 {
    let is_a = to_a.is_none();
    let (cross, runs) = if is_a {
        (&s.cross_a, &s.runs_a)
    } else {
        (&s.cross_b, &s.runs_b)
    };
    // The barrier edges of the flood fill: the crossing edges, with the direction at the
    // crossing nearest each end (> 0: walking lo → hi leaves the other body there).
    barriers(cross, &mut pen.barrier);
    let n = inner.mesh.vertices.len();
    // Only the vertices marked last time are cleared (no pass over the whole mesh).
    for &v in &s.inside_list {
        if let Some(x) = s.inside.get_mut(v as usize) {
            *x = false;
        }
    }
    if s.inside.len() < n {
        s.inside.resize(n, false);
    }
    s.inside_list.clear();
    {
        let (inside, list) = (&mut s.inside, &mut s.inside_list);
        flood_inside(inner, outer, to_outer, pen, |u| {
            inside[u as usize] = true;
            list.push(u);
        });
    }
    // The triangles with a part inside: the crossing ones first, then the others around an
    // inside vertex (wholly inside: an edge from an inside vertex to an outside one crosses).
    s.slots.begin(inner.bvh().tris.len());
    s.touched.clear();
    let by = if is_a { &s.by_a } else { &s.by_b };
    for &k in by {
        let seg = &s.segments[k as usize];
        let t = if is_a { seg.slot_a } else { seg.slot_b };
        if s.slots.mark(t) {
            s.touched.push(t);
        }
    }
    let crossing = s.touched.len();
    for &v in &s.inside_list {
        for &t in inner.slots_of(v) {
            if s.slots.mark(t) {
                s.touched.push(t);
            }
        }
    }
    let slot_of = |k: u32| {
        let seg = &s.segments[k as usize];
        if is_a {
            seg.slot_a
        } else {
            seg.slot_b
        }
    };
    let tris = inner.bvh().tris.len();
    let mut area = 0.0;
    // The crossing triangles come in `by`'s order: each one's segments are the next run.
    let mut next = 0;
    for (i, &t) in s.touched.iter().enumerate() {
        let tri = &inner.bvh().tris[t as usize];
        let tri = to_a.map_or(*tri, |f| f.tri(tri));
        let ids = inner.slot_vertices(t);
        if i >= crossing && ids.iter().all(|&v| s.inside[v as usize]) {
            // No crossing on it and every corner inside: the whole triangle, without looking
            // up its edges' crossings (most of a deep contact's parts).
            if let Some((nrm, p0, p)) = whole(&tri) {
                area += p.area;
                s.group.push(rec(t, !is_a, nrm, p0, p), tris);
            }
            continue;
        }
        // The triangles touched after the crossing ones have no segment.
        let lo = next;
        while next < by.len() && i < crossing && slot_of(by[next]) == t {
            next += 1;
        }
        let segs = by[lo..next].iter().map(|&k| {
            let seg = &s.segments[k as usize];
            // On A's triangle along n_A × n_B; on B's the reverse.
            if is_a {
                (seg.p, seg.q)
            } else {
                (seg.q, seg.p)
            }
        });
        if let Some((nrm, p0, p)) = part(ids, &tri, &s.inside, cross, runs, segs) {
            area += p.area;
            s.group.push(rec(t, !is_a, nrm, p0, p), tris);
        }
    }
    // The parts around an inside vertex touch there: one piece.
    for &v in &s.inside_list {
        s.group.join_around(!is_a, inner.slots_of(v));
    }
    area
}

/// The record of a part.
fn rec(slot: u32, of_b: bool, n: DVec3, p0: DVec3, p: Part) -> PartRec {
    PartRec {
        slot,
        of_b,
        n,
        p0,
        area: p.area,
        moment: p.moment,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes;
    use glam::DQuat;

    /// On closed meshes the flood trusts the crossings' directions; the winding number (what
    /// it falls back to on open meshes) gives the same volume, gradient and areas, bit for
    /// bit, pose after pose. And an open mesh is known as one.
    #[test]
    fn the_crossings_decide_as_the_winding_number_does_on_closed_meshes() {
        let (upper, lower) = shapes::tooth_pair(3);
        let a = ExactMesh::new(&upper).unwrap();
        let b = ExactMesh::new(&lower).unwrap();
        assert!(a.closed && b.closed);
        let (mut a_open, mut b_open) = (a.clone(), b.clone());
        a_open.closed = false;
        b_open.closed = false;
        let com = DVec3::ZERO;
        let (mut s1, mut s2) = (ExactScratch::new(), ExactScratch::new());
        let mut overlapping = 0;
        for i in 0..40 {
            let x = i as f64 / 40.0;
            let pose = Pose::new(
                DVec3::new(0.3 * (7.0 * x).sin(), 0.2 * (5.0 * x).cos(), 0.6 - 1.2 * x),
                DQuat::from_rotation_z(0.2 * x) * DQuat::from_rotation_x(0.05 * x),
            )
            .unwrap();
            let fast = intersection_volume(&a, &Pose::IDENTITY, &b, &pose, com, &mut s1);
            let wind = intersection_volume(&a_open, &Pose::IDENTITY, &b_open, &pose, com, &mut s2);
            assert_eq!(fast, wind, "pose {i}");
            overlapping += usize::from(fast.volume > 0.0);
        }
        assert!(overlapping > 10, "{overlapping} overlapping poses");

        let mut open = shapes::icosphere(2);
        open.triangles.pop();
        assert!(!ExactMesh::new(&open).unwrap().closed);
        let mut flipped = shapes::icosphere(2);
        flipped.triangles[0].swap(0, 1);
        assert!(!ExactMesh::new(&flipped).unwrap().closed);
    }

    /// The node-pair front carried along a coherent motion finds every crossing pair that a
    /// traversal from the roots finds, frame after frame: pressing in, sliding, twisting,
    /// pulling out, with steps small and large.
    #[test]
    fn a_carried_front_misses_no_crossing() {
        let (upper, lower) = shapes::tooth_pair(3);
        let a = ExactMesh::new(&upper).unwrap();
        let b = ExactMesh::new(&lower).unwrap();
        let com = DVec3::ZERO;
        let (mut warm, mut cold) = (ExactScratch::new(), ExactScratch::cold());
        let mut overlapping = 0;
        for i in 0..600 {
            // Mostly 1 µm-scale steps; every 50th frame a jump.
            let x = i as f64 / 600.0 + if i % 50 == 49 { 0.05 } else { 0.0 };
            let pose = Pose::new(
                DVec3::new(
                    0.2 * (9.0 * x).sin(),
                    0.15 * (6.0 * x).cos(),
                    0.4 * (3.0 * x).cos() - 0.2,
                ),
                DQuat::from_rotation_z(0.3 * (4.0 * x).sin()) * DQuat::from_rotation_y(0.05 * x),
            )
            .unwrap();
            let got = intersection_volume(&a, &Pose::IDENTITY, &b, &pose, com, &mut warm);
            let want = intersection_volume(&a, &Pose::IDENTITY, &b, &pose, com, &mut cold);
            assert_eq!(got.crossing_pairs, want.crossing_pairs, "frame {i}");
            let close = |p: f64, q: f64| (p - q).abs() <= 1e-9 * (1.0 + q.abs());
            assert!(
                close(got.volume, want.volume),
                "frame {i}: {got:?} {want:?}"
            );
            assert!(
                (got.gradient - want.gradient).length() <= 1e-9 * (1.0 + want.gradient.length())
            );
            overlapping += usize::from(want.volume > 0.0);
        }
        assert!(overlapping > 100, "{overlapping} overlapping frames");
        assert!(
            warm.front.carried() > 300,
            "{} frames carried",
            warm.front.carried()
        );
        assert_eq!(cold.front.carried(), 0);
        // Reset, the scratch answers as a new one does, bit for bit.
        let pose = Pose::from_translation(DVec3::new(0.05, 0.0, 0.0));
        warm.reset();
        let again = intersection_volume(&a, &Pose::IDENTITY, &b, &pose, com, &mut warm);
        let mut new = ExactScratch::new();
        let fresh = intersection_volume(&a, &Pose::IDENTITY, &b, &pose, com, &mut new);
        assert!(fresh.volume > 0.0);
        assert_eq!(again, fresh);
    }
}
