//! Kinetic front tracking (ours, beyond the paper): the frontier of the overlap traversal kept
//! from frame to frame, so that a frame only re-tests what the motion since could change.
//!
//! The front partitions all leaf pairs: every leaf pair lies below exactly one front entry,
//! either a *separated* node pair (no overlapping leaf pair below it, by a margin) or an
//! *overlapping leaf pair* (a hit). A separated pair measured with lower bound `d` stays
//! separated while the relative motion since its measurement is below `d`: every point of B
//! moves by at most `|Δc| + θ·ρ` per frame (root-centre displacement plus rotation angle
//! times B's radius about its root centre), and these bounds add up over frames. So each
//! separated pair gets an expiry (`motion so far + d`, less twice the f32 rounding slack) in
//! a bucket queue; a frame adds its motion bound and re-tests only the expired pairs
//! (refining the ones that now overlap) and the hits. The hits are then exactly the
//! overlapping leaf pairs of a full traversal, at the cost of what changed.
//!
//! The front is rebuilt from the roots on the first frame, after a jump (a motion bound above
//! a quarter of the smaller root radius) and when it has grown to 8 times its size after the
//! last rebuild and past 2¹⁹ pairs (it refines where contact was and never coarsens). A
//! rebuild is a full traversal (the worst frame of the tracked queries); fine pairs far from
//! contact have large margins and cost nothing per frame, so the floor lets a front grow to
//! several MB rather than rebuild in the middle of a contact: lower floors rebuilt as contact
//! began, or mid-press to a front that grew back to the same size (BENCHMARKS.md, "Tried and did not pay")).

use crate::pose::Pose;
use crate::query::kernel::buckets::{Buckets, Sep};
use crate::query::kernel::info::TreeInfo;
use crate::query::kernel::separation::motion_bound;
use crate::query::kernel::{expand_larger, Ctx, Item};

/// The front size below which growth alone never rebuilds it (see the module doc).
const REBUILD_FLOOR: usize = 1 << 19;

/// How far ahead the re-test loops prefetch the nodes of the pairs they will test (the pairs
/// lie scattered over both trees, so every test would otherwise wait for two cache misses).
const AHEAD: usize = 8;

/// An overlapping leaf pair with B's centre at the current pose.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Hit {
    pub a: u32,
    pub b: u32,
    pub c: [f32; 3],
    /// Split depth `key` was computed for (`u32::MAX`: not yet).
    pub split: u32,
    /// Key of the traversal pair at depth `split` above this leaf pair (multipoint).
    pub key: u64,
}

impl Hit {
    /// Leaf `a` of A and leaf `b` of B, B's centre at `c` (A's frame).
    pub(crate) fn new(a: u32, b: u32, c: [f32; 3]) -> Hit {
        Hit {
            a,
            b,
            c,
            split: u32::MAX,
            key: 0,
        }
    }
}

/// The tracked front of one pair.
///
/// Memory: 16 bytes per separated pair in the queue (plus a 504-byte chunk per non-empty
/// bucket, at most 2¹⁵ + 1 of them), 16 per pair in `due` and `pending` (each holds up to the
/// whole front, on a rebuild or a jump), 32 per hit. Reserved by [`Front::with_capacity`];
/// beyond that the buffers grow (geometrically, once, keeping their high-water mark), which
/// only a deep overlap needs: the front is rebuilt when it passes max(8 × its size after the
/// last rebuild, 2¹⁹) pairs, and a rebuild's front is the frontier of one overlap traversal.
#[derive(Debug)]
pub(crate) struct Front {
    /// Separated pairs by expiry.
    queue: Buckets,
    /// Expired pairs of this frame.
    due: Vec<Sep>,
    /// Separated pairs found in this frame, queued after the expired ones.
    pending: Vec<Sep>,
    /// Overlapping leaf pairs at the current pose.
    pub hits: Vec<Hit>,
    work: Vec<Item>,
    /// Cumulative motion bound since the last rebuild.
    moved: f64,
    last: Option<Pose>,
    /// Front size after the last rebuild.
    built: usize,
}

impl Front {
    /// Room for a front of `n` pairs (of which up to `n / 8` hits) without allocating, and a
    /// refinement stack of `work` pairs (its bound: depth × fan-out).
    pub(crate) fn with_capacity(n: usize, work: usize) -> Front {
        Front {
            queue: Buckets::with_capacity(n),
            due: Vec::with_capacity(n),
            pending: Vec::with_capacity(n),
            hits: Vec::with_capacity(n / 8),
            work: Vec::with_capacity(work),
            moved: 0.0,
            last: None,
            built: 0,
        }
    }

