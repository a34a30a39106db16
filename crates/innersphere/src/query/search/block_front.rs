//! The kinetic front of first contact, block by block (ours, beyond the paper): the tree of
//! overlapping node pairs of the overlap traversal, kept from frame to frame, so that a frame
//! only re-runs the 4×4 steps whose outcome the motion since could have changed.
//!
//! Every entry is an overlapping node pair whose child pairs (all children of one node
//! against all children of the other, one vectorised [`block_step`](crate::query::kernel::block::block_step)) were
//! tested at some pose. Each child pair is then either separated, an overlapping leaf pair (a
//! *hit*), or an overlapping inner pair with an entry of its own. The entry stays valid while
//! its B node has moved less than the smallest |separation| or overlap depth of its separated
//! children and hits (less twice the f32 rounding slack). Every point of B moves by at most
//! `|Δc| + θ·ρ` per frame (see [`motion_bound`]); these add up to a cumulative clock that
//! gives each entry an expiry (one flat array, scanned 8 at a time, branch-free). Slots come
//! in chunks of 8 of one traversal depth, so the scan, chunk by chunk in depth order, yields
//! the expired entries shallow first without a sort (or, read backwards, deepest first, to
//! find a contact fast after a contact frame). Expired entries are re-run: children that now
//! overlap get entries (a depth-first expansion at the current pose), entries of children
//! that separated are dropped with everything below them (the front coarsens where contact
//! ends). After a complete update the hits are exactly
//! the overlapping leaf pairs of a full traversal, so the contact answer equals
//! the paper's distance traversal's (`query/paper.rs`) on every frame; an update may also
//! stop at the first hit, the unfinished steps staying due.
//!
//! Why blocks and not single pairs ([`front`](super::front)): re-testing one expired pair at
//! a time cost a cache miss per pair and a bucket-queue push per re-test; an entry here is
//! one 4×4 step on two blocks, and nothing is queued. Near contact it re-runs a fraction of
//! the steps a traversal needs, each a little dearer than a traversal's step (BENCHMARKS.md, "Tried and did not pay")).
//!
//! Why an expired entry is stepped without first checking whether its step could have
//! changed: such checks (the B node's own displacement since its step, or the nearest pair's
//! direction) spare some steps but make frames slower: most steps are the common step, the
//! cheapest kind, and a check costs about as much as one (BENCHMARKS.md, "Tried and did not pay").
//!
//! Keeping every hit up to date through a deep contact costs far more than backtracking, so
//! `contact` (`query/contact.rs`) answers from recent contact pairs while in contact, and the
//! front only [tends](BlockFront::tend) its backlog there, a fixed number of steps a frame:
//! with the scan branch-free and no sort, the backlog of a deep contact is cheap to scan (a
//! scanned and sorted backlog made such a budget cost more than it saved (BENCHMARKS.md, "Tried and did not pay")). When the
//! recent pairs no longer overlap, the front catches up deepest first: a climb from the newest
//! pair needed a second slow frame when the contact had ended, and deepest first cut
//! `contact`'s p99 along the chew by about a third in the same process.

use crate::pose::Pose;
use crate::query::kernel::block::{block_gaps, inner_gaps, sides, TItem, B_LEAF};
use crate::query::kernel::expiry::{due_entries, CHUNK};
use crate::query::kernel::info::{TreeInfo, LANES};
use crate::query::kernel::separation::motion_bound;
use crate::query::kernel::Ctx;

const NONE: u32 = u32::MAX;

/// Depth keys of the expired-step order: traversal depths from `DEPTHS − 1` on share the
/// last key (the order only decides how much work an update does, never its result).
const DEPTHS: usize = 64;

/// How many expired entries ahead the re-run loop prefetches the blocks of.
const AHEAD: usize = 4;

/// One overlapping node pair of the front and what its step found: one cache line, all
/// that a step reads of its entry.
#[derive(Debug, Clone, Copy)]
#[repr(C, align(64))]
struct Entry {
    /// The pair (`item.c` is recomputed from `bc` when B's side is a leaf).
    item: TItem,
    /// B's node centre in B's frame: B's leaf centre without reading the node.
    bc: [f32; 3],
    /// First child entry, and the next entry with the same parent.
    kid: u32,
    sib: u32,
    /// Child pairs (bit `l·4 + i`) that overlap and have entries.
    expanded: u16,
    /// Child leaf pairs that overlap.
    hits: u16,
    /// Bit of this pair in its parent's step.
    lane: u8,
    live: bool,
}

