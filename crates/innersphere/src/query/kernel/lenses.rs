//! The per-pair terms of the penetration sums, four leaf pairs at a time: direction, lens
//! volume and centroid, contact point, depth, the centroid's moment arm and the lens disc's
//! area. Lane by lane and branch-free (selects instead of branches), so that the compiler
//! vectorises it, with the same operations in the same order as [`direction`] and
//! [`lens`] / [`lens_area`] per pair: the values are bit for bit the scalar ones (tested).
//!
//! [`direction`]: super::geometry::direction
//! [`lens`]: super::geometry::lens
//! [`lens_area`]: super::geometry::lens_area

/// Lanes of a batch.
pub(crate) const W: usize = 4;

/// The inputs of a batch: A's and B's sphere centres (A's frame) and radii, as f64.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Pairs4 {
    pub ca: [[f64; W]; 3],
    pub ra: [f64; W],
    pub cb: [[f64; W]; 3],
    pub rb: [f64; W],
}

/// The terms of a batch (per lane).
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Terms4 {
    /// Lens volume.
    pub v: [f64; W],
    /// Unit direction from A's centre to B's.
    pub u: [[f64; W]; 3],
    /// The lens centroid `ca + u·g`.
    pub p: [[f64; W]; 3],
    /// `p × u`.
    pub s: [[f64; W]; 3],
    /// `ra + rb − d`.
    pub depth: [f64; W],
    /// The lens disc's area (only when asked).
    pub area: [f64; W],
}

/// `if c { a } else { b }`, branch-free.
#[inline(always)]
fn sel(c: bool, a: f64, b: f64) -> f64 {
    if c {
        a
    } else {
        b
    }
}

/// [`super::geometry::lens`] of one lane, branch-free.
#[inline(always)]
fn lens_lane(ra: f64, rb: f64, d: f64) -> (f64, f64) {
    use std::f64::consts::PI;
    // The general case, computed whatever the lane's case (its value is discarded where
    // another case applies).
    let x = (d * d + ra * ra - rb * rb) / (2.0 * d);
    let ha = ra - x;
    let ha = sel(ha < 0.0, 0.0, ha);
    let ha = sel(ha > 2.0 * ra, 2.0 * ra, ha);
    let hb = rb - (d - x);
    let hb = sel(hb < 0.0, 0.0, hb);
    let hb = sel(hb > 2.0 * rb, 2.0 * rb, hb);
    let va = PI * ha * ha * (3.0 * ra - ha) / 3.0;
    let vb = PI * hb * hb * (3.0 * rb - hb) / 3.0;
    let v = va + vb;
    let ka = 3.0 * ra - ha;
    let ga = sel(
        ka <= 0.0,
        0.0,
        3.0 * (2.0 * ra - ha) * (2.0 * ra - ha) / (4.0 * ka),
    );
    let kb = 3.0 * rb - hb;
    let cb = sel(
        kb <= 0.0,
        0.0,
        3.0 * (2.0 * rb - hb) * (2.0 * rb - hb) / (4.0 * kb),
    );
    let gb = d - cb;
    let general = (
        sel(v <= 0.0, 0.0, v),
        sel(v <= 0.0, x, (va * ga + vb * gb) / v),
    );
    // One ball inside the other.
    let r = sel(ra < rb, ra, rb);
    let inside = (4.0 / 3.0 * PI * r * r * r, sel(ra <= rb, 0.0, d));
    let is_inside = d <= (ra - rb).abs();
    let apart = d >= ra + rb;
    (
        sel(apart, 0.0, sel(is_inside, inside.0, general.0)),
        sel(apart, 0.0, sel(is_inside, inside.1, general.1)),
    )
}

/// [`super::geometry::lens_area`] of one lane, branch-free.
#[inline(always)]
fn area_lane(ra: f64, rb: f64, d: f64) -> f64 {
    let x = (d * d + ra * ra - rb * rb) / (2.0 * d);
    let a = std::f64::consts::PI * (ra * ra - x * x);
    let a = sel(a < 0.0, 0.0, a);
    sel(d >= ra + rb || d <= (ra - rb).abs(), 0.0, a)
}

