//! The 4×4 block step of the overlap traversals (trees of fan-out ≤ 4): every child of one
//! node against every child of the other, side by side, with the overlap masks, the nearest
//! separation and the gaps the block front keys on; portable and AVX2 twins, bit for bit
//! the same.

use super::info::{Block, LANES};
use super::lanes;
#[cfg(all(test, target_arch = "x86_64"))]
use super::simd;
use super::{prefetch_at, Ctx};

/// A pair on the blocked traversal's stack (fan-outs ≤ 4): the node indices (for keys and
/// results), the block indices of the inner sides, which sides are leaves, the traversal
/// depth, and B's node centre in A's frame (used when B's side is a leaf).
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct TItem {
    pub na: u32,
    pub nb: u32,
    pub(crate) ba: u32,
    pub(crate) bb: u32,
    pub(crate) kind: u32,
    depth: u32,
    pub c: [f32; 3],
}

const INNER: u32 = 0;
const A_LEAF: u32 = 1;
pub(crate) const B_LEAF: u32 = 2;
const LEAFS: u32 = 3;

impl TItem {
    /// The pair of nodes `na`, `nb` (B's centre `c` in A's frame) at traversal `depth`.
    pub(crate) fn new(ctx: &Ctx, na: u32, nb: u32, c: [f32; 3], depth: u32) -> TItem {
        let al = ctx.a[na as usize].is_leaf();
        let bl = ctx.b[nb as usize].is_leaf();
        let kind = match (al, bl) {
            (false, false) => INNER,
            (true, false) => A_LEAF,
            (false, true) => B_LEAF,
            (true, true) => LEAFS,
        };
        TItem {
            na,
            nb,
            ba: if al { 0 } else { ctx.block_of_a[na as usize] },
            bb: if bl { 0 } else { ctx.block_of_b[nb as usize] },
            kind,
            depth,
            c,
        }
    }
}

/// One side of a blocked step, lane by lane (centres in A's frame): a node's children from
/// its block, or a leaf standing for itself in lane 0.
pub(crate) struct Side {
    pub(crate) x: [f32; LANES],
    pub(crate) y: [f32; LANES],
    pub(crate) z: [f32; LANES],
    pub(crate) r: [f32; LANES],
    pub(crate) leaf: u32,
    pub(crate) count: u32,
    pub(crate) node: [u32; LANES],
    pub(crate) child: [u32; LANES],
}

impl Side {
    /// A leaf standing for itself: centre `c` (A's frame), radius `r`, node `n`.
    #[inline(always)]
    fn leaf(c: [f32; 3], r: f32, n: u32) -> Side {
        let mut s = Side {
            x: [0.0; LANES],
            y: [0.0; LANES],
            z: [0.0; LANES],
            r: [f32::NEG_INFINITY; LANES],
            leaf: 1,
            count: 1,
            node: [n; LANES],
            child: [n; LANES],
        };
        (s.x[0], s.y[0], s.z[0], s.r[0]) = (c[0], c[1], c[2], r);
        s
    }

    /// The children of A's node from its block.
    #[inline(always)]
    fn a_block(k: &Block) -> Side {
        Side {
            x: k.x,
            y: k.y,
            z: k.z,
            r: k.r,
            leaf: k.leaf,
            count: k.count,
            node: k.node,
            child: k.child,
        }
    }

    /// The children of B's node from its block, moved into A's frame (the same operation
    /// order as [`Rel32::apply`](super::geometry::Rel32), so leaf tests equal brute force).
    #[inline(always)]
    fn b_block(ctx: &Ctx, k: &Block) -> Side {
        let mut s = Side::a_block(k);
        (s.x, s.y, s.z) = ctx.rel32.apply4(&k.x, &k.y, &k.z);
        s
    }
}

