//! Small geometry shared by the queries: the f32 relative transform, the pruning slack, the
//! leaf predicates, contacts of leaf pairs.

use super::info::Node;
use crate::pose::Pose;
use glam::{DMat3, DVec3};

/// The pose of B in A's frame in f32, applied to B's node centres during a traversal.
///
/// Every query and every brute-force reference transforms B's centres with [`Rel32::apply`],
/// so that they see bit-identical coordinates.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Rel32 {
    m: [f32; 9],
    t: [f32; 3],
}

impl Rel32 {
    /// The f32 matrix and translation of `p`.
    pub(crate) fn new(p: &Pose) -> Rel32 {
        let m = DMat3::from_quat(p.rotation);
        let (c0, c1, c2) = (m.x_axis, m.y_axis, m.z_axis);
        Rel32 {
            m: [
                c0.x as f32,
                c1.x as f32,
                c2.x as f32,
                c0.y as f32,
                c1.y as f32,
                c2.y as f32,
                c0.z as f32,
                c1.z as f32,
                c2.z as f32,
            ],
            t: [
                p.translation.x as f32,
                p.translation.y as f32,
                p.translation.z as f32,
            ],
        }
    }

    /// `R·p + t` in f32, always with the same operation order.
    #[inline(always)]
    pub(crate) fn apply(&self, x: f32, y: f32, z: f32) -> [f32; 3] {
        let m = &self.m;
        [
            m[0] * x + m[1] * y + m[2] * z + self.t[0],
            m[3] * x + m[4] * y + m[5] * z + self.t[1],
            m[6] * x + m[7] * y + m[8] * z + self.t[2],
        ]
    }

    /// [`Rel32::apply`] to four points given by coordinate, bit for bit (the same products
    /// and sums in the same order, four lanes per instruction on x86-64: the compiler kept
    /// the per-point loop scalar).
    #[inline(always)]
    pub(crate) fn apply4(
        &self,
        x: &[f32; 4],
        y: &[f32; 4],
        z: &[f32; 4],
    ) -> ([f32; 4], [f32; 4], [f32; 4]) {
        #[cfg(target_arch = "x86_64")]
        {
            use std::arch::x86_64::*;
            let (m, t) = (&self.m, &self.t);
            let mut out = ([0.0f32; 4], [0.0f32; 4], [0.0f32; 4]);
            // SAFETY: SSE2 is part of x86-64; unaligned loads and stores of four f32 from and
            // to `[f32; 4]` arrays.
            unsafe {
                let (x, y, z) = (
                    _mm_loadu_ps(x.as_ptr()),
                    _mm_loadu_ps(y.as_ptr()),
                    _mm_loadu_ps(z.as_ptr()),
                );
                let row = |i: usize| {
                    let a = _mm_mul_ps(_mm_set1_ps(m[3 * i]), x);
                    let b = _mm_mul_ps(_mm_set1_ps(m[3 * i + 1]), y);
                    let c = _mm_mul_ps(_mm_set1_ps(m[3 * i + 2]), z);
                    _mm_add_ps(_mm_add_ps(_mm_add_ps(a, b), c), _mm_set1_ps(t[i]))
                };
                _mm_storeu_ps(out.0.as_mut_ptr(), row(0));
                _mm_storeu_ps(out.1.as_mut_ptr(), row(1));
                _mm_storeu_ps(out.2.as_mut_ptr(), row(2));
            }
            out
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            let mut out = ([0.0f32; 4], [0.0f32; 4], [0.0f32; 4]);
            for l in 0..4 {
                [out.0[l], out.1[l], out.2[l]] = self.apply(x[l], y[l], z[l]);
            }
            out
        }
    }

    /// The row-major matrix and the translation.
    #[inline(always)]
    pub(crate) fn parts(&self) -> (&[f32; 9], &[f32; 3]) {
        (&self.m, &self.t)
    }

    /// Length of the translation.
    pub(crate) fn translation_len(&self) -> f32 {
        (self.t[0] * self.t[0] + self.t[1] * self.t[1] + self.t[2] * self.t[2]).sqrt()
    }
}

/// Extra radius added to every pruning test on inner nodes of a query, covering the f32
/// rounding of B's transform and of the distance itself, so that an inner-node test never
/// rejects a pair whose leaves overlap under the exact leaf test (`|Δ|² < (ra + rb)²` on the
/// transformed f32 centres). Leaf tests use no slack: they define the answer.
#[inline]
pub(crate) fn pruning_slack(extent_a: f32, extent_b: f32, rel: &Rel32) -> f32 {
    16.0 * f32::EPSILON * (extent_a + extent_b + rel.translation_len())
}

