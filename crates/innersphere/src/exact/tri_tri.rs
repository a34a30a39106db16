//! Triangle–triangle distance and intersection in f64.
//!
//! * [`triangles_intersect`] is exact: it decides with Shewchuk's adaptive orientation
//!   predicates (the `robust` crate) whether the two closed triangles share a point, with
//!   coplanar, touching and degenerate (needle, point) triangles handled by the same rules.
//!   It rests on one fact: two closed triangles meet if and only if an edge of one meets the
//!   other (the ends of the intersection lie on the boundary of one of them). Coplanar
//!   point sets are decided in all three coordinate projections.
//! * [`triangle_distance`]: 0 when the triangles intersect (decided exactly), else PQP's
//!   `TriDist` (nine edge pairs with slab certificates, then the vertex–face cases), falling
//!   back to the exhaustive minimum over the six vertex–triangle distances and the interior
//!   critical points of the nine edge pairs when `TriDist` cannot show them disjoint. Never
//!   NaN for finite input.

#![allow(clippy::neg_cmp_op_on_partial_ord)] // `!(x < y)` is deliberate: true for NaN too.

use crate::mesh::closest::closest_point_on_triangle;
use glam::DVec3;
use robust::{orient2d, orient3d, Coord, Coord3D};

/// The answer of [`triangle_distance`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct TriDistance {
    /// Squared distance between the triangles (0 when they intersect).
    pub dist_sq: f64,
    /// The closest point on the first triangle (a common point when they intersect).
    pub point_a: DVec3,
    /// The closest point on the second triangle.
    pub point_b: DVec3,
    /// True when the closed triangles share a point (decided exactly).
    pub intersecting: bool,
}

#[inline]
fn c3(p: DVec3) -> Coord3D<f64> {
    Coord3D {
        x: p.x,
        y: p.y,
        z: p.z,
    }
}

/// Exact orientation of `d` relative to the plane through `a, b, c` (sign only is exact).
///
/// The `robust` crate's own floating-point filter, inlined (the same operations in the same
/// order, so the same value): most calls end there, and the call into the crate cost more
/// than the filter. The adaptive stages run only when the filter cannot decide.
#[inline(always)]
fn o3(a: DVec3, b: DVec3, c: DVec3, d: DVec3) -> f64 {
    let (ad, bd, cd) = (a - d, b - d, c - d);
    let bdxcdy = bd.x * cd.y;
    let cdxbdy = cd.x * bd.y;
    let cdxady = cd.x * ad.y;
    let adxcdy = ad.x * cd.y;
    let adxbdy = ad.x * bd.y;
    let bdxady = bd.x * ad.y;
    let det = ad.z * (bdxcdy - cdxbdy) + bd.z * (cdxady - adxcdy) + cd.z * (adxbdy - bdxady);
    let permanent = (bdxcdy.abs() + cdxbdy.abs()) * ad.z.abs()
        + (cdxady.abs() + adxcdy.abs()) * bd.z.abs()
        + (adxbdy.abs() + bdxady.abs()) * cd.z.abs();
    if det > O3_ERRBOUND * permanent || -det > O3_ERRBOUND * permanent {
        return det;
    }
    orient3d(c3(a), c3(b), c3(c), c3(d))
}

/// Shewchuk's `o3derrboundA`, `(7 + 56ε)ε` with `ε = 2⁻⁵³`, as the `robust` crate has it.
const O3_ERRBOUND: f64 = (7.0 + 56.0 * 1.1102230246251565e-16) * 1.1102230246251565e-16;

/// Projection that drops coordinate `axis`.
#[inline]
fn proj(p: DVec3, axis: usize) -> Coord<f64> {
    match axis {
        0 => Coord { x: p.y, y: p.z },
        1 => Coord { x: p.z, y: p.x },
        _ => Coord { x: p.x, y: p.y },
    }
}

/// True when `c` and `d` lie strictly on the same side of the line `a b` in the plane they
/// all lie in (exact; false when the four points are not coplanar or either lies on the
/// line): two triangles `a b c` and `a b d` sharing the edge `a b` then fold onto each other.
pub(crate) fn same_side_coplanar(a: DVec3, b: DVec3, c: DVec3, d: DVec3) -> bool {
    if o3(a, b, c, d) != 0.0 {
        return false;
    }
    (0..3).any(|k| {
        let (pa, pb) = (proj(a, k), proj(b, k));
        let (sc, sd) = (orient2d(pa, pb, proj(c, k)), orient2d(pa, pb, proj(d, k)));
        (sc > 0.0 && sd > 0.0) || (sc < 0.0 && sd < 0.0)
    })
}

/// True when `a, b, c` are exactly collinear (every coordinate projection has zero area).
#[inline]
pub(crate) fn is_collinear(a: DVec3, b: DVec3, c: DVec3) -> bool {
    (0..3).all(|k| orient2d(proj(a, k), proj(b, k), proj(c, k)) == 0.0)
}

