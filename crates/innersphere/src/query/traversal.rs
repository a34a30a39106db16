//! The paper's traversals (section III): the distance traversal (III-A), the backtracking
//! traversal (III-B, Algorithms 1–2) and the multipoint traversal (III-C).
//!
//! As in the paper, a node pair that overlaps is refined into all pairs of children
//! (simultaneous descent; a leaf stands for itself against the other side's children), in
//! child order, depth first, and the traversal stops at the first overlapping leaf pair.
//! The depth of a pair in this traversal is the larger of its two node depths, so the pair
//! "above" a leaf pair at level `k` is (ancestor of A's leaf at depth `min(k, depth_a)`,
//! ancestor of B's leaf at depth `min(k, depth_b)`).
//!
//! Deviations from the paper's text, all for correctness:
//! * "distance" is never the literal `minDist` of Algorithm 2 (which collapses to 0 as soon
//!   as the roots overlap); when there is no contact it is the minimum over the separated
//!   pairs where the descent stopped, which is a proved lower bound on the distance of the
//!   two sphere sets (the bound the paper uses for its "predefined distance" skip).
//! * Backtracking skips the one already visited *pair* of subtrees when it climbs, not every
//!   pair involving an already visited node (which would skip unvisited pairs), and it climbs
//!   the two ancestor chains as one chain of traversal pairs, so trees of different depths
//!   never fall back to a restart from the roots. Its contact answer equals a full traversal.
//! * Multipoint has no cap on `k` (the paper's code stops at 3).

use super::geometry::{make_contact, Contact};
use super::info::{Block, Node, TreeInfo, LANES};
use super::lanes;
use super::state::{pair_key, prefetch_at, safe_separation, Ctx, Item, PairState, Scratch};
use crate::tree::NO_PARENT;
use crate::Pose;
use crate::SphereTree;

/// Options of [`distance_traversal`] and [`backtracking`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactOptions {
    /// Skip the traversal (answer "no contact") while the last proved separation cannot have
    /// been closed by the relative motion since ([`PairState::safe_separation`]).
    pub safe_motion: bool,
}

impl Default for ContactOptions {
    fn default() -> Self {
        ContactOptions { safe_motion: true }
    }
}

/// Result of [`distance_traversal`] and [`backtracking`].
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct ContactQuery {
    /// The first overlapping leaf pair found, if any.
    pub contact: Option<Contact>,
    /// 0 with a contact; otherwise a proved lower bound on the distance between the two
    /// inner-sphere packings (the minimum over the separated pairs where the descent stopped,
    /// or the safe-motion bound when skipped).
    pub distance: f64,
    /// Node pairs tested.
    pub visits: u64,
    /// True when the safe-motion bound answered without a traversal.
    pub skipped: bool,
}

impl ContactQuery {
    /// True when the packings overlap.
    pub fn in_contact(&self) -> bool {
        self.contact.is_some()
    }
}

/// Options of [`multipoint`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MultipointOptions {
    /// `false` (default): the paper's traversal. `true` (ours): the contacts are picked from
    /// the kinetic front (all overlapping leaf pairs, kept up to date at the cost of what the
    /// motion changed): last frame's contacts that still overlap first, then the others in
    /// front order, at most one per split-depth pair. Same guarantees.
    pub tracking: bool,
    /// At most this many contacts (no cap).
    pub k: usize,
    /// At most one contact below each traversal pair at this depth (pairs of nodes at this
    /// depth; a contact at a shallower leaf pair stands for itself).
    pub split_depth: u32,
    /// Keep last frame's contacts that still overlap and backtrack from the others.
    pub reuse: bool,
    /// Skip (answer "no contacts") while the last proved separation holds.
    pub safe_motion: bool,
}

impl Default for MultipointOptions {
    fn default() -> Self {
        MultipointOptions {
            tracking: false,
            k: 4,
            split_depth: 4,
            reuse: true,
            safe_motion: true,
        }
    }
}

