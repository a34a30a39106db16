//! Penetration volume, force, torque and contact patches (beyond the paper).
//!
//! Leaves within one tree are disjoint, so the sum of the lens volumes of all overlapping
//! leaf pairs is exactly the volume of the intersection of the two sphere unions.

use super::kernel::block::TItem;
use super::kernel::geometry::{direction, lens, lens_area};
use super::kernel::info::TreeInfo;
use super::kernel::separation::{record, safe_separation, SeparationRecord};
use super::kernel::{expand_larger, Ctx, Item};
use super::search::descent::{blocked, overlap_pairs_dispatch, Descent};
use super::search::front::Front;
use glam::{DMat3, DVec3};

/// Patches reserved per pair: `max_patches` up to this allocates nothing.
pub(crate) const RESERVED_PATCHES: usize = 64;

/// The scratch of penetration: the patches being summed and the finished ones.
#[derive(Debug)]
pub(crate) struct PenetrationScratch {
    /// The finished patches of the last query (world frame).
    pub patches: Vec<Patch>,
    /// Running sums of the patches.
    pub patch_acc: Vec<PatchAcc>,
}

impl PenetrationScratch {
    /// Reserved for up to [`RESERVED_PATCHES`] patches.
    pub(crate) fn new() -> PenetrationScratch {
        PenetrationScratch {
            patches: Vec::with_capacity(RESERVED_PATCHES),
            patch_acc: Vec::with_capacity(RESERVED_PATCHES),
        }
    }
}

/// Options of [`Pair::penetration`](crate::Pair::penetration).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PenetrationOptions {
    /// Force per unit of penetration volume (force = stiffness × volume).
    pub stiffness: f64,
    /// At most this many contact patches (0 = none).
    pub max_patches: usize,
    /// A pair joins the patch whose first point is nearest when within this distance (model
    /// units); 0 = automatic: 1/8 of the smaller root-sphere radius.
    pub patch_radius: f64,
    /// Skip (answer "no penetration") while the last proved separation holds (traversal
    /// only; the front needs no skip).
    pub safe_motion: bool,
    /// Where the overlapping leaf pairs come from (default [`Tracking::Auto`]).
    pub tracking: Tracking,
    /// Also sum [`Penetration::area`] and [`Penetration::stiffness`] (the linearised wrench
    /// an implicit integrator needs; the haptic loop sets it). Off by default: it adds about
    /// a quarter to the slowest frames of deep contact (measured on the jaw pair, see
    /// BENCHMARKS.md).
    pub linearize: bool,
}

/// The stiffest penalty accepted (force per unit volume): far above any material in any
/// units, low enough that stiffness × the largest volume of supported coordinates stays
/// finite.
pub const MAX_STIFFNESS: f64 = 1e30;

impl PenetrationOptions {
    /// Refuses a stiffness that is negative, not finite or above [`MAX_STIFFNESS`] (a force
    /// that would overflow to infinity and NaN).
    pub fn check(&self) -> crate::error::Result<()> {
        if !(self.stiffness.is_finite() && (0.0..=MAX_STIFFNESS).contains(&self.stiffness)) {
            return Err(crate::error::Error::InvalidOption(format!(
                "the stiffness must be from 0 to {} (force per unit volume), not {}",
                crate::error::num(MAX_STIFFNESS),
                crate::error::num(self.stiffness)
            )));
        }
        Ok(())
    }
}

impl Default for PenetrationOptions {
    fn default() -> Self {
        PenetrationOptions {
            stiffness: 1.0,
            max_patches: 8,
            patch_radius: 0.0,
            safe_motion: true,
            tracking: Tracking::Auto,
            linearize: false,
        }
    }
}

/// How [`Pair::penetration`](crate::Pair::penetration) finds the overlapping leaf pairs. Same result either way.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Tracking {
    /// The front for trees of up to [`AUTO_FRONT_NODES`] nodes together, else the traversal.
    #[default]
    Auto,
    /// The kinetic front (ours): re-test only what the motion since the last query could
    /// change. Far fewer node-pair tests, but each is a likely cache miss.
    Front,
    /// A depth-first traversal from the roots every query (larger sphere refined first).
    Traversal,
}

