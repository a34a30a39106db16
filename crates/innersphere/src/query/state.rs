//! The per-pair state: temporal coherence and all scratch memory of the queries.

use super::geometry::{pruning_slack, Contact, Rel32};
use super::heap::PairHeap;
use super::info::TreeInfo;
use super::penetration::{Patch, PatchAcc};
use super::Pose;
use crate::SphereTree;
use glam::DVec3;
use std::sync::Arc;

/// A lower bound on the separation of the two sphere sets, proved by a query at a relative
/// pose (B in A's frame).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SeparationRecord {
    /// The sphere sets were at least this far apart (already reduced by the f32 rounding
    /// slack of the query that measured it).
    pub lower: f64,
    /// Pose of B in A's frame when it was measured.
    pub relative: Pose,
}

/// Transformed centres of B's nodes (A's frame, f32) for the current query.
///
/// A traversal writes a node's entry when it transforms the node and only reads entries it
/// wrote in the same query; debug builds check this with a generation stamp per entry.
#[derive(Debug)]
pub(crate) struct TbCache {
    pos: Vec<[f32; 3]>,
    #[cfg(debug_assertions)]
    stamp: Vec<u32>,
    #[cfg(debug_assertions)]
    cur: u32,
}

impl TbCache {
    fn new(n: usize) -> Self {
        TbCache {
            pos: vec![[0.0; 3]; n],
            #[cfg(debug_assertions)]
            stamp: vec![0; n],
            #[cfg(debug_assertions)]
            cur: 0,
        }
    }

    #[inline]
    fn next_query(&mut self) {
        #[cfg(debug_assertions)]
        {
            self.cur = self.cur.wrapping_add(1);
            if self.cur == 0 {
                self.stamp.iter_mut().for_each(|s| *s = 0);
                self.cur = 1;
            }
        }
    }

    /// Transforms node `j` of `b`, stores and returns its centre.
    #[inline(always)]
    pub(crate) fn xf(&mut self, rel: &Rel32, b: &SphereTree, j: usize) -> [f32; 3] {
        let p = rel.apply(b.x[j], b.y[j], b.z[j]);
        self.pos[j] = p;
        #[cfg(debug_assertions)]
        {
            self.stamp[j] = self.cur;
        }
        p
    }

    /// The centre of node `j`, transformed earlier in this query.
    #[inline(always)]
    pub(crate) fn get(&self, j: usize) -> [f32; 3] {
        #[cfg(debug_assertions)]
        debug_assert_eq!(
            self.stamp[j], self.cur,
            "B node {j} read before it was transformed"
        );
        self.pos[j]
    }
}

/// One entry of a depth-first traversal stack.
#[derive(Debug, Clone, Copy)]
pub(crate) struct StackEntry {
    pub a: u32,
    pub b: u32,
    /// Depth of the pair in the traversal (simultaneous descent: max of the node depths).
    pub depth: u32,
}

/// Everything a query needs about the pair for one call: the trees, the poses, the f32
/// relative transform and the pruning slack.
pub(crate) struct Ctx<'t> {
    pub a: &'t SphereTree,
    pub b: &'t SphereTree,
    pub pose_a: Pose,
    pub rel: Pose,
    pub rel32: Rel32,
    pub slack: f32,
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
    pub(crate) tb: TbCache,
    pub(crate) heap: PairHeap,
    pub(crate) stack: Vec<StackEntry>,
    pub(crate) anc_a: Vec<u32>,
    pub(crate) anc_b: Vec<u32>,
    /// Sorted keys of traversal pairs excluded by the multipoint traversal.
    pub(crate) excluded: Vec<u64>,
    pub(crate) contacts: Vec<Contact>,
    pub(crate) mp_prev: Vec<(u32, u32)>,
    pub(crate) stale: Vec<(u32, u32)>,
    pub(crate) patches: Vec<Patch>,
    pub(crate) patch_acc: Vec<PatchAcc>,
    /// Leaf pair of the last exact proximity.
    pub(crate) prox_pair: Option<(u32, u32)>,
    /// Leaf pair of the last backtracking contact.
    pub(crate) bt_pair: Option<(u32, u32)>,
    pub(crate) separation: Option<SeparationRecord>,
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
        let heap_cap = ((a.nodes + b.nodes) / 4).clamp(1024, 1 << 20);
        PairState {
            tb: TbCache::new(b.nodes),
            heap: PairHeap::with_capacity(heap_cap),
            stack: Vec::with_capacity(depth * fan + 16),
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
        self.prox_pair = None;
        self.bt_pair = None;
        self.mp_prev.clear();
        self.separation = None;
    }

    /// The last separation bound recorded by a query, if any.
    pub fn separation_record(&self) -> Option<SeparationRecord> {
        self.separation
    }

    /// A guaranteed lower bound on the current separation of the two sphere sets at the world
    /// poses `pose_a`, `pose_b`, from the last recorded separation and the relative motion
    /// since: `d − (|Δc| + θ·ρ)`, where `Δc` is the displacement of B's root-sphere centre
    /// in A's frame, θ the rotation angle of B's relative rotation since then and ρ B's
    /// radius about its root centre ([`TreeInfo::radius`]). Positive means no query can find
    /// a contact; `None` when no separation has been recorded.
    pub fn safe_separation(&self, pose_a: &Pose, pose_b: &Pose) -> Option<f64> {
        let rel = Pose::relative(pose_a, pose_b);
        self.safe_separation_rel(&rel)
    }

    pub(crate) fn safe_separation_rel(&self, rel: &Pose) -> Option<f64> {
        let rec = self.separation?;
        let c = self.ib.root_center;
        let dc = (rel.transform_point(c) - rec.relative.transform_point(c)).length();
        let dq = rel.rotation * rec.relative.rotation.conjugate();
        let v = DVec3::new(dq.x, dq.y, dq.z).length();
        let angle = 2.0 * v.atan2(dq.w.abs());
        let moved = (dc + angle * self.ib.radius) * (1.0 + 1e-9);
        // The rounding slack of the query asking (its f32 transform differs from the one
        // that measured the record).
        let rel32 = Rel32::new(rel);
        let slack = pruning_slack(self.ia.extent, self.ib.extent, &rel32) as f64;
        Some(rec.lower - moved - slack)
    }

    /// Starts a query: checks the trees, computes the relative pose and transforms B's root.
    pub(crate) fn begin<'t>(
        &mut self,
        a: &'t SphereTree,
        pose_a: &Pose,
        b: &'t SphereTree,
        pose_b: &Pose,
    ) -> Ctx<'t> {
        assert!(
            a.len() == self.ia.nodes && b.len() == self.ib.nodes,
            "PairState used with trees it was not made for"
        );
        let rel = Pose::relative(pose_a, pose_b);
        let rel32 = Rel32::new(&rel);
        let slack = pruning_slack(self.ia.extent, self.ib.extent, &rel32);
        self.tb.next_query();
        self.tb.xf(&rel32, b, 0);
        Ctx {
            a,
            b,
            pose_a: *pose_a,
            rel,
            rel32,
            slack,
        }
    }

    /// Records that the sphere sets are at least `lower` apart at the query's pose
    /// (or forgets the record when `lower` is not positive).
    pub(crate) fn record_separation(&mut self, ctx: &Ctx, lower: f64) {
        self.separation = if lower > 0.0 {
            Some(SeparationRecord {
                lower,
                relative: ctx.rel,
            })
        } else {
            None
        };
    }
}

