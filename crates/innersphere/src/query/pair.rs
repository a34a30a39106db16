//! The pair: two shared trees and everything their queries keep from frame to frame. The
//! top of `query/`: it owns every query kind's scratch and is the only public way to query.

use super::budgeted::{self, BudgetedVolume};
use super::contact::{self, ContactResult};
use super::distance::{self, Distance, DistanceOptions, DistanceScratch};
use super::kernel::far::far;
use super::kernel::geometry::{pruning_slack, Contact, Rel32};
use super::kernel::heap::PairHeap;
use super::kernel::info::TreeInfo;
use super::kernel::separation::{safe_separation, SeparationRecord};
use super::kernel::Ctx;
use super::mesh_penetration::{self, MeshPenetration};
use super::multipoint::{self, Multipoint, MultipointOptions, MultipointScratch};
use super::paper::{self, TraversalOptions};
use super::penetration::{self, Patch, Penetration, PenetrationOptions, PenetrationScratch};
use super::refined::{self, RefineOptions, RefineScratch, RefinedDistance, Surfaces};
use super::search::block_front::BlockFront;
use super::search::descent::Descent;
use super::search::front::Front;
use crate::error::{Error, Result};
use crate::exact::{ExactMesh, ExactScratch};
use crate::mesh::Mesh;
use crate::pose::Pose;
use crate::tree::SphereTree;
use std::sync::Arc;

/// A tree ready for queries: the tree and its query-side facts ([`TreeInfo`], computed once
/// in O(nodes)), both shared read-only, and optionally the mesh it was built from (for
/// [`Pair::refined_distance`]). Clone it (a few reference counts) to give the same tree to
/// many [`Pair`]s and threads without computing its facts again.
#[derive(Debug, Clone)]
pub struct SharedTree {
    tree: Arc<SphereTree>,
    info: Arc<TreeInfo>,
    mesh: Option<Arc<ExactMesh>>,
}

impl SharedTree {
    /// Shares `tree` and computes its query-side facts.
    pub fn new(tree: impl Into<Arc<SphereTree>>) -> SharedTree {
        let tree = tree.into();
        let info = Arc::new(TreeInfo::new(&tree));
        SharedTree {
            tree,
            info,
            mesh: None,
        }
    }

    /// The same tree with the mesh it was built from, prepared for exact queries (its
    /// triangle BVH: about a second per jaw arch), for [`Pair::refined_distance`]. Refuses a
    /// mesh that is not the tree's source (bounding box, volume and its centroid against the
    /// tree's meta, as `ist check` does; open meshes too).
    pub fn with_mesh(self, mesh: &Mesh) -> Result<SharedTree> {
        self.with_exact_mesh(Arc::new(ExactMesh::new(mesh)?))
    }

    /// [`SharedTree::with_mesh`] with a mesh already prepared (shared, not copied).
    pub fn with_exact_mesh(mut self, mesh: Arc<ExactMesh>) -> Result<SharedTree> {
        if let Some(why) = crate::tree::check::source_mismatch(&self.tree, mesh.mesh()) {
            return Err(Error::InvalidMesh(format!(
                "not the mesh this tree was built from: {why}"
            )));
        }
        self.mesh = Some(mesh);
        Ok(self)
    }

    /// The mesh given with [`SharedTree::with_mesh`], if any.
    pub fn mesh(&self) -> Option<&Arc<ExactMesh>> {
        self.mesh.as_ref()
    }

    /// The tree.
    pub fn tree(&self) -> &Arc<SphereTree> {
        &self.tree
    }

    /// Its query-side facts.
    pub fn info(&self) -> &Arc<TreeInfo> {
        &self.info
    }
}

/// A shared tree reads as its tree.
impl std::ops::Deref for SharedTree {
    type Target = SphereTree;
    fn deref(&self) -> &SphereTree {
        &self.tree
    }
}

impl From<SphereTree> for SharedTree {
    fn from(tree: SphereTree) -> SharedTree {
        SharedTree::new(tree)
    }
}