/// [`Tracking::Auto`] uses the front up to this many nodes in both trees together: on the
/// jaw pair the front is 3–6× faster than the traversal with trees of 30k–100k leaves
/// (≈ 80k–300k nodes together) and slower with 570k (1.7M nodes), where its scattered
/// memory accesses dominate.
pub const AUTO_FRONT_NODES: usize = 1_000_000;

/// A cluster of overlapping leaf pairs (world frame).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Patch {
    /// Volume-weighted centroid of the pairs' lenses.
    pub point: DVec3,
    /// Unit volume-weighted direction from A into B (the direction B is pushed).
    pub normal: DVec3,
    /// Largest pair overlap `ra + rb − d` in the patch.
    pub depth: f64,
    /// Sum of the pairs' lens volumes.
    pub volume: f64,
    /// Number of leaf pairs.
    pub pairs: u32,
}

/// Running sums of one patch (A's frame).
#[derive(Debug, Clone, Copy)]
pub(crate) struct PatchAcc {
    seed: DVec3,
    vol: f64,
    vg: DVec3,
    vu: DVec3,
    depth: f64,
    pairs: u32,
}

/// Result of [`Pair::penetration`](crate::Pair::penetration). The patches themselves stay in
/// the pair until its next query: [`Pair::patches`](crate::Pair::patches).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Penetration {
    /// Volume of the intersection of the two inner-sphere unions: the sum of the lens
    /// volumes of all overlapping leaf pairs.
    pub volume: f64,
    /// Number of overlapping leaf pairs.
    pub pairs: usize,
    /// Largest leaf-pair overlap `ra + rb − d`.
    pub max_depth: f64,
    /// Contact normal (world): unit `Σ vᵢ·uᵢ`, `uᵢ` the direction from A's sphere centre to
    /// B's of pair `i` and `vᵢ` its lens volume. Zero without penetration.
    pub normal: DVec3,
    /// Force on B (world): `stiffness × volume × normal`. The force on A is its opposite.
    pub force: DVec3,
    /// Torque on A about A's centre of mass (world).
    pub torque_a: DVec3,
    /// Torque on B about B's centre of mass (world).
    pub torque_b: DVec3,
    /// Number of contact patches.
    pub patch_count: usize,
    /// Contact area: the summed areas of the discs where the overlapping leaf spheres'
    /// boundaries meet, which is how fast the volume shrinks per unit of separation
    /// (`−dV/dd` for a motion along every pair's own direction). Zero unless
    /// [`PenetrationOptions::linearize`] is set.
    pub area: f64,
    /// How the force and B's torque change as B moves: what an implicit integrator needs
    /// (see [`ContactStiffness`]). Zero unless [`PenetrationOptions::linearize`] is set.
    pub stiffness: ContactStiffness,
    /// 0 with penetration; otherwise a proved lower bound on the separation.
    pub distance: f64,
    /// Node pairs tested.
    pub visits: u64,
    /// True when the safe-motion bound answered without a traversal.
    pub skipped: bool,
}

/// The linearised penalty wrench: with `δ` a small translation of B and `θ` a small rotation
/// of B about its centre of mass (world frame), B's force and torque change by
/// `−[linear·δ + coupling·θ, couplingᵀ·δ + angular·θ]`. It is the Gauss–Newton part
/// `k Σ aᵢ JᵢJᵢᵀ`, `aᵢ` the area of pair `i`'s lens disc and `Jᵢ = [uᵢ; rᵢ × uᵢ]`: symmetric
/// and positive semi-definite (what an implicit integrator needs to stay stable with stiff
/// contact), leaving out the small terms from the pairs' directions turning.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct ContactStiffness {
    /// Force per translation (force / length).
    pub linear: DMat3,
    /// Force per rotation, and (transposed) torque per translation.
    pub coupling: DMat3,
    /// Torque per rotation (force · length / radian).
    pub angular: DMat3,
}