/// The block front of one pair of trees (fan-outs ≤ 4).
///
/// Memory: 77 bytes per slot (entry, expiry, its place in `due`, chunk bookkeeping), slots
/// reserved by [`BlockFront::with_capacity`]; beyond that they grow (geometrically, once,
/// keeping their high-water mark), which only a deep overlap needs: the live entries are the
/// overlapping node pairs of the overlap traversal, and the front is emptied when its slots
/// exceed 4 × its live entries + 1024.
#[derive(Debug)]
pub(crate) struct BlockFront {
    ent: Vec<Entry>,
    /// Per entry: the cumulative motion at which its step must be re-run (+∞ for free slots).
    expiry: Vec<f64>,
    /// Slots come in chunks of [`CHUNK`], each for entries of one depth key: per chunk, its key.
    chunk_depth: Vec<u8>,
    /// The chunks ordered by depth key (rebuilt when a chunk is added), so that the expiry
    /// scan yields the expired entries shallow first without a sort.
    chunks: Vec<u32>,
    chunks_stale: bool,
    /// Per depth key: the first free slot (free slots link through their `kid`).
    free_head: [u32; DEPTHS],
    /// Free slots.
    nfree: usize,
    /// The expired entries, by depth.
    due: Vec<u32>,
    work: Vec<u32>,
    kill: Vec<u32>,
    /// Entry of the root pair (`NONE` while the root spheres are apart).
    root: u32,
    /// When the root test must be repeated.
    root_expiry: f64,
    /// Cumulative motion bound since the last rebuild.
    moved: f64,
    last: Option<Pose>,
    /// Overlapping leaf pairs on the front.
    hits: usize,
    /// An entry that had hits when last stepped (a hint for [`BlockFront::hit`]).
    witness: u32,
    /// Smallest remaining margin over all entries at the last update.
    margin: f64,
    /// Whether the last answer was a contact.
    touching: bool,
    /// The last few distinct contact leaf pairs (A's, B's), newest first.
    recent: [(u32, u32); RECENT],
    /// An overlapping leaf pair found by a step of the current update.
    found: Option<(u32, u32, [f32; 3])>,
}

/// How many recent contact leaf pairs [`BlockFront::recall`] tests.
const RECENT: usize = 4;

impl BlockFront {
    /// Room for `n` slots (rounded up to whole chunks) without allocating, and work stacks
    /// of `stack` entries (their bound: depth × 16).
    pub(crate) fn with_capacity(n: usize, stack: usize) -> BlockFront {
        let n = n.div_ceil(CHUNK) * CHUNK;
        BlockFront {
            ent: Vec::with_capacity(n),
            expiry: Vec::with_capacity(n),
            chunk_depth: Vec::with_capacity(n / CHUNK),
            chunks: Vec::with_capacity(n / CHUNK),
            chunks_stale: false,
            free_head: [NONE; DEPTHS],
            nfree: 0,
            due: Vec::with_capacity(n),
            work: Vec::with_capacity(stack),
            kill: Vec::with_capacity(stack),
            root: NONE,
            root_expiry: f64::NEG_INFINITY,
            moved: 0.0,
            last: None,
            hits: 0,
            witness: NONE,
            margin: 0.0,
            touching: false,
            recent: [(NONE, NONE); RECENT],
            found: None,
        }
    }

    /// Forgets the front; the next update rebuilds it.
    pub(crate) fn reset(&mut self) {
        self.last = None;
        self.touching = false;
        self.recent = [(NONE, NONE); RECENT];
    }

    /// A lower bound on the separation of the sphere sets at the last update when there are
    /// no hits (the smallest remaining margin of the separated pairs; −∞ with hits).
    pub(crate) fn margin(&self) -> f64 {
        self.margin
    }

