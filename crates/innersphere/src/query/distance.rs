//! Exact distance of the two inner-sphere packings: branch and bound over both trees.

use super::kernel::far::{norm, Far};
use super::kernel::geometry::{direction, leaf_pair};
use super::kernel::heap::{Entry, PairHeap};
use super::kernel::info::{Node, TreeInfo, LANES};
use super::kernel::lanes;
#[cfg(target_arch = "x86_64")]
use super::kernel::nearest::step_avx2;
use super::kernel::nearest::{block_in_a, leaf_step, step_scalar, Prune};
use super::kernel::separation::{record, SeparationRecord};
use super::kernel::{expand_larger, prefetch, Ctx};
use glam::DVec3;

/// The scratch and coherence of the distance query.
#[derive(Debug)]
pub(crate) struct DistanceScratch {
    /// Depth-first stack of keyed pairs (fan-outs over 4).
    pub pstack: Vec<Entry>,
    /// Depth-first stack of the 4×4 search (fan-outs ≤ 4).
    pub bstack: Vec<BlockEntry>,
    /// Leaf pair of the last answer (the first upper bound of the next query).
    pub last: Option<(u32, u32)>,
}

/// Options of [`Pair::distance_with`](crate::Pair::distance_with).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DistanceOptions {
    /// Stop once the answer is proved within this absolute distance of the minimum (as PQP
    /// and FCL offer); 0 = exact.
    pub abs_tolerance: f64,
    /// Stop once the answer is proved within this fraction of the minimum; 0 = exact.
    pub rel_tolerance: f64,
    /// When the packings overlap: `false` (default) stops at the first overlapping leaf pair
    /// found and reports `distance = 0`; `true` finds the most deeply overlapping leaf pair
    /// and reports `distance = −(its overlap)` (slower: every node pair that could overlap
    /// deeper must be refined).
    pub signed: bool,
    /// Start from last query's closest leaf pair (an upper bound before the search starts).
    pub coherence: bool,
    /// Search order: `true` = best first (a priority queue of node pairs keyed by their
    /// lower bound, the classic formulation); `false` (default) = depth first, nearest child
    /// pair first. Both return the same answer; with the coherent upper bound they refine
    /// about the same pairs, and depth first is cheaper per pair (no heap, better locality).
    pub best_first: bool,
}

impl Default for DistanceOptions {
    fn default() -> Self {
        DistanceOptions {
            abs_tolerance: 0.0,
            rel_tolerance: 0.0,
            signed: false,
            coherence: true,
            best_first: false,
        }
    }
}

/// Result of [`Pair::distance`](crate::Pair::distance).
///
/// Its serde form is the answer every door prints (`ist query --json`, Python's `to_dict`,
/// the viewer): these fields under these names, `overlapping` as `contact`.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct Distance {
    /// Minimum distance between the two inner-sphere packings (the unions of the leaf
    /// spheres): `min |cb − ca| − ra − rb` over all leaf pairs. When the packings overlap it
    /// is 0, or with [`DistanceOptions::signed`] minus the deepest leaf-pair overlap. With
    /// tolerances: `true ≤ distance ≤ true + max(abs, rel·true)`.
    pub distance: f64,
    /// `|cb − ca| − ra − rb` of the reported leaf pair (negative when it overlaps).
    pub pair_distance: f64,
    /// A proved lower bound on the exact answer (equal to `distance` without tolerances).
    pub lower_bound: f64,
    /// True when the packings overlap (serialized as `contact`, the word every answer uses).
    #[serde(rename = "contact")]
    pub overlapping: bool,
    /// Closest point on A's leaf sphere (world): `ca + ra·n`.
    pub point_a: DVec3,
    /// Closest point on B's leaf sphere (world): `cb − rb·n`.
    pub point_b: DVec3,
    /// World unit direction from A's leaf centre to B's.
    pub normal: DVec3,
    /// The leaf of A (node index).
    pub leaf_a: u32,
    /// The leaf of B (node index).
    pub leaf_b: u32,
    /// Node pairs whose distance was computed.
    pub visits: u64,
}

