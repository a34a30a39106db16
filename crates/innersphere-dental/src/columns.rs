//! The first crossing of a surface's offset along the columns of a 2-D grid.
//!
//! For every vertical line `(x, y, ·)` of a [`ColumnGrid`], [`lowest_offset`] gives the lowest
//! `z` at which the line comes within `offset` of a triangle soup: the lowest point of the
//! level set `distance = offset` of the surface's exact distance field on that line. It is
//! exact (no sampling along `z`): the offset of one triangle is a convex body bounded by three
//! vertex balls, three edge cylinders and two faces, and the lowest point of a line in it is
//! the lowest of those pieces' crossings. Everything above that point in the column is
//! "behind" the surface as seen from below, so the answer is also the surface's offset with
//! its undercuts blocked out along `+z`; the splint's imprint surfaces are these heights.

use glam::{DVec2, DVec3};
use rayon::prelude::*;

/// A 2-D grid of vertical columns: column `(i, j)` is the line through
/// `origin + h · (i, j)`, parallel to `z`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ColumnGrid {
    /// `(x, y)` of column `(0, 0)`.
    pub origin: DVec2,
    /// Spacing of the columns.
    pub h: f64,
    /// Number of columns along x and y.
    pub dims: [usize; 2],
}

impl ColumnGrid {
    /// Number of columns.
    pub fn len(&self) -> usize {
        self.dims[0] * self.dims[1]
    }

    /// True when the grid has no column.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Index of column `(i, j)`: x fastest.
    #[inline]
    pub fn index(&self, i: usize, j: usize) -> usize {
        i + self.dims[0] * j
    }

    /// `(x, y)` of column `(i, j)`.
    #[inline]
    pub fn point(&self, i: usize, j: usize) -> DVec2 {
        self.origin + DVec2::new(i as f64, j as f64) * self.h
    }

    /// `(x, y)` of the column with index `idx`.
    #[inline]
    pub fn point_of(&self, idx: usize) -> DVec2 {
        self.point(idx % self.dims[0], idx / self.dims[0])
    }
}

/// For each column of `grid`, the lowest `z` of the points within distance `offset` (≥ 0)
/// of the triangles `tris` (`f64::INFINITY` where the column misses them all); see the
/// [module docs](self). Parallel over the triangles; the answer does not depend on the
/// thread count (a minimum).
pub fn lowest_offset(tris: &[[DVec3; 3]], grid: &ColumnGrid, offset: f64) -> Vec<f64> {
    let n = grid.len();
    let chunk = (tris.len() / (4 * rayon::current_num_threads().max(1))).max(4096);
    tris.par_chunks(chunk)
        .map(|part| {
            let mut low = vec![f64::INFINITY; n];
            for t in part {
                raster_triangle(t, grid, offset, &mut low);
            }
            low
        })
        .reduce_with(|mut a, b| {
            for (x, y) in a.iter_mut().zip(b) {
                *x = x.min(y);
            }
            a
        })
        .unwrap_or_else(|| vec![f64::INFINITY; n])
}

/// Lowers `low` at every column that the offset of triangle `t` reaches.
fn raster_triangle(t: &[DVec3; 3], grid: &ColumnGrid, c: f64, low: &mut [f64]) {
    let lo = t[0].min(t[1]).min(t[2]);
    let hi = t[0].max(t[1]).max(t[2]);
    let i0 = ((lo.x - c - grid.origin.x) / grid.h).ceil().max(0.0);
    let j0 = ((lo.y - c - grid.origin.y) / grid.h).ceil().max(0.0);
    let i1 = ((hi.x + c - grid.origin.x) / grid.h)
        .floor()
        .min(grid.dims[0] as f64 - 1.0);
    let j1 = ((hi.y + c - grid.origin.y) / grid.h)
        .floor()
        .min(grid.dims[1] as f64 - 1.0);
    if !(i0 <= i1 && j0 <= j1) {
        return;
    }
    let prep = Prepared::new(t);
    for j in j0 as usize..=j1 as usize {
        for i in i0 as usize..=i1 as usize {
            let q = grid.point(i, j);
            let z = prep.lowest(q, c);
            let slot = &mut low[grid.index(i, j)];
            if z < *slot {
                *slot = z;
            }
        }
    }
}

/// One triangle with what its offset's pieces need.
struct Prepared {
    v: [DVec3; 3],
    /// Unit normal (zero for a degenerate triangle).
    n: DVec3,
}

impl Prepared {
    fn new(t: &[DVec3; 3]) -> Self {
        let n = (t[1] - t[0]).cross(t[2] - t[0]);
        let l = n.length();
        Prepared {
            v: *t,
            n: if l > 0.0 { n / l } else { DVec3::ZERO },
        }
    }