    /// Adds the motion since the last call to the front's clock (or empties the front after
    /// a jump, or when most of its slots are free); every call must come through here, the
    /// steps themselves can wait ([`BlockFront::catch_up`]).
    pub(crate) fn advance(&mut self, ctx: &Ctx, ib: &TreeInfo) {
        let delta = match &self.last {
            Some(p) => motion_bound(ib, p, &ctx.rel),
            None => f64::INFINITY,
        };
        let small = ctx.a[0].r.min(ctx.b[0].r) as f64;
        // A rebuild costs one step per overlapping node pair now, and the per-frame scan of
        // the expiries is as long as the slots.
        let sparse = self.ent.len() > 4 * (self.ent.len() - self.nfree) + 1024;
        if delta.is_nan() || delta > 0.25 * small || sparse {
            self.clear();
        } else {
            self.moved += delta;
        }
        self.last = Some(ctx.rel);
    }

    /// Whether the last answer was a contact.
    pub(crate) fn in_contact(&self) -> bool {
        self.touching
    }

    /// The first of the recent contact leaf pairs (only the newest unless `all`) that
    /// overlaps at the pose of `ctx`, one leaf test each (counted in `tests`): contact
    /// mostly persists, or comes back, where it was.
    pub(crate) fn recall(
        &mut self,
        ctx: &Ctx,
        all: bool,
        tests: &mut u64,
    ) -> Option<(u32, u32, [f32; 3])> {
        let n = if all { RECENT } else { 1 };
        for k in 0..n {
            let (la, lb) = self.recent[k];
            if la == NONE {
                break;
            }
            let c = ctx.xf(lb);
            *tests += 1;
            if ctx.test(la, lb, c).0 {
                return Some((la, lb, c));
            }
        }
        None
    }

    /// Sets this frame's answer (and remembers a contact among the recent ones).
    pub(crate) fn set_answer(&mut self, answer: Option<(u32, u32, [f32; 3])>) {
        self.touching = answer.is_some();
        if let Some((la, lb, _)) = answer {
            let k = self
                .recent
                .iter()
                .position(|&p| p == (la, lb))
                .unwrap_or(RECENT - 1);
            self.recent.copy_within(0..k, 1);
            self.recent[0] = (la, lb);
        }
    }

    /// Re-runs the expired steps at the pose of `ctx` (after [`BlockFront::advance`]),
    /// shallow first (`deepest_first`: deepest first), up to the first overlapping leaf pair
    /// (unfinished steps stay expired for the next update); then [`BlockFront::hit`] is the
    /// contact answer. Any order gives the same answer: a step tests the spheres at the
    /// current pose, and a complete update leaves every live entry valid (a deep entry
    /// stepped before its ancestor separated is dropped with it). Returns the node-pair tests
    /// spent.
    pub(crate) fn catch_up(&mut self, ctx: &Ctx, deepest_first: bool) -> u64 {
        self.run(ctx, deepest_first, true, usize::MAX)
    }

    /// Re-runs at most `budget` expired steps (fresh entries' included) at the pose of
    /// `ctx`, shallow first, without stopping at overlapping leaf pairs: keeps the front
    /// close to current while [`contact`](super::contact) answers from the recent contact
    /// pairs, so that the catch-up where contact ends finds a smaller backlog. Leaves no
    /// answer ([`BlockFront::hit`] is none, the margin unknown). Returns the node-pair tests
    /// spent.
    pub(crate) fn tend(&mut self, ctx: &Ctx, budget: usize) -> u64 {
        let tests = self.run(ctx, false, false, budget);
        self.found = None;
        tests
    }

    /// [`BlockFront::catch_up`] and [`BlockFront::tend`], compiled for AVX2 where the CPU
    /// has it (the expiry scan and the 4×4 steps are vectorised).
    fn run(&mut self, ctx: &Ctx, deepest_first: bool, stop: bool, budget: usize) -> u64 {
        #[cfg(target_arch = "x86_64")]
        if ctx.simd.is_some() {
            // With `popcnt` and `bmi1` the bit counts of the masks are one instruction each
            // (without, `count_ones` was ≈ a tenth of a step's instructions under cachegrind).
            #[target_feature(enable = "avx2,popcnt,bmi1")]
            fn avx2(f: &mut BlockFront, ctx: &Ctx, deep: bool, stop: bool, budget: usize) -> u64 {
                f.run_impl::<true>(ctx, deep, stop, budget)
            }
            // SAFETY: an `Avx2` token exists only where the CPU has AVX2, POPCNT and BMI1
            // (`simd::detect`).
            return unsafe { avx2(self, ctx, deepest_first, stop, budget) };
        }
        self.run_impl::<false>(ctx, deepest_first, stop, budget)
    }