impl From<Arc<SphereTree>> for SharedTree {
    fn from(tree: Arc<SphereTree>) -> SharedTree {
        SharedTree::new(tree)
    }
}

impl From<&SharedTree> for SharedTree {
    fn from(t: &SharedTree) -> SharedTree {
        t.clone()
    }
}

/// Two trees and all per-pair state of their queries: what temporal coherence needs (last
/// contact pairs, last proved separation, the kinetic fronts) and all scratch memory,
/// reserved from the tree sizes when the pair is made, so that queries allocate nothing from
/// the first frame on (see [`Pair::new`] for what is reserved and what may still grow).
///
/// Every query takes the world poses of A and B (`p' = R p + t` applied to each tree's model
/// coordinates; [`Pose::IDENTITY`] for a body that does not move) and answers in the world
/// frame. Queries of every kind may be mixed on one pair; they share what one proves (a
/// separation proved by [`Pair::distance`] lets the next contact query skip its traversal).
/// A pair is `Send`: query many pairs from many threads, one thread per pair at a time; the
/// trees are shared read-only.
#[derive(Debug)]
pub struct Pair {
    a: SharedTree,
    b: SharedTree,
    /// The last proved separation (a lower bound at a relative pose).
    sep: Option<SeparationRecord>,
    descent: Descent,
    heap: PairHeap,
    front: Front,
    bfront: BlockFront,
    distance: DistanceScratch,
    /// Leaf pair of the last backtracking contact.
    backtrack: Option<(u32, u32)>,
    multipoint: MultipointScratch,
    penetration: PenetrationScratch,
    refine: RefineScratch,
    /// The exact queries' memory (the meshes' penetration).
    exact: ExactScratch,
}