/// One blocked step of the overlap traversals: all child pairs of `e` tested side by side
/// (4×4, or 1×4 when a side is a leaf). Returns both sides and the mask of overlapping
/// pairs (bit `l·4 + i`: A's lane `i` against B's lane `l`); separated pairs lower `min_sep`.
/// `AVX`: the AVX2 twin, set only within the `#[target_feature]` code a dispatcher runs when
/// the query's token (`Ctx::simd`) says the CPU has AVX2.
#[inline(always)]
pub(crate) fn block_step<const AVX: bool>(
    ctx: &Ctx,
    e: &TItem,
    min_sep: &mut f32,
    visits: &mut u64,
) -> (Side, Side, u32) {
    let (sa, sb) = sides(ctx, e);
    let m = *min_sep;
    let mut d2 = [0.0f32; 16];
    let mut sr = [0.0f32; 16];
    // Bit `l·4 + i` of the masks: B's lane `l` (rows) against A's lane `i` (columns).
    let ll = lanes::leaf_pairs_mask(sb.leaf, sa.leaf);
    let valid = lanes::valid_mask(sb.count, sa.count);
    #[cfg(target_arch = "x86_64")]
    let (over, mut near) = if AVX {
        // SAFETY: `AVX` is set only where the query's `Avx2` token proved the CPU has it.
        unsafe { overlap_masks_avx2(&sb, &sa, ll, valid, ctx.slack, m, &mut d2, &mut sr) }
    } else {
        overlap_masks(&sb, &sa, ll, valid, ctx.slack, m, &mut d2, &mut sr)
    };
    #[cfg(not(target_arch = "x86_64"))]
    let (over, mut near) = overlap_masks(&sb, &sa, ll, valid, ctx.slack, m, &mut d2, &mut sr);
    *visits += (sa.count * sb.count) as u64;
    while near != 0 {
        let q = near.trailing_zeros() as usize;
        near &= near - 1;
        let lb = d2[q].sqrt() - sr[q];
        if lb < *min_sep {
            *min_sep = lb;
        }
    }
    (sa, sb, over)
}

/// Both sides of a blocked step of pair `e`: A's children from its block (or A's leaf), and
/// B's children moved into A's frame (or B's leaf at its centre `e.c`).
#[inline(always)]
pub(crate) fn sides(ctx: &Ctx, e: &TItem) -> (Side, Side) {
    let sa = if e.kind == A_LEAF {
        let n = &ctx.a[e.na as usize];
        Side::leaf([n.x, n.y, n.z], n.r, e.na)
    } else {
        Side::a_block(&ctx.blocks_a[e.ba as usize])
    };
    let sb = if e.kind == B_LEAF {
        Side::leaf(e.c, ctx.b[e.nb as usize].r, e.nb)
    } else {
        Side::b_block(ctx, &ctx.blocks_b[e.bb as usize])
    };
    (sa, sb)
}

/// A [`block_step`] for the kinetic block front: the overlap mask, the mask of leaf pairs,
/// and how far the step is from changing its outcome: the smallest `|√d2 − sr|` (a
/// separation, or a leaf pair's overlap depth; the pruning slack is in `sr` for inner pairs)
/// over all pairs except the overlapping inner ones (+∞ when there are none). Any kind of
/// pair; [`inner_gaps`] is the same for two inner nodes without building the sides. `AVX`
/// as in [`block_step`].
#[inline(always)]
pub(crate) fn block_gaps<const AVX: bool>(
    ctx: &Ctx,
    e: &TItem,
    visits: &mut u64,
) -> (u32, u32, f32) {
    let (sa, sb) = sides(ctx, e);
    let ll = lanes::leaf_pairs_mask(sb.leaf, sa.leaf);
    let valid = lanes::valid_mask(sb.count, sa.count);
    let rows = [&sb.x, &sb.y, &sb.z, &sb.r];
    let (over, m) = gap_kernel::<AVX>(rows, [&sa.x, &sa.y, &sa.z, &sa.r], ll, valid, ctx.slack);
    *visits += (sa.count * sb.count) as u64;
    (over, ll & valid, m)
}

/// [`block_gaps`] of a pair of inner nodes (blocks `ba` of A and `bb` of B) without building
/// the sides. The block front's common step, which needs the sides only when its outcome
/// changed (cachegrind: building and returning
/// them was ≈ a quarter of a step's instructions). `AVX` as in [`block_step`].
#[inline(always)]
pub(crate) fn inner_gaps<const AVX: bool>(
    ctx: &Ctx,
    ba: u32,
    bb: u32,
    visits: &mut u64,
) -> (u32, u32, f32) {
    let ka = &ctx.blocks_a[ba as usize];
    let kb = &ctx.blocks_b[bb as usize];
    let (x, y, z) = ctx.rel32.apply4(&kb.x, &kb.y, &kb.z);
    let ll = lanes::leaf_pairs_mask(kb.leaf, ka.leaf);
    let valid = lanes::valid_mask(kb.count, ka.count);
    let (over, m) = gap_kernel::<AVX>(
        [&x, &y, &z, &kb.r],
        [&ka.x, &ka.y, &ka.z, &ka.r],
        ll,
        valid,
        ctx.slack,
    );
    *visits += (ka.count * kb.count) as u64;
    (over, ll & valid, m)
}

