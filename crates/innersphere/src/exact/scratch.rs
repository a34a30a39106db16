//! [`ExactScratch`], the per-pair memory and warm-start state of the exact queries, its
//! work counters [`ExactStats`], and `HeapItem`, the node pair on the branch and bound's
//! queue (kept here, with the queue it fills, so that the scratch needs nothing from `bnb`).

use super::penetration;

/// Reusable memory and warm-start state of the exact queries for one pair of meshes (or
/// several: the warm start is only a hint and never changes an answer).
#[derive(Debug, Clone)]
pub struct ExactScratch {
    pub(super) stack: Vec<(u32, u32, f64)>,
    pub(super) heap: std::collections::BinaryHeap<HeapItem>,
    /// Closest pair of the last [`distance`](fn@super::distance) (BVH slots), tried first next
    /// time.
    pub(super) last_pair: Option<(u32, u32)>,
    /// Crossing pair of the last [`intersects`](fn@super::intersects), tried first next time.
    pub(super) last_hit: Option<(u32, u32)>,
    pub(super) warm_start: bool,
    pub(super) stats: ExactStats,
    pub(crate) pen: penetration::PenScratch,
    pub(crate) vol: super::overlap_volume::VolumeScratch,
    /// The meshes' penetration's node-pair front, carried to the next query.
    pub(crate) front: super::front::PairFront,
}

/// Work counters of the last query run with an [`ExactScratch`].
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ExactStats {
    /// Node pairs taken from the traversal stack.
    pub node_pairs: usize,
    /// Leaf pairs reached.
    pub leaf_pairs: usize,
    /// Triangle pairs evaluated exactly (after the per-triangle box filter).
    pub triangle_pairs: usize,
    /// Winding-number evaluations of the containment test.
    pub winding_tests: usize,
}

impl Default for ExactScratch {
    fn default() -> Self {
        Self::new()
    }
}

impl ExactScratch {
    /// Scratch with warm start on: each query first evaluates the last answer's triangle
    /// pair, which bounds the search from the start on coherent motions.
    pub fn new() -> Self {
        ExactScratch {
            stack: Vec::new(),
            heap: Default::default(),
            last_pair: None,
            last_hit: None,
            warm_start: true,
            stats: ExactStats::default(),
            pen: Default::default(),
            vol: Default::default(),
            front: Default::default(),
        }
    }

    /// Scratch without warm start: every query starts from nothing (for fair timings).
    pub fn cold() -> Self {
        ExactScratch {
            warm_start: false,
            ..Self::new()
        }
    }

    /// Work counters of the last query.
    pub fn stats(&self) -> ExactStats {
        self.stats
    }

    /// The connected pieces of the intersection found by the last
    /// [`intersection_volume`](fn@super::intersection_volume) (A's frame), the largest first.
    pub fn patches(&self) -> &[super::OverlapPatch] {
        &self.vol.group.patches
    }

    /// Forgets the last answers.
    pub fn reset(&mut self) {
        self.last_pair = None;
        self.last_hit = None;
        self.front.reset();
    }
}

/// A node pair on the best-first queue, smallest lower bound on top.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct HeapItem(pub(crate) f64, pub(crate) u32, pub(crate) u32);
impl Eq for HeapItem {}
impl PartialOrd for HeapItem {
    fn partial_cmp(&self, o: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for HeapItem {
    fn cmp(&self, o: &Self) -> std::cmp::Ordering {
        o.0.total_cmp(&self.0)
    }
}