/// Result of [`multipoint`]; the contacts are borrowed from the [`PairState`].
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct MultipointResult<'s> {
    /// Up to `k` contacts, at most one per split-depth pair; reused ones first.
    pub contacts: &'s [Contact],
    /// How many of them were last frame's contacts, still valid.
    pub reused: usize,
    /// 0 with contacts; otherwise a proved lower bound on the separation.
    pub distance: f64,
    /// Node pairs tested.
    pub visits: u64,
    /// True when the safe-motion bound answered without a traversal.
    pub skipped: bool,
}

/// Key that never matches a node pair.
const NO_PAIR: u64 = u64::MAX;

/// Refines the overlapping pair `e` into all child pairs (simultaneous descent), pushing the
/// overlapping ones that are neither `skip` nor excluded (exclusions are checked for pairs of
/// depth ≤ `split`), in reverse so that they pop in child order; separated ones lower
/// `min_sep`.
#[inline]
#[allow(clippy::too_many_arguments)]
fn expand_sim(
    ctx: &Ctx,
    stack: &mut Vec<Item>,
    excl: &[u64],
    split: u32,
    skip: u64,
    e: Item,
    min_sep: &mut f32,
    visits: &mut u64,
) {
    let na = &ctx.a[e.a as usize];
    let nb = &ctx.b[e.b as usize];
    let (fa, ca) = if na.is_leaf() {
        (e.a as usize, 1)
    } else {
        (na.first as usize, na.count as usize)
    };
    let (fb, cbn) = if nb.is_leaf() {
        (e.b as usize, 1)
    } else {
        (nb.first as usize, nb.count as usize)
    };
    let depth = e.depth + 1;
    let check = depth <= split && !excl.is_empty();
    let akids = &ctx.a[fa..fa + ca];
    for j in (fb..fb + cbn).rev() {
        let m = &ctx.b[j];
        let cb = if nb.is_leaf() {
            e.c
        } else {
            ctx.rel32.apply(m.x, m.y, m.z)
        };
        let rb = m.r;
        let jleaf = m.is_leaf();
        for (k, n) in akids.iter().enumerate().rev() {
            let leafs = jleaf && n.is_leaf();
            let s = n.r + rb + if leafs { 0.0 } else { ctx.slack };
            let dx = n.x - cb[0];
            let dy = n.y - cb[1];
            let dz = n.z - cb[2];
            let d2 = dx * dx + dy * dy + dz * dz;
            if d2 < s * s {
                let key = pair_key((fa + k) as u32, j as u32);
                if key == skip || (check && excl.binary_search(&key).is_ok()) {
                    continue;
                }
                ctx.prefetch((fa + k) as u32, j as u32);
                stack.push(Item {
                    a: (fa + k) as u32,
                    b: j as u32,
                    c: cb,
                    depth,
                });
            } else if d2 < (s + *min_sep) * (s + *min_sep) {
                let lb = d2.sqrt() - s;
                if lb < *min_sep {
                    *min_sep = lb;
                }
            }
        }
        *visits += ca as u64;
    }
}