impl Pair {
    /// The pair of trees `a` (body A) and `b` (body B): a [`SphereTree`], an
    /// `Arc<SphereTree>` or a [`SharedTree`] each.
    ///
    /// Reserves, from the trees' depths `d`, largest fan-outs `f`, node counts `n` and leaf
    /// counts `l` (A's and B's):
    /// * every depth-first stack to its bound: a pair is at most `d_A + d_B` refinements
    ///   below the roots and a refinement pushes at most `f_A · f_B` pairs (16 on blocks);
    ///   ancestor chains `d + 1`;
    /// * the kinetic front ([`Pair::contact`] on fan-outs over 4, [`Pair::penetration`] with
    ///   the front, [`Pair::multipoint`] with tracking) for `l_A + l_B` node pairs, within
    ///   2¹³ ..= 2¹⁹ (its rebuild floor): along the jaw chew and grind it held at most
    ///   ≈ 0.2 × (l_A + l_B) pairs (0.1 and 0.3 mm voxels), pressed 1 mm past the bite
    ///   ≈ 0.96 × (l_A + l_B) (0.1 mm);
    /// * the block front of [`Pair::contact`] (fan-outs ≤ 4) for `(l_A + l_B) / 16` entries,
    ///   within 2¹¹ ..= 2¹⁶ (the jaw used at most ≈ 6,700);
    /// * the priority queue of best-first [`Pair::distance_with`] and of
    ///   [`Pair::penetration_within`] for `(n_A + n_B) / 8` pairs, within 2¹² ..= 2¹⁸ (the
    ///   jaw used at most 8,192);
    /// * [`Pair::multipoint`] for `k` up to 1024 contacts and [`Pair::penetration`] for up
    ///   to 64 patches.
    ///
    /// On the jaw arches at a 0.3 mm voxel (300k nodes, 200k leaves) that is 16 MiB (their
    /// two [`TreeInfo`]s: 26 MiB), reserved but not written: pages no query reaches need not
    /// become resident; on small trees the floors make it ≈ 5 MiB. What may still grow,
    /// once, to a high-water mark that is then kept: a front or queue in a deep overlap
    /// beyond its reservation (each is bounded, see the fronts' docs), the queue of
    /// [`Pair::penetration_within`] with a larger budget (at most the budget plus a
    /// fan-out), `k` over 1024 (at most `k` contacts, `2k` keys) and `max_patches` over 64
    /// (at most `max_patches`).
    pub fn new(a: impl Into<SharedTree>, b: impl Into<SharedTree>) -> Pair {
        let (a, b) = (a.into(), b.into());
        let (ia, ib) = (&a.info, &b.info);
        let depth = ia.max_depth as usize + ib.max_depth as usize + 2;
        let (fa, fb) = (ia.max_children.max(1), ib.max_children.max(1));
        let blocks = !ia.blocks.is_empty() && !ib.blocks.is_empty();
        // Depth-first stacks (the blocked ones on fan-outs ≤ 4, the others otherwise):
        // simultaneous descent pushes up to fa·fb pairs per refinement, refining the larger
        // sphere up to max(fa, fb).
        let stack = if blocks { 0 } else { depth * fa * fb + 16 };
        let single = depth * fa.max(fb) + 16;
        let block_stack = if blocks { depth * 16 + 16 } else { 0 };
        let leaves = ia.leaves + ib.leaves;
        let front = leaves.clamp(1 << 13, 1 << 19);
        let block_front = if blocks {
            (leaves / 16).clamp(1 << 11, 1 << 16)
        } else {
            0
        };
        let heap = ((ia.nodes + ib.nodes) / 8).clamp(1 << 12, 1 << 18);
        Pair {
            sep: None,
            descent: Descent {
                stack: Vec::with_capacity(stack),
                tstack: Vec::with_capacity(block_stack),
                anc_a: Vec::with_capacity(ia.max_depth as usize + 1),
                anc_b: Vec::with_capacity(ib.max_depth as usize + 1),
            },
            heap: PairHeap::with_capacity(heap),
            front: Front::with_capacity(front, single),
            bfront: BlockFront::with_capacity(block_front, block_stack),
            distance: DistanceScratch {
                pstack: Vec::with_capacity(if blocks { 0 } else { single }),
                bstack: Vec::with_capacity(block_stack),
                last: None,
            },
            backtrack: None,
            multipoint: MultipointScratch::new(),
            penetration: PenetrationScratch::new(),
            refine: RefineScratch::new(),
            exact: ExactScratch::new(),
            a,
            b,
        }
    }

    /// Tree A.
    pub fn tree_a(&self) -> &SharedTree {
        &self.a
    }

    /// Tree B.
    pub fn tree_b(&self) -> &SharedTree {
        &self.b
    }

    /// Exact minimum distance between the two inner-sphere packings at the world poses, with
    /// the closest points and the leaf pair ([`DistanceOptions::default`]: exact, unsigned,
    /// coherent, depth first).
    ///
    /// Branch and bound over node pairs with the lower bound `|ca − cb| − ra − rb`, refining
    /// the larger sphere first and pruning pairs that cannot beat the best leaf pair so far
    /// (seeded with last query's pair). Records the proved separation for the safe-motion
    /// skip of the other queries.
    pub fn distance(&mut self, pose_a: &Pose, pose_b: &Pose) -> Distance {
        self.distance_with(pose_a, pose_b, &DistanceOptions::default())
    }

    /// [`Pair::distance`] with options: tolerances, signed distance, coherence, search
    /// order.
    pub fn distance_with(
        &mut self,
        pose_a: &Pose,
        pose_b: &Pose,
        opts: &DistanceOptions,
    ) -> Distance {
        let ctx = ctx(&self.a.info, &self.b.info, pose_a, pose_b);
        let mut opts = *opts;
        if let Some(f) = far(&self.a.info, &self.b.info, &ctx.rel) {
            if f.roots_only {
                let d =
                    distance::far_roots(&ctx, &self.a.info, &self.b.info, &f, &mut self.distance);
                return d.in_world(pose_a);
            }
            opts.abs_tolerance = opts.abs_tolerance.max(f.tolerance);
        }
        distance::distance(
            &ctx,
            &self.a.info,
            &self.b.info,
            &mut self.heap,
            &mut self.sep,
            &mut self.distance,
            &opts,
        )
        .in_world(pose_a)
    }