/// `r`, known to be collinear with `p, q`, lies on the closed segment `[p, q]`.
#[inline]
fn on_segment_2d(p: Coord<f64>, q: Coord<f64>, r: Coord<f64>) -> bool {
    r.x >= p.x.min(q.x) && r.x <= p.x.max(q.x) && r.y >= p.y.min(q.y) && r.y <= p.y.max(q.y)
}

/// Closed segments `[p, q]` and `[r, s]` in the plane share a point (exact; point segments
/// allowed).
fn segments_intersect_2d(p: Coord<f64>, q: Coord<f64>, r: Coord<f64>, s: Coord<f64>) -> bool {
    let d1 = orient2d(r, s, p);
    let d2 = orient2d(r, s, q);
    let d3 = orient2d(p, q, r);
    let d4 = orient2d(p, q, s);
    if ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0))
        && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0))
    {
        return true;
    }
    (d1 == 0.0 && on_segment_2d(r, s, p))
        || (d2 == 0.0 && on_segment_2d(r, s, q))
        || (d3 == 0.0 && on_segment_2d(p, q, r))
        || (d4 == 0.0 && on_segment_2d(p, q, s))
}

/// Closed segment `[p, q]` and closed (possibly degenerate) triangle `a, b, c` in the plane
/// share a point (exact).
fn segment_triangle_2d(
    p: Coord<f64>,
    q: Coord<f64>,
    a: Coord<f64>,
    b: Coord<f64>,
    c: Coord<f64>,
) -> bool {
    if orient2d(a, b, c) != 0.0 {
        // The signed areas add up to the non-zero area, so "all ≥ 0 or all ≤ 0" is the
        // closed point-in-triangle test for either orientation.
        let o1 = orient2d(a, b, p);
        let o2 = orient2d(b, c, p);
        let o3 = orient2d(c, a, p);
        if (o1 >= 0.0 && o2 >= 0.0 && o3 >= 0.0) || (o1 <= 0.0 && o2 <= 0.0 && o3 <= 0.0) {
            return true;
        }
    }
    // Otherwise the segment meets the triangle only by crossing (or touching) its boundary;
    // a degenerate triangle is the union of its edges.
    segments_intersect_2d(p, q, a, b)
        || segments_intersect_2d(p, q, b, c)
        || segments_intersect_2d(p, q, c, a)
}

/// Closed segments `[p, q]` and `[r, s]` in space share a point (exact; point segments
/// allowed).
///
/// Non-coplanar segments never meet. Coplanar point sets meet in space if and only if they
/// meet in all three coordinate projections: every projection keeps an intersection, and at
/// least one projection is one-to-one on their plane (or line).
pub(crate) fn segments_intersect(p: DVec3, q: DVec3, r: DVec3, s: DVec3) -> bool {
    if o3(p, q, r, s) != 0.0 {
        return false;
    }
    (0..3).all(|k| segments_intersect_2d(proj(p, k), proj(q, k), proj(r, k), proj(s, k)))
}

/// Closed segment `[p, q]` and closed triangle `a, b, c` share a point (exact; degenerate
/// segments and triangles allowed).
pub(crate) fn segment_triangle_intersect(p: DVec3, q: DVec3, a: DVec3, b: DVec3, c: DVec3) -> bool {
    if is_collinear(a, b, c) {
        return segments_intersect(p, q, a, b)
            || segments_intersect(p, q, b, c)
            || segments_intersect(p, q, c, a);
    }
    let op = o3(a, b, c, p);
    let oq = o3(a, b, c, q);
    segment_triangle_with_sides(p, q, op, oq, [a, b, c])
}

/// The corners of a triangle against the plane of another, by a floating-point filter: each
/// corner's offset `n · (p − t₀)` (`n` the plane's unnormalised normal) and the bound on its
/// rounding error beyond which its sign is exact. Found once per triangle pair, it both
/// rejects the pair ([`separates`](Self::separates)) and gives the segment tests their
/// sides ([`SidesOf::with`]) without an exact predicate where the filter decides.
#[derive(Debug, Clone, Copy)]
pub(crate) struct PlaneSides {
    d: [f64; 3],
    bound: [f64; 3],
    n: DVec3,
    nabs: DVec3,
}

impl PlaneSides {
    /// The corners `pts` against the plane of `t`.
    #[inline]
    pub(crate) fn new(t: &[DVec3; 3], pts: &[DVec3; 3]) -> Self {
        let ab = t[1] - t[0];
        let ac = t[2] - t[0];
        let n = ab.cross(ac);
        let nabs = DVec3::new(
            (ab.y * ac.z).abs() + (ab.z * ac.y).abs(),
            (ab.z * ac.x).abs() + (ab.x * ac.z).abs(),
            (ab.x * ac.y).abs() + (ab.y * ac.x).abs(),
        );
        let mut d = [0.0; 3];
        let mut bound = [0.0; 3];
        for k in 0..3 {
            let ap = pts[k] - t[0];
            d[k] = n.dot(ap);
            // Shewchuk's orient3d forward error bound is (7 + 56ε)ε times this permanent.
            bound[k] = 1e-15 * ap.abs().dot(nabs);
        }
        PlaneSides { d, bound, n, nabs }
    }

