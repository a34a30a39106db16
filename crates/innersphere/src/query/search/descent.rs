//! The depth-first overlap descents: from a node pair down to overlapping leaf pairs, by
//! simultaneous descent (the paper's traversal order) or by 4×4 block steps on trees of
//! fan-out ≤ 4, with exclusions, a skipped pair, and the climb of the backtracking traversal
//! (Algorithms 1–2 of the paper). The paper's traversals, multipoint and penetration run on
//! these.

use crate::query::kernel::block::{block_step, TItem};
use crate::query::kernel::info::{Node, LANES};
use crate::query::kernel::{pair_key, Ctx, Item};
use crate::tree::NO_PARENT;

/// The stacks and ancestor chains of the descents (one per pair, reserved at its creation).
#[derive(Debug)]
pub(crate) struct Descent {
    /// Depth-first stack of simultaneous descent (fan-outs over 4).
    pub stack: Vec<Item>,
    /// Depth-first stack of the blocked descent (fan-outs ≤ 4).
    pub tstack: Vec<TItem>,
    /// Ancestors of the climb's leaf of A, root first.
    pub anc_a: Vec<u32>,
    /// Ancestors of the climb's leaf of B, root first.
    pub anc_b: Vec<u32>,
}

/// Key that never matches a node pair.
pub(crate) const NO_PAIR: u64 = u64::MAX;

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

/// [`expand_sim`] on blocks: a [`block_step`], overlapping pairs pushed in the same order (so
/// that they pop in child order), with the same exclusions.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn expand_blocks<const AVX: bool>(
    ctx: &Ctx,
    stack: &mut Vec<TItem>,
    excl: &[u64],
    split: u32,
    skip: u64,
    e: TItem,
    min_sep: &mut f32,
    visits: &mut u64,
) {
    let (sa, sb, mut over) = block_step::<AVX>(ctx, &e, min_sep, visits);
    let depth = e.depth() + 1;
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
fn dfs_blocks<const AVX: bool>(
    ctx: &Ctx,
    stack: &mut Vec<TItem>,
    excl: &[u64],
    split: u32,
    skip: u64,
    min_sep: &mut f32,
    visits: &mut u64,
) -> Option<Item> {
    while let Some(e) = stack.pop() {
        if e.leaves() {
            return Some(Item {
                a: e.na,
                b: e.nb,
                c: e.c,
                depth: e.depth(),
            });
        }
        expand_blocks::<AVX>(ctx, stack, excl, split, skip, e, min_sep, visits);
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
    if ctx.simd.is_some() {
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
            dfs_blocks::<true>(ctx, stack, excl, split, skip, min_sep, visits)
        }
        // SAFETY: an `Avx2` token exists only where the CPU has AVX2 (`simd::detect`).
        return unsafe { avx2(ctx, stack, excl, split, skip, min_sep, visits) };
    }
    dfs_blocks::<false>(ctx, stack, excl, split, skip, min_sep, visits)
}

/// Every overlapping leaf pair below the pairs on `stack` (all of them, no order), by
/// blocked steps: `leaf(a, b, B's centre in A's frame)` for each; separated pairs lower
/// `min_sep`. The enumeration of the penetration query.
#[inline(always)]
fn overlap_pairs<const AVX: bool, F: FnMut(u32, u32, [f32; 3])>(
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
        let (sa, sb, mut over) = block_step::<AVX>(ctx, &e, min_sep, visits);
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
    if ctx.simd.is_some() {
        #[target_feature(enable = "avx2")]
        fn avx2(
            ctx: &Ctx,
            stack: &mut Vec<TItem>,
            min_sep: &mut f32,
            visits: &mut u64,
            leaf: &mut dyn FnMut(u32, u32, [f32; 3]),
        ) {
            overlap_pairs::<true, _>(ctx, stack, min_sep, visits, leaf)
        }
        // SAFETY: an `Avx2` token exists only where the CPU has AVX2 (`simd::detect`).
        unsafe { avx2(ctx, stack, min_sep, visits, leaf) };
        return;
    }
    overlap_pairs::<false, _>(ctx, stack, min_sep, visits, leaf)
}

/// True when both trees have blocks (fan-out ≤ 4): the traversals then run on them.
pub(crate) fn blocked(ctx: &Ctx) -> bool {
    !ctx.blocks_a.is_empty() && !ctx.blocks_b.is_empty()
}

/// Starts a depth-first search at node pair (`a`, `b`), B's centre `c`, traversal `depth`.
pub(crate) fn start(ctx: &Ctx, s: &mut Descent, a: u32, b: u32, c: [f32; 3], depth: u32) {
    if blocked(ctx) {
        s.tstack.clear();
        s.tstack.push(TItem::new(ctx, a, b, c, depth));
    } else {
        s.stack.clear();
        s.stack.push(Item { a, b, c, depth });
    }
}

/// Goes on with the search until the next overlapping leaf pair (or none), skipping the
/// pair `skip` and the pairs in `excl` (sorted keys) down to depth `split`.
pub(crate) fn resume(
    ctx: &Ctx,
    s: &mut Descent,
    excl: &[u64],
    split: u32,
    skip: u64,
    min_sep: &mut f32,
    visits: &mut u64,
) -> Option<Item> {
    if blocked(ctx) {
        dfs_blocks_dispatch(ctx, &mut s.tstack, excl, split, skip, min_sep, visits)
    } else {
        dfs_sim(ctx, &mut s.stack, excl, split, skip, min_sep, visits)
    }
}

/// Drops the pairs deeper than `split` from the search's stack (leaves the current
/// split-depth pair after a contact was found in it).
pub(crate) fn leave_below(ctx: &Ctx, s: &mut Descent, split: u32) {
    if blocked(ctx) {
        while s.tstack.last().is_some_and(|t| t.depth() > split) {
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
pub(crate) fn split_key(ctx: &Ctx, la: u32, lb: u32, split: u32) -> u64 {
    pair_key(ancestor_at(ctx.a, la, split), ancestor_at(ctx.b, lb, split))
}

/// Inserts into a sorted vector; false when already present.
pub(crate) fn insert_sorted(v: &mut Vec<u64>, key: u64) -> bool {
    match v.binary_search(&key) {
        Ok(_) => false,
        Err(p) => {
            v.insert(p, key);
            true
        }
    }
}

/// Root test, then a full traversal from the roots.
pub(crate) fn full(
    ctx: &Ctx,
    s: &mut Descent,
    min_sep: &mut f32,
    visits: &mut u64,
) -> Option<Item> {
    let c0 = ctx.xf(0);
    let (ov, lb) = ctx.test(0, 0, c0);
    *visits += 1;
    if !ov {
        *min_sep = min_sep.min(lb);
        return None;
    }
    start(ctx, s, 0, 0, c0, 0);
    resume(ctx, s, &[], u32::MAX, NO_PAIR, min_sep, visits)
}

/// Climbs from the stale leaf pair (`la`, `lb`) toward the root (Algorithms 1–2): the leaf
/// pair itself, then each traversal pair above it from level `top − 1` down to `stop`, each
/// searched without the already visited child pair.
pub(crate) fn climb(
    ctx: &Ctx,
    s: &mut Descent,
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
        if let Some(e) = resume(ctx, s, &[], u32::MAX, skip, min_sep, visits) {
            return Some(e);
        }
    }
    None
}
