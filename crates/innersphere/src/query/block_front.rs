//! The kinetic front of first contact, block by block (ours, beyond the paper): the tree of
//! overlapping node pairs of the overlap traversal, kept from frame to frame, so that a frame
//! only re-runs the 4×4 steps whose outcome the motion since could have changed.
//!
//! Every entry is an overlapping node pair whose child pairs (all children of one node
//! against all children of the other, one vectorised [`block_step`](super::traversal)) were
//! tested at some pose. Each child pair is then either separated, an overlapping leaf pair (a
//! *hit*), or an overlapping inner pair with an entry of its own. The entry stays valid while
//! the relative motion since its step is below the smallest |separation| or overlap depth of
//! its separated children and hits (less twice the f32 rounding slack): every point of B moves
//! by at most `|Δc| + θ·ρ` per frame (see [`motion_bound`]), and these bounds add up. So each
//! entry gets an expiry, a frame adds its motion bound and re-runs only the expired steps:
//! children that now overlap get entries (a depth-first expansion at the current pose),
//! entries of children that separated are dropped with everything below them (the front
//! coarsens where contact ends). The hits are then exactly the overlapping leaf pairs of a
//! full traversal, so the contact answer equals [`distance_traversal`](super::distance_traversal)'s
//! on every frame.
//!
//! Why blocks and not single pairs ([`front`](super::front)): re-testing one expired pair at
//! a time cost a cache miss per pair and a bucket-queue push per re-test (≈ 40 ns per test
//! on the jaw chew); an entry here is one 4×4 step on two blocks, the expiries sit in one
//! flat array scanned once per frame, and nothing is queued. Measured on the jaw chew
//! (BENCHMARKS.md, "Session 10"): on the fast frames a few microns from contact it re-runs
//! 400–500 steps where a traversal needs ≈ 1,750, but its steps come in slot order rather
//! than depth first and cost 3–4× a traversal's; and keeping every hit up to date through a
//! deep contact costs far more than backtracking. So [`contact`](super::contact) answers
//! from last frame's contact while in contact and lets the front wait (its clock runs on).

use super::front::motion_bound;
use super::info::{TreeInfo, LANES};
use super::state::Ctx;
use super::traversal::{block_gaps, sides, TItem, B_LEAF};
use super::Pose;

const NONE: u32 = u32::MAX;

/// How many expired entries ahead the re-run loop prefetches the blocks of.
const AHEAD: usize = 4;

/// One overlapping node pair of the front and what its step found.
#[derive(Debug, Clone, Copy)]
struct Entry {
    /// The pair (B's centre in `item.c` is refreshed when B's side is a leaf).
    item: TItem,
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
#[derive(Debug)]
pub(crate) struct BlockFront {
    ent: Vec<Entry>,
    /// Per entry: the cumulative motion at which its step must be re-run (+∞ for free slots).
    expiry: Vec<f64>,
    free: Vec<u32>,
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
    /// The contact answered last (A's leaf, B's leaf, B's centre in A's frame), if any.
    answer: Option<(u32, u32, [f32; 3])>,
}

impl BlockFront {
    pub(crate) fn with_capacity(n: usize) -> BlockFront {
        BlockFront {
            ent: Vec::with_capacity(n),
            expiry: Vec::with_capacity(n),
            free: Vec::with_capacity(n),
            due: Vec::with_capacity(n),
            work: Vec::with_capacity(256),
            kill: Vec::with_capacity(256),
            root: NONE,
            root_expiry: f64::NEG_INFINITY,
            moved: 0.0,
            last: None,
            hits: 0,
            witness: NONE,
            margin: 0.0,
            answer: None,
        }
    }

    /// Forgets the front; the next update rebuilds it.
    pub(crate) fn reset(&mut self) {
        self.last = None;
        self.answer = None;
    }

    /// (live entries, slots, overlapping leaf pairs).
    pub(crate) fn size(&self) -> (usize, usize, usize) {
        (self.ent.len() - self.free.len(), self.ent.len(), self.hits)
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
        let sparse = self.ent.len() > 4 * (self.ent.len() - self.free.len()) + 1024;
        if delta.is_nan() || delta > 0.25 * small || sparse {
            self.clear();
        } else {
            self.moved += delta;
        }
        self.last = Some(ctx.rel);
    }

    /// The last answer's leaf pair, if it still overlaps at the pose of `ctx` (one leaf
    /// test; the answer is then refreshed).
    pub(crate) fn quick(&mut self, ctx: &Ctx) -> Option<(u32, u32, [f32; 3])> {
        let (la, lb, _) = self.answer?;
        let c = ctx.xf(lb);
        self.answer = ctx.test(la, lb, c).0.then_some((la, lb, c));
        self.answer
    }

    /// Sets the answer (a contact found by other means, or none).
    pub(crate) fn set_answer(&mut self, answer: Option<(u32, u32, [f32; 3])>) {
        self.answer = answer;
    }

    /// Re-runs every expired step at the pose of `ctx` (after [`BlockFront::advance`]); the
    /// hits are then exactly the overlapping leaf pairs. Returns the node-pair tests spent.
    pub(crate) fn catch_up(&mut self, ctx: &Ctx) -> u64 {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            #[target_feature(enable = "avx2")]
            fn avx2(f: &mut BlockFront, ctx: &Ctx) -> u64 {
                f.catch_up_impl(ctx)
            }
            // SAFETY: the CPU has AVX2 (checked above).
            return unsafe { avx2(self, ctx) };
        }
        self.catch_up_impl(ctx)
    }

