//! A bucket queue of node pairs keyed by an expiry (a cumulative motion), for the kinetic
//! fronts: push and pop in O(1), storage in fixed-size chunks so that draining and moving a
//! bucket reads memory sequentially (a linked list of single entries spread over a large slab
//! cost a cache miss per entry and dominated the front's time on the jaw trees).

/// A node pair and the key at which it must be looked at again.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Sep {
    pub expiry: f64,
    pub a: u32,
    pub b: u32,
}

const NIL: u32 = u32::MAX;
/// Entries per chunk (a chunk is 16·31 + 8 = 504 bytes; the fill of a chain's head chunk is
/// kept in the ring, the chunks behind it are full).
const CHUNK: usize = 31;
/// Buckets in the ring (a power of two; 128 KiB of chain heads). A single level on purpose:
/// a two-level queue moved a whole coarse bucket into the fine level when its block began,
/// a large part of the front in one frame (BENCHMARKS.md, "Tried and did not pay")).
const RING: i64 = 1 << 15;

/// Non-empty buckets that [`Buckets::with_capacity`] reserves chunks for (a quarter of the
/// ring; the jaw fronts of up to 80k pairs spread over ≈ 3,000–4,400 chunks in all).
const HEADS: usize = RING as usize / 4;

#[derive(Debug, Clone, Copy)]
struct Chunk {
    items: [Sep; CHUNK],
    next: u32,
}

const EMPTY: Chunk = Chunk {
    items: [Sep {
        expiry: 0.0,
        a: 0,
        b: 0,
    }; CHUNK],
    next: NIL,
};

/// A bucket queue by expiry: a ring of `RING` buckets of width `width` holds the expiries
/// from the current bucket on; anything beyond sits in a far list, re-sorted whenever the
/// ring has advanced by half its length. Every bucket is a chain of chunks taken from one
/// pool; no allocation once the pool has grown to the front's size. A bitmap of the
/// non-empty buckets finds the next expiry without scanning empty ones.
#[derive(Debug)]
pub(crate) struct Buckets {
    pool: Vec<Chunk>,
    /// Chunks not in use (a stack, so that taking one reads no chunk memory).
    free: Vec<u32>,
    /// Head chunk of every bucket's chain (`NIL` when empty).
    ring: Vec<u32>,
    /// Entries in each bucket's head chunk (the chunks behind the head are full; left stale
    /// when the head is `NIL`, which every reader checks first). Kept
    /// beside the heads so that a push only writes to the chunk: reading the chunk's own
    /// count was a cache miss per push, a third of the front's time on the jaw chew.
    fill: Vec<u32>,
    /// Bit `k` set when bucket slot `k` may be non-empty.
    used: Vec<u64>,
    far: u32,
    /// Entries in the far list's head chunk.
    far_fill: u32,
    /// Smallest expiry in the far list (a far entry can be due as early as half a ring
    /// after it was pushed, before the far list is next re-sorted).
    far_min: f64,
    /// Index (expiry / width) of the first bucket not yet drained.
    cur: i64,
    width: f64,
    pub len: usize,
}

impl Buckets {
    /// An empty queue with room for `n` entries in up to `min(n, HEADS)` non-empty buckets
    /// (every non-empty bucket holds a chunk of its own; past that, the pool grows).
    pub(crate) fn with_capacity(n: usize) -> Self {
        let chunks = n / CHUNK + n.min(HEADS) + 2;
        Buckets {
            pool: Vec::with_capacity(chunks),
            free: Vec::with_capacity(chunks),
            ring: vec![NIL; RING as usize],
            fill: vec![0; RING as usize],
            used: vec![0; RING as usize / 64],
            far: NIL,
            far_fill: 0,
            far_min: f64::INFINITY,
            cur: 0,
            width: 1.0,
            len: 0,
        }
    }