/// Depth-first search over the stack until an overlapping leaf pair is popped.
#[allow(clippy::too_many_arguments)]
fn dfs_sim(
    ctx: &Ctx,
    stack: &mut Vec<Item>,
    excl: &[u64],
    split: u32,
    skip: u64,
    min_sep: &mut f32,
    visits: &mut u64,
) -> Option<Item> {
    while let Some(e) = stack.pop() {
        if ctx.a[e.a as usize].is_leaf() && ctx.b[e.b as usize].is_leaf() {
            return Some(e);
        }
        expand_sim(ctx, stack, excl, split, skip, e, min_sep, visits);
    }
    None
}

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
#[inline(always)]
pub(crate) fn block_step(
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
    let (over, mut near) = if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2 (checked just above; the check is a cached load).
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
/// pair; [`inner_gaps`] is the same for two inner nodes without building the sides.
#[inline(always)]
pub(crate) fn block_gaps(ctx: &Ctx, e: &TItem, visits: &mut u64) -> (u32, u32, f32) {
    let (sa, sb) = sides(ctx, e);
    let ll = lanes::leaf_pairs_mask(sb.leaf, sa.leaf);
    let valid = lanes::valid_mask(sb.count, sa.count);
    let rows = [&sb.x, &sb.y, &sb.z, &sb.r];
    let (over, m) = gap_kernel(rows, [&sa.x, &sa.y, &sa.z, &sa.r], ll, valid, ctx.slack);
    *visits += (sa.count * sb.count) as u64;
    (over, ll & valid, m)
}

/// [`block_gaps`] of a pair of inner nodes (blocks `ba` of A and `bb` of B) without building
/// the sides. The block front's common step, which needs the sides only when its outcome
/// changed (cachegrind: building and returning
/// them was ≈ a quarter of a step's instructions).
#[inline(always)]
pub(crate) fn inner_gaps(ctx: &Ctx, ba: u32, bb: u32, visits: &mut u64) -> (u32, u32, f32) {
    let ka = &ctx.blocks_a[ba as usize];
    let kb = &ctx.blocks_b[bb as usize];
    let (x, y, z) = ctx.rel32.apply4(&kb.x, &kb.y, &kb.z);
    let ll = lanes::leaf_pairs_mask(kb.leaf, ka.leaf);
    let valid = lanes::valid_mask(kb.count, ka.count);
    let (over, m) = gap_kernel(
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

/// [`overlap_gap_avx2`] where the CPU has AVX2, else [`overlap_gap`].
#[inline(always)]
fn gap_kernel(r: Lanes4, c: Lanes4, ll: u32, valid: u32, slack: f32) -> (u32, f32) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2 (checked just above; the check is a cached load).
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

/// [`expand_sim`] on blocks: a [`block_step`], overlapping pairs pushed in the same order (so
/// that they pop in child order), with the same exclusions.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn expand_blocks(
    ctx: &Ctx,
    stack: &mut Vec<TItem>,
    excl: &[u64],
    split: u32,
    skip: u64,
    e: TItem,
    min_sep: &mut f32,
    visits: &mut u64,
) {
    let (sa, sb, mut over) = block_step(ctx, &e, min_sep, visits);
    let depth = e.depth + 1;
    let check = depth <= split && !excl.is_empty();
    while over != 0 {
        let q = 31 - over.leading_zeros() as usize;
        over &= !(1 << q);
        let (l, i) = (q / LANES, q % LANES);
        let key = pair_key(sa.node[i], sb.node[l]);
        if key == skip || (check && excl.binary_search(&key).is_ok()) {
            continue;
        }
        let t = TItem::child(&sa, &sb, i, l, depth);
        t.prefetch(ctx);
        stack.push(t);
    }
}

/// [`dfs_sim`] on blocks.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn dfs_blocks(
    ctx: &Ctx,
    stack: &mut Vec<TItem>,
    excl: &[u64],
    split: u32,
    skip: u64,
    min_sep: &mut f32,
    visits: &mut u64,
) -> Option<Item> {
    while let Some(e) = stack.pop() {
        if e.kind == LEAFS {
            return Some(Item {
                a: e.na,
                b: e.nb,
                c: e.c,
                depth: e.depth,
            });
        }
        expand_blocks(ctx, stack, excl, split, skip, e, min_sep, visits);
    }
    None
}

/// [`dfs_blocks`] compiled for AVX2 when the CPU has it (8-wide lanes; no FMA, so every
/// result is bit for bit the same as the baseline build's).
#[allow(clippy::too_many_arguments)]
fn dfs_blocks_dispatch(
    ctx: &Ctx,
    stack: &mut Vec<TItem>,
    excl: &[u64],
    split: u32,
    skip: u64,
    min_sep: &mut f32,
    visits: &mut u64,
) -> Option<Item> {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        #[target_feature(enable = "avx2")]
        #[allow(clippy::too_many_arguments)]
        fn avx2(
            ctx: &Ctx,
            stack: &mut Vec<TItem>,
            excl: &[u64],
            split: u32,
            skip: u64,
            min_sep: &mut f32,
            visits: &mut u64,
        ) -> Option<Item> {
            dfs_blocks(ctx, stack, excl, split, skip, min_sep, visits)
        }
        // SAFETY: the CPU has AVX2 (checked above).
        return unsafe { avx2(ctx, stack, excl, split, skip, min_sep, visits) };
    }
    dfs_blocks(ctx, stack, excl, split, skip, min_sep, visits)
}

