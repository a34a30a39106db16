//! The paper's traversals (section III), kept as the baselines our queries are measured
//! against: the distance traversal (III-A) and the backtracking traversal (III-B, Algorithms
//! 1–2). Both answer what [`Pair::contact`](crate::Pair::contact) answers (same contact on
//! every frame), more slowly; the multipoint traversal (III-C) is
//! [`Pair::multipoint`](crate::Pair::multipoint)'s default. Reached through
//! [`Pair::paper`](crate::Pair::paper).
//!
//! As in the paper, a node pair that overlaps is refined into all pairs of children
//! (simultaneous descent; a leaf stands for itself against the other side's children), in
//! child order, depth first, and the traversal stops at the first overlapping leaf pair.
//! The depth of a pair in this traversal is the larger of its two node depths, so the pair
//! "above" a leaf pair at level `k` is (ancestor of A's leaf at depth `min(k, depth_a)`,
//! ancestor of B's leaf at depth `min(k, depth_b)`).
//!
//! Deviations from the paper's text, all for correctness:
//! * "distance" is never the literal `minDist` of Algorithm 2 (which collapses to 0 as soon
//!   as the roots overlap); when there is no contact it is the minimum over the separated
//!   pairs where the descent stopped, which is a proved lower bound on the distance of the
//!   two sphere sets (the bound the paper uses for its "predefined distance" skip).
//! * Backtracking skips the one already visited *pair* of subtrees when it climbs, not every
//!   pair involving an already visited node (which would skip unvisited pairs), and it climbs
//!   the two ancestor chains as one chain of traversal pairs, so trees of different depths
//!   never fall back to a restart from the roots. Its contact answer equals a full traversal.
//! * Multipoint has no cap on `k` (the paper's code stops at 3).

use super::contact::ContactResult;
use super::kernel::geometry::make_contact;
use super::kernel::info::TreeInfo;
use super::kernel::separation::{record, safe_skip, SeparationRecord};
use super::kernel::{Ctx, Item};
use super::search::descent::{climb, full, Descent};

/// Options of the paper's traversals ([`Paper::distance_traversal`](crate::query::Paper::distance_traversal), [`Paper::backtracking`](crate::query::Paper::backtracking)).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TraversalOptions {
    /// Skip the traversal (answer "no contact") while the last proved separation cannot have
    /// been closed by the relative motion since ([`Pair::safe_separation`](crate::Pair::safe_separation)).
    pub safe_motion: bool,
}

impl Default for TraversalOptions {
    fn default() -> Self {
        TraversalOptions { safe_motion: true }
    }
}

/// Result of a contact traversal, recording the separation for the safe-motion skip.
fn finish(
    ctx: &Ctx,
    sep: &mut Option<SeparationRecord>,
    found: Option<Item>,
    min_sep: f32,
    visits: u64,
) -> ContactResult {
    match found {
        Some(e) => {
            *sep = None;
            ContactResult {
                contact: Some(make_contact(ctx.a, e.a, ctx.b, e.b, e.c)),
                distance: 0.0,
                visits,
                skipped: false,
            }
        }
        None => {
            let d = min_sep.max(0.0) as f64;
            record(sep, ctx, d);
            ContactResult {
                contact: None,
                distance: d,
                visits,
                skipped: false,
            }
        }
    }
}

fn skipped(d: f64) -> ContactResult {
    ContactResult {
        contact: None,
        distance: d,
        visits: 0,
        skipped: true,
    }
}

/// The paper's distance traversal (III-A): from the roots, descend while the spheres
/// overlap, stop at the first overlapping leaf pair (the contact) or when every branch has
/// reached a separated pair (no contact; `distance` = the smallest separation seen there).
pub(crate) fn distance_traversal(
    ctx: &Ctx,
    ia: &TreeInfo,
    ib: &TreeInfo,
    desc: &mut Descent,
    sep: &mut Option<SeparationRecord>,
    opts: &TraversalOptions,
) -> ContactResult {
    if let Some(d) = safe_skip(ia, ib, *sep, ctx, opts.safe_motion) {
        return skipped(d);
    }
    let mut min_sep = f32::INFINITY;
    let mut visits = 0;
    let found = full(ctx, desc, &mut min_sep, &mut visits);
    finish(ctx, sep, found, min_sep, visits)
}

/// The paper's backtracking traversal (III-B, Algorithms 1–2): restart from the previous
/// frame's contact pair; if it no longer overlaps, search the traversal pair above it, then
/// climb toward the root, each time skipping the subtree pair already searched. Without a
/// previous contact it is the full distance traversal. Same contact answer as
/// [`distance_traversal`] on every frame.
pub(crate) fn backtracking(
    ctx: &Ctx,
    ia: &TreeInfo,
    ib: &TreeInfo,
    desc: &mut Descent,
    sep: &mut Option<SeparationRecord>,
    last: &mut Option<(u32, u32)>,
    opts: &TraversalOptions,
) -> ContactResult {
    if let Some(d) = safe_skip(ia, ib, *sep, ctx, opts.safe_motion) {
        return skipped(d);
    }
    let mut min_sep = f32::INFINITY;
    let mut visits = 0;
    let found = match *last {
        None => full(ctx, desc, &mut min_sep, &mut visits),
        Some((la, lb)) => {
            // Broad phase first.
            let (ov, lbr) = ctx.test(0, 0, ctx.xf(0));
            visits += 1;
            if ov {
                climb(ctx, desc, la, lb, 0, &mut min_sep, &mut visits)
            } else {
                min_sep = lbr;
                None
            }
        }
    };
    if let Some(e) = found {
        *last = Some((e.a, e.b));
    }
    finish(ctx, sep, found, min_sep, visits)
}