/// One contact between a leaf sphere of A and a leaf sphere of B.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Contact {
    /// Leaf (node index) of tree A.
    pub leaf_a: u32,
    /// Leaf (node index) of tree B.
    pub leaf_b: u32,
    /// World point in the middle of the overlap, on the line through both centres.
    pub point: DVec3,
    /// World unit direction from A's sphere centre to B's (zero when the centres coincide).
    pub normal: DVec3,
    /// Overlap of the two spheres along the centre line, `ra + rb − |cb − ca|` (> 0).
    pub depth: f64,
}

/// Centre (A's frame, f64 of the f32 values) and radius of leaf `na` of A and of leaf `nb`
/// of B whose transformed centre is `cb`.
#[inline]
pub(crate) fn leaf_pair(na: &Node, nb: &Node, cb: [f32; 3]) -> (DVec3, f64, DVec3, f64) {
    let ca = DVec3::new(na.x as f64, na.y as f64, na.z as f64);
    let cb = DVec3::new(cb[0] as f64, cb[1] as f64, cb[2] as f64);
    (ca, na.r as f64, cb, nb.r as f64)
}

/// Unit vector from `ca` to `cb` (zero when they coincide) and their distance.
#[inline]
pub(crate) fn direction(ca: DVec3, cb: DVec3) -> (DVec3, f64) {
    let v = cb - ca;
    let d = v.length();
    if d > 0.0 {
        (v / d, d)
    } else {
        (DVec3::ZERO, 0.0)
    }
}

/// The contact of an (overlapping) leaf pair, in A's frame ([`Contact::in_world`] at the
/// `Pair` door).
pub(crate) fn make_contact(a: &[Node], la: u32, b: &[Node], lb: u32, cb: [f32; 3]) -> Contact {
    let (ca, ra, cb, rb) = leaf_pair(&a[la as usize], &b[lb as usize], cb);
    let (u, d) = direction(ca, cb);
    let depth = ra + rb - d;
    let p = ca + u * (ra - 0.5 * depth);
    Contact {
        leaf_a: la,
        leaf_b: lb,
        point: p,
        normal: u,
        depth,
    }
}

impl Contact {
    /// This contact, found in A's frame, in the world frame (A at `pose_a`).
    pub(crate) fn in_world(self, pose_a: &Pose) -> Contact {
        Contact {
            point: pose_a.transform_point(self.point),
            normal: pose_a.transform_vector(self.normal),
            ..self
        }
    }
}

#[cfg(test)]
/// True when the f32 spheres overlap (the exact leaf predicate of every query).
#[inline(always)]
pub(crate) fn overlaps(ax: f32, ay: f32, az: f32, ar: f32, b: [f32; 3], br: f32) -> bool {
    let dx = b[0] - ax;
    let dy = b[1] - ay;
    let dz = b[2] - az;
    let s = ar + br;
    dx * dx + dy * dy + dz * dz < s * s
}

#[cfg(test)]
/// Signed distance `|Δ| − ra − rb` of two f32 spheres (the exact leaf distance of every query).
#[inline(always)]
pub(crate) fn sphere_distance(ax: f32, ay: f32, az: f32, ar: f32, b: [f32; 3], br: f32) -> f32 {
    let dx = b[0] - ax;
    let dy = b[1] - ay;
    let dz = b[2] - az;
    (dx * dx + dy * dy + dz * dz).sqrt() - (ar + br)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// The four-lane transform gives bit for bit the per-point one.
        #[test]
        fn apply4_equals_apply(
            q in prop::array::uniform4(-1.0f64..1.0),
            t in prop::array::uniform3(-50.0f64..50.0),
            p in prop::array::uniform12(-40.0f32..40.0),
        ) {
            prop_assume!(q.iter().map(|v| v * v).sum::<f64>() > 0.01);
            let pose = Pose::from_array([t[0], t[1], t[2], q[0], q[1], q[2], q[3]]).unwrap();
            let r = Rel32::new(&pose);
            let (x, y, z) = ([p[0], p[1], p[2], p[3]], [p[4], p[5], p[6], p[7]], [p[8], p[9], p[10], p[11]]);
            let (ox, oy, oz) = r.apply4(&x, &y, &z);
            for l in 0..4 {
                let want = r.apply(x[l], y[l], z[l]);
                prop_assert_eq!([ox[l].to_bits(), oy[l].to_bits(), oz[l].to_bits()], want.map(f32::to_bits));
            }
        }
    }
}