    /// The lowest `z` on the vertical line through `q` within distance `c` of the triangle
    /// (`INFINITY` when none): the lowest crossing of its vertex balls, edge cylinders
    /// (where the foot lies on the edge) and offset faces (where the foot lies in the
    /// triangle).
    fn lowest(&self, q: DVec2, c: f64) -> f64 {
        let c2 = c * c;
        let mut best = f64::INFINITY;
        for v in &self.v {
            let r2 = (q - v.truncate()).length_squared();
            if r2 <= c2 {
                best = best.min(v.z - (c2 - r2).sqrt());
            }
        }
        for k in 0..3 {
            let p0 = self.v[k];
            let d = self.v[(k + 1) % 3] - p0;
            let len2 = d.length_squared();
            if len2 == 0.0 {
                continue;
            }
            let u = d / len2.sqrt();
            // w(z) = w0 + z·e_z; |w|² − (w·u)² = c² is a quadratic in z.
            let w0 = DVec3::new(q.x - p0.x, q.y - p0.y, -p0.z);
            let wu = w0.dot(u);
            let a = 1.0 - u.z * u.z;
            if a < 1e-12 {
                continue; // a vertical edge: its lowest point is the lower vertex's ball
            }
            let b = 2.0 * (w0.z - wu * u.z);
            let cc = w0.length_squared() - wu * wu - c2;
            let disc = b * b - 4.0 * a * cc;
            if disc < 0.0 {
                continue;
            }
            let z = (-b - disc.sqrt()) / (2.0 * a);
            let t = (wu + z * u.z) / len2.sqrt();
            if (0.0..=1.0).contains(&t) {
                best = best.min(z);
            }
        }
        let n = self.n;
        if n.z.abs() > 1e-12 {
            for s in [-1.0, 1.0] {
                // The plane n·(X − v0) = s·c, at (q, z).
                let z = (s * c + n.dot(self.v[0]) - n.x * q.x - n.y * q.y) / n.z;
                if z < best && self.foot_inside(DVec3::new(q.x, q.y, z) - n * (s * c)) {
                    best = z;
                }
            }
        }
        best
    }

    /// True when `p` (in the triangle's plane) lies in the triangle.
    fn foot_inside(&self, p: DVec3) -> bool {
        let [a, b, c] = self.v;
        let n = self.n;
        let e0 = (b - a).cross(p - a).dot(n);
        let e1 = (c - b).cross(p - b).dot(n);
        let e2 = (a - c).cross(p - c).dot(n);
        e0 >= 0.0 && e1 >= 0.0 && e2 >= 0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use innersphere::mesh::closest::point_triangle_distance_sq;
    use proptest::prelude::*;

    fn grid() -> ColumnGrid {
        ColumnGrid {
            origin: DVec2::new(-1.0, -1.0),
            h: 0.05,
            dims: [41, 41],
        }
    }

    /// The lowest z within `c` of `t` on the line through `q`, by bisection on the convex
    /// distance along the line from its minimum downwards.
    fn reference(t: &[DVec3; 3], q: DVec2, c: f64) -> f64 {
        let d =
            |z: f64| point_triangle_distance_sq(DVec3::new(q.x, q.y, z), t[0], t[1], t[2]).sqrt();
        // Minimum of the convex d(z) by golden-section search.
        let (mut lo, mut hi) = (-10.0, 10.0);
        for _ in 0..200 {
            let m1 = lo + (hi - lo) * 0.382;
            let m2 = lo + (hi - lo) * 0.618;
            if d(m1) <= d(m2) {
                hi = m2;
            } else {
                lo = m1;
            }
        }
        let zmin = 0.5 * (lo + hi);
        if d(zmin) > c {
            return f64::INFINITY;
        }
        let (mut a, mut b) = (-10.0, zmin);
        for _ in 0..200 {
            let m = 0.5 * (a + b);
            if d(m) > c {
                a = m;
            } else {
                b = m;
            }
        }
        b
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        /// Every column's answer equals the bisection on the exact point–triangle distance.
        #[test]
        fn lowest_offset_is_the_exact_lowest_crossing(
            pts in proptest::array::uniform9(-0.8f64..0.8),
            c in 0.0f64..0.3,
        ) {
            let t = [
                DVec3::new(pts[0], pts[1], pts[2]),
                DVec3::new(pts[3], pts[4], pts[5]),
                DVec3::new(pts[6], pts[7], pts[8]),
            ];
            let g = grid();
            let low = lowest_offset(&[t], &g, c);
            for idx in (0..g.len()).step_by(7) {
                let want = reference(&t, g.point_of(idx), c);
                let got = low[idx];
                if want.is_infinite() {
                    // A miss is allowed to be a touch within rounding.
                    let q = g.point_of(idx);
                    let touch = got.is_infinite()
                        || point_triangle_distance_sq(DVec3::new(q.x, q.y, got), t[0], t[1], t[2]).sqrt() <= c + 1e-9;
                    prop_assert!(touch, "column {} answers {} where none reaches", idx, got);
                } else {
                    prop_assert!((got - want).abs() < 1e-6, "column {idx}: {got} vs {want}");
                }
            }
        }
    }

    #[test]
    fn a_flat_square_is_lowered_by_the_offset_and_rounded_at_its_edge() {
        let a = DVec3::new(-0.5, -0.5, 1.0);
        let b = DVec3::new(0.5, -0.5, 1.0);
        let c = DVec3::new(0.5, 0.5, 1.0);
        let d = DVec3::new(-0.5, 0.5, 1.0);
        let g = grid();
        let low = lowest_offset(&[[a, b, c], [a, c, d]], &g, 0.1);
        let at = |x: f64, y: f64| {
            let i = ((x - g.origin.x) / g.h).round() as usize;
            let j = ((y - g.origin.y) / g.h).round() as usize;
            low[g.index(i, j)]
        };
        assert!((at(0.0, 0.0) - 0.9).abs() < 1e-12);
        assert!((at(0.55, 0.0) - (1.0 - (0.01f64 - 0.0025).sqrt())).abs() < 1e-12);
        assert!(at(0.7, 0.0).is_infinite());
    }
}