impl Distance {
    /// This answer, found in A's frame, in the world frame (A at `pose_a`).
    pub(crate) fn in_world(self, pose_a: &crate::pose::Pose) -> Distance {
        Distance {
            point_a: pose_a.transform_point(self.point_a),
            point_b: pose_a.transform_point(self.point_b),
            normal: pose_a.transform_vector(self.normal),
            ..self
        }
    }
}

/// Exact minimum distance between the inner-sphere packings of `a` at `pose_a` and `b` at
/// `pose_b` (world poses), with the closest points and the leaf pair.
///
/// Branch and bound over node pairs with the lower bound `|ca − cb| − ra − rb`, refining the
/// larger sphere first and pruning pairs that cannot beat the best leaf pair so far (seeded
/// with last query's pair); best first or depth first ([`DistanceOptions::best_first`]).
/// Records the proved separation for the safe-motion skip of the contact queries.
// Kept whole (over 120 lines): the seed, the two search orders and the separation record
// share the bound and the best pair of one query on the hot path.
#[allow(clippy::too_many_arguments)]
pub(crate) fn distance(
    ctx: &Ctx,
    ia: &TreeInfo,
    ib: &TreeInfo,
    heap: &mut PairHeap,
    sep: &mut Option<SeparationRecord>,
    s: &mut DistanceScratch,
    opts: &DistanceOptions,
) -> Distance {
    let abs = opts.abs_tolerance.max(0.0) as f32;
    let rel = opts.rel_tolerance.max(0.0) as f32;
    let signed = opts.signed;
    // A pair whose lower bound is `lb` cannot improve `ub` by more than the tolerance.
    let done = |lb: f32, ub: f32| ub - lb <= abs.max(rel * lb.max(0.0));
    let clamp = |d: f32| if signed { d } else { d.max(0.0) };
    let mut ub = f32::INFINITY;
    let mut best = (0u32, 0u32);
    let mut visits = 0u64;
    if opts.coherence {
        if let Some((la, lb)) = s.last {
            let (_, d) = ctx.test(la, lb, ctx.xf(lb));
            ub = d;
            best = (la, lb);
            visits += 1;
        }
    }
    let c0 = ctx.xf(0);
    let (_, root_lb) = ctx.test(0, 0, c0);
    visits += 1;
    let mut lower = f32::INFINITY;
    let root = Entry {
        key: root_lb,
        a: 0,
        b: 0,
        c: c0,
    };
    if ctx.a[0].is_leaf() && ctx.b[0].is_leaf() {
        if root_lb < ub {
            ub = root_lb;
            best = (0, 0);
        }
    } else if opts.best_first {
        // In the non-signed mode overlapping pairs are all "distance 0"; among them the
        // smallest spheres go first, so that the search dives to an overlapping leaf pair.
        let key_of = |d: f32, s: f32| if signed || d > 0.0 { d } else { -1.0 / s };
        heap.clear();
        if !done(clamp(root_lb), ub) {
            let sr = ctx.a[0].r + ctx.b[0].r + ctx.slack;
            heap.push(Entry {
                key: key_of(root_lb, sr),
                ..root
            });
        } else {
            lower = clamp(root_lb);
        }
        // The proved lower bound is the smallest bound of everything pruned and of what is
        // left on the heap when the search stops (a child's sphere may reach beyond its
        // parent's, so heap keys need not grow as the search goes on).
        while let Some(e) = heap.pop() {
            let elb = clamp(e.key);
            if done(elb, ub) {
                lower = lower.min(elb);
                break;
            }
            expand_larger(ctx, e.a, e.b, e.c, |i, j, c, d2, sr, leafs| {
                visits += 1;
                let d = d2.sqrt() - sr;
                if leafs {
                    if d < ub {
                        ub = d;
                        best = (i, j);
                    }
                } else if !done(clamp(d), ub) {
                    heap.push(Entry {
                        key: key_of(d, sr),
                        a: i,
                        b: j,
                        c,
                    });
                } else {
                    lower = lower.min(clamp(d));
                }
            });
        }
    } else {
        let prune = Prune { abs, rel, signed };
        let mut f = Found { ub, best, visits };
        if f.ub == f32::INFINITY {
            dive(ctx, c0, &mut f);
        } else if root_lb > 0.0 {
            // Separated roots: after a large motion the last answer's pair may be a poor
            // bound (a turned body far away: 456k tests instead of 13k on the jaw); a dive
            // gives a second seed and the better one is kept.
            let mut g = Found {
                ub: f32::INFINITY,
                best: f.best,
                visits: f.visits,
            };
            dive(ctx, c0, &mut g);
            f.visits = g.visits;
            if g.ub < f.ub {
                (f.ub, f.best) = (g.ub, g.best);
            }
        }
        if !ia.blocks.is_empty() && !ib.blocks.is_empty() {
            let root = root_entry(ctx, c0);
            depth_first_blocks_dispatch(ctx, ia, ib, root, &mut s.bstack, prune, &mut f);
        } else {
            let stack = &mut s.pstack;
            stack.clear();
            let (dx, dy, dz) = (ctx.a[0].x - c0[0], ctx.a[0].y - c0[1], ctx.a[0].z - c0[2]);
            stack.push(Entry {
                key: dx * dx + dy * dy + dz * dz,
                ..root
            });
            depth_first_nodes(ctx, stack, prune, &mut f);
        }
        (ub, best, visits) = (f.ub, f.best, f.visits);
        // Pruned pairs all had bounds ≥ the threshold of their time, so the final threshold
        // is a proved lower bound.
        lower = if signed {
            prune.thr(ub)
        } else {
            prune.thr(ub).max(0.0)
        };
    }
    let lower = lower.min(ub);
    s.last = Some(best);
    let (la, lb) = best;
    let cb = ctx.xf(lb);
    let (ca, ra, cbd, rb) = leaf_pair(&ctx.a[la as usize], &ctx.b[lb as usize], cb);
    let (mut n, _) = direction(ca, cbd);
    if n == DVec3::ZERO {
        n = DVec3::X;
    }
    let overlapping = ub < 0.0;
    if overlapping {
        *sep = None;
    } else {
        record(sep, ctx, lower as f64);
    }
    Distance {
        distance: clamp(ub) as f64,
        pair_distance: ub as f64,
        lower_bound: clamp(lower) as f64,
        overlapping,
        point_a: ca + n * ra,
        point_b: cbd - n * rb,
        normal: n,
        leaf_a: la,
        leaf_b: lb,
        visits,
    }
}

