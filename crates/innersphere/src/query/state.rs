//! The per-pair state: temporal coherence and all scratch memory of the queries.

use super::block_front::BlockFront;
use super::front::Front;
use super::geometry::{pruning_slack, Contact, Rel32};
use super::heap::{Entry, PairHeap};
use super::info::{Block, Node, TreeInfo};
use super::penetration::{Patch, PatchAcc};
use super::proximity::BlockEntry;
use super::traversal::TItem;
use super::Pose;
use crate::SphereTree;
use glam::DVec3;
use std::sync::Arc;

/// A lower bound on the separation of the two sphere sets, proved by a query at a relative
/// pose (B in A's frame).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SeparationRecord {
    /// The sphere sets were at least this far apart.
    pub lower: f64,
    /// Pose of B in A's frame when it was measured.
    pub relative: Pose,
}

/// A node pair on a traversal stack, with B's node centre already transformed into A's frame.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Item {
    pub a: u32,
    pub b: u32,
    pub c: [f32; 3],
    /// Depth of the pair in the traversal (simultaneous descent: the larger node depth).
    pub depth: u32,
}

/// All mutable memory of a pair: coherence and scratch.
#[derive(Debug)]
pub(crate) struct Scratch {
    pub stack: Vec<Item>,
    /// Depth-first stack of keyed pairs (proximity).
    pub pstack: Vec<Entry>,
    /// Depth-first stack of the 4×4 proximity search.
    pub bstack: Vec<BlockEntry>,
    /// Depth-first stack of the paper's traversals on blocks.
    pub tstack: Vec<TItem>,
    pub heap: PairHeap,
    pub anc_a: Vec<u32>,
    pub anc_b: Vec<u32>,
    /// Sorted keys of traversal pairs excluded by the multipoint traversal.
    pub excluded: Vec<u64>,
    pub contacts: Vec<Contact>,
    pub mp_prev: Vec<(u32, u32)>,
    pub stale: Vec<(u32, u32)>,
    pub patches: Vec<Patch>,
    pub patch_acc: Vec<PatchAcc>,
    /// Leaf pair of the last exact proximity.
    pub prox_pair: Option<(u32, u32)>,
    /// Leaf pair of the last backtracking contact.
    pub bt_pair: Option<(u32, u32)>,
    pub separation: Option<SeparationRecord>,
    /// The kinetic front of the tracked queries.
    pub front: Front,
    /// The block front of first contact ([`contact`](super::contact) on fan-outs ≤ 4).
    pub bfront: BlockFront,
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
    pub pose_a: Pose,
    pub rel: Pose,
    pub rel32: Rel32,
    pub slack: f32,
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

/// Per-pair state: what temporal coherence needs (last contact pairs, last separation bound
/// and the pose it was measured at) and all scratch memory (stacks, heaps, result buffers),
/// pre-reserved from the tree sizes, so that queries allocate nothing in steady state.
///
/// Create one per pair of trees with [`PairState::new`] and pass it to every query on that
/// pair; it must always be used with the same two trees (checked by node counts). It is
/// `Send`, so pairs can be queried from many threads, one state per pair and thread.
#[derive(Debug)]
pub struct PairState {
    pub(crate) ia: Arc<TreeInfo>,
    pub(crate) ib: Arc<TreeInfo>,
    pub(crate) s: Scratch,
}

/// Key of a node pair.
#[inline(always)]
pub(crate) fn pair_key(a: u32, b: u32) -> u64 {
    ((a as u64) << 32) | b as u64
}

impl PairState {
    /// The state of the pair (`a`, `b`); computes both trees' [`TreeInfo`].
    pub fn new(a: &SphereTree, b: &SphereTree) -> PairState {
        PairState::with_info(Arc::new(TreeInfo::new(a)), Arc::new(TreeInfo::new(b)))
    }

    /// The state of a pair from [`TreeInfo`]s shared with other pairs.
    pub fn with_info(a: Arc<TreeInfo>, b: Arc<TreeInfo>) -> PairState {
        let depth = a.max_depth as usize + b.max_depth as usize + 2;
        let fan = a.max_children.max(1) * b.max_children.max(1);
        let heap_cap = ((a.nodes + b.nodes) / 8).clamp(1024, 1 << 18);
        PairState {
            s: Scratch {
                stack: Vec::with_capacity((depth * fan + 16).max(heap_cap / 4)),
                pstack: Vec::with_capacity((depth * fan + 16).max(heap_cap / 4)),
                // Each pop of the 4×4 search pushes at most 16 pairs, one level deeper.
                bstack: Vec::with_capacity(depth * 16 + 16),
                tstack: Vec::with_capacity((depth * fan + 16).max(heap_cap / 4)),
                heap: PairHeap::with_capacity(heap_cap),
                anc_a: Vec::with_capacity(a.max_depth as usize + 1),
                anc_b: Vec::with_capacity(b.max_depth as usize + 1),
                excluded: Vec::with_capacity(256),
                contacts: Vec::with_capacity(256),
                mp_prev: Vec::with_capacity(256),
                stale: Vec::with_capacity(256),
                patches: Vec::with_capacity(64),
                patch_acc: Vec::with_capacity(64),
                prox_pair: None,
                bt_pair: None,
                separation: None,
                front: Front::with_capacity(heap_cap),
                bfront: BlockFront::with_capacity(heap_cap / 4),
            },
            ia: a,
            ib: b,
        }
    }