    /// The distance between the two meshes, refined from the sphere distance (ours): the
    /// exact distance of the triangles near the closest leaf pair, never below the exact
    /// mesh distance and never above the sphere distance ([`RefineOptions::default`]).
    /// Needs both trees' meshes ([`SharedTree::with_mesh`]); an error without them.
    ///
    /// On the jaw preset's trees it takes the sphere distance's error against the exact
    /// mesh distance from 0.02–0.045 mm to a few µm at p95 (docs/RESULTS.md).
    pub fn refined_distance(&mut self, pose_a: &Pose, pose_b: &Pose) -> Result<RefinedDistance> {
        self.refined_distance_with(pose_a, pose_b, &RefineOptions::default())
    }

    /// [`Pair::refined_distance`] with options: the balls searched, the local search's
    /// budget. Bad options are an error.
    pub fn refined_distance_with(
        &mut self,
        pose_a: &Pose,
        pose_b: &Pose,
        opts: &RefineOptions,
    ) -> Result<RefinedDistance> {
        opts.check()?;
        if self.a.mesh.is_none() || self.b.mesh.is_none() {
            return Err(refined::missing_meshes("the refined distance"));
        }
        let spheres = self.distance(pose_a, pose_b);
        let (Some(ma), Some(mb)) = (self.a.mesh.as_deref(), self.b.mesh.as_deref()) else {
            return Err(refined::missing_meshes("the refined distance"));
        };
        let radius = |t: &SphereTree, leaf: u32| t.r.get(leaf as usize).map_or(0.0, |&r| r as f64);
        let (ta, tb) = (&self.a.tree, &self.b.tree);
        let surfaces = Surfaces {
            a: ma,
            b: mb,
            leaf_radii: (radius(ta, spheres.leaf_a), radius(tb, spheres.leaf_b)),
            default_margin: ta.meta.voxel_size.max(tb.meta.voxel_size).max(0.0),
        };
        Ok(refined::refine(
            spheres,
            &surfaces,
            pose_a,
            pose_b,
            opts,
            &mut self.refine,
        ))
    }

    /// The penetration of the meshes themselves (ours): the exact volume of the
    /// intersection of the two solids the trees were built from, with the penalty force
    /// and torques of [`PenetrationOptions::stiffness`] from its exact gradient
    /// ([`MeshPenetration`]). Needs both trees' meshes ([`SharedTree::with_mesh`]); an error
    /// without them. Of the options the stiffness and `max_patches` apply: the pair keeps
    /// that many of the largest patches ([`Pair::patches`]).
    pub fn mesh_penetration_with(
        &mut self,
        pose_a: &Pose,
        pose_b: &Pose,
        opts: &PenetrationOptions,
    ) -> Result<MeshPenetration> {
        opts.check()?;
        let (Some(ma), Some(mb)) = (self.a.mesh.as_deref(), self.b.mesh.as_deref()) else {
            return Err(refined::missing_meshes("the meshes' penetration"));
        };
        Ok(mesh_penetration::mesh_penetration(
            ma,
            pose_a,
            mb,
            pose_b,
            self.a.info.center_of_mass,
            self.b.info.center_of_mass,
            opts.stiffness,
            opts.max_patches,
            &mut self.exact,
            &mut self.penetration.patches,
        ))
    }

    /// First contact (ours): whether the packings overlap, with one overlapping leaf pair,
    /// or a proved lower bound on their separation. The paper's contact answer on every
    /// frame (its traversals are under [`Pair::paper`]), from a kinetic front that re-tests
    /// only what the motion since the last query could change.
    pub fn contact(&mut self, pose_a: &Pose, pose_b: &Pose) -> ContactResult {
        let ctx = ctx(&self.a.info, &self.b.info, pose_a, pose_b);
        if let Some(f) = far(&self.a.info, &self.b.info, &ctx.rel) {
            return contact::separated(f.separation);
        }
        contact::contact(&ctx, &self.b.info, &mut self.front, &mut self.bfront).in_world(pose_a)
    }