    #[inline(always)]
    fn run_impl<const AVX: bool>(
        &mut self,
        ctx: &Ctx,
        deepest_first: bool,
        stop: bool,
        budget: usize,
    ) -> u64 {
        self.found = None;
        let slack2 = 2.0 * ctx.slack as f64;
        let moved = self.moved;
        let mut tests = 0;
        let mut left = budget;
        // The root pair, a child of no step.
        if self.root_expiry <= moved {
            let c0 = ctx.xf(0);
            let (ov, d) = ctx.test(0, 0, c0);
            tests += 1;
            if ov && self.root == NONE {
                let r = &ctx.b[0];
                let s = [r.x, r.y, r.z];
                self.root = self.alloc(TItem::new(ctx, 0, 0, c0, 0), s, NONE, 0);
                self.work.push(self.root);
                tests += self.drain::<AVX>(ctx, slack2, stop, &mut left);
            } else if !ov && self.root != NONE {
                self.drop_subtree(self.root);
                self.root = NONE;
            }
            self.root_expiry = moved + d.abs() as f64 - slack2;
        }
        // Expired steps, by depth: shallow pairs first to bring the front up to date (a pair
        // that separated drops its subtree, whose expired entries then need no step), the
        // deepest first to find a contact (they lie next to the last frame's overlaps).
        if self.chunks_stale {
            order_chunks(&self.chunk_depth, &mut self.chunks);
            self.chunks_stale = false;
        }
        due_entries::<AVX>(&self.expiry, &self.chunks, moved, &mut self.due);
        if deepest_first {
            self.due.reverse();
        }
        let len = self.due.len();
        let mut k = 0;
        while k < len && left > 0 && !(stop && self.found.is_some()) {
            if k + AHEAD < len {
                let n = self.due[k + AHEAD];
                self.ent[n as usize].item.prefetch(ctx);
            }
            let e = self.due[k];
            if self.ent[e as usize].live && self.expiry[e as usize] <= moved {
                tests += self.step::<AVX>(ctx, e, slack2);
                left -= 1;
                tests += self.drain::<AVX>(ctx, slack2, stop, &mut left);
            }
            k += 1;
        }
        // Entries left on the work stack (an early stop) keep their expiry of −∞. Without
        // an early stop the update was complete: the hits are then exactly the overlapping
        // leaf pairs, and the margin is valid when there are none.
        let complete = k == len && self.work.is_empty();
        self.work.clear();
        self.margin = if complete && self.hits == 0 {
            min_expiry(&self.expiry).min(self.root_expiry) - moved
        } else {
            f64::NEG_INFINITY
        };
        if self.found.is_none() && stop {
            self.found = self.find_hit(ctx);
        }
        tests
    }

    /// The answer of the last update: an overlapping leaf pair (A's leaf, B's leaf, B's
    /// centre in A's frame) found by a step or else any of the front's, or none.
    pub(crate) fn hit(&self) -> Option<(u32, u32, [f32; 3])> {
        self.found
    }

    /// Empties the front (the next root test rebuilds it).
    fn clear(&mut self) {
        self.ent.clear();
        self.expiry.clear();
        self.chunk_depth.clear();
        self.chunks.clear();
        self.chunks_stale = false;
        self.free_head = [NONE; DEPTHS];
        self.nfree = 0;
        self.root = NONE;
        self.root_expiry = f64::NEG_INFINITY;
        self.moved = 0.0;
        self.hits = 0;
        self.witness = NONE;
    }

    /// Steps the fresh entries on the work stack (and the ones they create), depth first,
    /// while steps are `left`; with `stop`, stops at the first hit (the rest keep their
    /// expiry of −∞).
    #[inline(always)]
    fn drain<const AVX: bool>(
        &mut self,
        ctx: &Ctx,
        slack2: f64,
        stop: bool,
        left: &mut usize,
    ) -> u64 {
        let mut tests = 0;
        while *left > 0 && !(stop && self.found.is_some()) {
            let Some(e) = self.work.pop() else { break };
            tests += self.step::<AVX>(ctx, e, slack2);
            *left -= 1;
        }
        tests
    }