/// Test of node pair (`ia`, `ib`) with B's centre `cb`: (overlap, lower bound of the distance).
/// Inner nodes get the pruning slack; leaf pairs are exact.
#[inline(always)]
pub(crate) fn test_pair(ctx: &Ctx, ia: usize, ib: usize, cb: [f32; 3]) -> (bool, f32) {
    let a = ctx.a;
    let leafs = a.child_count[ia] == 0 && ctx.b.child_count[ib] == 0;
    let s = a.r[ia] + ctx.b.r[ib] + if leafs { 0.0 } else { ctx.slack };
    let dx = cb[0] - a.x[ia];
    let dy = cb[1] - a.y[ia];
    let dz = cb[2] - a.z[ia];
    let d2 = dx * dx + dy * dy + dz * dz;
    (d2 < s * s, d2.sqrt() - s)
}

/// Expands node pair (`ea`, `eb`) by splitting the larger sphere (the one that is not a
/// leaf; A on ties) and calls `f(child_a, child_b, b_centre, |Δ|², ra + rb (+ slack unless
/// both are leaves), both_leaves)` for every child pair. B children are transformed (and
/// cached).
#[inline(always)]
pub(crate) fn expand_larger<F: FnMut(u32, u32, [f32; 3], f32, f32, bool)>(
    ctx: &Ctx,
    tb: &mut TbCache,
    ea: u32,
    eb: u32,
    mut f: F,
) {
    let a = ctx.a;
    let b = ctx.b;
    let (ia, ib) = (ea as usize, eb as usize);
    let a_int = a.child_count[ia] != 0;
    let b_int = b.child_count[ib] != 0;
    if a_int && (!b_int || a.r[ia] >= b.r[ib]) {
        let cb = tb.get(ib);
        let rb = b.r[ib];
        let f0 = a.first_child[ia] as usize;
        let n = a.child_count[ia] as usize;
        let xs = &a.x[f0..f0 + n];
        let ys = &a.y[f0..f0 + n];
        let zs = &a.z[f0..f0 + n];
        let rs = &a.r[f0..f0 + n];
        let cs = &a.child_count[f0..f0 + n];
        for k in 0..n {
            let dx = xs[k] - cb[0];
            let dy = ys[k] - cb[1];
            let dz = zs[k] - cb[2];
            let d2 = dx * dx + dy * dy + dz * dz;
            let leafs = !b_int && cs[k] == 0;
            let s = rs[k] + rb + if leafs { 0.0 } else { ctx.slack };
            f((f0 + k) as u32, eb, cb, d2, s, leafs);
        }
    } else {
        let (ax, ay, az, ra) = (a.x[ia], a.y[ia], a.z[ia], a.r[ia]);
        let f0 = b.first_child[ib] as usize;
        let n = b.child_count[ib] as usize;
        for j in f0..f0 + n {
            let p = tb.xf(&ctx.rel32, b, j);
            let dx = p[0] - ax;
            let dy = p[1] - ay;
            let dz = p[2] - az;
            let d2 = dx * dx + dy * dy + dz * dz;
            let leafs = !a_int && b.child_count[j] == 0;
            let s = ra + b.r[j] + if leafs { 0.0 } else { ctx.slack };
            f(ea, j as u32, p, d2, s, leafs);
        }
    }
}