/// The distance at a far pose whose tolerance exceeds the trees' size
/// ([`Far::roots_only`]), in f64: each tree descends greedily toward the other's root centre
/// to a leaf, and that leaf pair is the answer. The exact distance lies between the root
/// spheres' separation (the lower bound) and that pair's distance, which are at most
/// `2(ρ_A + ρ_B)` apart, within the far tolerance.
pub(crate) fn far_roots(
    ctx: &Ctx,
    ia: &TreeInfo,
    ib: &TreeInfo,
    far: &Far,
    s: &mut DistanceScratch,
) -> Distance {
    let rel = &ctx.rel;
    let mut visits = 0u64;
    let la = dive_toward(ctx.a, rel.transform_point(ib.root_center), &mut visits);
    let lb = dive_toward(
        ctx.b,
        rel.inverse().transform_point(ia.root_center),
        &mut visits,
    );
    let (na, nb) = (&ctx.a[la as usize], &ctx.b[lb as usize]);
    let ca = DVec3::new(na.x as f64, na.y as f64, na.z as f64);
    let cb = rel.transform_point(DVec3::new(nb.x as f64, nb.y as f64, nb.z as f64));
    let delta = cb - ca;
    let len = norm(delta);
    let n = if len > 0.0 && len.is_finite() {
        let m = delta.abs().max_element();
        (delta / m).normalize()
    } else {
        DVec3::X
    };
    let (ra, rb) = (na.r as f64, nb.r as f64);
    let pair = (len - ra - rb).min(f64::MAX);
    s.last = Some((la, lb));
    Distance {
        distance: pair.max(far.separation),
        pair_distance: pair,
        lower_bound: far.separation,
        overlapping: false,
        point_a: ca + n * ra,
        point_b: cb - n * rb,
        normal: n,
        leaf_a: la,
        leaf_b: lb,
        visits,
    }
}