/// Every overlapping leaf pair below the pairs on `stack` (all of them, no order), by
/// blocked steps: `leaf(a, b, B's centre in A's frame)` for each; separated pairs lower
/// `min_sep`. The enumeration of the penetration query.
#[inline(always)]
fn overlap_pairs<F: FnMut(u32, u32, [f32; 3])>(
    ctx: &Ctx,
    stack: &mut Vec<TItem>,
    min_sep: &mut f32,
    visits: &mut u64,
    mut leaf: F,
) {
    while let Some(e) = stack.pop() {
        if e.leaves() {
            leaf(e.na, e.nb, e.c);
            continue;
        }
        let (sa, sb, mut over) = block_step(ctx, &e, min_sep, visits);
        while over != 0 {
            let q = over.trailing_zeros() as usize;
            over &= over - 1;
            let t = TItem::child(&sa, &sb, q % LANES, q / LANES, 0);
            if t.leaves() {
                leaf(t.na, t.nb, t.c);
            } else {
                t.prefetch(ctx);
                stack.push(t);
            }
        }
    }
}

/// [`overlap_pairs`] compiled for AVX2 when the CPU has it (same results bit for bit).
pub(crate) fn overlap_pairs_dispatch(
    ctx: &Ctx,
    stack: &mut Vec<TItem>,
    min_sep: &mut f32,
    visits: &mut u64,
    leaf: &mut dyn FnMut(u32, u32, [f32; 3]),
) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        #[target_feature(enable = "avx2")]
        fn avx2(
            ctx: &Ctx,
            stack: &mut Vec<TItem>,
            min_sep: &mut f32,
            visits: &mut u64,
            leaf: &mut dyn FnMut(u32, u32, [f32; 3]),
        ) {
            overlap_pairs(ctx, stack, min_sep, visits, leaf)
        }
        // SAFETY: the CPU has AVX2 (checked above).
        unsafe { avx2(ctx, stack, min_sep, visits, leaf) };
        return;
    }
    overlap_pairs(ctx, stack, min_sep, visits, leaf)
}

/// True when both trees have blocks (fan-out ≤ 4): the traversals then run on them.
pub(crate) fn blocked(ctx: &Ctx) -> bool {
    !ctx.blocks_a.is_empty() && !ctx.blocks_b.is_empty()
}

/// Starts a depth-first search at node pair (`a`, `b`), B's centre `c`, traversal `depth`.
fn start(ctx: &Ctx, s: &mut Scratch, a: u32, b: u32, c: [f32; 3], depth: u32) {
    if blocked(ctx) {
        s.tstack.clear();
        s.tstack.push(TItem::new(ctx, a, b, c, depth));
    } else {
        s.stack.clear();
        s.stack.push(Item { a, b, c, depth });
    }
}

/// Goes on with the search until the next overlapping leaf pair (or none), skipping the
/// pair `skip` and, with `use_excluded`, the excluded pairs down to depth `split`.
fn resume(
    ctx: &Ctx,
    s: &mut Scratch,
    use_excluded: bool,
    split: u32,
    skip: u64,
    min_sep: &mut f32,
    visits: &mut u64,
) -> Option<Item> {
    let excl: &[u64] = if use_excluded { &s.excluded } else { &[] };
    if blocked(ctx) {
        dfs_blocks_dispatch(ctx, &mut s.tstack, excl, split, skip, min_sep, visits)
    } else {
        dfs_sim(ctx, &mut s.stack, excl, split, skip, min_sep, visits)
    }
}

/// Drops the pairs deeper than `split` from the search's stack (leaves the current
/// split-depth pair after a contact was found in it).
fn leave_below(ctx: &Ctx, s: &mut Scratch, split: u32) {
    if blocked(ctx) {
        while s.tstack.last().is_some_and(|t| t.depth > split) {
            s.tstack.pop();
        }
    } else {
        while s.stack.last().is_some_and(|t| t.depth > split) {
            s.stack.pop();
        }
    }
}

/// Ancestors of `n`, root first (`out[d]` is the ancestor at depth `d`).
fn chain(nodes: &[Node], n: u32, out: &mut Vec<u32>) {
    out.clear();
    let mut n = n;
    loop {
        out.push(n);
        let p = nodes[n as usize].parent;
        if p == NO_PARENT {
            break;
        }
        n = p;
    }
    out.reverse();
}