    #[inline(always)]
    fn catch_up_impl(&mut self, ctx: &Ctx) -> u64 {
        let slack2 = 2.0 * ctx.slack as f64;
        let moved = self.moved;
        let mut tests = 0;
        // The root pair, a child of no step.
        if self.root_expiry <= moved {
            let c0 = ctx.xf(0);
            let (ov, d) = ctx.test(0, 0, c0);
            tests += 1;
            if ov && self.root == NONE {
                self.root = self.alloc(TItem::new(ctx, 0, 0, c0, 0), NONE, 0);
                self.work.push(self.root);
                tests += self.drain(ctx, slack2);
            } else if !ov && self.root != NONE {
                self.drop_subtree(self.root);
                self.root = NONE;
            }
            self.root_expiry = moved + d.abs() as f64 - slack2;
        }
        // Expired steps.
        self.due.clear();
        due_entries(&self.expiry, moved, &mut self.due);
        // Shallow pairs first: a pair that separated drops its subtree, whose expired
        // entries then need no step.
        let ent = &self.ent;
        self.due
            .sort_unstable_by_key(|&e| ent[e as usize].item.depth());
        for k in 0..self.due.len() {
            if let Some(&n) = self.due.get(k + AHEAD) {
                self.ent[n as usize].item.prefetch(ctx);
            }
            let e = self.due[k];
            if self.ent[e as usize].live && self.expiry[e as usize] <= moved {
                tests += self.step(ctx, e, slack2);
                tests += self.drain(ctx, slack2);
            }
        }
        let margin = if self.hits == 0 {
            min_expiry(&self.expiry).min(self.root_expiry)
        } else {
            f64::NEG_INFINITY
        };
        self.margin = margin - moved;
        self.answer = self.find_hit(ctx);
        tests
    }

    /// Empties the front (the next root test rebuilds it).
    fn clear(&mut self) {
        self.ent.clear();
        self.expiry.clear();
        self.free.clear();
        self.root = NONE;
        self.root_expiry = f64::NEG_INFINITY;
        self.moved = 0.0;
        self.hits = 0;
        self.witness = NONE;
    }

    /// Steps the fresh entries on the work stack (and the ones they create).
    #[inline(always)]
    fn drain(&mut self, ctx: &Ctx, slack2: f64) -> u64 {
        let mut tests = 0;
        while let Some(e) = self.work.pop() {
            tests += self.step(ctx, e, slack2);
        }
        tests
    }

    /// A new entry for `item`, child `lane` of entry `parent` (linked into its kid list).
    #[inline(always)]
    fn alloc(&mut self, item: TItem, parent: u32, lane: u8) -> u32 {
        let sib = if parent == NONE {
            NONE
        } else {
            self.ent[parent as usize].kid
        };
        let e = Entry {
            item,
            kid: NONE,
            sib,
            expanded: 0,
            hits: 0,
            lane,
            live: true,
        };
        let i = match self.free.pop() {
            Some(i) => {
                self.ent[i as usize] = e;
                self.expiry[i as usize] = f64::NEG_INFINITY;
                i
            }
            None => {
                self.ent.push(e);
                self.expiry.push(f64::NEG_INFINITY);
                (self.ent.len() - 1) as u32
            }
        };
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
            self.ent[x as usize].live = false;
            self.expiry[x as usize] = f64::INFINITY;
            self.free.push(x);
        }
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
    fn step(&mut self, ctx: &Ctx, e: u32, slack2: f64) -> u64 {
        let mut item = self.ent[e as usize].item;
        if item.kind == B_LEAF {
            item.c = ctx.xf(item.nb);
        }
        let mut tests = 0;
        let (sa, sb, over, ll, m) = block_gaps(ctx, &item, &mut tests);
        let inner = over & !ll;
        let hits = (over & ll) as u16;
        let old = self.ent[e as usize];
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
            let child = TItem::child(&sa, &sb, q % LANES, q / LANES, item.depth() + 1);
            child.prefetch(ctx);
            let c = self.alloc(child, e, q as u8);
            self.work.push(c);
        }
        let en = &mut self.ent[e as usize];
        en.item = item;
        en.expanded = inner as u16;
        en.hits = hits;
        self.expiry[e as usize] = self.moved + m as f64 - slack2;
        if hits != 0 {
            self.witness = e;
        }
        tests
    }

    /// The answer of the last update: an overlapping leaf pair (A's leaf, B's leaf, B's
    /// centre in A's frame), or none.
    pub(crate) fn hit(&self) -> Option<(u32, u32, [f32; 3])> {
        self.answer
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
            item.c = ctx.xf(item.nb);
        }
        let (sa, sb) = sides(ctx, &item);
        let q = en.hits.trailing_zeros() as usize;
        let (la, lb) = (sa.node[q % LANES], sb.node[q / LANES]);
        Some((la, lb, ctx.xf(lb)))
    }
}

/// Width of the chunks the expiry scans read (a vector's worth of comparisons per branch).
const CHUNK: usize = 8;

/// Appends to `due` the index of every expiry ≤ `moved` (in index order). Reads chunks with
/// one branch each: the scan runs over every slot every frame, and nearly all are not due.
#[inline(always)]
fn due_entries(expiry: &[f64], moved: f64, due: &mut Vec<u32>) {
    let mut chunks = expiry.chunks_exact(CHUNK);
    let mut base = 0u32;
    for c in &mut chunks {
        let mut bits = 0u32;
        for (k, &e) in c.iter().enumerate() {
            bits |= ((e <= moved) as u32) << k;
        }
        while bits != 0 {
            due.push(base + bits.trailing_zeros());
            bits &= bits - 1;
        }
        base += CHUNK as u32;
    }
    for (k, &e) in chunks.remainder().iter().enumerate() {
        if e <= moved {
            due.push(base + k as u32);
        }
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