    /// Empties the queue; buckets get width `width` from now on.
    pub(crate) fn clear(&mut self, width: f64) {
        self.pool.clear();
        self.free.clear();
        self.ring.iter_mut().for_each(|h| *h = NIL);
        self.used.iter_mut().for_each(|w| *w = 0);
        self.far = NIL;
        self.far_fill = 0;
        self.far_min = f64::INFINITY;
        self.cur = 0;
        self.width = width;
        self.len = 0;
    }

    /// Bucket index of `expiry`, for expiries ≥ 0 (truncation equals `floor` there, without
    /// a libm call on the baseline target; negative expiries are already due and clamped to
    /// the current bucket by the callers).
    #[inline]
    fn bucket(&self, expiry: f64) -> i64 {
        (expiry / self.width) as i64
    }

    #[inline]
    fn slot(k: i64) -> usize {
        (k & (RING - 1)) as usize
    }

    /// A chunk in front of chain `next`, by writes only.
    #[inline]
    fn new_chunk(&mut self, next: u32) -> u32 {
        match self.free.pop() {
            Some(c) => {
                self.pool[c as usize].next = next;
                c
            }
            None => {
                self.pool.push(Chunk { next, ..EMPTY });
                if self.free.capacity() < self.pool.len() {
                    self.free.reserve(self.pool.capacity() - self.free.len());
                }
                (self.pool.len() - 1) as u32
            }
        }
    }

    #[inline]
    fn free_chunk(&mut self, c: u32) {
        self.free.push(c);
    }

    /// Appends `sep` to the bucket of its expiry (the current one when already due), or to
    /// the far list (without counting it). Reads only the ring, writes the chunk.
    #[inline]
    fn link(&mut self, sep: Sep) {
        let k = self.bucket(sep.expiry).max(self.cur);
        let slot = if k - self.cur < RING {
            let s = Self::slot(k);
            self.used[s / 64] |= 1 << (s % 64);
            Some(s)
        } else {
            self.far_min = self.far_min.min(sep.expiry);
            None
        };
        let (head, fill) = match slot {
            Some(s) => (self.ring[s], self.fill[s]),
            None => (self.far, self.far_fill),
        };
        let (c, at) = if head == NIL || fill as usize == CHUNK {
            let c = self.new_chunk(head);
            match slot {
                Some(s) => self.ring[s] = c,
                None => self.far = c,
            }
            (c, 0)
        } else {
            (head, fill)
        };
        match slot {
            Some(s) => self.fill[s] = at + 1,
            None => self.far_fill = at + 1,
        }
        self.pool[c as usize].items[at as usize] = sep;
    }

    /// Adds `sep`.
    #[inline]
    pub(crate) fn push(&mut self, sep: Sep) {
        self.len += 1;
        self.link(sep);
    }

    /// Re-links every entry of chain `c` whose head chunk holds `fill` entries (the far
    /// list, after the ring has advanced).
    fn relink_chain(&mut self, mut c: u32, mut fill: u32) {
        while c != NIL {
            let next = self.pool[c as usize].next;
            for i in 0..std::mem::replace(&mut fill, CHUNK as u32) as usize {
                let sep = self.pool[c as usize].items[i];
                self.link(sep);
            }
            self.free_chunk(c);
            c = next;
        }
    }

    /// Moves every entry with `expiry ≤ moved` into `out` (the others stay).
    pub(crate) fn drain_expired(&mut self, moved: f64, out: &mut Vec<Sep>) {
        let last = self.bucket(moved);
        loop {
            let s = Self::slot(self.cur);
            if self.used[s / 64] & (1 << (s % 64)) != 0 {
                self.used[s / 64] &= !(1 << (s % 64));
                let mut c = std::mem::replace(&mut self.ring[s], NIL);
                let mut fill = self.fill[s];
                while c != NIL {
                    let next = self.pool[c as usize].next;
                    for j in 0..std::mem::replace(&mut fill, CHUNK as u32) as usize {
                        let sep = self.pool[c as usize].items[j];
                        if sep.expiry <= moved {
                            out.push(sep);
                            self.len -= 1;
                        } else {
                            // Not due yet (the last, partly due bucket).
                            self.link(sep);
                        }
                    }
                    self.free_chunk(c);
                    c = next;
                }
            }
            if self.cur >= last {
                break;
            }
            self.cur += 1;
            if self.cur & (RING / 2 - 1) == 0 {
                let f = std::mem::replace(&mut self.far, NIL);
                let fill = std::mem::replace(&mut self.far_fill, 0);
                self.far_min = f64::INFINITY;
                self.relink_chain(f, fill);
            }
        }
    }

