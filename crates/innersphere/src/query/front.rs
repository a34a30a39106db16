//! Kinetic front tracking (ours, beyond the paper): the frontier of the overlap traversal kept
//! from frame to frame, so that a frame only re-tests what the motion since could change.
//!
//! The front partitions all leaf pairs: every leaf pair lies below exactly one front entry,
//! either a *separated* node pair (no overlapping leaf pair below it, by a margin) or an
//! *overlapping leaf pair* (a contact). A separated pair measured with lower bound `d` stays
//! separated while the relative motion since its measurement is below `d`: every point of B
//! moves by at most `|Δc| + θ·ρ` per frame (root-centre displacement plus rotation angle
//! times B's radius about its root centre), and these bounds add up over frames. So each
//! separated pair gets an expiry (`motion so far + d`, less the f32 rounding slack) in a
//! bucket queue; a frame adds its motion bound and re-tests only the expired pairs (refining the
//! ones that now overlap) and the contacts. The contacts are then exactly the overlapping
//! leaf pairs of a full traversal, at the cost of what changed.

use super::info::TreeInfo;
use super::state::{expand_larger, Ctx, Item};
use super::Pose;
use glam::DVec3;

/// A separated node pair and the cumulative motion at which it may stop being separated.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Sep {
    expiry: f64,
    a: u32,
    b: u32,
}

/// Slab entry of the bucket queue: a separated pair and the next entry of its list.
#[derive(Debug, Clone, Copy)]
struct Slot {
    sep: Sep,
    next: u32,
}

const NIL: u32 = u32::MAX;
/// Buckets per level of the bucket queue.
const RING: i64 = 1024;

/// A two-level bucket queue of separated pairs by expiry (linked lists in one slab). Fine
/// buckets of width `width` hold the current block of `RING` fine buckets; coarse buckets
/// (one block each) hold the next `RING − 1` blocks and move into the fine level when their
/// block begins; anything beyond sits in a far list, re-sorted when the coarse level wraps.
/// Push and pop are O(1); no allocation once the slab has grown to the front's size.
#[derive(Debug)]
struct Buckets {
    slab: Vec<Slot>,
    free: u32,
    fine: Vec<u32>,
    coarse: Vec<u32>,
    far: u32,
    /// Index (expiry / width) of the first fine bucket not yet drained.
    cur: i64,
    width: f64,
    len: usize,
}

impl Buckets {
    fn with_capacity(n: usize) -> Self {
        Buckets {
            slab: Vec::with_capacity(n),
            free: NIL,
            fine: vec![NIL; RING as usize],
            coarse: vec![NIL; RING as usize],
            far: NIL,
            cur: 0,
            width: 1.0,
            len: 0,
        }
    }

    fn clear(&mut self, width: f64) {
        self.slab.clear();
        self.free = NIL;
        self.fine.iter_mut().for_each(|h| *h = NIL);
        self.coarse.iter_mut().for_each(|h| *h = NIL);
        self.far = NIL;
        self.cur = 0;
        self.width = width;
        self.len = 0;
    }

    /// Re-buckets every entry with bucket width `width` (when the motion per frame outgrew
    /// the old width); `moved` is the current cumulative motion.
    fn rebucket(&mut self, width: f64, moved: f64, tmp: &mut Vec<Sep>) {
        tmp.clear();
        for h in 0..2 * RING as usize + 1 {
            let head = if h < RING as usize {
                &mut self.fine[h]
            } else if h < 2 * RING as usize {
                &mut self.coarse[h - RING as usize]
            } else {
                &mut self.far
            };
            let mut s = std::mem::replace(head, NIL);
            while s != NIL {
                tmp.push(self.slab[s as usize].sep);
                s = self.slab[s as usize].next;
            }
        }
        self.clear(width);
        self.cur = (moved / width).floor() as i64;
        for &e in tmp.iter() {
            self.push(e);
        }
    }

    /// A lower bound on every expiry in the queue: exact over the current fine bucket (which
    /// also holds entries pushed already due), bucket starts beyond it.
    fn min_bound(&self) -> f64 {
        let mut m = f64::INFINITY;
        let mut s = self.fine[self.cur.rem_euclid(RING) as usize];
        while s != NIL {
            m = m.min(self.slab[s as usize].sep.expiry);
            s = self.slab[s as usize].next;
        }
        let block = self.cur.div_euclid(RING);
        for k in self.cur + 1..(block + 1) * RING {
            if self.fine[k.rem_euclid(RING) as usize] != NIL {
                return m.min(k as f64 * self.width);
            }
        }
        for kb in block + 1..block + RING {
            if self.coarse[kb.rem_euclid(RING) as usize] != NIL {
                return m.min((kb * RING) as f64 * self.width);
            }
        }
        if self.far != NIL {
            m = m.min(((block + RING) * RING) as f64 * self.width);
        }
        m
    }

    #[inline]
    fn bucket(&self, expiry: f64) -> i64 {
        (expiry / self.width).floor() as i64
    }

    #[inline]
    fn link(&mut self, slot: u32, k: i64) {
        let k = k.max(self.cur); // anything already due goes into the current bucket
        let block = self.cur.div_euclid(RING);
        let kb = k.div_euclid(RING);
        let head = if kb == block {
            &mut self.fine[k.rem_euclid(RING) as usize]
        } else if kb < block + RING {
            &mut self.coarse[kb.rem_euclid(RING) as usize]
        } else {
            &mut self.far
        };
        self.slab[slot as usize].next = *head;
        *head = slot;
    }