    /// Certified: all three corners lie strictly on one side of the plane. `false` means
    /// "not certain" (they may still be on one side).
    #[inline]
    pub(crate) fn separates(&self) -> bool {
        let pos = (0..3).filter(|&k| self.d[k] > self.bound[k]).count();
        let neg = (0..3).filter(|&k| self.d[k] < -self.bound[k]).count();
        pos == 3 || neg == 3
    }

    /// Certified by the filter: the plane's triangle is not a line (its normal has a
    /// component beyond the orient2d error bound, `(3 + 16ε)ε` of its permanent).
    #[inline]
    fn surely_not_collinear(&self) -> bool {
        let (n, m) = (self.n.abs(), self.nabs * 1e-15);
        n.x > m.x || n.y > m.y || n.z > m.z
    }
}

/// The triangle `t` prepared for segment tests: whether it is degenerate and the sides of its
/// plane of given points, found once for all of a triangle's edges. `segment(k, j)` says of
/// the closed segment `pts[k] → pts[j]` what [`segment_triangle_intersect`] says.
pub(crate) struct SidesOf<'t> {
    t: &'t [DVec3; 3],
    collinear: bool,
    side: [f64; 3],
}

impl<'t> SidesOf<'t> {
    /// The sides of `pts` of `t`'s plane (exact signs); `None` when all three lie strictly on
    /// one side, so that no segment between them meets `t`.
    #[cfg(test)]
    pub(crate) fn new(t: &'t [DVec3; 3], pts: &[DVec3; 3]) -> Option<Self> {
        let [a, b, c] = *t;
        if is_collinear(a, b, c) {
            return Some(SidesOf {
                t,
                collinear: true,
                side: [0.0; 3],
            });
        }
        let side = [
            o3(a, b, c, pts[0]),
            o3(a, b, c, pts[1]),
            o3(a, b, c, pts[2]),
        ];
        if side.iter().all(|&o| o > 0.0) || side.iter().all(|&o| o < 0.0) {
            return None;
        }
        Some(SidesOf {
            t,
            collinear: false,
            side,
        })
    }

    /// [`new`](Self::new) from the filtered sides of `pts` (`sides`, found for the same
    /// `t` and `pts`): exact predicates only where the filter cannot decide. The same signs,
    /// so the same answers.
    #[inline]
    pub(crate) fn with(t: &'t [DVec3; 3], pts: &[DVec3; 3], sides: &PlaneSides) -> Option<Self> {
        let [a, b, c] = *t;
        if !sides.surely_not_collinear() && is_collinear(a, b, c) {
            return Some(SidesOf {
                t,
                collinear: true,
                side: [0.0; 3],
            });
        }
        // o3(a, b, c, p) = −n · (p − a) in exact arithmetic.
        let side = std::array::from_fn(|k| {
            if sides.d[k].abs() > sides.bound[k] {
                -sides.d[k]
            } else {
                o3(a, b, c, pts[k])
            }
        });
        if side.iter().all(|&o| o > 0.0) || side.iter().all(|&o| o < 0.0) {
            return None;
        }
        Some(SidesOf {
            t,
            collinear: false,
            side,
        })
    }

    /// The closed segment `p → q` between the points `k` and `j` of `pts` meets `t`.
    #[inline]
    pub(crate) fn segment(&self, p: DVec3, q: DVec3, k: usize, j: usize) -> bool {
        let [a, b, c] = *self.t;
        if self.collinear {
            return segments_intersect(p, q, a, b)
                || segments_intersect(p, q, b, c)
                || segments_intersect(p, q, c, a);
        }
        segment_triangle_with_sides(p, q, self.side[k], self.side[j], *self.t)
    }

    /// [`segment`](Self::segment), and whether the decision met a coincidence: `t` is a
    /// line, an end of the segment lies on `t`'s plane, or the segment's line passes through
    /// an edge or corner of `t` (an orientation exactly 0). Such a crossing is decided, but a
    /// boundary built from it may not close.
    #[inline]
    pub(crate) fn segment_or_coincident(
        &self,
        p: DVec3,
        q: DVec3,
        k: usize,
        j: usize,
    ) -> (bool, bool) {
        let (op, oq) = (self.side[k], self.side[j]);
        if self.collinear || op == 0.0 || oq == 0.0 {
            let meets = self.segment(p, q, k, j);
            return (meets, meets);
        }
        if (op > 0.0) == (oq > 0.0) {
            return (false, false);
        }
        let [a, b, c] = *self.t;
        let s = [o3(p, q, a, b), o3(p, q, b, c), o3(p, q, c, a)];
        let meets = s.iter().all(|&x| x >= 0.0) || s.iter().all(|&x| x <= 0.0);
        (meets, meets && s.contains(&0.0))
    }
}