/// Four lanes of `[x, y, z, r]`: one side of a 4×4 step.
type Lanes4<'a> = [&'a [f32; LANES]; 4];

/// [`overlap_gap_avx2`] with `AVX` (as in [`block_step`]), else [`overlap_gap`].
#[inline(always)]
fn gap_kernel<const AVX: bool>(
    r: Lanes4,
    c: Lanes4,
    ll: u32,
    valid: u32,
    slack: f32,
) -> (u32, f32) {
    #[cfg(target_arch = "x86_64")]
    if AVX {
        // SAFETY: `AVX` is set only where the query's `Avx2` token proved the CPU has it.
        return unsafe { overlap_gap_avx2(r, c, ll, valid, slack) };
    }
    overlap_gap(r, c, ll, valid, slack)
}

/// The overlap mask of rows `r` against columns `c` (bit `4·row + col`, unused lanes
/// masked by `valid`) and the smallest `|√d2 − sr|` over the pairs that are not overlapping
/// inner pairs (`ll` marks leaf pairs; unused lanes have radius −∞ and so never count),
/// portable: the twin of [`overlap_gap_avx2`].
#[inline(always)]
fn overlap_gap(r: Lanes4, c: Lanes4, ll: u32, valid: u32, slack: f32) -> (u32, f32) {
    let (mut d2, mut sr) = ([0.0f32; 16], [0.0f32; 16]);
    lanes::pairs(r, c, ll, slack, &mut d2, &mut sr);
    let (mut over, mut m) = (0u32, f32::INFINITY);
    for q in 0..16 {
        let (d, s) = (d2[q], sr[q]);
        let ov = d < s * s;
        over |= (ov as u32) << q;
        let inner = ov && (ll >> q) & 1 == 0;
        let g = (d.sqrt() - s).abs();
        if !inner && g < m {
            m = g;
        }
    }
    (over & valid, m)
}

/// [`overlap_gap`] in AVX2 intrinsics, bit for bit the same (the square root is correctly
/// rounded in both).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn overlap_gap_avx2(r: Lanes4, c: Lanes4, ll: u32, valid: u32, slack: f32) -> (u32, f32) {
    use std::arch::x86_64::*;
    let [(dlo, slo), (dhi, shi)] = lanes::pairs_avx2(r, c, ll, slack);
    let bits = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
    let inf = _mm256_set1_ps(f32::INFINITY);
    let sign = _mm256_set1_ps(-0.0);
    let mut over = 0u32;
    let mut best = inf;
    for (h, (d, s)) in [(dlo, slo), (dhi, shi)].into_iter().enumerate() {
        let ov = _mm256_cmp_ps::<_CMP_LT_OQ>(d, _mm256_mul_ps(s, s));
        over |= (_mm256_movemask_ps(ov) as u32) << (8 * h);
        let llv = _mm256_set1_epi32(((ll >> (8 * h)) & 0xFF) as i32);
        let is_ll = _mm256_castsi256_ps(_mm256_cmpeq_epi32(_mm256_and_si256(llv, bits), bits));
        let inner = _mm256_andnot_ps(is_ll, ov);
        let g = _mm256_andnot_ps(sign, _mm256_sub_ps(_mm256_sqrt_ps(d), s));
        // Where `g` is not below `best` (or the lane is an inner overlap), `best` stays.
        best = _mm256_blendv_ps(
            best,
            g,
            _mm256_andnot_ps(inner, _mm256_cmp_ps::<_CMP_LT_OQ>(g, best)),
        );
    }
    // The smallest lane: `best` holds no NaN (it starts at +∞ and takes only `g < best`),
    // so `min` equals the portable loop's running minimum.
    let h = _mm_min_ps(
        _mm256_castps256_ps128(best),
        _mm256_extractf128_ps::<1>(best),
    );
    let h = _mm_min_ps(h, _mm_movehl_ps(h, h));
    let h = _mm_min_ss(h, _mm_shuffle_ps::<0b01>(h, h));
    (over & valid, _mm_cvtss_f32(h))
}

