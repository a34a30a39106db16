//! The lens of two overlapping spheres and the penetration terms of a leaf pair: direction,
//! lens volume and centroid, contact point, depth, moment arm and the lens disc's area; for
//! one pair and for four pairs at a time.
//!
//! One formula serves both: [`pair`] is branch-free (selects instead of branches) and
//! [`terms`] runs it lane by lane, so that the compiler vectorises the four lanes while every
//! lane gives the one-pair value bit for bit. It divides twice per pair: the centroid's
//! moment `va·ga + vb·gb` is summed in closed form (`π/4·h²(2r − h)²` per cap), where the
//! cap-by-cap centroids cost four more divisions.

use std::f64::consts::PI;

/// Lanes of a batch.
pub(crate) const W: usize = 4;

/// `if c { a } else { b }`, branch-free.
#[inline(always)]
fn sel(c: bool, a: f64, b: f64) -> f64 {
    if c {
        a
    } else {
        b
    }
}

/// Lens volume of two balls of radii `ra`, `rb` whose centres are `d` apart (`inv` = 1/d)
/// and the distance of its centroid from A's centre along the centre line: the smaller ball
/// (centred at its own centre) when one holds the other, zero when they are apart.
#[inline(always)]
fn lens_at(ra: f64, rb: f64, d: f64, inv: f64) -> (f64, f64) {
    // The general case, computed whatever the case (its value is discarded where another
    // applies). The boundaries meet in a circle `x` from A's centre; the caps are `ha`, `hb`
    // high.
    let x = (d * d + ra * ra - rb * rb) * (0.5 * inv);
    let ha = ra - x;
    let ha = sel(ha < 0.0, 0.0, ha);
    let ha = sel(ha > 2.0 * ra, 2.0 * ra, ha);
    let hb = rb - (d - x);
    let hb = sel(hb < 0.0, 0.0, hb);
    let hb = sel(hb > 2.0 * rb, 2.0 * rb, hb);
    let va = PI / 3.0 * ha * ha * (3.0 * ra - ha);
    let vb = PI / 3.0 * hb * hb * (3.0 * rb - hb);
    let v = va + vb;
    // A cap's volume times its centroid's distance from its centre: π/4·(h(2r − h))².
    let ea = ha * (2.0 * ra - ha);
    let eb = hb * (2.0 * rb - hb);
    let moment = PI / 4.0 * (ea * ea - eb * eb) + vb * d;
    let general = (sel(v <= 0.0, 0.0, v), sel(v <= 0.0, x, moment / v));
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

/// Area of the disc where the boundaries of two overlapping spheres meet (`inv` = 1/d): minus
/// the derivative of the lens volume with respect to `d`. Zero when they do not overlap or
/// one holds the other (moving it changes nothing then).
#[inline(always)]
fn disc_at(ra: f64, rb: f64, d: f64, inv: f64) -> f64 {
    let x = (d * d + ra * ra - rb * rb) * (0.5 * inv);
    let a = PI * (ra * ra - x * x);
    let a = sel(a < 0.0, 0.0, a);
    sel(d >= ra + rb || d <= (ra - rb).abs(), 0.0, a)
}

/// Lens volume and centroid distance from A's centre of balls `ra`, `rb` with centres `d`
/// apart (see [`pair`]).
#[inline]
pub(crate) fn lens(ra: f64, rb: f64, d: f64) -> (f64, f64) {
    lens_at(ra, rb, d, 1.0 / d)
}

#[cfg(test)]
/// Volume of the intersection of two balls of radii `ra`, `rb` whose centres are `d` apart
/// (the spherical lens; the smaller ball when one contains the other; 0 when disjoint).
pub(crate) fn lens_volume(ra: f64, rb: f64, d: f64) -> f64 {
    lens(ra, rb, d).0
}

/// The terms of one leaf pair (A's frame).
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct PairTerms {
    /// Lens volume.
    pub v: f64,
    /// Unit direction from A's centre to B's (zero when they coincide).
    pub u: [f64; 3],
    /// The lens centroid `ca + u·g`.
    pub p: [f64; 3],
    /// `p × u`.
    pub s: [f64; 3],
    /// `ra + rb − d`.
    pub depth: f64,
    /// The lens disc's area (only when asked).
    pub area: f64,
}

/// The terms of A's sphere (`ca`, `ra`) and B's (`cb`, `rb`); the disc's area when `AREA`.
#[inline(always)]
pub(crate) fn pair<const AREA: bool>(ca: [f64; 3], ra: f64, cb: [f64; 3], rb: f64) -> PairTerms {
    let vx = cb[0] - ca[0];
    let vy = cb[1] - ca[1];
    let vz = cb[2] - ca[2];
    let d = (vx * vx + vy * vy + vz * vz).sqrt();
    let pos = d > 0.0;
    let inv = 1.0 / d;
    let u = [
        sel(pos, vx * inv, 0.0),
        sel(pos, vy * inv, 0.0),
        sel(pos, vz * inv, 0.0),
    ];
    let d = sel(pos, d, 0.0);
    let (v, g) = lens_at(ra, rb, d, inv);
    let p = [ca[0] + u[0] * g, ca[1] + u[1] * g, ca[2] + u[2] * g];
    PairTerms {
        v,
        u,
        p,
        s: [
            p[1] * u[2] - u[1] * p[2],
            p[2] * u[0] - u[2] * p[0],
            p[0] * u[1] - u[0] * p[1],
        ],
        depth: ra + rb - d,
        area: if AREA { disc_at(ra, rb, d, inv) } else { 0.0 },
    }
}

/// The inputs of a batch: A's and B's sphere centres (A's frame) and radii, as f64.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Pairs4 {
    pub ca: [[f64; W]; 3],
    pub ra: [f64; W],
    pub cb: [[f64; W]; 3],
    pub rb: [f64; W],
}