    /// A new entry for `item` (B's node centre `bc` in B's frame), child `lane` of entry `parent`
    /// (linked into its kid list).
    #[inline(always)]
    fn alloc(&mut self, item: TItem, bc: [f32; 3], parent: u32, lane: u8) -> u32 {
        let sib = if parent == NONE {
            NONE
        } else {
            self.ent[parent as usize].kid
        };
        let e = Entry {
            item,
            bc,
            kid: NONE,
            sib,
            expanded: 0,
            hits: 0,
            lane,
            live: true,
        };
        let d = item.depth().min(DEPTHS as u32 - 1) as usize;
        if self.free_head[d] == NONE {
            self.add_chunk(d);
        }
        let i = self.free_head[d];
        self.free_head[d] = self.ent[i as usize].kid;
        self.nfree -= 1;
        self.ent[i as usize] = e;
        self.expiry[i as usize] = f64::NEG_INFINITY;
        if parent != NONE {
            self.ent[parent as usize].kid = i;
        }
        i
    }

    /// Drops entry `e` and everything below it (their hits included).
    fn drop_subtree(&mut self, e: u32) {
        self.kill.clear();
        self.kill.push(e);
        while let Some(x) = self.kill.pop() {
            let en = self.ent[x as usize];
            self.hits -= en.hits.count_ones() as usize;
            let mut k = en.kid;
            while k != NONE {
                self.kill.push(k);
                k = self.ent[k as usize].sib;
            }
            self.free(x);
        }
    }

    /// Returns slot `x` to the free list of its chunk's depth key.
    #[inline(always)]
    fn free(&mut self, x: u32) {
        let d = self.chunk_depth[x as usize / CHUNK] as usize;
        let en = &mut self.ent[x as usize];
        en.live = false;
        en.kid = self.free_head[d];
        self.free_head[d] = x;
        self.expiry[x as usize] = f64::INFINITY;
        self.nfree += 1;
    }

    /// A chunk of [`CHUNK`] free slots for depth key `d`.
    #[cold]
    fn add_chunk(&mut self, d: usize) {
        let base = self.ent.len();
        let dead = Entry {
            item: TItem::default(),
            bc: [0.0; 3],
            kid: NONE,
            sib: NONE,
            expanded: 0,
            hits: 0,
            lane: 0,
            live: false,
        };
        self.ent.resize(base + CHUNK, dead);
        self.expiry.resize(base + CHUNK, f64::INFINITY);
        self.chunk_depth.push(d as u8);
        self.chunks_stale = true;
        for x in (base..base + CHUNK).rev() {
            self.ent[x].kid = self.free_head[d];
            self.free_head[d] = x as u32;
        }
        self.nfree += CHUNK;
    }

    /// Unlinks and drops the child entry of `e` at `lane`.
    fn drop_child(&mut self, e: u32, lane: u8) {
        let mut prev = NONE;
        let mut k = self.ent[e as usize].kid;
        while k != NONE && self.ent[k as usize].lane != lane {
            prev = k;
            k = self.ent[k as usize].sib;
        }
        if k == NONE {
            return;
        }
        let next = self.ent[k as usize].sib;
        if prev == NONE {
            self.ent[e as usize].kid = next;
        } else {
            self.ent[prev as usize].sib = next;
        }
        self.drop_subtree(k);
    }