/// The masks of a [`block_step`], portable: for rows `r` (B's lanes) against columns `c` (A's
/// lanes), bit `4·row + col` of `over` when the spheres overlap, of `near` when they do not
/// but come within `m`; `valid` masks unused lanes, `ll` marks leaf pairs (no rounding slack).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn overlap_masks(
    r: &Side,
    c: &Side,
    ll: u32,
    valid: u32,
    slack: f32,
    m: f32,
    d2: &mut [f32; 16],
    sr: &mut [f32; 16],
) -> (u32, u32) {
    lanes::pairs(
        [&r.x, &r.y, &r.z, &r.r],
        [&c.x, &c.y, &c.z, &c.r],
        ll,
        slack,
        d2,
        sr,
    );
    let (mut over, mut near) = (0u32, 0u32);
    for q in 0..16 {
        let (d, s) = (d2[q], sr[q]);
        let ov = d < s * s;
        over |= (ov as u32) << q;
        near |= ((!ov & (d < (s + m) * (s + m))) as u32) << q;
    }
    (over & valid, near & valid)
}

/// [`overlap_masks`] in AVX2 intrinsics, bit for bit the same (no FMA; the lane formulas are
/// [`lanes::pairs_avx2`]'s).
#[cfg(target_arch = "x86_64")]
#[allow(clippy::too_many_arguments)]
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn overlap_masks_avx2(
    r: &Side,
    c: &Side,
    ll: u32,
    valid: u32,
    slack: f32,
    m: f32,
    d2: &mut [f32; 16],
    sr: &mut [f32; 16],
) -> (u32, u32) {
    use std::arch::x86_64::*;
    let [(dlo, slo), (dhi, shi)] = lanes::pairs_avx2(
        [&r.x, &r.y, &r.z, &r.r],
        [&c.x, &c.y, &c.z, &c.r],
        ll,
        slack,
    );
    let mm = _mm256_set1_ps(m);
    let (mut over, mut near) = (0u32, 0u32);
    for (h, (d, s)) in [(dlo, slo), (dhi, shi)].into_iter().enumerate() {
        let ov = _mm256_cmp_ps::<_CMP_LT_OQ>(d, _mm256_mul_ps(s, s));
        let sm = _mm256_add_ps(s, mm);
        let nr = _mm256_andnot_ps(ov, _mm256_cmp_ps::<_CMP_LT_OQ>(d, _mm256_mul_ps(sm, sm)));
        over |= (_mm256_movemask_ps(ov) as u32) << (8 * h);
        near |= (_mm256_movemask_ps(nr) as u32) << (8 * h);
        _mm256_storeu_ps(d2.as_mut_ptr().add(8 * h), d);
        _mm256_storeu_ps(sr.as_mut_ptr().add(8 * h), s);
    }
    (over & valid, near & valid)
}

impl TItem {
    /// The child pair in lanes (`i`, `l`) of a [`block_step`], one traversal level deeper.
    #[inline(always)]
    pub(crate) fn child(sa: &Side, sb: &Side, i: usize, l: usize, depth: u32) -> TItem {
        let (al, bl) = ((sa.leaf >> i) & 1 != 0, (sb.leaf >> l) & 1 != 0);
        let kind = match (al, bl) {
            (false, false) => INNER,
            (true, false) => A_LEAF,
            (false, true) => B_LEAF,
            (true, true) => LEAFS,
        };
        TItem {
            na: sa.node[i],
            nb: sb.node[l],
            ba: sa.child[i],
            bb: sb.child[l],
            kind,
            depth,
            c: [sb.x[l], sb.y[l], sb.z[l]],
        }
    }

    /// Depth of the pair in its traversal.
    #[inline(always)]
    pub(crate) fn depth(&self) -> u32 {
        self.depth
    }

    /// True for a pair of leaves.
    #[inline(always)]
    pub(crate) fn leaves(&self) -> bool {
        self.kind == LEAFS
    }

