//! The query kernel: the pair context of one query (packed nodes, relative pose in f32,
//! pruning slack), the node-pair tests, the 4×4 block step and its SIMD twins, and the small
//! containers the traversals share. Everything above (fronts, descents, query kinds, the
//! pair) builds on this module; it imports nothing from them.

pub(crate) mod block;
pub(crate) mod buckets;
pub(crate) mod expiry;
pub(crate) mod far;
pub(crate) mod geometry;
pub(crate) mod heap;
pub(crate) mod info;
pub(crate) mod lanes;
pub(crate) mod lenses;
pub(crate) mod nearest;
pub(crate) mod separation;
pub(crate) mod simd;

use crate::pose::Pose;
use geometry::Rel32;
use info::{Block, Node};

/// A node pair on a traversal stack, with B's node centre already transformed into A's frame.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Item {
    pub a: u32,
    pub b: u32,
    pub c: [f32; 3],
    /// Depth of the pair in the traversal (simultaneous descent: the larger node depth).
    pub depth: u32,
}

/// Everything a query needs about the pair for one call: the packed nodes, the poses, the
/// f32 relative transform and the pruning slack.
pub(crate) struct Ctx<'t> {
    pub a: &'t [Node],
    pub b: &'t [Node],
    /// A's and B's [`Block`]s (empty for fan-outs over 4) and each node's block index.
    pub blocks_a: &'t [Block],
    pub blocks_b: &'t [Block],
    pub block_of_a: &'t [u32],
    pub block_of_b: &'t [u32],
    pub rel: Pose,
    pub rel32: Rel32,
    pub slack: f32,
    /// The query's one CPU-dispatch decision ([`simd::detect`], made at the `Pair` door):
    /// the AVX2 kernels run when it holds the token.
    pub simd: Option<simd::Avx2>,
}

impl Ctx<'_> {
    /// B's node `j` transformed into A's frame.
    #[inline(always)]
    pub(crate) fn xf(&self, j: u32) -> [f32; 3] {
        let n = &self.b[j as usize];
        self.rel32.apply(n.x, n.y, n.z)
    }

    /// Hints the memory system that the children of nodes `ia` and `ib` will be read soon
    /// (called when a pair is pushed for later refinement; the traversals are bound by
    /// memory latency, and this overlaps the loads of queued pairs).
    #[inline(always)]
    pub(crate) fn prefetch(&self, ia: u32, ib: u32) {
        prefetch(&self.a[self.a[ia as usize].first as usize]);
        prefetch(&self.b[self.b[ib as usize].first as usize]);
    }

    /// Hints the memory system that nodes `ia` and `ib` themselves will be read soon (the
    /// kinetic front re-tests pairs scattered over both trees).
    #[inline(always)]
    pub(crate) fn prefetch_nodes(&self, ia: u32, ib: u32) {
        if let (Some(a), Some(b)) = (self.a.get(ia as usize), self.b.get(ib as usize)) {
            prefetch(a);
            prefetch(b);
        }
    }

    /// Test of node pair (`ia`, `ib`) with B's centre `cb`: (overlap, lower bound of the
    /// distance). Inner nodes get the pruning slack; leaf pairs are exact.
    #[inline(always)]
    pub(crate) fn test(&self, ia: u32, ib: u32, cb: [f32; 3]) -> (bool, f32) {
        let na = &self.a[ia as usize];
        let nb = &self.b[ib as usize];
        let leafs = na.is_leaf() && nb.is_leaf();
        let s = na.r + nb.r + if leafs { 0.0 } else { self.slack };
        let dx = na.x - cb[0];
        let dy = na.y - cb[1];
        let dz = na.z - cb[2];
        let d2 = dx * dx + dy * dy + dz * dz;
        (d2 < s * s, d2.sqrt() - s)
    }
}

/// Hints the memory system that every cache line of `r` will be read soon (a hint without
/// architectural effect; nothing on other targets). A [`Block`](super::info::Block) is two
/// lines, and its second (what to descend to) is read as soon as the block is tested.
#[inline(always)]
pub(crate) fn prefetch<T>(r: &T) {
    prefetch_at(r as *const T)
}

/// [`prefetch`] by address: `p` need not point into anything (a prefetch never faults).
#[inline(always)]
pub(crate) fn prefetch_at<T>(p: *const T) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: a prefetch has no architectural effect, whatever the address (it never
    // faults), and the pointers are only offset, never read.
    unsafe {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        let p = p as *const i8;
        let mut off = 0;
        while off < std::mem::size_of::<T>() {
            _mm_prefetch::<_MM_HINT_T0>(p.wrapping_add(off));
            off += 64;
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = p;
}

/// Key of a node pair.
#[inline(always)]
pub(crate) fn pair_key(a: u32, b: u32) -> u64 {
    ((a as u64) << 32) | b as u64
}

/// Expands node pair (`ea`, `eb`), B's centre `cb`, by splitting the larger sphere (the one
/// that is not a leaf; A on ties) and calls `f(child_a, child_b, b_centre, |Δ|², ra + rb
/// (+ slack unless both are leaves), both_leaves)` for every child pair.
#[inline(always)]
pub(crate) fn expand_larger<F: FnMut(u32, u32, [f32; 3], f32, f32, bool)>(
    ctx: &Ctx,
    ea: u32,
    eb: u32,
    cb: [f32; 3],
    mut f: F,
) {
    let na = &ctx.a[ea as usize];
    let nb = &ctx.b[eb as usize];
    if !na.is_leaf() && (nb.is_leaf() || na.r >= nb.r) {
        let rb = nb.r;
        let b_leaf = nb.is_leaf();
        let f0 = na.first as usize;
        let kids = &ctx.a[f0..f0 + na.count as usize];
        for (k, n) in kids.iter().enumerate() {
            let dx = n.x - cb[0];
            let dy = n.y - cb[1];
            let dz = n.z - cb[2];
            let d2 = dx * dx + dy * dy + dz * dz;
            let leafs = b_leaf && n.is_leaf();
            let s = n.r + rb + if leafs { 0.0 } else { ctx.slack };
            f((f0 + k) as u32, eb, cb, d2, s, leafs);
        }
    } else {
        let (ax, ay, az, ra) = (na.x, na.y, na.z, na.r);
        let a_leaf = na.is_leaf();
        let f0 = nb.first as usize;
        let kids = &ctx.b[f0..f0 + nb.count as usize];
        for (k, n) in kids.iter().enumerate() {
            let p = ctx.rel32.apply(n.x, n.y, n.z);
            let dx = ax - p[0];
            let dy = ay - p[1];
            let dz = az - p[2];
            let d2 = dx * dx + dy * dy + dz * dz;
            let leafs = a_leaf && n.is_leaf();
            let s = ra + n.r + if leafs { 0.0 } else { ctx.slack };
            f(ea, (f0 + k) as u32, p, d2, s, leafs);
        }
    }
}
