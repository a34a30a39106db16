//! The per-pair state: temporal coherence and all scratch memory of the queries.

use super::block_front::BlockFront;
use super::front::Front;
use super::geometry::{pruning_slack, Contact, Rel32};
use super::heap::{Entry, PairHeap};
use super::info::{Block, Node, TreeInfo};
use super::penetration::{Patch, PatchAcc};
use super::proximity::BlockEntry;
use super::traversal::TItem;
use crate::Pose;
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
/// and the pose it was measured at) and all scratch memory (stacks, heaps, fronts, result
/// buffers), reserved from the tree sizes when it is made, so that queries allocate nothing
/// from the first frame on (see [`PairState::with_info`] for what is reserved and what may
/// still grow).
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

/// Contacts reserved for [`multipoint`](super::multipoint) (64 KiB): `k` up to this
/// allocates nothing.
const MULTIPOINT_K: usize = 1024;

/// Patches reserved for [`penetration`](super::penetration): `max_patches` up to this
/// allocates nothing.
const PATCHES: usize = 64;

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
    ///
    /// Reserves, from the trees' depths `d`, largest fan-outs `f`, node counts `n` and leaf
    /// counts `l` (A's and B's):
    /// * every depth-first stack to its bound: a pair is at most `d_A + d_B` refinements
    ///   below the roots and a refinement pushes at most `f_A · f_B` pairs (16 on blocks);
    ///   ancestor chains `d + 1`;
    /// * the kinetic front ([`contact`](super::contact), [`penetration`](super::penetration)
    ///   with the front, [`multipoint`](super::multipoint) with tracking) for
    ///   `(l_A + l_B) / 3` node pairs, within 2¹³ ..= 2¹⁷ (its rebuild floor): along the jaw
    ///   chew and grind it held at most ≈ 0.2 × (l_A + l_B) pairs (0.1 and 0.3 mm voxels);
    /// * the block front of [`contact`](super::contact) (fan-outs ≤ 4) for `(l_A + l_B) / 16`
    ///   entries, within 2¹¹ ..= 2¹⁶ (the jaw used at most ≈ 6,700);
    /// * the priority queue of best-first [`proximity`](super::proximity) and of
    ///   [`penetration_budgeted`](super::penetration_budgeted) for `(n_A + n_B) / 8` pairs,
    ///   within 2¹² ..= 2¹⁸ (the jaw used at most 8,192);
    /// * [`multipoint`](super::multipoint) for `k` up to 1024 contacts and
    ///   [`penetration`](super::penetration) for up to 64 patches.
    ///
    /// On the jaw arches at a 0.3 mm voxel (300k nodes, 200k leaves) that is 9.5 MiB (their
    /// two [`TreeInfo`]s: 26 MiB), reserved but not written: pages no query reaches need not
    /// become resident; on small trees the floors make it ≈ 5 MiB. What may still grow,
    /// once, to a high-water mark that is then kept: a front or queue in a deep overlap
    /// beyond its reservation (each is bounded, see the fronts' docs), the queue of
    /// [`penetration_budgeted`](super::penetration_budgeted) with a larger budget (at most
    /// the budget plus a fan-out), `k` over 1024 (at most `k` contacts, `2k` keys) and
    /// `max_patches` over 64 (at most `max_patches`).
    pub fn with_info(a: Arc<TreeInfo>, b: Arc<TreeInfo>) -> PairState {
        let depth = a.max_depth as usize + b.max_depth as usize + 2;
        let (fa, fb) = (a.max_children.max(1), b.max_children.max(1));
        let blocks = !a.blocks.is_empty() && !b.blocks.is_empty();
        // Depth-first stacks (the blocked ones on fan-outs ≤ 4, the others otherwise):
        // simultaneous descent pushes up to fa·fb pairs per refinement, refining the larger
        // sphere up to max(fa, fb).
        let stack = if blocks { 0 } else { depth * fa * fb + 16 };
        let single = depth * fa.max(fb) + 16;
        let block_stack = if blocks { depth * 16 + 16 } else { 0 };
        let leaves = a.leaves + b.leaves;
        let front = (leaves / 3).clamp(1 << 13, 1 << 17);
        let block_front = if blocks {
            (leaves / 16).clamp(1 << 11, 1 << 16)
        } else {
            0
        };
        let heap = ((a.nodes + b.nodes) / 8).clamp(1 << 12, 1 << 18);
        PairState {
            s: Scratch {
                stack: Vec::with_capacity(stack),
                pstack: Vec::with_capacity(if blocks { 0 } else { single }),
                bstack: Vec::with_capacity(block_stack),
                tstack: Vec::with_capacity(block_stack),
                heap: PairHeap::with_capacity(heap),
                anc_a: Vec::with_capacity(a.max_depth as usize + 1),
                anc_b: Vec::with_capacity(b.max_depth as usize + 1),
                // Stale contacts and found ones: at most 2k keys.
                excluded: Vec::with_capacity(2 * MULTIPOINT_K),
                contacts: Vec::with_capacity(MULTIPOINT_K),
                mp_prev: Vec::with_capacity(MULTIPOINT_K),
                stale: Vec::with_capacity(MULTIPOINT_K),
                patches: Vec::with_capacity(PATCHES),
                patch_acc: Vec::with_capacity(PATCHES),
                prox_pair: None,
                bt_pair: None,
                separation: None,
                front: Front::with_capacity(front, single),
                bfront: BlockFront::with_capacity(block_front, block_stack),
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