    /// Prefetches the blocks of the pair's inner sides.
    #[inline(always)]
    pub(crate) fn prefetch(&self, ctx: &Ctx) {
        // No branch on the kind: a leaf side's index may name no block, and a prefetch of
        // any address is harmless (it never faults).
        prefetch_at(ctx.blocks_a.as_ptr().wrapping_add(self.ba as usize));
        prefetch_at(ctx.blocks_b.as_ptr().wrapping_add(self.bb as usize));
    }

    /// Whether both sides are inner nodes (the step reads two blocks).
    #[inline(always)]
    pub(crate) fn inner(&self) -> bool {
        self.kind == INNER
    }
}

#[cfg(test)]
mod lane_tests {
    use super::*;
    use proptest::prelude::*;

    fn side(v: &[f32], leaf: u32, count: u32) -> Side {
        Side::a_block(&Block::from_spheres(v, leaf, count))
    }

    proptest! {
        /// The AVX2 masks of the overlap traversals' step equal the portable ones bit for bit.
        #[test]
        fn avx2_overlap_masks_equal_portable(
            vr in prop::collection::vec(-20.0f32..20.0, 16),
            vc in prop::collection::vec(-20.0f32..20.0, 16),
            (lr, lc, nr, nc) in (0u32..16, 0u32..16, 1u32..=4, 1u32..=4),
            m in prop_oneof![Just(f32::INFINITY), 0.0f32..10.0],
        ) {
            #[cfg(target_arch = "x86_64")]
            if simd::detect().is_some() {
                let (r, c) = (side(&vr, lr, nr), side(&vc, lc, nc));
                let ll = lanes::leaf_pairs_mask(r.leaf, c.leaf);
                let valid = lanes::valid_mask(r.count, c.count);
                let (mut d1, mut s1, mut d2, mut s2) = ([0.0; 16], [0.0; 16], [0.0; 16], [0.0; 16]);
                let m1 = overlap_masks(&r, &c, ll, valid, 1e-4, m, &mut d1, &mut s1);
                // SAFETY: the CPU has AVX2 (checked above).
                let m2 = unsafe { overlap_masks_avx2(&r, &c, ll, valid, 1e-4, m, &mut d2, &mut s2) };
                prop_assert_eq!(m1, m2);
                let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                prop_assert_eq!(bits(&d1), bits(&d2));
                prop_assert_eq!(bits(&s1), bits(&s2));
                prop_assert_eq!(m1.0 & !valid, 0);
            }
        }

        /// The AVX2 gap of the block front's step equals the portable one bit for bit.
        #[test]
        fn avx2_overlap_gap_equals_portable(
            vr in prop::collection::vec(-20.0f32..20.0, 16),
            vc in prop::collection::vec(-20.0f32..20.0, 16),
            (lr, lc, nr, nc) in (0u32..16, 0u32..16, 1u32..=4, 1u32..=4),
        ) {
            let (r, c) = (side(&vr, lr, nr), side(&vc, lc, nc));
            let ll = lanes::leaf_pairs_mask(r.leaf, c.leaf);
            let valid = lanes::valid_mask(r.count, c.count);
            let (rl, cl) = ([&r.x, &r.y, &r.z, &r.r], [&c.x, &c.y, &c.z, &c.r]);
            let (o1, g1) = overlap_gap(rl, cl, ll, valid, 1e-4);
            // The gap by its definition: over the used pairs that are not inner overlaps.
            let (mut d2, mut sr) = ([0.0; 16], [0.0; 16]);
            let (o0, _) = overlap_masks(&r, &c, ll, valid, 1e-4, 0.0, &mut d2, &mut sr);
            prop_assert_eq!(o0, o1);
            let want = (0..16)
                .filter(|&q| (valid >> q) & 1 != 0 && !((o0 >> q) & 1 != 0 && (ll >> q) & 1 == 0))
                .map(|q| (d2[q].sqrt() - sr[q]).abs())
                .fold(f32::INFINITY, f32::min);
            prop_assert_eq!(g1.to_bits(), want.to_bits());
            #[cfg(target_arch = "x86_64")]
            if simd::detect().is_some() {
                // SAFETY: the CPU has AVX2 (checked above).
                let (o2, g2) = unsafe { overlap_gap_avx2(rl, cl, ll, valid, 1e-4) };
                prop_assert_eq!(o1, o2);
                prop_assert_eq!(g1.to_bits(), g2.to_bits());
            }
        }
    }
}