    /// Forgets the front; the next update rebuilds it.
    pub(crate) fn reset(&mut self) {
        self.last = None;
        self.queue.clear(1.0);
        self.hits.clear();
    }

    /// Smallest remaining separation margin of the separated pairs (a lower bound on the
    /// separation when there are no hits), at the last update.
    pub(crate) fn margin(&self) -> f64 {
        self.queue.min_bound() - self.moved
    }

    /// Brings the front to the pose of `ctx`; returns the node-pair tests spent.
    pub(crate) fn update(&mut self, ctx: &Ctx, ib: &TreeInfo) -> u64 {
        let delta = match &self.last {
            Some(p) => motion_bound(ib, p, &ctx.rel),
            None => f64::INFINITY,
        };
        let size = self.queue.len + self.hits.len();
        let small = ctx.a[0].r.min(ctx.b[0].r) as f64;
        let rebuild =
            delta.is_nan() || delta > 0.25 * small || size > (8 * self.built).max(REBUILD_FLOOR);
        let slack2 = 2.0 * ctx.slack as f64;
        let mut tests = 0;
        if rebuild {
            // Bucket width: a small fraction of the bodies (about a frame's motion at haptic
            // rates); a frame crosses at most a few thousand buckets before a rebuild.
            self.queue.clear((small * 1e-4).max(f64::MIN_POSITIVE));
            self.hits.clear();
            self.pending.clear();
            self.moved = 0.0;
            tests += self.refine(ctx, 0, 0, slack2);
            for k in 0..self.pending.len() {
                self.queue.push(self.pending[k]);
            }
            self.built = self.queue.len + self.hits.len();
        } else {
            self.moved += delta;
            self.pending.clear();
            // Hits: still overlapping, or separated from now on.
            let mut i = 0;
            while i < self.hits.len() {
                if let Some(n) = self.hits.get(i + AHEAD) {
                    ctx.prefetch_nodes(n.a, n.b);
                }
                let h = self.hits[i];
                let c = ctx.xf(h.b);
                let (ov, d) = ctx.test(h.a, h.b, c);
                tests += 1;
                if ov {
                    self.hits[i].c = c;
                    i += 1;
                } else {
                    self.pending.push(Sep {
                        expiry: self.moved + d as f64 - slack2,
                        a: h.a,
                        b: h.b,
                    });
                    self.hits.swap_remove(i);
                }
            }
            // Separated pairs whose margin the motion may have used up.
            self.due.clear();
            self.queue.drain_expired(self.moved, &mut self.due);
            for k in 0..self.due.len() {
                if let Some(n) = self.due.get(k + AHEAD) {
                    ctx.prefetch_nodes(n.a, n.b);
                }
                let e = self.due[k];
                tests += self.refine(ctx, e.a, e.b, slack2);
            }
            for k in 0..self.pending.len() {
                self.queue.push(self.pending[k]);
            }
        }
        self.last = Some(ctx.rel);
        tests
    }

    /// Tests pair (`a`, `b`) at the current pose and refines it: separated pairs go to
    /// `pending`, overlapping leaf pairs to `hits`.
    fn refine(&mut self, ctx: &Ctx, a: u32, b: u32, slack2: f64) -> u64 {
        let c = ctx.xf(b);
        let (ov, d) = ctx.test(a, b, c);
        let moved = self.moved;
        if !ov {
            self.pending.push(Sep {
                expiry: moved + d as f64 - slack2,
                a,
                b,
            });
            return 1;
        }
        if ctx.a[a as usize].is_leaf() && ctx.b[b as usize].is_leaf() {
            self.hits.push(Hit::new(a, b, c));
            return 1;
        }
        let mut tests = 1;
        let work = &mut self.work;
        let pending = &mut self.pending;
        let hits = &mut self.hits;
        work.clear();
        work.push(Item { a, b, c, depth: 0 });
        while let Some(e) = work.pop() {
            expand_larger(ctx, e.a, e.b, e.c, |i, j, c, d2, sr, leafs| {
                tests += 1;
                if d2 < sr * sr {
                    if leafs {
                        hits.push(Hit::new(i, j, c));
                    } else {
                        work.push(Item {
                            a: i,
                            b: j,
                            c,
                            depth: 0,
                        });
                    }
                } else {
                    pending.push(Sep {
                        expiry: moved + (d2.sqrt() - sr) as f64 - slack2,
                        a: i,
                        b: j,
                    });
                }
            });
        }
        tests
    }
}
