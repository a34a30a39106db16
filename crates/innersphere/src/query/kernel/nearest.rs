//! The distance search's pruning rule and its 4×4 step (trees of fan-out ≤ 4): B's block
//! centres in A's frame, every child pair's squared distance and radius sum, and the mask of
//! pairs that may still hold a closer leaf pair; portable and AVX2 twins, bit for bit the
//! same.

use super::info::{Block, LANES};
use super::lanes;
#[cfg(all(test, target_arch = "x86_64"))]
use super::simd;
use super::Ctx;

/// The depth-first search's pruning rule, without square roots: a pair is refined while its
/// lower bound `|Δ| − s` is below the threshold `t` of the best pair so far, i.e. while
/// `|Δ|² < (t + s)²`; the stack keeps `|Δ|²` and recomputes `s` from the nodes.
#[derive(Clone, Copy)]
pub(crate) struct Prune {
    pub(crate) abs: f32,
    pub(crate) rel: f32,
    pub(crate) signed: bool,
}

/// The squared comparison may round the other way than `sqrt(d2) − s < t` by an ulp; a
/// relative margin of 2⁻¹⁸ keeps it on the refining side (inner pairs) and sends borderline
/// leaf pairs to the exact comparison, so the answer equals brute force.
pub(crate) const MARGIN: f32 = 1.0 + 1.0 / 262_144.0;

impl Prune {
    /// Bound below which a pair can still improve the best distance `ub` by more than the
    /// tolerances.
    #[inline(always)]
    pub(crate) fn thr(&self, ub: f32) -> f32 {
        if self.signed && ub <= 0.0 {
            ub - self.abs
        } else {
            (ub - self.abs).min(ub / (1.0 + self.rel))
        }
    }

    /// True when nothing is left to improve (non-signed mode, overlap found).
    #[inline(always)]
    pub(crate) fn finished(&self, t: f32) -> bool {
        !self.signed && t <= 0.0
    }

    /// Whether a pair at squared centre distance `d2` with radius sum `s` may hold a leaf
    /// pair closer than the threshold `t`.
    #[inline(always)]
    pub(crate) fn refine(d2: f32, s: f32, t: f32) -> bool {
        let l = t + s;
        l > 0.0 && d2 < l * l * MARGIN
    }
}

/// B's block centres in A's frame, lane by lane (the same operation order as
/// [`Rel32::apply`](super::geometry::Rel32), so leaf distances equal brute force).
#[inline(always)]
pub(crate) fn block_in_a(ctx: &Ctx, k: &Block) -> ([f32; LANES], [f32; LANES], [f32; LANES]) {
    let mut x = [0.0f32; LANES];
    let mut y = [0.0f32; LANES];
    let mut z = [0.0f32; LANES];
    for l in 0..LANES {
        [x[l], y[l], z[l]] = ctx.rel32.apply(k.x[l], k.y[l], k.z[l]);
    }
    (x, y, z)
}

/// A leaf sphere `p` (`[x, y, z, r]`, A's frame) against one block's four lanes (centres
/// `x`, `y`, `z` in A's frame, radii `r`): each lane's squared centre distance and radius sum
/// (+ the rounding slack unless the lane is a leaf, bit `l` of `leaf`), and the mask of lanes
/// to refine under threshold `t` (bit `l`). Serves a leaf of A against B's block and a leaf
/// of B against A's alike: the squares and the sums do not depend on the order, bit for bit.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(crate) fn leaf_step(
    p: [f32; 4],
    x: &[f32; LANES],
    y: &[f32; LANES],
    z: &[f32; LANES],
    r: &[f32; LANES],
    leaf: u32,
    slack: f32,
    t: f32,
) -> ([f32; LANES], [f32; LANES], u32) {
    let [px, py, pz, pr] = p;
    let mut d2 = [0.0f32; LANES];
    let mut sr = [0.0f32; LANES];
    let mut mask = 0u32;
    for l in 0..LANES {
        let dx = px - x[l];
        let dy = py - y[l];
        let dz = pz - z[l];
        d2[l] = dx * dx + dy * dy + dz * dz;
        sr[l] = pr + r[l];
        if (leaf >> l) & 1 == 0 {
            sr[l] += slack;
        }
        mask |= (Prune::refine(d2[l], sr[l], t) as u32) << l;
    }
    (d2, sr, mask)
}

/// The 4×4 step, portable: B's children into A's frame (`bxyz`), every child pair's squared
/// centre distance and radius sum (+ the rounding slack unless both are leaves, `ll`), and
/// the mask of pairs to refine under threshold `t` (bit `4i + l`).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(crate) fn step_scalar(
    ctx: &Ctx,
    ka: &Block,
    kb: &Block,
    ll: u32,
    t: f32,
    bxyz: &mut [[f32; LANES]; 3],
    d2: &mut [f32; 16],
    sr: &mut [f32; 16],
) -> u32 {
    let (bx, by, bz) = block_in_a(ctx, kb);
    *bxyz = [bx, by, bz];
    let cols = [&bxyz[0], &bxyz[1], &bxyz[2], &kb.r];
    lanes::pairs([&ka.x, &ka.y, &ka.z, &ka.r], cols, ll, ctx.slack, d2, sr);
    let mut mask = 0u32;
    for q in 0..16 {
        mask |= (Prune::refine(d2[q], sr[q], t) as u32) << q;
    }
    mask
}