/// The ancestor of `n` at `depth` (`n` itself when it is not deeper).
fn ancestor_at(nodes: &[Node], mut n: u32, depth: u32) -> u32 {
    while nodes[n as usize].depth > depth {
        n = nodes[n as usize].parent;
    }
    n
}

/// Key of the traversal pair at `split` depth above leaf pair (`la`, `lb`).
fn split_key(ctx: &Ctx, la: u32, lb: u32, split: u32) -> u64 {
    pair_key(ancestor_at(ctx.a, la, split), ancestor_at(ctx.b, lb, split))
}

/// Inserts into a sorted vector; false when already present.
fn insert_sorted(v: &mut Vec<u64>, key: u64) -> bool {
    match v.binary_search(&key) {
        Ok(_) => false,
        Err(p) => {
            v.insert(p, key);
            true
        }
    }
}

/// The safe-motion answer, when enabled and positive.
fn safe_skip(ia: &TreeInfo, ib: &TreeInfo, s: &Scratch, ctx: &Ctx, on: bool) -> Option<f64> {
    if !on {
        return None;
    }
    safe_separation(ia, ib, s.separation, &ctx.rel).filter(|&d| d > 0.0)
}

/// Root test, then a full traversal from the roots.
fn full(ctx: &Ctx, s: &mut Scratch, min_sep: &mut f32, visits: &mut u64) -> Option<Item> {
    let c0 = ctx.xf(0);
    let (ov, lb) = ctx.test(0, 0, c0);
    *visits += 1;
    if !ov {
        *min_sep = min_sep.min(lb);
        return None;
    }
    start(ctx, s, 0, 0, c0, 0);
    resume(ctx, s, false, u32::MAX, NO_PAIR, min_sep, visits)
}

/// Climbs from the stale leaf pair (`la`, `lb`) toward the root (Algorithms 1–2): the leaf
/// pair itself, then each traversal pair above it from level `top − 1` down to `stop`, each
/// searched without the already visited child pair.
fn climb(
    ctx: &Ctx,
    s: &mut Scratch,
    la: u32,
    lb: u32,
    stop: u32,
    min_sep: &mut f32,
    visits: &mut u64,
) -> Option<Item> {
    let cb = ctx.xf(lb);
    let (ov, d) = ctx.test(la, lb, cb);
    *visits += 1;
    if ov {
        return Some(Item {
            a: la,
            b: lb,
            c: cb,
            depth: 0,
        });
    }
    *min_sep = min_sep.min(d);
    chain(ctx.a, la, &mut s.anc_a);
    chain(ctx.b, lb, &mut s.anc_b);
    let da = s.anc_a.len() - 1;
    let db = s.anc_b.len() - 1;
    let top = da.max(db);
    for k in (stop as usize..top).rev() {
        let (pa, pb) = (s.anc_a[k.min(da)], s.anc_b[k.min(db)]);
        let cb = ctx.xf(pb);
        let (ov, d) = ctx.test(pa, pb, cb);
        *visits += 1;
        if !ov {
            *min_sep = min_sep.min(d);
            continue;
        }
        let skip = pair_key(s.anc_a[(k + 1).min(da)], s.anc_b[(k + 1).min(db)]);
        start(ctx, s, pa, pb, cb, k as u32);
        if let Some(e) = resume(ctx, s, false, u32::MAX, skip, min_sep, visits) {
            return Some(e);
        }
    }
    None
}

/// Result of a contact traversal, recording the separation for the safe-motion skip.
fn finish(
    ctx: &Ctx,
    s: &mut Scratch,
    found: Option<Item>,
    min_sep: f32,
    visits: u64,
) -> ContactQuery {
    match found {
        Some(e) => {
            s.separation = None;
            ContactQuery {
                contact: Some(make_contact(ctx.a, e.a, ctx.b, e.b, e.c, &ctx.pose_a)),
                distance: 0.0,
                visits,
                skipped: false,
            }
        }
        None => {
            let d = min_sep.max(0.0) as f64;
            s.record_separation(ctx, d);
            ContactQuery {
                contact: None,
                distance: d,
                visits,
                skipped: false,
            }
        }
    }
}