    /// Up to `opts.k` contacts, at most one below each node pair at the split depth (the
    /// paper's multipoint traversal, III-C, reusing last frame's contacts; or ours, picked
    /// from the kinetic front, with [`MultipointOptions::tracking`]). The contacts are
    /// [`Pair::contacts`] until the next query.
    pub fn multipoint(
        &mut self,
        pose_a: &Pose,
        pose_b: &Pose,
        opts: &MultipointOptions,
    ) -> Multipoint {
        let ctx = ctx(&self.a.info, &self.b.info, pose_a, pose_b);
        if let Some(f) = far(&self.a.info, &self.b.info, &ctx.rel) {
            return multipoint::separated(&mut self.multipoint, f.separation);
        }
        let m = multipoint::multipoint(
            &ctx,
            &self.a.info,
            &self.b.info,
            &mut self.descent,
            &mut self.front,
            &mut self.sep,
            &mut self.multipoint,
            opts,
        );
        for c in &mut self.multipoint.contacts {
            *c = c.in_world(pose_a);
        }
        m
    }

    /// The contacts found by the last [`Pair::multipoint`] (world frame), reused ones first;
    /// other query kinds leave them as they are.
    pub fn contacts(&self) -> &[Contact] {
        &self.multipoint.contacts
    }

    /// Penetration volume (the volume of the intersection of the two sphere unions, exact),
    /// with the contact normal, the penalty force, the torques about both centres of mass
    /// and the contact patches ([`PenetrationOptions::default`]). The patches are
    /// [`Pair::patches`] until the next query.
    pub fn penetration(&mut self, pose_a: &Pose, pose_b: &Pose) -> Penetration {
        self.penetration_with(pose_a, pose_b, &PenetrationOptions::default())
    }

    /// [`Pair::penetration`] with options: stiffness, patches, how pairs are found.
    pub fn penetration_with(
        &mut self,
        pose_a: &Pose,
        pose_b: &Pose,
        opts: &PenetrationOptions,
    ) -> Penetration {
        let ctx = ctx(&self.a.info, &self.b.info, pose_a, pose_b);
        if let Some(f) = far(&self.a.info, &self.b.info, &ctx.rel) {
            return penetration::separated(&mut self.penetration, f.separation);
        }
        let p = penetration::penetration(
            &ctx,
            &self.a.info,
            &self.b.info,
            &mut self.descent,
            &mut self.front,
            &mut self.sep,
            &mut self.penetration,
            opts,
        );
        self.penetration_in_world(p, pose_a)
    }

    /// A penetration answer and the patches of the pair, found in A's frame, in the world
    /// frame: the one place the penetration queries' answers change frame.
    fn penetration_in_world(&mut self, p: Penetration, pose_a: &Pose) -> Penetration {
        for q in &mut self.penetration.patches {
            *q = q.in_world(pose_a);
        }
        p.in_world(pose_a)
    }

    /// The contact patches of the last [`Pair::penetration`] or
    /// [`Pair::mesh_penetration_with`] (world frame); other query kinds leave them as they
    /// are.
    pub fn patches(&self) -> &[Patch] {
        &self.penetration.patches
    }

    /// The overlapping leaf pairs at the world poses (A's leaf, B's leaf; node indices, as
    /// [`Distance::leaf_a`] and [`Distance::leaf_b`]), in the order of one depth-first
    /// traversal, into `out` (emptied first): the pairs whose lenses [`Pair::penetration`]
    /// sums. Allocates as `out` grows; not for the real-time path.
    pub fn overlapping_leaves(&mut self, pose_a: &Pose, pose_b: &Pose, out: &mut Vec<[u32; 2]>) {
        let ctx = ctx(&self.a.info, &self.b.info, pose_a, pose_b);
        if far(&self.a.info, &self.b.info, &ctx.rel).is_some() {
            out.clear();
            return;
        }
        penetration::overlapping_leaves(&ctx, &mut self.descent, out);
    }