/// [`segment_triangle_intersect`] for a non-degenerate triangle, with the orientations of
/// the segment ends relative to its plane already known.
#[inline]
fn segment_triangle_with_sides(p: DVec3, q: DVec3, op: f64, oq: f64, t: [DVec3; 3]) -> bool {
    let [a, b, c] = t;
    if (op > 0.0 && oq > 0.0) || (op < 0.0 && oq < 0.0) {
        return false;
    }
    if op == 0.0 && oq == 0.0 {
        return (0..3).all(|k| {
            segment_triangle_2d(proj(p, k), proj(q, k), proj(a, k), proj(b, k), proj(c, k))
        });
    }
    // The segment meets the plane in one point; it lies in the closed triangle exactly when
    // the line p q passes on the same side of (or through) all three edges.
    let s1 = o3(p, q, a, b);
    let s2 = o3(p, q, b, c);
    let s3 = o3(p, q, c, a);
    (s1 >= 0.0 && s2 >= 0.0 && s3 >= 0.0) || (s1 <= 0.0 && s2 <= 0.0 && s3 <= 0.0)
}

/// Where the edges of `s` meet the closed triangle `t`: the first crossing point found
/// (approximate position), or `None` when no edge of `s` meets `t`. Exact decision.
fn edges_meet_triangle(s: &[DVec3; 3], t: &[DVec3; 3], t_collinear: bool) -> Option<DVec3> {
    if t_collinear {
        for i in 0..3 {
            let (p, q) = (s[i], s[(i + 1) % 3]);
            for j in 0..3 {
                if segments_intersect(p, q, t[j], t[(j + 1) % 3]) {
                    return Some(segment_pair_point(p, q, t[j], t[(j + 1) % 3]));
                }
            }
        }
        return None;
    }
    let o = [
        o3(t[0], t[1], t[2], s[0]),
        o3(t[0], t[1], t[2], s[1]),
        o3(t[0], t[1], t[2], s[2]),
    ];
    if (o[0] > 0.0 && o[1] > 0.0 && o[2] > 0.0) || (o[0] < 0.0 && o[1] < 0.0 && o[2] < 0.0) {
        return None;
    }
    for i in 0..3 {
        let j = (i + 1) % 3;
        let (p, q) = (s[i], s[j]);
        if segment_triangle_with_sides(p, q, o[i], o[j], *t) {
            let point = if o[i] != 0.0 || o[j] != 0.0 {
                // The ends are on opposite sides (or one is on the plane).
                let u = (o[i] / (o[i] - o[j])).clamp(0.0, 1.0);
                p + (q - p) * if u.is_finite() { u } else { 0.0 }
            } else {
                // Coplanar: the nearest point of the segment to the triangle (distance ~0).
                segment_triangle_point(p, q, t)
            };
            return Some(point);
        }
    }
    None
}

/// A point of the segment `[p, q]` close to the triangle (used only to report where
/// coplanar triangles touch).
fn segment_triangle_point(p: DVec3, q: DVec3, t: &[DVec3; 3]) -> DVec3 {
    let mut best = p;
    let mut best_d = f64::INFINITY;
    for x in [p, q] {
        let d = (x - closest_point_on_triangle(x, t[0], t[1], t[2])).length_squared();
        if d < best_d {
            best_d = d;
            best = x;
        }
    }
    for i in 0..3 {
        let (x, y) = edge_pair_closest(p, q, t[i], t[(i + 1) % 3]);
        let d = (x - y).length_squared();
        if d < best_d {
            best_d = d;
            best = x;
        }
    }
    best
}

/// A point near where two (touching) segments meet.
fn segment_pair_point(p: DVec3, q: DVec3, r: DVec3, s: DVec3) -> DVec3 {
    let (x, y) = edge_pair_closest(p, q, r, s);
    (x + y) * 0.5
}