    /// Re-runs the step of entry `e` at the current pose: new overlapping inner children get
    /// entries (queued on the work stack), separated ones lose theirs; sets its expiry.
    #[inline(always)]
    fn step<const AVX: bool>(&mut self, ctx: &Ctx, e: u32, slack2: f64) -> u64 {
        let old = self.ent[e as usize];
        let (mut item, own) = (old.item, old.bc);
        if item.kind == B_LEAF {
            item.c = ctx.rel32.apply(own[0], own[1], own[2]);
        }
        let mut tests = 0;
        let (over, ll, m) = if item.inner() {
            inner_gaps::<AVX>(ctx, item.ba, item.bb, &mut tests)
        } else {
            block_gaps::<AVX>(ctx, &item, &mut tests)
        };
        // The common step: nothing but the expiry changes.
        if over & !ll == old.expanded as u32 && over & ll == 0 && old.hits == 0 {
            self.expiry[e as usize] = self.moved + m as f64 - slack2;
            return tests;
        }
        // Otherwise the sides name the children that get entries and the hit.
        let (sa, sb) = sides(ctx, &item);
        let inner = over & !ll;
        let hits = (over & ll) as u16;
        self.hits = self.hits + hits.count_ones() as usize - old.hits.count_ones() as usize;
        let mut gone = old.expanded as u32 & !inner;
        while gone != 0 {
            let q = gone.trailing_zeros();
            gone &= gone - 1;
            self.drop_child(e, q as u8);
        }
        let mut fresh = inner & !(old.expanded as u32);
        while fresh != 0 {
            let q = fresh.trailing_zeros() as usize;
            fresh &= fresh - 1;
            let l = q / LANES;
            let child = TItem::child(&sa, &sb, q % LANES, l, item.depth() + 1);
            // B's node centre in B's frame: this entry's own when B's side is a leaf, else
            // from the block just read.
            let bs = if item.kind == B_LEAF {
                own
            } else {
                let k = &ctx.blocks_b[item.bb as usize];
                [k.x[l], k.y[l], k.z[l]]
            };
            child.prefetch(ctx);
            let c = self.alloc(child, bs, e, q as u8);
            self.work.push(c);
        }
        let en = &mut self.ent[e as usize];
        en.expanded = inner as u16;
        en.hits = hits;
        self.expiry[e as usize] = self.moved + m as f64 - slack2;
        if hits != 0 {
            self.witness = e;
            if self.found.is_none() {
                let q = hits.trailing_zeros() as usize;
                let l = q / LANES;
                self.found = Some((sa.node[q % LANES], sb.node[l], [sb.x[l], sb.y[l], sb.z[l]]));
            }
        }
        tests
    }

    /// An overlapping leaf pair of the front, when there is one.
    fn find_hit(&mut self, ctx: &Ctx) -> Option<(u32, u32, [f32; 3])> {
        if self.hits == 0 {
            return None;
        }
        let w = self.witness;
        let ok = w != NONE && self.ent[w as usize].live && self.ent[w as usize].hits != 0;
        let w = if ok {
            w
        } else {
            let found = self.ent.iter().position(|en| en.live && en.hits != 0)?;
            self.witness = found as u32;
            found as u32
        };
        let en = &self.ent[w as usize];
        let mut item = en.item;
        if item.kind == B_LEAF {
            let s = en.bc;
            item.c = ctx.rel32.apply(s[0], s[1], s[2]);
        }
        let (sa, sb) = sides(ctx, &item);
        let q = en.hits.trailing_zeros() as usize;
        let (la, lb) = (sa.node[q % LANES], sb.node[q / LANES]);
        Some((la, lb, ctx.xf(lb)))
    }
}

/// `chunks` set to every chunk index, ordered by its depth key (a counting sort; run only
/// when chunks were added).
#[cold]
fn order_chunks(chunk_depth: &[u8], chunks: &mut Vec<u32>) {
    let mut start = [0u32; DEPTHS + 1];
    for &d in chunk_depth {
        start[d as usize + 1] += 1;
    }
    for d in 0..DEPTHS {
        start[d + 1] += start[d];
    }
    chunks.clear();
    chunks.resize(chunk_depth.len(), 0);
    for (c, &d) in chunk_depth.iter().enumerate() {
        chunks[start[d as usize] as usize] = c as u32;
        start[d as usize] += 1;
    }
}

/// The smallest expiry (+∞ for none), with independent per-lane minima so that the scan
/// vectorises (a single running minimum is one long dependency chain).
#[inline(always)]
fn min_expiry(expiry: &[f64]) -> f64 {
    let mut acc = [f64::INFINITY; CHUNK];
    let mut chunks = expiry.chunks_exact(CHUNK);
    for c in &mut chunks {
        for (a, &e) in acc.iter_mut().zip(c) {
            *a = if e < *a { e } else { *a };
        }
    }
    let m = chunks
        .remainder()
        .iter()
        .fold(f64::INFINITY, |m, &e| m.min(e));
    acc.iter().fold(m, |m, &e| m.min(e))
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// The chunk order lists every chunk once, by depth key.
        #[test]
        fn chunks_are_ordered_by_depth(depth in prop::collection::vec(0u8..DEPTHS as u8, 0..60)) {
            let mut order = vec![3, 1];
            order_chunks(&depth, &mut order);
            let mut seen = order.clone();
            seen.sort_unstable();
            prop_assert_eq!(seen, (0..depth.len() as u32).collect::<Vec<_>>());
            prop_assert!(order.windows(2).all(|w| depth[w[0] as usize] <= depth[w[1] as usize]));
        }
    }
}