    /// [`Pair::penetration_with`]'s answer summed over the leaf pairs `leaves` alone (node
    /// indices, A's then B's), with no search: given [`Pair::overlapping_leaves`], the
    /// query's output-sensitive floor, the work no search can avoid. Pairs that do not
    /// overlap at the poses add nothing, a pair given twice counts twice; the sums run in
    /// the order given, so the last bits may differ from the query's (which sums in its
    /// own order). `distance` is 0 and `visits` the number of pairs given; the patches are
    /// [`Pair::patches`]. Errors when an index is no leaf of its tree.
    pub fn penetration_of_leaves(
        &mut self,
        pose_a: &Pose,
        pose_b: &Pose,
        leaves: &[[u32; 2]],
        opts: &PenetrationOptions,
    ) -> Result<Penetration> {
        let ctx = ctx(&self.a.info, &self.b.info, pose_a, pose_b);
        if let Some(f) = far(&self.a.info, &self.b.info, &ctx.rel) {
            for (k, &[i, j]) in leaves.iter().enumerate() {
                penetration::check_leaves(ctx.a, ctx.b, k, i, j)?;
            }
            let mut p = penetration::separated(&mut self.penetration, f.separation);
            p.visits = leaves.len() as u64;
            return Ok(p);
        }
        let s = &mut self.penetration;
        let mut hits = std::mem::take(&mut s.floor);
        let p = penetration::penetration_of_leaves(
            &ctx,
            &self.a.info,
            &self.b.info,
            leaves,
            &mut hits,
            s,
            opts,
        );
        s.floor = hits;
        Ok(self.penetration_in_world(p?, pose_a))
    }

    /// Time-critical penetration volume: the volume found within `budget` node-pair tests
    /// and a proved upper bound on the exact one (see [`BudgetedVolume`] for choosing the
    /// budget). With `u64::MAX` the volume is [`Pair::penetration`]'s.
    pub fn penetration_within(
        &mut self,
        pose_a: &Pose,
        pose_b: &Pose,
        budget: u64,
    ) -> BudgetedVolume {
        self.penetration_within_with(pose_a, pose_b, budget, &PenetrationOptions::default())
    }

    /// [`Pair::penetration_within`] with options: of [`PenetrationOptions`] only the
    /// stiffness (the force of the pairs found) and `linearize` apply.
    pub fn penetration_within_with(
        &mut self,
        pose_a: &Pose,
        pose_b: &Pose,
        budget: u64,
        opts: &PenetrationOptions,
    ) -> BudgetedVolume {
        let ctx = ctx(&self.a.info, &self.b.info, pose_a, pose_b);
        if far(&self.a.info, &self.b.info, &ctx.rel).is_some() {
            return budgeted::separated();
        }
        budgeted::penetration_within(
            &ctx,
            &self.a.info,
            &self.b.info,
            &mut self.heap,
            budget,
            opts.stiffness,
            opts.linearize,
        )
        .in_world(pose_a)
    }

    /// The paper's traversals on this pair (its baselines: same contact answers as
    /// [`Pair::contact`], slower).
    pub fn paper(&mut self) -> Paper<'_> {
        Paper(self)
    }

    /// Forgets all temporal coherence (previous contacts, closest pair, separation record,
    /// fronts); the next queries start from scratch. Keeps the reserved memory.
    pub fn reset(&mut self) {
        self.distance.last = None;
        self.backtrack = None;
        self.multipoint.prev.clear();
        self.sep = None;
        self.front.reset();
        self.bfront.reset();
        self.refine.reset();
        self.exact.reset();
    }

    /// A guaranteed lower bound on the current separation of the two sphere sets at the
    /// world poses `pose_a`, `pose_b`, from the last recorded separation and the relative
    /// motion since: `d − (|Δc| + θ·ρ)`, where `Δc` is the displacement of B's root-sphere
    /// centre in A's frame, θ the rotation angle of B's relative rotation since then and ρ
    /// B's radius about its root centre ([`TreeInfo::radius`]), less the f32 rounding slack.
    /// Positive means no query can find a contact; `None` when no separation is recorded.
    pub fn safe_separation(&self, pose_a: &Pose, pose_b: &Pose) -> Option<f64> {
        safe_separation(
            &self.a.info,
            &self.b.info,
            self.sep,
            &Pose::relative(pose_a, pose_b),
        )
    }
}

