//! The packing's queue of voxels by remaining distance: a monotone bucket queue.
//!
//! The greedy packing pops the largest remaining distance, and every value pushed after the
//! start is at most the value last popped (remaining distances only shrink), so the largest
//! key never grows. Entries are bucketed by their value (2¹⁶ buckets over the value range,
//! monotone: a larger value never lands in a lower bucket), each bucket a small binary heap;
//! the top bucket's heap holds the overall maximum. The pops come in exactly the order of
//! one binary heap over all entries (value, then the smaller voxel index), in heaps of a few
//! hundred entries that stay in cache instead of one of millions (measured: the single
//! heap's pops were a third of the jaw build's time).

use std::cmp::Ordering;
use std::collections::BinaryHeap;

/// Max-heap entry: remaining distance, ties broken by the smaller voxel index (deterministic).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Entry {
    pub(super) value: f64,
    pub(super) cell: u32,
}
impl Eq for Entry {}
impl PartialOrd for Entry {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Entry {
    fn cmp(&self, other: &Self) -> Ordering {
        self.value
            .total_cmp(&other.value)
            .then_with(|| other.cell.cmp(&self.cell))
    }
}

/// Number of buckets.
const BUCKETS: usize = 1 << 16;

/// A max-queue of [`Entry`]s whose pushes never exceed the last pop (see the module docs).
pub(super) struct MaxQueue {
    buckets: Vec<BinaryHeap<Entry>>,
    lo: f64,
    scale: f64,
    top: usize,
}

impl MaxQueue {
    /// The queue holding `entries` (finite values).
    #[cfg(test)]
    pub(super) fn new(entries: Vec<Entry>) -> MaxQueue {
        Self::with(|emit| entries.iter().for_each(|e| emit(*e)))
    }

    /// The queue holding the entries that `each` emits (finite values); `each` runs three
    /// times (range, counts, fill), so that the buckets are allocated at their final sizes
    /// and no second list of all entries is held.
    pub(super) fn with(each: impl Fn(&mut dyn FnMut(Entry))) -> MaxQueue {
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        each(&mut |e| {
            lo = lo.min(e.value);
            hi = hi.max(e.value);
        });
        let span = hi - lo;
        let scale = if span > 0.0 && span.is_finite() {
            (BUCKETS as f64 - 1.0) / span
        } else {
            0.0
        };
        let mut q = MaxQueue {
            buckets: Vec::new(),
            lo: if lo.is_finite() { lo } else { 0.0 },
            scale,
            top: 0,
        };
        let mut counts = vec![0usize; BUCKETS];
        each(&mut |e| counts[q.bucket(e.value)] += 1);
        let mut lists: Vec<Vec<Entry>> = counts.iter().map(|&n| Vec::with_capacity(n)).collect();
        each(&mut |e| lists[q.bucket(e.value)].push(e));
        q.top = counts.iter().rposition(|&n| n > 0).unwrap_or(0);
        q.buckets = lists.into_iter().map(BinaryHeap::from).collect();
        q
    }

    #[inline]
    fn bucket(&self, v: f64) -> usize {
        let b = ((v - self.lo) * self.scale).floor();
        if b >= 0.0 {
            (b as usize).min(BUCKETS - 1)
        } else {
            0
        }
    }

    /// Adds an entry whose value is at most the last popped one.
    #[inline]
    pub(super) fn push(&mut self, e: Entry) {
        let b = self.bucket(e.value);
        debug_assert!(b <= self.top, "a push above the last pop");
        self.buckets[b].push(e);
    }

    /// The largest entry.
    #[inline]
    pub(super) fn pop(&mut self) -> Option<Entry> {
        loop {
            if let Some(e) = self.buckets[self.top].pop() {
                return Some(e);
            }
            if self.top == 0 {
                return None;
            }
            // Nothing is pushed above the last pop again: give the bucket's memory back.
            self.buckets[self.top] = BinaryHeap::new();
            self.top -= 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// Pops equal one binary heap's, with pushes at most the last pop.
        #[test]
        fn pops_in_the_order_of_one_heap(
            start in proptest::collection::vec((0.0f64..10.0, 0u32..1000), 1..300),
            shrink in proptest::collection::vec(0.0f64..1.0, 0..300),
        ) {
            let entries: Vec<Entry> = start
                .iter()
                .enumerate()
                .map(|(k, (v, _))| Entry { value: *v, cell: k as u32 })
                .collect();
            let mut q = MaxQueue::new(entries.clone());
            let mut h: BinaryHeap<Entry> = entries.into_iter().collect();
            let mut s = shrink.iter();
            loop {
                let (a, b) = (q.pop(), h.pop());
                prop_assert_eq!(a, b);
                let Some(e) = a else { break };
                if let Some(f) = s.next() {
                    let again = Entry { value: e.value * f, cell: e.cell + 1000 };
                    q.push(again);
                    h.push(again);
                }
            }
        }
    }
}