    /// Info of tree A.
    pub fn info_a(&self) -> &TreeInfo {
        &self.ia
    }

    /// Info of tree B.
    pub fn info_b(&self) -> &TreeInfo {
        &self.ib
    }

    /// Forgets all temporal coherence (previous contacts, proximity pair, separation record);
    /// the next queries start from scratch.
    pub fn reset(&mut self) {
        self.s.prox_pair = None;
        self.s.bt_pair = None;
        self.s.mp_prev.clear();
        self.s.separation = None;
        self.s.front.reset();
        self.s.bfront.reset();
    }

    /// Size of the kinetic front: (separated node pairs on it, overlapping leaf pairs).
    pub fn front_size(&self) -> (usize, usize) {
        self.s.front.size()
    }

    /// Size of the block front of [`contact`](super::contact): (live entries, allocated
    /// slots, overlapping leaf pairs).
    pub fn block_front_size(&self) -> (usize, usize, usize) {
        self.s.bfront.size()
    }

    /// The last separation bound recorded by a query, if any.
    pub fn separation_record(&self) -> Option<SeparationRecord> {
        self.s.separation
    }

    /// A guaranteed lower bound on the current separation of the two sphere sets at the world
    /// poses `pose_a`, `pose_b`, from the last recorded separation and the relative motion
    /// since: `d − (|Δc| + θ·ρ)`, where `Δc` is the displacement of B's root-sphere centre
    /// in A's frame, θ the rotation angle of B's relative rotation since then and ρ B's
    /// radius about its root centre ([`TreeInfo::radius`]), less the f32 rounding slack.
    /// Positive means no query can find a contact; `None` when no separation is recorded.
    pub fn safe_separation(&self, pose_a: &Pose, pose_b: &Pose) -> Option<f64> {
        safe_separation(
            &self.ia,
            &self.ib,
            self.s.separation,
            &Pose::relative(pose_a, pose_b),
        )
    }

    /// Starts a query: checks the trees and computes the relative pose; splits the state
    /// into the read-only context and the scratch.
    pub(crate) fn begin(
        &mut self,
        a: &SphereTree,
        pose_a: &Pose,
        b: &SphereTree,
        pose_b: &Pose,
    ) -> (Ctx<'_>, &mut Scratch, &TreeInfo, &TreeInfo) {
        let PairState { ia, ib, s } = self;
        assert!(
            a.len() == ia.nodes && b.len() == ib.nodes,
            "PairState used with trees it was not made for"
        );
        let rel = Pose::relative(pose_a, pose_b);
        let rel32 = Rel32::new(&rel);
        let slack = pruning_slack(ia.extent, ib.extent, &rel32);
        (
            Ctx {
                a: &ia.packed,
                b: &ib.packed,
                blocks_a: &ia.blocks,
                blocks_b: &ib.blocks,
                block_of_a: &ia.block_of,
                block_of_b: &ib.block_of,
                pose_a: *pose_a,
                rel,
                rel32,
                slack,
            },
            s,
            ia,
            ib,
        )
    }
}

/// See [`PairState::safe_separation`].
pub(crate) fn safe_separation(
    ia: &TreeInfo,
    ib: &TreeInfo,
    rec: Option<SeparationRecord>,
    rel: &Pose,
) -> Option<f64> {
    let rec = rec?;
    let c = ib.root_center;
    let dc = (rel.transform_point(c) - rec.relative.transform_point(c)).length();
    let dq = rel.rotation * rec.relative.rotation.conjugate();
    let v = DVec3::new(dq.x, dq.y, dq.z).length();
    let angle = 2.0 * v.atan2(dq.w.abs());
    let moved = (dc + angle * ib.radius) * (1.0 + 1e-9);
    // The rounding slack of the query asking (its f32 transform differs from the one that
    // measured the record).
    let slack = pruning_slack(ia.extent, ib.extent, &Rel32::new(rel)) as f64;
    Some(rec.lower - moved - slack)
}

impl Scratch {
    /// Records that the sphere sets are at least `lower` apart at the query's pose (or
    /// forgets the record when `lower` is not positive).
    pub(crate) fn record_separation(&mut self, ctx: &Ctx, lower: f64) {
        self.separation = (lower > 0.0).then_some(SeparationRecord {
            lower,
            relative: ctx.rel,
        });
    }
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
