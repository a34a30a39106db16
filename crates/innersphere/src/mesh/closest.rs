//! Closest point on a triangle (after Ericson, *Real-Time Collision Detection*, 5.1.5), in f64.
//!
//! Robust for degenerate input: zero-area, needle and point triangles give the closest point
//! on their segments, never NaN (for finite input).

use glam::DVec3;

/// Closest point to `p` on the segment `[a, b]` (a point segment gives `a`).
#[inline]
pub(crate) fn closest_point_on_segment(p: DVec3, a: DVec3, b: DVec3) -> DVec3 {
    let ab = b - a;
    let len_sq = ab.length_squared();
    if len_sq.is_nan() || len_sq <= 0.0 {
        return a;
    }
    let t = ((p - a).dot(ab) / len_sq).clamp(0.0, 1.0);
    if t.is_finite() {
        a + ab * t
    } else {
        a
    }
}

/// Closest point to `p` on the (filled) triangle `a, b, c`.
///
/// Ericson's Voronoi-region method. The vertex regions are exact for any triangle; a
/// zero-length edge, or a face-region answer on a (nearly) degenerate triangle — an angle at
/// `a` whose sine is below 1e-5 — falls back to the nearest point on the three edges, which
/// such a triangle lies within rounding distance of. Never NaN for finite input.
///
/// The answer is clamped into the triangle's bounding box, so that the squared distance to
/// it is never below the (identically rounded) squared distance to any box around the
/// triangle: tree searches that prune boxes give bit-identical results to brute force.
#[inline]
pub(crate) fn closest_point_on_triangle(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> DVec3 {
    let q = region_closest(p, a, b, c);
    q.max(a.min(b).min(c)).min(a.max(b).max(c))
}

/// Ericson's region method (before the clamp): vertex regions first (exact for any
/// triangle), then edge regions, then the face; zero-length edges and thin triangles fall
/// back to the edges.
#[inline]
fn region_closest(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> DVec3 {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(ap);
    let d2 = ac.dot(ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return a; // vertex region A
    }
    let bp = p - b;
    let d3 = ab.dot(bp);
    let d4 = ac.dot(bp);
    if d3 >= 0.0 && d4 <= d3 {
        return b; // vertex region B
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        // Edge region AB: d1 - d3 = |ab|², zero only for a point edge.
        let den = d1 - d3;
        return if den > 0.0 {
            a + ab * (d1 / den)
        } else {
            closest_on_edges(p, a, b, c)
        };
    }
    let cp = p - c;
    let d5 = ab.dot(cp);
    let d6 = ac.dot(cp);
    if d6 >= 0.0 && d5 <= d6 {
        return c; // vertex region C
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        // Edge region AC.
        let den = d2 - d6;
        return if den > 0.0 {
            a + ac * (d2 / den)
        } else {
            closest_on_edges(p, a, b, c)
        };
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        // Edge region BC.
        let den = (d4 - d3) + (d5 - d6);
        return if den > 0.0 {
            b + (c - b) * ((d4 - d3) / den)
        } else {
            closest_on_edges(p, a, b, c)
        };
    }
    // Face region: the barycentric projection, unless the triangle is too thin for it.
    let denom = va + vb + vc;
    let nn = ab.cross(ac).length_squared();
    if denom > 0.0 && nn > 1e-10 * ab.length_squared() * ac.length_squared() {
        let q = a + ab * (vb / denom) + ac * (vc / denom);
        if q.is_finite() {
            return q;
        }
    }
    closest_on_edges(p, a, b, c)
}

/// Nearest point to `p` on the three edges of a triangle.
fn closest_on_edges(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> DVec3 {
    let mut best = closest_point_on_segment(p, a, b);
    let mut best_d = (p - best).length_squared();
    for q in [
        closest_point_on_segment(p, b, c),
        closest_point_on_segment(p, c, a),
    ] {
        let d = (p - q).length_squared();
        if d < best_d {
            best = q;
            best_d = d;
        }
    }
    best
}

/// Squared distance from `p` to the triangle `a, b, c`.
#[inline]
pub fn point_triangle_distance_sq(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> f64 {
    (p - closest_point_on_triangle(p, a, b, c)).length_squared()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Independent reference: plane projection when it falls inside, else the edges.
    fn reference(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> f64 {
        let mut best = [(a, b), (b, c), (c, a)]
            .iter()
            .map(|&(u, v)| (p - closest_point_on_segment(p, u, v)).length_squared())
            .fold(f64::INFINITY, f64::min);
        let n = (b - a).cross(c - a);
        let nn = n.length_squared();
        if nn > 0.0 {
            let q = p - n * (n.dot(p - a) / nn);
            let inside = [(a, b), (b, c), (c, a)]
                .iter()
                .all(|&(u, v)| (v - u).cross(q - u).dot(n) >= 0.0);
            if inside {
                best = best.min((p - q).length_squared());
            }
        }
        best
    }

    /// Dense sampling of the triangle: an upper bound on the true distance.
    fn sampled(p: DVec3, a: DVec3, b: DVec3, c: DVec3, n: usize) -> f64 {
        let mut best = f64::INFINITY;
        for i in 0..=n {
            for j in 0..=(n - i) {
                let u = i as f64 / n as f64;
                let v = j as f64 / n as f64;
                let q = a + (b - a) * u + (c - a) * v;
                best = best.min((p - q).length_squared());
            }
        }
        best
    }

    fn v3() -> impl Strategy<Value = DVec3> {
        (-2.0..2.0f64, -2.0..2.0f64, -2.0..2.0f64).prop_map(|(x, y, z)| DVec3::new(x, y, z))
    }

    proptest! {
        #[test]
        fn matches_reference(p in v3(), a in v3(), b in v3(), c in v3()) {
            let q = closest_point_on_triangle(p, a, b, c);
            let d = (p - q).length_squared();
            let r = reference(p, a, b, c);
            prop_assert!((d.sqrt() - r.sqrt()).abs() <= 1e-9, "d {} ref {}", d, r);
            // The point lies on the triangle: its distance to the triangle is 0.
            prop_assert!(reference(q, a, b, c) <= 1e-18 * (1.0 + a.length_squared() + b.length_squared() + c.length_squared()));
            let s = sampled(p, a, b, c, 60);
            prop_assert!(d <= s + 1e-12);
        }

        #[test]
        fn degenerate_triangles_never_nan(p in v3(), a in v3(), b in v3(), t in 0.0..1.0f64, eps in prop::sample::select(vec![0.0, 1e-300, 1e-17, 1e-12, 1e-8])) {
            // c on (or a hair off) the line through a and b; also point triangles.
            let c = a + (b - a) * t + DVec3::new(eps, -eps, eps);
            for (x, y, z) in [(a, b, c), (a, a, b), (a, a, a), (c, b, a), (b, c, a)] {
                let q = closest_point_on_triangle(p, x, y, z);
                prop_assert!(q.is_finite());
                let d = (p - q).length_squared().sqrt();
                // The sliver is at most ~eps wide: its distance is within that of its edges.
                let e = [(x, y), (y, z), (z, x)]
                    .iter()
                    .map(|&(u, v)| (p - closest_point_on_segment(p, u, v)).length())
                    .fold(f64::INFINITY, f64::min);
                prop_assert!(d <= e + 1e-12 && d >= e - 1e-7, "d {} edges {}", d, e);
            }
        }
    }

    #[test]
    fn needle_and_point() {
        let a = DVec3::new(0.0, 0.0, 0.0);
        let b = DVec3::new(1.0, 0.0, 0.0);
        let c = DVec3::new(0.5, 1e-300, 0.0);
        let p = DVec3::new(0.5, 1.0, 0.0);
        let q = closest_point_on_triangle(p, a, b, c);
        assert!((q - DVec3::new(0.5, 0.0, 0.0)).length() < 1e-12);
        assert_eq!(closest_point_on_triangle(p, a, a, a), a);
        assert_eq!(point_triangle_distance_sq(DVec3::ZERO, b, b, b), 1.0);
    }
}