fn skipped(d: f64) -> ContactQuery {
    ContactQuery {
        contact: None,
        distance: d,
        visits: 0,
        skipped: true,
    }
}

/// The paper's distance traversal (III-A): from the roots, descend while the spheres
/// overlap, stop at the first overlapping leaf pair (the contact) or when every branch has
/// reached a separated pair (no contact; `distance` = the smallest separation seen there).
pub fn distance_traversal(
    a: &SphereTree,
    pose_a: &Pose,
    b: &SphereTree,
    pose_b: &Pose,
    st: &mut PairState,
    opts: &ContactOptions,
) -> ContactQuery {
    let (ctx, s, ia, ib) = st.begin(a, pose_a, b, pose_b);
    if let Some(d) = safe_skip(ia, ib, s, &ctx, opts.safe_motion) {
        return skipped(d);
    }
    let mut min_sep = f32::INFINITY;
    let mut visits = 0;
    let found = full(&ctx, s, &mut min_sep, &mut visits);
    finish(&ctx, s, found, min_sep, visits)
}

/// The paper's backtracking traversal (III-B, Algorithms 1–2): restart from the previous
/// frame's contact pair; if it no longer overlaps, search the traversal pair above it, then
/// climb toward the root, each time skipping the subtree pair already searched. Without a
/// previous contact it is the full distance traversal. Same contact answer as
/// [`distance_traversal`] on every frame.
pub fn backtracking(
    a: &SphereTree,
    pose_a: &Pose,
    b: &SphereTree,
    pose_b: &Pose,
    st: &mut PairState,
    opts: &ContactOptions,
) -> ContactQuery {
    let (ctx, s, ia, ib) = st.begin(a, pose_a, b, pose_b);
    if let Some(d) = safe_skip(ia, ib, s, &ctx, opts.safe_motion) {
        return skipped(d);
    }
    let mut min_sep = f32::INFINITY;
    let mut visits = 0;
    let found = match s.bt_pair {
        None => full(&ctx, s, &mut min_sep, &mut visits),
        Some((la, lb)) => {
            // Broad phase first.
            let (ov, lbr) = ctx.test(0, 0, ctx.xf(0));
            visits += 1;
            if ov {
                climb(&ctx, s, la, lb, 0, &mut min_sep, &mut visits)
            } else {
                min_sep = lbr;
                None
            }
        }
    };
    if let Some(e) = found {
        s.bt_pair = Some((e.a, e.b));
    }
    finish(&ctx, s, found, min_sep, visits)
}

/// Steps of the block front per contact frame of [`contact`] (`BlockFront::tend`): ≈ 4 µs.
/// On the jaw chew, 64 gave the lowest p99 of 0 / 32 / 64 / 128 in the same process (the
/// frames where contact ends fell from ≈ 22 to 15–18 over 20 µs; 128 made contact frames
/// themselves slow in the VM's slower phases).
const TEND: usize = 64;