/// The terms of four pairs; the lens areas when `AREA`.
#[inline(always)]
pub(crate) fn terms<const AREA: bool>(q: &Pairs4) -> Terms4 {
    let mut t = Terms4::default();
    for l in 0..W {
        let (ra, rb) = (q.ra[l], q.rb[l]);
        let vx = q.cb[0][l] - q.ca[0][l];
        let vy = q.cb[1][l] - q.ca[1][l];
        let vz = q.cb[2][l] - q.ca[2][l];
        let d = (vx * vx + vy * vy + vz * vz).sqrt();
        let pos = d > 0.0;
        let u = [
            sel(pos, vx / d, 0.0),
            sel(pos, vy / d, 0.0),
            sel(pos, vz / d, 0.0),
        ];
        let d = sel(pos, d, 0.0);
        let (v, g) = lens_lane(ra, rb, d);
        let p = [
            q.ca[0][l] + u[0] * g,
            q.ca[1][l] + u[1] * g,
            q.ca[2][l] + u[2] * g,
        ];
        t.v[l] = v;
        t.depth[l] = ra + rb - d;
        t.s[0][l] = p[1] * u[2] - u[1] * p[2];
        t.s[1][l] = p[2] * u[0] - u[2] * p[0];
        t.s[2][l] = p[0] * u[1] - u[0] * p[1];
        for k in 0..3 {
            t.u[k][l] = u[k];
            t.p[k][l] = p[k];
        }
        if AREA {
            t.area[l] = area_lane(ra, rb, d);
        }
    }
    t
}

#[cfg(test)]
mod tests {
    use super::super::geometry::{direction, lens, lens_area};
    use super::*;
    use glam::DVec3;
    use proptest::prelude::*;

    proptest! {
        /// Every term equals the scalar functions' bit for bit: apart, overlapping, one
        /// inside the other, concentric, tangent.
        #[test]
        fn terms_equal_the_scalar_ones(
            lanes in prop::collection::vec(
                ([-3.0f64..3.0, -3.0f64..3.0, -3.0f64..3.0], 0.01f64..2.0,
                 prop_oneof![
                     [-3.0f64..3.0, -3.0f64..3.0, -3.0f64..3.0].prop_map(Some),
                     Just(None),
                 ],
                 0.01f64..2.0),
                W,
            ),
        ) {
            let mut q = Pairs4::default();
            for (l, (ca, ra, cb, rb)) in lanes.iter().enumerate() {
                let cb = cb.unwrap_or(*ca); // concentric lanes too
                for k in 0..3 {
                    q.ca[k][l] = ca[k];
                    q.cb[k][l] = cb[k];
                }
                q.ra[l] = *ra;
                q.rb[l] = *rb;
            }
            let t = terms::<true>(&q);
            let bits = |x: f64| x.to_bits();
            for l in 0..W {
                let ca = DVec3::new(q.ca[0][l], q.ca[1][l], q.ca[2][l]);
                let cb = DVec3::new(q.cb[0][l], q.cb[1][l], q.cb[2][l]);
                let (u, d) = direction(ca, cb);
                let (v, g) = lens(q.ra[l], q.rb[l], d);
                let p = ca + u * g;
                let s = p.cross(u);
                prop_assert_eq!(bits(t.v[l]), bits(v));
                prop_assert_eq!(bits(t.depth[l]), bits(q.ra[l] + q.rb[l] - d));
                prop_assert_eq!(bits(t.area[l]), bits(lens_area(q.ra[l], q.rb[l], d)));
                for k in 0..3 {
                    prop_assert_eq!(bits(t.u[k][l]), bits(u[k]));
                    prop_assert_eq!(bits(t.p[k][l]), bits(p[k]));
                    prop_assert_eq!(bits(t.s[k][l]), bits(s[k]));
                }
            }
        }
    }
}