/// The leaf reached from the root by always entering the child whose sphere comes nearest to
/// `p` (node frame, f64).
fn dive_toward(nodes: &[Node], p: DVec3, visits: &mut u64) -> u32 {
    let mut i = 0u32;
    loop {
        let n = &nodes[i as usize];
        if n.is_leaf() {
            return i;
        }
        let kids = n.first..n.first + n.count;
        i = kids
            .min_by(|&x, &y| {
                let gap = |k: u32| {
                    let c = &nodes[k as usize];
                    norm(DVec3::new(c.x as f64, c.y as f64, c.z as f64) - p) - c.r as f64
                };
                gap(x).total_cmp(&gap(y))
            })
            .unwrap_or(n.first);
        *visits += n.count as u64;
    }
}

/// The best leaf pair so far of the depth-first search, and the node-pair tests spent.
struct Found {
    ub: f32,
    best: (u32, u32),
    visits: u64,
}

/// No pair from the last query: dives to a leaf pair along the nearest child pairs for a
/// first upper bound (unordered depth first could wander far first).
fn dive(ctx: &Ctx, c0: [f32; 3], f: &mut Found) {
    let (mut ea, mut eb, mut ec) = (0u32, 0u32, c0);
    loop {
        let mut next = (f32::INFINITY, 0u32, 0u32, c0, false);
        expand_larger(ctx, ea, eb, ec, |i, j, c, d2, sr, leafs| {
            f.visits += 1;
            let d = d2.sqrt() - sr;
            if d < next.0 {
                next = (d, i, j, c, leafs);
            }
        });
        let (d, i, j, c, leafs) = next;
        if leafs {
            f.ub = d;
            f.best = (i, j);
            return;
        }
        if d == f32::INFINITY {
            return;
        }
        (ea, eb, ec) = (i, j, c);
    }
}

/// Depth first over the stack, one child at a time (any fan-out).
fn depth_first_nodes(ctx: &Ctx, stack: &mut Vec<Entry>, p: Prune, f: &mut Found) {
    while let Some(e) = stack.pop() {
        let t = p.thr(f.ub);
        if p.finished(t) {
            break;
        }
        let sr = ctx.a[e.a as usize].r + ctx.b[e.b as usize].r + ctx.slack;
        if !Prune::refine(e.key, sr, t) {
            continue;
        }
        expand_larger(ctx, e.a, e.b, e.c, |i, j, c, d2, sr, leafs| {
            f.visits += 1;
            if leafs {
                if Prune::refine(d2, sr, f.ub) {
                    let d = d2.sqrt() - sr;
                    if d < f.ub {
                        f.ub = d;
                        f.best = (i, j);
                    }
                }
            } else if Prune::refine(d2, sr, p.thr(f.ub)) {
                stack.push(Entry {
                    key: d2,
                    a: i,
                    b: j,
                    c,
                });
            }
        });
    }
}

/// A pair on the 4×4 search's stack: two inner nodes (block indices), or a leaf and an
/// inner node with the leaf's sphere inline (centre in A's frame), plus the pair's squared
/// centre distance and radius sum at the time it was pushed.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct BlockEntry {
    /// Block of A's node, or A's leaf node index when `kind == A_LEAF`.
    a: u32,
    /// Block of B's node, or B's leaf node index when `kind == B_LEAF`.
    b: u32,
    kind: u32,
    d2: f32,
    s: f32,
    /// The leaf's sphere (A's frame) when one side is a leaf.
    p: [f32; 4],
}

const INNER: u32 = 0;
const A_LEAF: u32 = 1;
const B_LEAF: u32 = 2;

/// Records leaf pair (`i`, `j`) at `d2`, `s` when it beats the best so far.
#[inline(always)]
fn leaf_pair_found(f: &mut Found, d2: f32, s: f32, i: u32, j: u32) {
    let d = d2.sqrt() - s;
    if d < f.ub {
        f.ub = d;
        f.best = (i, j);
    }
}