/// First contact from a kinetic front (ours, beyond the paper): the same contact answer as
/// [`distance_traversal`] and [`backtracking`] on every frame, at the cost of what the motion
/// changed.
///
/// On trees of fan-out ≤ 4 (the default): the newest contact leaf pair (after a contact
/// frame, the last four) is tested first; if none overlaps, the block front re-runs the 4×4
/// steps of the overlap traversal whose outcome the motion since could have changed, up to
/// the first overlapping leaf pair: shallow first after a frame without contact, deepest
/// first after a contact frame (the deepest expired steps lie next to the overlaps that just
/// ended; when none is left, the front has proved the separation in the same frame). While
/// the recent pairs answer, a few expired steps a frame (shallow first) keep the front close
/// to current, so that the frame where contact ends has less to catch up; its clock runs on,
/// so it stays valid. Other fan-outs use the pair-by-pair front of the tracked queries.
/// The first frame, and a frame after a jump, builds the front by a full traversal. The
/// front subsumes the safe-motion skip, so `opts` changes nothing.
pub fn contact(
    a: &SphereTree,
    pose_a: &Pose,
    b: &SphereTree,
    pose_b: &Pose,
    st: &mut PairState,
    opts: &ContactOptions,
) -> ContactQuery {
    let _ = opts;
    let (ctx, s, _, ib) = st.begin(a, pose_a, b, pose_b);
    let mut visits = 0;
    let distance;
    let found = if blocked(&ctx) {
        let f = &mut s.bfront;
        f.advance(&ctx, ib);
        // Contact mostly persists, or comes back, where it was: a leaf test or a few decide
        // most frames in contact.
        let was = f.in_contact();
        let found = match f.recall(&ctx, was, &mut visits) {
            // While the contact lasts, a few steps a frame keep the front near current, so
            // that the frame where it ends has less to catch up.
            Some(hit) => {
                visits += f.tend(&ctx, TEND);
                Some(hit)
            }
            // After a contact frame the deepest expired steps first; a climb from the newest
            // pair (as `backtracking`) cost a second slow frame when the contact had ended:
            // the front's catch-up on the next one.
            None => {
                visits += f.catch_up(&ctx, was);
                f.hit()
            }
        };
        // Without a contact the front is complete, so its margin bounds the separation.
        distance = f.margin().max(0.0);
        f.set_answer(found);
        found
    } else {
        visits += s.front.update(&ctx, ib);
        distance = s.front.margin().max(0.0);
        s.front.hits.first().map(|h| (h.a, h.b, h.c))
    };
    match found {
        Some((la, lb, c)) => ContactQuery {
            contact: Some(make_contact(ctx.a, la, ctx.b, lb, c, &ctx.pose_a)),
            distance: 0.0,
            visits,
            skipped: false,
        },
        None => ContactQuery {
            contact: None,
            distance,
            visits,
            skipped: false,
        },
    }
}

/// The paper's multipoint traversal (III-C): up to `k` contacts, at most one below each
/// traversal pair at the split depth.
///
/// Each frame: (1) last frame's contacts that still overlap are kept and their split-depth
/// pairs excluded; (2) from each stale one, backtrack within its split-depth pair for a
/// replacement (the pair is excluded afterwards, with or without one); (3) while fewer than
/// `k`, a traversal from the roots skipping excluded pairs; after each contact found the
/// search leaves that contact's split-depth pair.
pub fn multipoint<'s>(
    a: &SphereTree,
    pose_a: &Pose,
    b: &SphereTree,
    pose_b: &Pose,
    st: &'s mut PairState,
    opts: &MultipointOptions,
) -> MultipointResult<'s> {
    let (ctx, s, ia, ib) = st.begin(a, pose_a, b, pose_b);
    let k = opts.k;
    s.contacts.clear();
    s.excluded.clear();
    s.stale.clear();
    let mut min_sep = f32::INFINITY;
    let mut visits = 0u64;
    let mut reused = 0;
    let mut skip = false;
    if k > 0 && !opts.tracking && s.mp_prev.is_empty() {
        if let Some(d) = safe_skip(ia, ib, s, &ctx, opts.safe_motion) {
            min_sep = d as f32;
            skip = true;
        }
    }
    if k > 0 && opts.tracking {
        visits = s.front.update(&ctx, ib);
        multipoint_pick(&ctx, s, opts, &mut visits, &mut reused);
        min_sep = s.front.margin().max(0.0) as f32;
    } else if k > 0 && !skip {
        multipoint_search(&ctx, s, opts, &mut min_sep, &mut visits, &mut reused);
        if s.contacts.is_empty() {
            s.record_separation(&ctx, min_sep.max(0.0) as f64);
        } else {
            s.separation = None;
        }
    }
    s.mp_prev.clear();
    s.mp_prev
        .extend(s.contacts.iter().map(|c| (c.leaf_a, c.leaf_b)));
    let distance = if s.contacts.is_empty() {
        min_sep.max(0.0) as f64
    } else {
        0.0
    };
    MultipointResult {
        contacts: &s.contacts,
        reused,
        distance,
        visits,
        skipped: skip,
    }
}

