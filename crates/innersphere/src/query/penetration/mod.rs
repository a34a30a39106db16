//! Penetration volume, force, torque and contact patches (beyond the paper).
//!
//! Leaves within one tree are disjoint, so the sum of the lens volumes of all overlapping
//! leaf pairs is exactly the volume of the intersection of the two sphere unions.

mod answer;
mod floor;
mod options;
mod patches;
mod sums;

pub use answer::{ContactStiffness, Patch, Penetration};
pub(crate) use floor::{check as check_leaves, overlapping_leaves, penetration_of_leaves};
pub use options::{PenetrationOptions, Tracking, AUTO_FRONT_NODES, MAX_STIFFNESS};
pub(crate) use patches::PenetrationScratch;
pub(crate) use sums::Sums;

use crate::query::kernel::block::TItem;
use crate::query::kernel::info::TreeInfo;
use crate::query::kernel::separation::{record, safe_separation, SeparationRecord};
use crate::query::kernel::{expand_larger, Ctx, Item};
use crate::query::search::descent::{blocked, overlap_pairs_dispatch, Descent};
use crate::query::search::front::Front;
use glam::DVec3;
use sums::{add_hits, LeafBatch, Sink};

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
    begin_patches(ctx, s, opts);
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
    let mut to = Sink {
        sums: &mut sums,
        patches: &mut s.acc,
    };
    if let Some(d) = safe {
        skipped = true;
        min_sep = d as f32;
    } else {
        let (na, nb) = (ctx.a, ctx.b);
        if use_front {
            visits = front.update(ctx, ib);
            add_hits(ctx.simd, &front.hits, na, nb, &mut to);
            if front.hits.is_empty() {
                min_sep = front.margin().max(0.0) as f32;
            }
        } else {
            let mut batch = LeafBatch::default();
            let mut leaf = |i: u32, j: u32, cb: [f32; 3]| {
                batch.push(&na[i as usize], &nb[j as usize], cb, &mut to);
            };
            traverse(ctx, desc, &mut min_sep, &mut visits, &mut leaf);
            batch.flush(&mut to);
        }
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
    let mut p = answer(ctx, ia, ib, &mut sums, s, opts, distance);
    p.visits = visits;
    p.skipped = skipped;
    p
}

/// Empties the patches' sums for a query with `opts`.
fn begin_patches(ctx: &Ctx, s: &mut PenetrationScratch, opts: &PenetrationOptions) {
    let radius = if opts.patch_radius > 0.0 {
        opts.patch_radius
    } else {
        0.125 * (ctx.a[0].r.min(ctx.b[0].r) as f64)
    };
    s.acc.begin(opts.max_patches, radius);
}

/// Every overlapping leaf pair at `ctx`'s poses, to `leaf` (A's leaf, B's leaf, B's centre
/// in A's frame), depth first from the roots (larger sphere refined first; blocked steps on
/// fan-outs ≤ 4). `min_sep` ends as a lower bound on the separation when there is none;
/// `visits` counts the node pairs tested.
fn traverse(
    ctx: &Ctx,
    desc: &mut Descent,
    min_sep: &mut f32,
    visits: &mut u64,
    leaf: &mut impl FnMut(u32, u32, [f32; 3]),
) {
    let c0 = ctx.xf(0);
    let (ov, lbr) = ctx.test(0, 0, c0);
    *visits += 1;
    let (na, nb) = (ctx.a, ctx.b);
    if !ov {
        *min_sep = lbr;
    } else if na[0].is_leaf() && nb[0].is_leaf() {
        leaf(0, 0, c0);
    } else if blocked(ctx) {
        // Fan-outs ≤ 4: blocked steps (4×4 child pairs at a time).
        let stack = &mut desc.tstack;
        stack.clear();
        stack.push(TItem::new(ctx, 0, 0, c0, 0));
        overlap_pairs_dispatch(ctx, stack, min_sep, visits, leaf);
    } else {
        desc.stack.clear();
        desc.stack.push(Item {
            a: 0,
            b: 0,
            c: c0,
            depth: 0,
        });
        let stack = &mut desc.stack;
        while let Some(e) = stack.pop() {
            let visit = |i: u32, j: u32, cb: [f32; 3], d2: f32, sr: f32, leafs: bool| {
                *visits += 1;
                if d2 < sr * sr {
                    if leafs {
                        leaf(i, j, cb);
                    } else {
                        ctx.prefetch(i, j);
                        stack.push(Item {
                            a: i,
                            b: j,
                            c: cb,
                            depth: 0,
                        });
                    }
                } else if d2 < (sr + *min_sep) * (sr + *min_sep) {
                    let lb = d2.sqrt() - sr;
                    if lb < *min_sep {
                        *min_sep = lb;
                    }
                }
            };
            expand_larger(ctx, e.a, e.b, e.c, visit);
        }
    }
}

/// The answer from the settled-to-be `sums` (A's frame) and the patches being summed in `s`:
/// the wrench, the stiffness and the patches in the world frame; `visits` 0, not skipped.
fn answer<const L: bool>(
    ctx: &Ctx,
    ia: &TreeInfo,
    ib: &TreeInfo,
    sums: &mut Sums<L>,
    s: &mut PenetrationScratch,
    opts: &PenetrationOptions,
    distance: f64,
) -> Penetration {
    sums.settle();
    let com_a = ia.center_of_mass;
    let com_b = ctx.rel.transform_point(ib.center_of_mass);
    let (n, f, ta, tb) = sums.wrench(opts.stiffness, com_a, com_b);
    let stiffness = sums.stiffness(opts.stiffness, com_b);
    s.acc.finish(&mut s.patches);
    Penetration {
        volume: sums.volume,
        pairs: sums.pairs,
        max_depth: sums.max_depth,
        normal: n,
        force: f,
        torque_a: ta,
        torque_b: tb,
        patch_count: s.patches.len(),
        area: sums.area,
        stiffness,
        distance,
        visits: 0,
        skipped: false,
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