/// The paper's traversals on a [`Pair`] (section III), kept as the baselines our queries are
/// measured against; from [`Pair::paper`].
#[derive(Debug)]
pub struct Paper<'p>(&'p mut Pair);

impl Paper<'_> {
    /// The paper's distance traversal (III-A): from the roots, descend while the spheres
    /// overlap, stop at the first overlapping leaf pair (the contact) or when every branch
    /// has reached a separated pair (no contact; `distance` = the smallest separation seen
    /// there, a proved lower bound).
    pub fn distance_traversal(
        &mut self,
        pose_a: &Pose,
        pose_b: &Pose,
        opts: &TraversalOptions,
    ) -> ContactResult {
        let p = &mut *self.0;
        let ctx = ctx(&p.a.info, &p.b.info, pose_a, pose_b);
        if let Some(f) = far(&p.a.info, &p.b.info, &ctx.rel) {
            return contact::separated(f.separation);
        }
        paper::distance_traversal(&ctx, &p.a.info, &p.b.info, &mut p.descent, &mut p.sep, opts)
            .in_world(pose_a)
    }

    /// The paper's backtracking traversal (III-B, Algorithms 1–2): restart from the previous
    /// frame's contact pair; if it no longer overlaps, search the traversal pair above it,
    /// then climb toward the root, each time skipping the subtree pair already searched.
    /// Without a previous contact it is the full distance traversal. Same contact answer as
    /// [`Paper::distance_traversal`] on every frame.
    pub fn backtracking(
        &mut self,
        pose_a: &Pose,
        pose_b: &Pose,
        opts: &TraversalOptions,
    ) -> ContactResult {
        let p = &mut *self.0;
        let ctx = ctx(&p.a.info, &p.b.info, pose_a, pose_b);
        if let Some(f) = far(&p.a.info, &p.b.info, &ctx.rel) {
            return contact::separated(f.separation);
        }
        paper::backtracking(
            &ctx,
            &p.a.info,
            &p.b.info,
            &mut p.descent,
            &mut p.sep,
            &mut p.backtrack,
            opts,
        )
        .in_world(pose_a)
    }
}

/// The context of one query at world poses `pose_a`, `pose_b`: B's pose in A's frame, in
/// f64 and in f32, and the pruning slack of that f32 transform.
#[inline]
fn ctx<'t>(ia: &'t TreeInfo, ib: &'t TreeInfo, pose_a: &Pose, pose_b: &Pose) -> Ctx<'t> {
    let rel = Pose::relative(pose_a, pose_b);
    let rel32 = Rel32::new(&rel);
    let slack = pruning_slack(ia.extent, ib.extent, &rel32);
    Ctx {
        a: &ia.packed,
        b: &ib.packed,
        blocks_a: &ia.blocks,
        blocks_b: &ib.blocks,
        block_of_a: &ia.block_of,
        block_of_b: &ib.block_of,
        rel,
        rel32,
        slack,
        simd: super::kernel::simd::detect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Pairs move between threads; shared trees are read from many at once.
    #[test]
    fn pairs_are_send_and_shared_trees_send_and_sync() {
        fn send<T: Send>() {}
        fn sync<T: Send + Sync>() {}
        send::<Pair>();
        sync::<SharedTree>();
    }
}