impl Default for ContactStiffness {
    /// Zero (no contact). By hand: glam's default matrix is the identity.
    fn default() -> ContactStiffness {
        ContactStiffness {
            linear: DMat3::ZERO,
            coupling: DMat3::ZERO,
            angular: DMat3::ZERO,
        }
    }
}

impl ContactStiffness {
    /// The 6×6 matrix `[[linear, coupling], [couplingᵀ, angular]]`, row-major.
    pub fn to_matrix6(&self) -> [[f64; 6]; 6] {
        let mut m = [[0.0; 6]; 6];
        let (l, c, a) = (
            self.linear.to_cols_array_2d(),
            self.coupling.to_cols_array_2d(),
            self.angular.to_cols_array_2d(),
        );
        for i in 0..3 {
            for j in 0..3 {
                // Column-major sources: l[j][i] is row i, column j.
                m[i][j] = l[j][i];
                m[i][j + 3] = c[j][i];
                m[i + 3][j] = c[i][j];
                m[i + 3][j + 3] = a[j][i];
            }
        }
        m
    }

    /// Rotated into another frame: `R K Rᵀ` block by block.
    pub(crate) fn rotated(&self, r: DMat3) -> ContactStiffness {
        let rt = r.transpose();
        ContactStiffness {
            linear: r * self.linear * rt,
            coupling: r * self.coupling * rt,
            angular: r * self.angular * rt,
        }
    }
}

/// `u vᵀ`.
#[inline]
fn outer(u: DVec3, v: DVec3) -> DMat3 {
    DMat3::from_cols(u * v.x, u * v.y, u * v.z)
}

/// The cross-product matrix `[c]×` (`[c]× v = c × v`).
fn cross_matrix(c: DVec3) -> DMat3 {
    DMat3::from_cols(
        DVec3::new(0.0, c.z, -c.y),
        DVec3::new(-c.z, 0.0, c.x),
        DVec3::new(c.y, -c.x, 0.0),
    )
}

/// Sums over the overlapping leaf pairs (A's frame); with `L` also the contact area and the
/// linearised wrench (a type parameter, so that the plain query's loop carries none of it:
/// a run-time flag measured +15 % at the p99 of deep contact).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Sums<const L: bool> {
    pub volume: f64,
    /// Σ v·u.
    pub vu: DVec3,
    /// Σ v·(g × u), g the lens centroid.
    pub vgu: DVec3,
    pub max_depth: f64,
    pub pairs: usize,
    /// Σ a, a the lens disc's area.
    pub area: f64,
    /// Σ a·u uᵀ.
    pub auu: DMat3,
    /// Σ a·u sᵀ, s = g × u.
    pub aus: DMat3,
    /// Σ a·s sᵀ.
    pub ass: DMat3,
}

impl<const L: bool> Default for Sums<L> {
    // By hand: glam's default matrix is the identity, not zero.
    fn default() -> Sums<L> {
        Sums {
            volume: 0.0,
            vu: DVec3::ZERO,
            vgu: DVec3::ZERO,
            max_depth: 0.0,
            pairs: 0,
            area: 0.0,
            auu: DMat3::ZERO,
            aus: DMat3::ZERO,
            ass: DMat3::ZERO,
        }
    }
}

impl<const L: bool> Sums<L> {
    /// Adds one overlapping leaf pair (A's centre and radius, B's transformed centre and
    /// radius, all f32); returns its (volume, centroid, direction, depth).
    #[inline]
    pub(crate) fn add(
        &mut self,
        ca: [f32; 3],
        ra: f32,
        cb: [f32; 3],
        rb: f32,
    ) -> (f64, DVec3, DVec3, f64) {
        let ca = DVec3::new(ca[0] as f64, ca[1] as f64, ca[2] as f64);
        let cbd = DVec3::new(cb[0] as f64, cb[1] as f64, cb[2] as f64);
        let (ra, rb) = (ra as f64, rb as f64);
        let (u, d) = direction(ca, cbd);
        let (v, g) = lens(ra, rb, d);
        let p = ca + u * g;
        let depth = ra + rb - d;
        let s = p.cross(u);
        self.pairs += 1;
        self.volume += v;
        self.vu += u * v;
        self.vgu += s * v;
        self.max_depth = self.max_depth.max(depth);
        if L {
            let a = lens_area(ra, rb, d);
            self.area += a;
            let au = u * a;
            self.auu += outer(au, u);
            self.aus += outer(au, s);
            self.ass += outer(s * a, s);
        }
        (v, p, u, depth)
    }