/// The terms of a batch, lane by lane (see [`PairTerms`]).
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Terms4 {
    pub v: [f64; W],
    pub u: [[f64; W]; 3],
    pub p: [[f64; W]; 3],
    pub s: [[f64; W]; 3],
    pub depth: [f64; W],
    pub area: [f64; W],
}

/// The terms of four pairs; the discs' areas when `AREA`.
#[inline(always)]
pub(crate) fn terms<const AREA: bool>(q: &Pairs4) -> Terms4 {
    let mut t = Terms4::default();
    for l in 0..W {
        let ca = [q.ca[0][l], q.ca[1][l], q.ca[2][l]];
        let cb = [q.cb[0][l], q.cb[1][l], q.cb[2][l]];
        let one = pair::<AREA>(ca, q.ra[l], cb, q.rb[l]);
        t.v[l] = one.v;
        t.depth[l] = one.depth;
        t.area[l] = one.area;
        for k in 0..3 {
            t.u[k][l] = one.u[k];
            t.p[k][l] = one.p[k];
            t.s[k][l] = one.s[k];
        }
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;
    use proptest::prelude::*;

    proptest! {
        /// Every lane equals the one-pair terms bit for bit: apart, overlapping, one inside
        /// the other, concentric.
        #[test]
        fn lanes_equal_the_one_pair_terms(
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
                let ca = [q.ca[0][l], q.ca[1][l], q.ca[2][l]];
                let cb = [q.cb[0][l], q.cb[1][l], q.cb[2][l]];
                let one = pair::<true>(ca, q.ra[l], cb, q.rb[l]);
                prop_assert_eq!(bits(t.v[l]), bits(one.v));
                prop_assert_eq!(bits(t.depth[l]), bits(one.depth));
                prop_assert_eq!(bits(t.area[l]), bits(one.area));
                for k in 0..3 {
                    prop_assert_eq!(bits(t.u[k][l]), bits(one.u[k]));
                    prop_assert_eq!(bits(t.p[k][l]), bits(one.p[k]));
                    prop_assert_eq!(bits(t.s[k][l]), bits(one.s[k]));
                }
            }
        }

        /// The closed-form centroid agrees with the cap-by-cap one (the formula it replaced)
        /// and the volume with the classic closed form, to rounding.
        #[test]
        fn lens_agrees_with_the_cap_by_cap_formula(
            ra in 0.01f64..2.0, rb in 0.01f64..2.0, t in 0.0f64..1.0,
        ) {
            let (lo, hi) = ((ra - rb).abs(), ra + rb);
            let d = lo + (hi - lo) * t;
            prop_assume!(d > lo && d < hi);
            let (v, g) = lens(ra, rb, d);
            let cap = |r: f64, h: f64| (PI * h * h * (3.0 * r - h) / 3.0, 3.0 * (2.0 * r - h).powi(2) / (4.0 * (3.0 * r - h)));
            let x = (d * d + ra * ra - rb * rb) / (2.0 * d);
            let (va, ga) = cap(ra, (ra - x).clamp(0.0, 2.0 * ra));
            let (vb, cb) = cap(rb, (rb - (d - x)).clamp(0.0, 2.0 * rb));
            let want = va + vb;
            let scale = hi.powi(3);
            prop_assert!((v - want).abs() <= 1e-13 * scale, "{} vs {}", v, want);
            if want > 1e-9 * scale {
                let gw = (va * ga + vb * (d - cb)) / want;
                prop_assert!((g - gw).abs() <= 1e-9 * hi, "{} vs {}", g, gw);
            }
        }
    }

    #[test]
    fn lens_limits_and_symmetry() {
        assert_eq!(lens_volume(1.0, 1.0, 2.0), 0.0);
        assert!((lens_volume(1.0, 0.5, 0.2) - 4.0 / 3.0 * PI * 0.125).abs() < 1e-12);
        assert!((lens_volume(1.0, 1.0, 1e-9) - 4.0 / 3.0 * PI).abs() < 1e-6);
        for &(ra, rb, d) in &[(1.0, 0.7, 1.2), (0.3, 0.9, 0.8), (1.0, 1.0, 1.0)] {
            let v1 = lens_volume(ra, rb, d);
            let v2 = lens_volume(rb, ra, d);
            assert!((v1 - v2).abs() < 1e-12);
            // The classic closed form.
            let f = PI
                * (ra + rb - d).powi(2)
                * (d * d + 2.0 * d * (ra + rb) - 3.0 * (ra - rb).powi(2))
                / (12.0 * d);
            assert!((v1 - f).abs() < 1e-12, "{v1} vs {f}");
            // Centroid between the two centres, mirrored when swapped.
            let (_, g1) = lens(ra, rb, d);
            let (_, g2) = lens(rb, ra, d);
            assert!((g1 + g2 - d).abs() < 1e-12);
        }
        // Equal radii: the centroid is half-way.
        assert!((lens(1.0, 1.0, 1.3).1 - 0.65).abs() < 1e-12);
    }

    #[test]
    fn lens_by_monte_carlo() {
        let (ra, rb, d) = (1.0f64, 0.6f64, 1.1f64);
        let mut state = 12345u64;
        let mut rnd = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 11) as f64) / ((1u64 << 53) as f64)
        };
        let n = 400_000;
        let (mut hits, mut gx) = (0usize, 0.0);
        for _ in 0..n {
            let p = DVec3::new(
                rnd() * 2.0 - 1.0 + 0.5,
                rnd() * 2.0 - 1.0,
                rnd() * 2.0 - 1.0,
            );
            if p.length() < ra && (p - DVec3::new(d, 0.0, 0.0)).length() < rb {
                hits += 1;
                gx += p.x;
            }
        }
        let vol = 8.0 * hits as f64 / n as f64;
        let (v, g) = lens(ra, rb, d);
        assert!((vol - v).abs() < 0.02 * v + 1e-3, "{vol} vs {v}");
        assert!(
            (gx / hits as f64 - g).abs() < 0.01,
            "{} vs {g}",
            gx / hits as f64
        );
    }

    #[test]
    fn disc_area_is_minus_the_volumes_derivative() {
        for &(ra, rb, d) in &[(1.0, 0.7, 1.2), (0.3, 0.9, 0.8), (1.0, 1.0, 1.0)] {
            let h = 1e-6;
            let dv = (lens_volume(ra, rb, d + h) - lens_volume(ra, rb, d - h)) / (2.0 * h);
            let a = pair::<true>([0.0; 3], ra, [d, 0.0, 0.0], rb).area;
            assert!((a + dv).abs() < 1e-6 * a.max(1.0), "{a} vs {}", -dv);
        }
    }
}