/// Depth first for fan-outs ≤ 4, splitting both nodes of a pair at once: the children of
/// both are tested 4×4 in one vectorised step from their [`Block`]s (two cache lines per
/// node), a pair with a leaf side tests the leaf against the other's 4 children. Twice the
/// sphere tests of splitting the larger node, but half the stack pops, and a pop is what
/// costs, far more than a lane test (BENCHMARKS.md, "Tried and did not pay")). `AVX`: the step in AVX2
/// intrinsics (set only after the CPU was checked).
// Kept whole (over 120 lines): the descent's stack, bound and best pair stay locals of one
// loop on the hot path; split into calls they would pass by reference through every step.
#[inline(always)]
fn depth_first_blocks<const AVX: bool>(
    ctx: &Ctx,
    ia: &TreeInfo,
    ib: &TreeInfo,
    root: BlockEntry,
    stack: &mut Vec<BlockEntry>,
    p: Prune,
    f: &mut Found,
) {
    stack.clear();
    stack.push(root);
    let (ba, bb) = (&ia.blocks[..], &ib.blocks[..]);
    while let Some(e) = stack.pop() {
        let t = p.thr(f.ub);
        if p.finished(t) {
            break;
        }
        if !Prune::refine(e.d2, e.s, t) {
            continue;
        }
        match e.kind {
            INNER => {
                let ka = &ba[e.a as usize];
                let kb = &bb[e.b as usize];
                let mut d2 = [0.0f32; 16];
                let mut sr = [0.0f32; 16];
                let mut bxyz = [[0.0f32; LANES]; 3];
                let ll = lanes::leaf_pairs_mask(ka.leaf, kb.leaf);
                #[cfg(target_arch = "x86_64")]
                let mut mask = if AVX {
                    // SAFETY: `AVX` is only set by the dispatch after checking the CPU.
                    unsafe { step_avx2(ctx, ka, kb, ll, t, &mut bxyz, &mut d2, &mut sr) }
                } else {
                    step_scalar(ctx, ka, kb, ll, t, &mut bxyz, &mut d2, &mut sr)
                };
                #[cfg(not(target_arch = "x86_64"))]
                let mut mask = step_scalar(ctx, ka, kb, ll, t, &mut bxyz, &mut d2, &mut sr);
                f.visits += (ka.count * kb.count) as u64;
                let mut lm = mask & ll;
                if lm != 0 {
                    let ub0 = f.ub;
                    while lm != 0 {
                        let q = lm.trailing_zeros() as usize;
                        lm &= lm - 1;
                        let (ca, cb) = (ka.child[q / LANES], kb.child[q % LANES]);
                        leaf_pair_found(f, d2[q], sr[q], ca, cb);
                    }
                    if f.ub < ub0 {
                        let t = p.thr(f.ub);
                        let mut m = mask & !ll;
                        while m != 0 {
                            let q = m.trailing_zeros() as usize;
                            m &= m - 1;
                            if !Prune::refine(d2[q], sr[q], t) {
                                mask &= !(1 << q);
                            }
                        }
                    }
                }
                let mut im = mask & !ll;
                while im != 0 {
                    let q = im.trailing_zeros() as usize;
                    im &= im - 1;
                    let (i, l) = (q / LANES, q % LANES);
                    let a_leaf = (ka.leaf >> i) & 1;
                    let b_leaf = (kb.leaf >> l) & 1;
                    let (ca, cb) = (ka.child[i], kb.child[l]);
                    // A leaf side travels inline in the entry; block sides are prefetched
                    // (`kind` is `A_LEAF` / `B_LEAF` from the leaf bits).
                    let pp = if a_leaf != 0 {
                        prefetch(&bb[cb as usize]);
                        [ka.x[i], ka.y[i], ka.z[i], ka.r[i]]
                    } else {
                        prefetch(&ba[ca as usize]);
                        if b_leaf == 0 {
                            prefetch(&bb[cb as usize]);
                        }
                        [bxyz[0][l], bxyz[1][l], bxyz[2][l], kb.r[l]]
                    };
                    stack.push(BlockEntry {
                        a: ca,
                        b: cb,
                        kind: a_leaf | (b_leaf << 1),
                        d2: d2[q],
                        s: sr[q],
                        p: pp,
                    });
                }
            }
            // The leaf-side kinds are few of the pops. Written with the traversals' `Side`
            // (one code path for all three kinds) the search was slower (BENCHMARKS.md, "Tried and did not pay"),
            // so the inner-pair step keeps reading the two blocks directly.
            A_LEAF => {
                let kb = &bb[e.b as usize];
                let (bx, by, bz) = block_in_a(ctx, kb);
                let (d2, sr, mut mask) =
                    leaf_step(e.p, &bx, &by, &bz, &kb.r, kb.leaf, ctx.slack, t);
                f.visits += kb.count as u64;
                while mask != 0 {
                    let l = mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    let cb = kb.child[l];
                    if (kb.leaf >> l) & 1 != 0 {
                        leaf_pair_found(f, d2[l], sr[l], e.a, cb);
                    } else if Prune::refine(d2[l], sr[l], p.thr(f.ub)) {
                        prefetch(&bb[cb as usize]);
                        stack.push(BlockEntry {
                            b: cb,
                            d2: d2[l],
                            s: sr[l],
                            ..e
                        });
                    }
                }
            }
            _ => {
                let ka = &ba[e.a as usize];
                let (d2, sr, mut mask) =
                    leaf_step(e.p, &ka.x, &ka.y, &ka.z, &ka.r, ka.leaf, ctx.slack, t);
                f.visits += ka.count as u64;
                while mask != 0 {
                    let i = mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    let ca = ka.child[i];
                    if (ka.leaf >> i) & 1 != 0 {
                        leaf_pair_found(f, d2[i], sr[i], ca, e.b);
                    } else if Prune::refine(d2[i], sr[i], p.thr(f.ub)) {
                        prefetch(&ba[ca as usize]);
                        stack.push(BlockEntry {
                            a: ca,
                            d2: d2[i],
                            s: sr[i],
                            ..e
                        });
                    }
                }
            }
        }
    }
}