    #[inline]
    fn push(&mut self, sep: Sep) {
        let slot = if self.free != NIL {
            let s = self.free;
            self.free = self.slab[s as usize].next;
            self.slab[s as usize].sep = sep;
            s
        } else {
            self.slab.push(Slot { sep, next: NIL });
            (self.slab.len() - 1) as u32
        };
        self.len += 1;
        let k = self.bucket(sep.expiry);
        self.link(slot, k);
    }

    /// Moves every entry with `expiry ≤ moved` into `out` (the others stay); returns the
    /// entries scanned.
    fn drain_expired(&mut self, moved: f64, out: &mut Vec<Sep>) -> u64 {
        let mut scanned = 0;
        let last = self.bucket(moved);
        loop {
            let i = self.cur.rem_euclid(RING) as usize;
            let mut s = std::mem::replace(&mut self.fine[i], NIL);
            while s != NIL {
                scanned += 1;
                let next = self.slab[s as usize].next;
                let sep = self.slab[s as usize].sep;
                if sep.expiry <= moved {
                    out.push(sep);
                    self.slab[s as usize].next = self.free;
                    self.free = s;
                    self.len -= 1;
                } else {
                    // Not due yet (the last, partly due bucket).
                    self.slab[s as usize].next = self.fine[i];
                    self.fine[i] = s;
                }
                s = next;
            }
            if self.cur >= last {
                break;
            }
            self.cur += 1;
            if self.cur.rem_euclid(RING) == 0 {
                // A new block: its coarse bucket moves into the fine level; when the coarse
                // level wraps, the far list is re-sorted.
                let block = self.cur.div_euclid(RING);
                let mut s =
                    std::mem::replace(&mut self.coarse[block.rem_euclid(RING) as usize], NIL);
                while s != NIL {
                    let next = self.slab[s as usize].next;
                    let k = self.bucket(self.slab[s as usize].sep.expiry);
                    self.link(s, k);
                    s = next;
                }
                if block.rem_euclid(RING / 2) == 0 {
                    let mut s = std::mem::replace(&mut self.far, NIL);
                    while s != NIL {
                        let next = self.slab[s as usize].next;
                        let k = self.bucket(self.slab[s as usize].sep.expiry);
                        self.link(s, k);
                        s = next;
                    }
                }
            }
        }
        scanned
    }
}

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

/// The tracked front of one pair.
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
    /// Motion bound of the last frame.
    last_delta: f64,
    /// Counters for diagnostics: rebuilds, re-bucketings, entries scanned while draining.
    pub stats: [u64; 3],
}

/// Upper bound on the displacement of any point of B between two relative poses.
pub(crate) fn motion_bound(ib: &TreeInfo, from: &Pose, to: &Pose) -> f64 {
    let c = ib.root_center;
    let dc = (to.transform_point(c) - from.transform_point(c)).length();
    let dq = to.rotation * from.rotation.conjugate();
    let v = DVec3::new(dq.x, dq.y, dq.z).length();
    let angle = 2.0 * v.atan2(dq.w.abs());
    (dc + angle * ib.radius) * (1.0 + 1e-9)
}

impl Front {
    pub(crate) fn with_capacity(n: usize) -> Front {
        Front {
            queue: Buckets::with_capacity(n),
            due: Vec::with_capacity(n / 8),
            pending: Vec::with_capacity(n / 4),
            hits: Vec::with_capacity(n / 8),
            work: Vec::with_capacity(1024),
            moved: 0.0,
            last: None,
            built: 0,
            last_delta: 0.0,
            stats: [0; 3],
        }
    }

    /// (front entries, hits, rebuilds, re-bucketings, entries scanned).
    pub(crate) fn diagnostics(&self) -> [u64; 5] {
        [
            self.queue.len as u64,
            self.hits.len() as u64,
            self.stats[0],
            self.stats[1],
            self.stats[2],
        ]
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
        let small = (ctx.a[0].r.min(ctx.b[0].r)) as f64;
        let rebuild =
            delta.is_nan() || delta > 0.25 * small || size > (8 * self.built).max(1 << 14);
        let slack2 = 2.0 * ctx.slack as f64;
        let mut tests = 0;
        if rebuild {
            // Bucket width: an eighth of a frame's motion, at least a small fraction of the
            // bodies.
            self.stats[0] += 1;
            self.queue.clear((small * 1e-4).max(self.last_delta / 8.0));
            self.hits.clear();
            self.pending.clear();
            self.moved = 0.0;
            tests += self.refine(ctx, 0, 0, slack2);
            for k in 0..self.pending.len() {
                self.queue.push(self.pending[k]);
            }
            self.built = self.queue.len + self.hits.len();
        } else {
            if delta > 64.0 * self.queue.width {
                self.stats[1] += 1;
                self.queue
                    .rebucket(delta / 8.0, self.moved, &mut self.pending);
            }
            self.moved += delta;
            self.pending.clear();
            // Contacts: still overlapping, or separated from now on.
            let mut i = 0;
            while i < self.hits.len() {
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
            self.stats[2] += self.queue.drain_expired(self.moved, &mut self.due);
            for k in 0..self.due.len() {
                let e = self.due[k];
                tests += self.refine(ctx, e.a, e.b, slack2);
            }
            for k in 0..self.pending.len() {
                self.queue.push(self.pending[k]);
            }
        }
        self.last = Some(ctx.rel);
        if delta.is_finite() {
            self.last_delta = delta;
        }
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
            self.hits.push(Hit {
                a,
                b,
                c,
                split: u32::MAX,
                key: 0,
            });
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
                        hits.push(Hit {
                            a: i,
                            b: j,
                            c,
                            split: u32::MAX,
                            key: 0,
                        });
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