/// [`multipoint`] from the kinetic front: last frame's contacts that still overlap, then the
/// front's overlapping leaf pairs, at most one per split-depth pair.
fn multipoint_pick(
    ctx: &Ctx,
    s: &mut Scratch,
    opts: &MultipointOptions,
    visits: &mut u64,
    reused: &mut usize,
) {
    let k = opts.k;
    let split = opts.split_depth;
    if opts.reuse {
        for idx in 0..s.mp_prev.len() {
            if s.contacts.len() >= k {
                break;
            }
            let (la, lb) = s.mp_prev[idx];
            let cb = ctx.xf(lb);
            let (ov, _) = ctx.test(la, lb, cb);
            *visits += 1;
            if ov && insert_sorted(&mut s.excluded, split_key(ctx, la, lb, split)) {
                s.contacts
                    .push(make_contact(ctx.a, la, ctx.b, lb, cb, &ctx.pose_a));
                *reused += 1;
            }
        }
    }
    for h in s.front.hits.iter_mut() {
        if s.contacts.len() >= k {
            break;
        }
        if h.split != split {
            h.key = split_key(ctx, h.a, h.b, split);
            h.split = split;
        }
        if insert_sorted(&mut s.excluded, h.key) {
            s.contacts
                .push(make_contact(ctx.a, h.a, ctx.b, h.b, h.c, &ctx.pose_a));
        }
    }
}

/// The three stages of [`multipoint`].
fn multipoint_search(
    ctx: &Ctx,
    s: &mut Scratch,
    opts: &MultipointOptions,
    min_sep: &mut f32,
    visits: &mut u64,
    reused: &mut usize,
) {
    let k = opts.k;
    let split = opts.split_depth;
    let c0 = ctx.xf(0);
    let (ov, lbr) = ctx.test(0, 0, c0);
    *visits += 1;
    if !ov {
        *min_sep = lbr;
        return;
    }
    // (1) Still valid contacts.
    if opts.reuse {
        for idx in 0..s.mp_prev.len() {
            let (la, lb) = s.mp_prev[idx];
            let cb = ctx.xf(lb);
            let (ov, d) = ctx.test(la, lb, cb);
            *visits += 1;
            if !ov {
                *min_sep = min_sep.min(d);
                s.stale.push((la, lb));
            } else if s.contacts.len() < k
                && insert_sorted(&mut s.excluded, split_key(ctx, la, lb, split))
            {
                s.contacts
                    .push(make_contact(ctx.a, la, ctx.b, lb, cb, &ctx.pose_a));
                *reused += 1;
            }
        }
    }
    // (2) Backtrack from stale contacts within their split-depth pairs.
    for idx in 0..s.stale.len() {
        if s.contacts.len() >= k {
            break;
        }
        let (la, lb) = s.stale[idx];
        let key = split_key(ctx, la, lb, split);
        if s.excluded.binary_search(&key).is_ok() {
            continue;
        }
        let found = climb(ctx, s, la, lb, split, min_sep, visits);
        insert_sorted(&mut s.excluded, key);
        if let Some(e) = found {
            s.contacts
                .push(make_contact(ctx.a, e.a, ctx.b, e.b, e.c, &ctx.pose_a));
        }
    }
    // (3) Search from the roots for the rest.
    if s.contacts.len() < k && s.excluded.binary_search(&pair_key(0, 0)).is_err() {
        start(ctx, s, 0, 0, c0, 0);
        while let Some(e) = resume(ctx, s, true, split, NO_PAIR, min_sep, visits) {
            s.contacts
                .push(make_contact(ctx.a, e.a, ctx.b, e.b, e.c, &ctx.pose_a));
            insert_sorted(&mut s.excluded, split_key(ctx, e.a, e.b, split));
            if s.contacts.len() >= k {
                break;
            }
            leave_below(ctx, s, split);
        }
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
            if std::arch::is_x86_feature_detected!("avx2") {
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
            if std::arch::is_x86_feature_detected!("avx2") {
                // SAFETY: the CPU has AVX2 (checked above).
                let (o2, g2) = unsafe { overlap_gap_avx2(rl, cl, ll, valid, 1e-4) };
                prop_assert_eq!(o1, o2);
                prop_assert_eq!(g1.to_bits(), g2.to_bits());
            }
        }
    }
}