    /// Adds a pair of node spheres not refined (the time-critical query ran out of budget)
    /// as if it were one overlap of volume `v` (its bound) along its centres' direction, so
    /// that the force of an unfinished query still pushes the right way with about the
    /// right size. Its area is the node lens's scaled by `v` over the node lens's volume.
    /// Counts in neither `pairs` nor `max_depth`.
    #[inline]
    pub(crate) fn add_coarse(&mut self, ca: [f32; 3], ra: f32, cb: [f32; 3], rb: f32, v: f64) {
        let ca = DVec3::new(ca[0] as f64, ca[1] as f64, ca[2] as f64);
        let cbd = DVec3::new(cb[0] as f64, cb[1] as f64, cb[2] as f64);
        let (ra, rb) = (ra as f64, rb as f64);
        let (u, d) = direction(ca, cbd);
        let (lv, g) = lens(ra, rb, d);
        let p = ca + u * g;
        let s = p.cross(u);
        self.volume += v;
        self.vu += u * v;
        self.vgu += s * v;
        if L && lv > 0.0 {
            let a = lens_area(ra, rb, d) * (v / lv).min(1.0);
            self.area += a;
            let au = u * a;
            self.auu += outer(au, u);
            self.aus += outer(au, s);
            self.ass += outer(s * a, s);
        }
    }

    /// The [`ContactStiffness`] (A's frame) of penalty stiffness `k`, rotations about
    /// `com_b` (A's frame).
    pub(crate) fn stiffness(&self, k: f64, com_b: DVec3) -> ContactStiffness {
        // Jᵢ = [u; s − C u] with C = [com_b]×: the lever arm from B's centre of mass.
        let c = cross_matrix(com_b);
        let ct = c.transpose();
        let coupling = self.aus - self.auu * ct;
        let angular = self.ass - self.aus.transpose() * ct - c * self.aus + c * self.auu * ct;
        ContactStiffness {
            linear: self.auu * k,
            coupling: coupling * k,
            angular: angular * k,
        }
    }

    /// (normal, force on B, torque on A, torque on B) in A's frame, torques about `com_a`
    /// and `com_b` (A's frame). The per-pair forces `s·vᵢ·uᵢ` are scaled so that they sum to
    /// the force `k·V·n`.
    pub(crate) fn wrench(
        &self,
        k: f64,
        com_a: DVec3,
        com_b: DVec3,
    ) -> (DVec3, DVec3, DVec3, DVec3) {
        let len = self.vu.length();
        if len <= 0.0 || self.volume <= 0.0 {
            return (DVec3::ZERO, DVec3::ZERO, DVec3::ZERO, DVec3::ZERO);
        }
        let n = self.vu / len;
        let s = k * self.volume / len;
        let force = n * (k * self.volume);
        let torque_b = (self.vgu - com_b.cross(self.vu)) * s;
        let torque_a = -(self.vgu - com_a.cross(self.vu)) * s;
        (n, force, torque_a, torque_b)
    }
}