/// [`depth_first_blocks`] compiled for AVX2 when the CPU has it (8-wide lanes; no FMA, so
/// every result is bit for bit the same as the baseline build's).
fn depth_first_blocks_dispatch(
    ctx: &Ctx,
    ia: &TreeInfo,
    ib: &TreeInfo,
    root: BlockEntry,
    stack: &mut Vec<BlockEntry>,
    p: Prune,
    f: &mut Found,
) {
    #[cfg(target_arch = "x86_64")]
    if ctx.simd.is_some() {
        #[target_feature(enable = "avx2")]
        fn avx2(
            ctx: &Ctx,
            ia: &TreeInfo,
            ib: &TreeInfo,
            root: BlockEntry,
            stack: &mut Vec<BlockEntry>,
            p: Prune,
            f: &mut Found,
        ) {
            depth_first_blocks::<true>(ctx, ia, ib, root, stack, p, f)
        }
        // SAFETY: an `Avx2` token exists only where the CPU has AVX2 (`simd::detect`).
        unsafe { avx2(ctx, ia, ib, root, stack, p, f) };
        return;
    }
    depth_first_blocks::<false>(ctx, ia, ib, root, stack, p, f)
}

/// The 4×4 search's first pair: the two roots.
fn root_entry(ctx: &Ctx, c0: [f32; 3]) -> BlockEntry {
    let (na, nb) = (&ctx.a[0], &ctx.b[0]);
    let (dx, dy, dz) = (na.x - c0[0], na.y - c0[1], na.z - c0[2]);
    let d2 = dx * dx + dy * dy + dz * dz;
    let s = na.r + nb.r + ctx.slack;
    let (kind, p) = if na.is_leaf() {
        (A_LEAF, [na.x, na.y, na.z, na.r])
    } else if nb.is_leaf() {
        (B_LEAF, [c0[0], c0[1], c0[2], nb.r])
    } else {
        (INNER, [0.0; 4])
    };
    BlockEntry {
        a: 0,
        b: 0,
        kind,
        d2,
        s,
        p,
    }
}