/// Closest points of two segments (clamped Lumelsky/Ericson), never NaN.
fn edge_pair_closest(p1: DVec3, q1: DVec3, p2: DVec3, q2: DVec3) -> (DVec3, DVec3) {
    let d1 = q1 - p1;
    let d2 = q2 - p2;
    let r = p1 - p2;
    let a = d1.length_squared();
    let e = d2.length_squared();
    let f = d2.dot(r);
    let (s, t);
    if !(a > 0.0) && !(e > 0.0) {
        return (p1, p2);
    }
    if !(a > 0.0) {
        s = 0.0;
        t = (f / e).clamp(0.0, 1.0);
    } else {
        let c = d1.dot(r);
        if !(e > 0.0) {
            t = 0.0;
            s = (-c / a).clamp(0.0, 1.0);
        } else {
            let b = d1.dot(d2);
            let denom = a * e - b * b;
            let s0 = if denom > 0.0 {
                ((b * f - c * e) / denom).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let t0 = (b * s0 + f) / e;
            if t0 < 0.0 {
                t = 0.0;
                s = (-c / a).clamp(0.0, 1.0);
            } else if t0 > 1.0 {
                t = 1.0;
                s = ((b - c) / a).clamp(0.0, 1.0);
            } else {
                t = t0;
                s = s0;
            }
        }
    }
    let s = if s.is_finite() { s } else { 0.0 };
    let t = if t.is_finite() { t } else { 0.0 };
    (p1 + d1 * s, p2 + d2 * t)
}

#[cfg(test)]
/// Closest points of two segments `[p1, q1]`, `[p2, q2]` and their squared distance.
///
/// Robust (clamped) form of Ericson's *Real-Time Collision Detection* 5.1.9: point segments
/// and parallel segments are handled, the result is never NaN for finite input.
pub(crate) fn segment_segment_closest(
    p1: DVec3,
    q1: DVec3,
    p2: DVec3,
    q2: DVec3,
) -> (f64, DVec3, DVec3) {
    let (x, y) = edge_pair_closest(p1, q1, p2, q2);
    // The clamped formula can miss the true minimum for nearly parallel segments: the ends
    // against the other segment are always candidates too.
    let mut best = ((x - y).length_squared(), x, y);
    for (u, v, w, flip) in [
        (p1, p2, q2, false),
        (q1, p2, q2, false),
        (p2, p1, q1, true),
        (q2, p1, q1, true),
    ] {
        let c = crate::mesh::closest::closest_point_on_segment(u, v, w);
        let d = (u - c).length_squared();
        if d < best.0 {
            best = if flip { (d, c, u) } else { (d, u, c) };
        }
    }
    best
}

/// Certifies with a floating-point filter that the three `pts` lie strictly on one side of
/// the plane of `t`. `false` means "not certain" (they may still be on one side).
#[inline]
pub(crate) fn plane_separates(t: &[DVec3; 3], pts: &[DVec3; 3]) -> bool {
    PlaneSides::new(t, pts).separates()
}

#[cfg(test)]
/// True when the closed triangles `a` and `b` share a point. Exact for every input,
/// including coplanar, touching and degenerate triangles.
pub(crate) fn triangles_intersect(a: &[DVec3; 3], b: &[DVec3; 3]) -> bool {
    intersection_point(a, b).is_some()
}

/// A common point of the closed triangles (approximate position), or `None` when they are
/// disjoint (exact decision).
pub(crate) fn intersection_point(a: &[DVec3; 3], b: &[DVec3; 3]) -> Option<DVec3> {
    if plane_separates(a, b) || plane_separates(b, a) {
        return None;
    }
    let ca = is_collinear(a[0], a[1], a[2]);
    let cb = is_collinear(b[0], b[1], b[2]);
    edges_meet_triangle(a, b, cb).or_else(|| edges_meet_triangle(b, a, ca))
}

/// Squared distance and closest points over the vertex–triangle and edge–edge candidates
/// (the distance of the triangles when they do not intersect).
#[inline]
fn feature_distance(a: &[DVec3; 3], b: &[DVec3; 3]) -> (f64, DVec3, DVec3) {
    let mut best = f64::INFINITY;
    let mut pa = a[0];
    let mut pb = b[0];
    for &v in a {
        let q = closest_point_on_triangle(v, b[0], b[1], b[2]);
        let d = (v - q).length_squared();
        if d < best {
            best = d;
            pa = v;
            pb = q;
        }
    }
    for &v in b {
        let q = closest_point_on_triangle(v, a[0], a[1], a[2]);
        let d = (v - q).length_squared();
        if d < best {
            best = d;
            pa = q;
            pb = v;
        }
    }
    // Edge pairs: only the interior critical point is new (ends are vertex candidates).
    for i in 0..3 {
        let p1 = a[i];
        let d1 = a[(i + 1) % 3] - p1;
        let aa = d1.length_squared();
        for j in 0..3 {
            let p2 = b[j];
            let d2 = b[(j + 1) % 3] - p2;
            let r = p1 - p2;
            let e = d2.length_squared();
            let bb = d1.dot(d2);
            let denom = aa * e - bb * bb;
            if !(denom > 0.0) {
                continue;
            }
            let c = d1.dot(r);
            let f = d2.dot(r);
            let s = (bb * f - c * e) / denom;
            let t = (aa * f - bb * c) / denom;
            if !((0.0..=1.0).contains(&s) && (0.0..=1.0).contains(&t)) {
                continue;
            }
            let x = p1 + d1 * s;
            let y = p2 + d2 * t;
            let d = (x - y).length_squared();
            if d < best {
                best = d;
                pa = x;
                pb = y;
            }
        }
    }
    (best, pa, pb)
}

/// Closest points of the segments `p + t·a` and `q + u·b` (t, u in [0, 1]) and a direction
/// `vec` from the first towards the second that, where possible, is normal to a separating
/// slab (PQP's `SegPoints`, Larsen et al. 1999). Never NaN for finite input.
#[inline]
fn seg_points(p: DVec3, a: DVec3, q: DVec3, b: DVec3) -> (DVec3, DVec3, DVec3) {
    let t0 = q - p;
    let aa = a.dot(a);
    let bb = b.dot(b);
    let ab = a.dot(b);
    let at = a.dot(t0);
    let bt = b.dot(t0);
    let denom = aa * bb - ab * ab;
    let mut t = (at * bb - bt * ab) / denom;
    if !(t >= 0.0) {
        t = 0.0; // also NaN
    } else if t > 1.0 {
        t = 1.0;
    }
    let u = (t * ab - bt) / bb;
    if !(u > 0.0) {
        // u <= 0 or NaN
        let y = q;
        let t = at / aa;
        if !(t > 0.0) {
            (p, y, q - p)
        } else if t >= 1.0 {
            let x = p + a;
            (x, y, q - x)
        } else {
            let x = p + a * t;
            (x, y, a.cross(t0.cross(a)))
        }
    } else if u >= 1.0 {
        let y = q + b;
        let t = (ab + at) / aa;
        if !(t > 0.0) {
            (p, y, y - p)
        } else if t >= 1.0 {
            let x = p + a;
            (x, y, y - x)
        } else {
            let x = p + a * t;
            let tt = y - p;
            (x, y, a.cross(tt.cross(a)))
        }
    } else {
        let y = q + b * u;
        if !(t > 0.0) {
            (p, y, b.cross(t0.cross(b)))
        } else if t >= 1.0 {
            let x = p + a;
            let tt = q - x;
            (x, y, b.cross(tt.cross(b)))
        } else {
            let x = p + a * t;
            let mut v = a.cross(b);
            if v.dot(t0) < 0.0 {
                v = -v;
            }
            (x, y, v)
        }
    }
}

/// Vertex–face step of PQP's `TriDist`: when the normal of `s` separates `t`, the vertex of
/// `t` nearest the plane, if it projects into `s`, and its projection. Sets `shown` when the
/// normal separates.
#[inline]
fn vertex_face(
    s: &[DVec3; 3],
    sv: &[DVec3; 3],
    t: &[DVec3; 3],
    shown: &mut bool,
) -> Option<(DVec3, DVec3)> {
    let sn = sv[0].cross(sv[1]);
    let snl = sn.length_squared();
    // Relative form of PQP's `Snl > 1e-15`.
    if !(snl > 1e-15 * sv[0].length_squared() * sv[1].length_squared()) {
        return None;
    }
    let tp = [
        (s[0] - t[0]).dot(sn),
        (s[0] - t[1]).dot(sn),
        (s[0] - t[2]).dot(sn),
    ];
    let point = if tp[0] > 0.0 && tp[1] > 0.0 && tp[2] > 0.0 {
        let p = if tp[0] < tp[1] { 0 } else { 1 };
        if tp[2] < tp[p] {
            2
        } else {
            p
        }
    } else if tp[0] < 0.0 && tp[1] < 0.0 && tp[2] < 0.0 {
        let p = if tp[0] > tp[1] { 0 } else { 1 };
        if tp[2] > tp[p] {
            2
        } else {
            p
        }
    } else {
        return None;
    };
    *shown = true;
    let tv = t[point];
    for k in 0..3 {
        if !((tv - s[k]).dot(sn.cross(sv[k])) > 0.0) {
            return None;
        }
    }
    let onto = tv + sn * (tp[point] / snl);
    onto.is_finite().then_some((onto, tv))
}

/// PQP's `TriDist` (Larsen, Gottschalk, Lin, Manocha 1999): the closest points of two
/// triangles by the nine edge pairs with slab certificates, then the vertex–face cases.
/// `None` when it could not show the triangles disjoint (they may intersect).
#[inline]
fn tri_dist_pqp(s: &[DVec3; 3], t: &[DVec3; 3]) -> Option<(f64, DVec3, DVec3)> {
    let sv = [s[1] - s[0], s[2] - s[1], s[0] - s[2]];
    let tv = [t[1] - t[0], t[2] - t[1], t[0] - t[2]];
    let mut shown = false;
    let mut mindd = (s[0] - t[0]).length_squared() + 1.0;
    let mut min_p = s[0];
    let mut min_q = t[0];
    for i in 0..3 {
        for j in 0..3 {
            let (p, q, vec) = seg_points(s[i], sv[i], t[j], tv[j]);
            let v = q - p;
            let dd = v.length_squared();
            if dd <= mindd {
                min_p = p;
                min_q = q;
                mindd = dd;
                let mut a = (s[(i + 2) % 3] - p).dot(vec);
                let mut b = (t[(j + 2) % 3] - q).dot(vec);
                if a <= 0.0 && b >= 0.0 {
                    return Some((dd, p, q));
                }
                let pp = v.dot(vec);
                if a < 0.0 {
                    a = 0.0;
                }
                if b > 0.0 {
                    b = 0.0;
                }
                if pp - a + b > 0.0 {
                    shown = true;
                }
            }
        }
    }
    if let Some((p, q)) = vertex_face(s, &sv, t, &mut shown) {
        return Some(((p - q).length_squared(), p, q));
    }
    if let Some((q, p)) = vertex_face(t, &tv, s, &mut shown) {
        return Some(((p - q).length_squared(), p, q));
    }
    (shown && mindd.is_finite()).then_some((mindd, min_p, min_q))
}

/// Distance of two triangles known (or assumed) not to intersect: PQP's `TriDist`, or the
/// exhaustive feature pairs when it cannot show them disjoint.
#[inline]
fn disjoint_distance(a: &[DVec3; 3], b: &[DVec3; 3]) -> (f64, DVec3, DVec3) {
    match tri_dist_pqp(a, b) {
        Some(r) if r.0.is_finite() => r,
        _ => feature_distance(a, b),
    }
}

#[cfg(test)]
/// Exact-decision distance between two closed triangles with the closest points.
///
/// Intersecting triangles (decided exactly by [`triangles_intersect`]) give 0 and a common
/// point; others the minimum over the feature pairs. Never NaN for finite input.
pub(crate) fn triangle_distance(a: &[DVec3; 3], b: &[DVec3; 3]) -> TriDistance {
    triangle_distance_hint(a, b, true)
}

/// [`triangle_distance`] that skips the intersection test when `may_touch` is false (the
/// caller knows the triangles' boxes are disjoint).
#[inline]
pub(crate) fn triangle_distance_hint(
    a: &[DVec3; 3],
    b: &[DVec3; 3],
    may_touch: bool,
) -> TriDistance {
    if may_touch && !plane_separates(a, b) && !plane_separates(b, a) {
        if let Some(p) = intersection_point(a, b) {
            return TriDistance {
                dist_sq: 0.0,
                point_a: p,
                point_b: p,
                intersecting: true,
            };
        }
    }
    let (dist_sq, point_a, point_b) = disjoint_distance(a, b);
    TriDistance {
        dist_sq,
        point_a,
        point_b,
        intersecting: false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn v3(r: f64) -> impl Strategy<Value = DVec3> {
        (-r..r, -r..r, -r..r).prop_map(|(x, y, z)| DVec3::new(x, y, z))
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(3000))]

        /// The prepared triangle answers every edge of another triangle as the one-shot
        /// segment test does, for either direction of the edge; degenerate triangles, shared
        /// corners and corners on the plane included.
        #[test]
        fn sides_of_agrees_with_the_segment_test(
            s in (v3(1.0), v3(1.0), v3(1.0)), t in (v3(1.0), v3(1.0), v3(1.0)),
            degenerate in 0u8..8, u in 0.0..1.0f64,
        ) {
            let mut s = [s.0, s.1, s.2];
            let mut t = [t.0, t.1, t.2];
            match degenerate {
                1 => t[2] = t[0] + (t[1] - t[0]) * u,
                2 => s[1] = t[0],
                3 => { s[0] = t[1]; s[1] = t[0] + (t[2] - t[0]) * u; }
                4 => s[2] = s[0],
                5 => s = [t[0] + (t[1] - t[0]) * u, t[2], t[0] * (1.0 - u) + t[2] * u],
                // Within rounding of t's plane: the filter cannot decide, the exact test does.
                6 => s = [
                    t[0] + (t[1] - t[0]) * u + (t[2] - t[0]) * 0.3,
                    t[1] * (1.0 - u) + t[2] * u,
                    t[0] * 0.25 + t[1] * 0.5 + t[2] * 0.25 - (t[1] - t[0]) * u,
                ],
                _ => {}
            }
            let sides = SidesOf::new(&t, &s);
            let filtered = PlaneSides::new(&t, &s);
            let with = SidesOf::with(&t, &s, &filtered);
            prop_assert_eq!(sides.is_none(), with.is_none());
            if filtered.separates() {
                prop_assert!(sides.is_none());
            }
            for k in 0..3 {
                let j = (k + 1) % 3;
                let want = segment_triangle_intersect(s[k], s[j], t[0], t[1], t[2]);
                let got = sides.as_ref().is_some_and(|x| x.segment(s[k], s[j], k, j));
                let back = sides.as_ref().is_some_and(|x| x.segment(s[j], s[k], j, k));
                prop_assert_eq!(got, want);
                prop_assert_eq!(back, want);
                // The filtered sides decide as the exact ones, coincidences too.
                let exact = sides.as_ref().map(|x| x.segment_or_coincident(s[k], s[j], k, j));
                let fast = with.as_ref().map(|x| x.segment_or_coincident(s[k], s[j], k, j));
                prop_assert_eq!(exact, fast);
            }
        }

        /// PQP's TriDist agrees with the exhaustive feature pairs on disjoint triangles,
        /// degenerate ones included.
        #[test]
        fn tridist_matches_features(
            a in (v3(1.0), v3(1.0), v3(1.0)), b in (v3(1.0), v3(1.0), v3(1.0)), shift in v3(3.0),
            degenerate in 0u8..6, t in 0.0..1.0f64,
        ) {
            let mut a = [a.0, a.1, a.2];
            let mut b = [b.0 + shift, b.1 + shift, b.2 + shift];
            match degenerate {
                1 => a[2] = a[0] + (a[1] - a[0]) * t,
                2 => b[1] = b[0],
                3 => { a[1] = a[0]; a[2] = a[0]; }
                4 => { b[2] = b[0] + (b[1] - b[0]) * t; a[2] = a[1]; }
                _ => {}
            }
            prop_assume!(!triangles_intersect(&a, &b));
            let (fd, _, _) = feature_distance(&a, &b);
            let (d, p, q) = disjoint_distance(&a, &b);
            prop_assert!((d.sqrt() - fd.sqrt()).abs() <= 1e-12, "tridist {} features {}", d.sqrt(), fd.sqrt());
            prop_assert!(((p - q).length_squared() - d).abs() <= 1e-12);
            let on = |x: DVec3, t: &[DVec3; 3]| (x - closest_point_on_triangle(x, t[0], t[1], t[2])).length();
            // The points lie on their triangles up to rounding: the projection onto a thin
            // triangle's plane loses a few thousand ulps (4.6e-12 seen on unit-sized ones).
            prop_assert!(on(p, &a) < 1e-10 && on(q, &b) < 1e-10, "{} {}", on(p, &a), on(q, &b));
        }
    }

    #[test]
    fn simple_cases() {
        let t = [DVec3::ZERO, DVec3::X, DVec3::Y];
        // Parallel above.
        let u = [DVec3::Z, DVec3::Z + DVec3::X, DVec3::Z + DVec3::Y];
        let r = triangle_distance(&t, &u);
        assert!(!r.intersecting);
        assert!((r.dist_sq - 1.0).abs() < 1e-15);
        // Piercing: an edge of u passes through t's interior, no vertex near.
        let u = [
            DVec3::new(0.2, 0.2, -1.0),
            DVec3::new(0.2, 0.2, 1.0),
            DVec3::new(5.0, 5.0, 0.0 + 3.0),
        ];
        let r = triangle_distance(&t, &u);
        assert!(r.intersecting && r.dist_sq == 0.0);
        // The reported point lies on both triangles.
        for tri in [&t, &u] {
            let q = closest_point_on_triangle(r.point_a, tri[0], tri[1], tri[2]);
            assert!((q - r.point_a).length() < 1e-12);
        }
        // Touching at a shared vertex, coplanar.
        let u = [
            DVec3::X,
            DVec3::new(2.0, 0.0, 0.0),
            DVec3::new(2.0, 1.0, 0.0),
        ];
        assert!(triangles_intersect(&t, &u));
        // Coplanar, one inside the other.
        let u = [
            DVec3::new(0.1, 0.1, 0.0),
            DVec3::new(0.2, 0.1, 0.0),
            DVec3::new(0.1, 0.2, 0.0),
        ];
        assert!(triangles_intersect(&t, &u) && triangles_intersect(&u, &t));
        // Coplanar, disjoint.
        let u = [
            DVec3::new(0.6, 0.6, 0.0),
            DVec3::new(1.0, 0.6, 0.0),
            DVec3::new(0.6, 1.0, 0.0),
        ];
        assert!(!triangles_intersect(&t, &u));
        let r = triangle_distance(&t, &u);
        assert!((r.dist_sq - 0.02).abs() < 1e-12, "{}", r.dist_sq);
        // Point triangle on the face / off the face.
        let p = DVec3::new(0.25, 0.25, 0.0);
        assert!(triangles_intersect(&t, &[p; 3]));
        assert!(!triangles_intersect(&t, &[p + DVec3::Z * 1e-300; 3]));
        let r = triangle_distance(&t, &[p + DVec3::Z; 3]);
        assert!((r.dist_sq - 1.0).abs() < 1e-15);
        // Needles crossing in space vs. skew.
        let n1 = [
            DVec3::new(-1.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(0.5, 0.0, 0.0),
        ];
        let n2 = [
            DVec3::new(0.0, -1.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
            DVec3::new(0.0, 0.5, 0.0),
        ];
        assert!(triangles_intersect(&n1, &n2));
        let n3 = n2.map(|v| v + DVec3::Z * 1e-200);
        assert!(!triangles_intersect(&n1, &n3));
        let r = triangle_distance(&n1, &n2.map(|v| v + DVec3::Z));
        assert!((r.dist_sq - 1.0).abs() < 1e-15);
    }

    #[test]
    fn segments() {
        let (d, x, y) = segment_segment_closest(
            DVec3::ZERO,
            DVec3::X,
            DVec3::new(0.5, 1.0, 1.0),
            DVec3::new(0.5, -1.0, 1.0),
        );
        assert!((d - 1.0).abs() < 1e-15);
        assert!((x - DVec3::new(0.5, 0.0, 0.0)).length() < 1e-15);
        assert!((y - DVec3::new(0.5, 0.0, 1.0)).length() < 1e-15);
        // Parallel, overlapping.
        let (d, _, _) = segment_segment_closest(
            DVec3::ZERO,
            DVec3::X,
            DVec3::new(0.5, 2.0, 0.0),
            DVec3::new(3.0, 2.0, 0.0),
        );
        assert!((d - 4.0).abs() < 1e-15);
        // Points.
        let (d, _, _) = segment_segment_closest(DVec3::ZERO, DVec3::ZERO, DVec3::Y, DVec3::Y);
        assert_eq!(d, 1.0);
        assert!(segments_intersect(
            DVec3::ZERO,
            DVec3::X,
            DVec3::X,
            DVec3::ONE
        ));
        assert!(!segments_intersect(
            DVec3::ZERO,
            DVec3::X,
            DVec3::new(1.0 + 1e-15, 0.0, 0.0),
            DVec3::ONE
        ));
        // Collinear overlapping along a diagonal (projections degenerate on no axis).
        assert!(segments_intersect(
            DVec3::ZERO,
            DVec3::ONE,
            DVec3::ONE * 0.5,
            DVec3::ONE * 2.0
        ));
        assert!(!segments_intersect(
            DVec3::ZERO,
            DVec3::ONE,
            DVec3::ONE * 1.5,
            DVec3::ONE * 2.0
        ));
    }
}