/// Adds a pair to the nearest patch within `radius`, or opens a new one while fewer than
/// `max` exist, else adds it to the nearest.
#[inline]
fn assign_patch(
    acc: &mut Vec<PatchAcc>,
    max: usize,
    r2: f64,
    v: f64,
    p: DVec3,
    u: DVec3,
    depth: f64,
) {
    if max == 0 {
        return;
    }
    let mut best = usize::MAX;
    let mut bd = f64::INFINITY;
    for (i, pa) in acc.iter().enumerate() {
        let dd = (pa.seed - p).length_squared();
        if dd < bd {
            bd = dd;
            best = i;
        }
    }
    if best == usize::MAX || (bd > r2 && acc.len() < max) {
        acc.push(PatchAcc {
            seed: p,
            vol: 0.0,
            vg: DVec3::ZERO,
            vu: DVec3::ZERO,
            depth: 0.0,
            pairs: 0,
        });
        best = acc.len() - 1;
    }
    let pa = &mut acc[best];
    pa.vol += v;
    pa.vg += p * v;
    pa.vu += u * v;
    pa.depth = pa.depth.max(depth);
    pa.pairs += 1;
}

/// Penetration volume of `a` at `pose_a` and `b` at `pose_b` (world poses), with the contact
/// normal, force, torques about both centres of mass and contact patches.
///
/// Depth-first over the overlapping node pairs (larger sphere refined first), summing the
/// exact lens volume of every overlapping leaf pair.
#[allow(clippy::too_many_arguments)]
pub(crate) fn penetration(
    ctx: &Ctx,
    ia: &TreeInfo,
    ib: &TreeInfo,
    desc: &mut Descent,
    front: &mut Front,
    sep: &mut Option<SeparationRecord>,
    s: &mut PenetrationScratch,
    opts: &PenetrationOptions,
) -> Penetration {
    if opts.linearize {
        penetration_sums::<true>(ctx, ia, ib, desc, front, sep, s, opts)
    } else {
        penetration_sums::<false>(ctx, ia, ib, desc, front, sep, s, opts)
    }
}