/// [`step_scalar`] in AVX2 intrinsics (two 8-lane vectors for the 16 pairs; the same
/// operations in the same order, no FMA, so the results are bit for bit the portable ones).
#[cfg(target_arch = "x86_64")]
#[allow(clippy::too_many_arguments)]
#[target_feature(enable = "avx2")]
#[inline]
pub(crate) unsafe fn step_avx2(
    ctx: &Ctx,
    ka: &Block,
    kb: &Block,
    ll: u32,
    t: f32,
    bxyz: &mut [[f32; LANES]; 3],
    d2: &mut [f32; 16],
    sr: &mut [f32; 16],
) -> u32 {
    use std::arch::x86_64::*;
    let (m, tr) = ctx.rel32.parts();
    let (x, y, z) = (
        _mm_loadu_ps(kb.x.as_ptr()),
        _mm_loadu_ps(kb.y.as_ptr()),
        _mm_loadu_ps(kb.z.as_ptr()),
    );
    let row = |k: usize, t: f32| {
        _mm_add_ps(
            _mm_add_ps(
                _mm_add_ps(
                    _mm_mul_ps(_mm_set1_ps(m[k]), x),
                    _mm_mul_ps(_mm_set1_ps(m[k + 1]), y),
                ),
                _mm_mul_ps(_mm_set1_ps(m[k + 2]), z),
            ),
            _mm_set1_ps(t),
        )
    };
    let (bx, by, bz) = (row(0, tr[0]), row(3, tr[1]), row(6, tr[2]));
    _mm_storeu_ps(bxyz[0].as_mut_ptr(), bx);
    _mm_storeu_ps(bxyz[1].as_mut_ptr(), by);
    _mm_storeu_ps(bxyz[2].as_mut_ptr(), bz);
    let t = _mm256_set1_ps(t);
    let zero = _mm256_setzero_ps();
    let margin = _mm256_set1_ps(MARGIN);
    let halves = lanes::pairs_avx2(
        [&ka.x, &ka.y, &ka.z, &ka.r],
        [&bxyz[0], &bxyz[1], &bxyz[2], &kb.r],
        ll,
        ctx.slack,
    );
    let mut mask = 0u32;
    for (h, (dd, s)) in halves.into_iter().enumerate() {
        let l = _mm256_add_ps(t, s);
        let ok = _mm256_and_ps(
            _mm256_cmp_ps::<_CMP_GT_OQ>(l, zero),
            _mm256_cmp_ps::<_CMP_LT_OQ>(dd, _mm256_mul_ps(_mm256_mul_ps(l, l), margin)),
        );
        mask |= (_mm256_movemask_ps(ok) as u32) << (8 * h);
        _mm256_storeu_ps(d2.as_mut_ptr().add(8 * h), dd);
        _mm256_storeu_ps(sr.as_mut_ptr().add(8 * h), s);
    }
    mask
}

#[cfg(test)]
mod tests {
    use super::super::geometry::Rel32;
    use super::super::Ctx;
    use super::*;
    use crate::pose::Pose;
    use glam::DQuat;
    use glam::DVec3;
    use proptest::prelude::*;

    proptest! {
        /// The AVX2 4×4 step gives bit for bit the portable step's distances, radius sums,
        /// transformed centres and refine mask (the dispatch may pick either).
        #[test]
        fn avx2_step_equals_portable(
            va in prop::collection::vec(-40.0f32..40.0, 16),
            vb in prop::collection::vec(-40.0f32..40.0, 16),
            (la, lb, na, nb) in (0u32..16, 0u32..16, 1u32..=4, 1u32..=4),
            q in prop::array::uniform4(-1.0f64..1.0),
            tr in prop::array::uniform3(-20.0f64..20.0),
            t in -5.0f32..30.0,
        ) {
            #[cfg(target_arch = "x86_64")]
            if simd::detect().is_some() {
                let (ka, kb) = (Block::from_spheres(&va, la, na), Block::from_spheres(&vb, lb, nb));
                let rot = DQuat::from_xyzw(q[0], q[1], q[2], q[3] + 1.5).normalize();
                let rel = Pose::new(DVec3::from_array(tr), rot).unwrap();
                let rel32 = Rel32::new(&rel);
                let ctx = Ctx {
                    a: &[],
                    b: &[],
                    blocks_a: &[],
                    blocks_b: &[],
                    block_of_a: &[],
                    block_of_b: &[],
                    rel,
                    rel32,
                    slack: 1e-4,
                    simd: simd::detect(),
                };
                let ll = lanes::leaf_pairs_mask(ka.leaf, kb.leaf);
                let (mut x1, mut d1, mut s1) = ([[0.0; LANES]; 3], [0.0; 16], [0.0; 16]);
                let (mut x2, mut d2, mut s2) = ([[0.0; LANES]; 3], [0.0; 16], [0.0; 16]);
                let m1 = step_scalar(&ctx, &ka, &kb, ll, t, &mut x1, &mut d1, &mut s1);
                // SAFETY: the CPU has AVX2 (checked above).
                let m2 = unsafe { step_avx2(&ctx, &ka, &kb, ll, t, &mut x2, &mut d2, &mut s2) };
                prop_assert_eq!(m1, m2);
                let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                prop_assert_eq!(bits(&d1), bits(&d2));
                prop_assert_eq!(bits(&s1), bits(&s2));
                prop_assert_eq!(bits(x1.as_flattened()), bits(x2.as_flattened()));
                // Unused lanes never refine.
                for q in 0..16 {
                    if q / LANES >= na as usize || q % LANES >= nb as usize {
                        prop_assert_eq!((m1 >> q) & 1, 0);
                    }
                }
            }
        }
    }
}