    /// A lower bound on every expiry in the queue: exact over the current bucket (which
    /// also holds entries pushed already due), bucket starts beyond it.
    pub(crate) fn min_bound(&self) -> f64 {
        let mut m = f64::INFINITY;
        let mut c = self.ring[Self::slot(self.cur)];
        let mut fill = self.fill[Self::slot(self.cur)];
        while c != NIL {
            let ch = &self.pool[c as usize];
            for s in &ch.items[..std::mem::replace(&mut fill, CHUNK as u32) as usize] {
                m = m.min(s.expiry);
            }
            c = ch.next;
        }
        // The first non-empty bucket after the current one, by the bitmap, in ring order.
        let words = self.used.len();
        let start = Self::slot(self.cur + 1);
        let (w0, b0) = (start / 64, start % 64);
        for step in 0..=words {
            let w = (w0 + step) % words;
            let mut bits = self.used[w];
            if step == 0 {
                bits &= !0u64 << b0;
            } else if step == words {
                bits &= !(!0u64 << b0);
            }
            if bits != 0 {
                let slot = (w * 64 + bits.trailing_zeros() as usize) as i64;
                let k = self.cur + 1 + ((slot - start as i64) & (RING - 1));
                if k != self.cur + RING {
                    return m.min(k as f64 * self.width);
                }
            }
        }
        if self.far != NIL {
            m = m.min(self.far_min);
        }
        m
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Draining returns exactly the due entries, over many blocks and the far list.
    #[test]
    fn drains_exactly_the_due_entries() {
        let mut q = Buckets::with_capacity(16);
        q.clear(0.01);
        let mut x = 12345u64;
        let mut all = Vec::new();
        for i in 0..20_000u32 {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let e = (x >> 11) as f64 / (1u64 << 53) as f64 * 2000.0;
            q.push(Sep {
                expiry: e,
                a: i,
                b: 0,
            });
            all.push(e);
        }
        let mut out = Vec::new();
        let mut got = 0;
        for step in 1..=40 {
            let moved = step as f64 * 50.0;
            out.clear();
            assert!(
                q.min_bound()
                    <= all
                        .iter()
                        .cloned()
                        .filter(|&e| e > moved - 50.0)
                        .fold(f64::INFINITY, f64::min)
            );
            q.drain_expired(moved, &mut out);
            assert!(out.iter().all(|s| s.expiry <= moved));
            let want = all
                .iter()
                .filter(|&&e| e <= moved && e > moved - 50.0)
                .count();
            assert_eq!(out.len(), want, "step {step}");
            got += out.len();
            assert_eq!(q.len, all.len() - got);
        }
        assert_eq!(q.len, 0);
    }

    /// The lower bound holds when only far entries are left, also after the queue has
    /// advanced since they were pushed (it once assumed they began a full ring ahead).
    #[test]
    fn min_bound_covers_far_entries() {
        let mut q = Buckets::with_capacity(16);
        q.clear(1.0);
        let mut out = Vec::new();
        // Advance by 3200 buckets, then push an entry just beyond the ring.
        q.drain_expired(3200.0, &mut out);
        let e = (3200 + RING) as f64 + 0.5;
        q.push(Sep {
            expiry: e,
            a: 1,
            b: 2,
        });
        for buckets in [6400, 9600, 12800] {
            q.drain_expired(buckets as f64, &mut out);
            assert!(out.is_empty());
            assert!(q.min_bound() <= e, "{} > {e}", q.min_bound());
        }
        q.drain_expired(e, &mut out);
        assert_eq!(out.len(), 1);
    }
}