/// [`penetration`] with the sums of `L` (see [`Sums`]).
#[allow(clippy::too_many_arguments)]
fn penetration_sums<const L: bool>(
    ctx: &Ctx,
    ia: &TreeInfo,
    ib: &TreeInfo,
    desc: &mut Descent,
    front: &mut Front,
    sep: &mut Option<SeparationRecord>,
    s: &mut PenetrationScratch,
    opts: &PenetrationOptions,
) -> Penetration {
    let pose_a = &ctx.pose_a;
    s.patch_acc.clear();
    s.patches.clear();
    let mut visits = 0u64;
    let mut min_sep = f32::INFINITY;
    let mut sums = Sums::<L>::default();
    let mut skipped = false;
    let use_front = match opts.tracking {
        Tracking::Front => true,
        Tracking::Traversal => false,
        Tracking::Auto => ia.nodes + ib.nodes <= AUTO_FRONT_NODES,
    };
    let safe = if opts.safe_motion && !use_front {
        safe_separation(ia, ib, *sep, &ctx.rel).filter(|&d| d > 0.0)
    } else {
        None
    };
    if let Some(d) = safe {
        skipped = true;
        min_sep = d as f32;
    } else {
        let c0 = ctx.xf(0);
        let (ov, lbr) = ctx.test(0, 0, c0);
        visits += 1;
        let r2 = {
            let r = if opts.patch_radius > 0.0 {
                opts.patch_radius
            } else {
                0.125 * (ctx.a[0].r.min(ctx.b[0].r) as f64)
            };
            r * r
        };
        let maxp = opts.max_patches;
        let (na, nb) = (ctx.a, ctx.b);
        if use_front {
            visits = front.update(ctx, ib);
            for h in &front.hits {
                let n = &na[h.a as usize];
                let (v, p, u, depth) = sums.add([n.x, n.y, n.z], n.r, h.c, nb[h.b as usize].r);
                assign_patch(&mut s.patch_acc, maxp, r2, v, p, u, depth);
            }
            if front.hits.is_empty() {
                min_sep = front.margin().max(0.0) as f32;
            }
        } else if !ov {
            min_sep = lbr;
        } else if na[0].is_leaf() && nb[0].is_leaf() {
            let (v, p, u, depth) = sums.add([na[0].x, na[0].y, na[0].z], na[0].r, c0, nb[0].r);
            assign_patch(&mut s.patch_acc, maxp, r2, v, p, u, depth);
        } else if blocked(ctx) {
            // Fan-outs ≤ 4: blocked steps (4×4 child pairs at a time).
            let stack = &mut desc.tstack;
            stack.clear();
            stack.push(TItem::new(ctx, 0, 0, c0, 0));
            let patch_acc = &mut s.patch_acc;
            let mut leaf = |i: u32, j: u32, cb: [f32; 3]| {
                let n = &na[i as usize];
                let (v, p, u, depth) = sums.add([n.x, n.y, n.z], n.r, cb, nb[j as usize].r);
                assign_patch(patch_acc, maxp, r2, v, p, u, depth);
            };
            overlap_pairs_dispatch(ctx, stack, &mut min_sep, &mut visits, &mut leaf);
        } else {
            desc.stack.clear();
            desc.stack.push(Item {
                a: 0,
                b: 0,
                c: c0,
                depth: 0,
            });
            let stack = &mut desc.stack;
            let patch_acc = &mut s.patch_acc;
            while let Some(e) = stack.pop() {
                let visit = |i: u32, j: u32, cb: [f32; 3], d2: f32, sr: f32, leafs: bool| {
                    visits += 1;
                    if d2 < sr * sr {
                        if leafs {
                            let n = &na[i as usize];
                            let (v, p, u, depth) =
                                sums.add([n.x, n.y, n.z], n.r, cb, nb[j as usize].r);
                            assign_patch(patch_acc, maxp, r2, v, p, u, depth);
                        } else {
                            ctx.prefetch(i, j);
                            stack.push(Item {
                                a: i,
                                b: j,
                                c: cb,
                                depth: 0,
                            });
                        }
                    } else if d2 < (sr + min_sep) * (sr + min_sep) {
                        let lb = d2.sqrt() - sr;
                        if lb < min_sep {
                            min_sep = lb;
                        }
                    }
                };
                expand_larger(ctx, e.a, e.b, e.c, visit);
            }
        }
    }
    let com_a = ia.center_of_mass;
    let com_b = ctx.rel.transform_point(ib.center_of_mass);
    let (n, f, ta, tb) = sums.wrench(opts.stiffness, com_a, com_b);
    let stiffness = sums
        .stiffness(opts.stiffness, com_b)
        .rotated(DMat3::from_quat(pose_a.rotation));
    let rot = |v: DVec3| pose_a.transform_vector(v);
    for pa in &s.patch_acc {
        s.patches.push(Patch {
            point: pose_a.transform_point(if pa.vol > 0.0 {
                pa.vg / pa.vol
            } else {
                pa.seed
            }),
            normal: rot(pa.vu.normalize_or_zero()),
            depth: pa.depth,
            volume: pa.vol,
            pairs: pa.pairs,
        });
    }
    let distance = if sums.pairs > 0 {
        if !skipped {
            *sep = None;
        }
        0.0
    } else {
        let d = min_sep.max(0.0) as f64;
        if !skipped {
            record(sep, ctx, d);
        }
        d
    };
    Penetration {
        volume: sums.volume,
        pairs: sums.pairs,
        max_depth: sums.max_depth,
        normal: rot(n),
        force: rot(f),
        torque_a: rot(ta),
        torque_b: rot(tb),
        patch_count: s.patches.len(),
        area: sums.area,
        stiffness,
        distance,
        visits,
        skipped,
    }
}

/// The answer at a far pose ([`far`](super::kernel::far)): no penetration, no patches, the
/// bodies at least the root spheres' separation apart.
pub(crate) fn separated(s: &mut PenetrationScratch, separation: f64) -> Penetration {
    s.patches.clear();
    Penetration {
        volume: 0.0,
        pairs: 0,
        max_depth: 0.0,
        normal: DVec3::ZERO,
        force: DVec3::ZERO,
        torque_a: DVec3::ZERO,
        torque_b: DVec3::ZERO,
        patch_count: 0,
        area: 0.0,
        stiffness: ContactStiffness::default(),
        distance: separation,
        visits: 1,
        skipped: false,
    }
}
