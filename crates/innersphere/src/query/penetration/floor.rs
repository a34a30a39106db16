//! The penetration query's output-sensitive floor: its answer summed over given overlapping
//! leaf pairs, with no search. The time of that sum is the work no search can avoid; the
//! query's time over it is the search's overhead (`benches/queries.rs` reports both).

use super::sums::{add_hits, Sink};
use super::Sums;
use super::{answer, begin_patches, traverse, Penetration, PenetrationOptions, PenetrationScratch};
use crate::error::{Error, Result};
use crate::query::kernel::info::{Node, TreeInfo};
use crate::query::kernel::Ctx;
use crate::query::search::descent::Descent;
use crate::query::search::front::Hit;

/// The overlapping leaf pairs at `ctx`'s poses (A's leaf, B's leaf; node indices), in the
/// order of one depth-first traversal, into `out` (emptied first).
pub(crate) fn overlapping_leaves(ctx: &Ctx, desc: &mut Descent, out: &mut Vec<[u32; 2]>) {
    out.clear();
    let (mut min_sep, mut visits) = (f32::INFINITY, 0);
    traverse(ctx, desc, &mut min_sep, &mut visits, &mut |i, j, _| {
        out.push([i, j])
    });
}

/// The penetration answer of the leaf pairs `leaves` alone (node indices, A's then B's):
/// those that overlap at `ctx`'s poses are summed as the query sums its own, in the order
/// given, four at a time. `distance` is 0 and `visits` the number of pairs given. An index
/// that is no leaf of its tree is an error.
pub(crate) fn penetration_of_leaves(
    ctx: &Ctx,
    ia: &TreeInfo,
    ib: &TreeInfo,
    leaves: &[[u32; 2]],
    hits: &mut Vec<Hit>,
    s: &mut PenetrationScratch,
    opts: &PenetrationOptions,
) -> Result<Penetration> {
    hits.clear();
    for (k, &[i, j]) in leaves.iter().enumerate() {
        check(ctx.a, ctx.b, k, i, j)?;
        let c = ctx.xf(j);
        if ctx.test(i, j, c).0 {
            hits.push(Hit::new(i, j, c));
        }
    }
    begin_patches(ctx, s, opts);
    let mut p = if opts.linearize {
        sum::<true>(ctx, ia, ib, hits, s, opts)
    } else {
        sum::<false>(ctx, ia, ib, hits, s, opts)
    };
    p.visits = leaves.len() as u64;
    Ok(p)
}

/// An error unless `i` is a leaf of `na` and `j` one of `nb` (`k`: the pair's place).
#[inline]
pub(crate) fn check(na: &[Node], nb: &[Node], k: usize, i: u32, j: u32) -> Result<()> {
    let is_leaf = |nodes: &[Node], i: u32| nodes.get(i as usize).is_some_and(|n| n.is_leaf());
    if is_leaf(na, i) && is_leaf(nb, j) {
        return Ok(());
    }
    Err(Error::InvalidOption(format!(
        "leaf pair {k} ({i}, {j}) is no pair of leaves of the trees ({} and {} nodes)",
        na.len(),
        nb.len()
    )))
}

/// The answer of `hits` with the sums of `L`.
fn sum<const L: bool>(
    ctx: &Ctx,
    ia: &TreeInfo,
    ib: &TreeInfo,
    hits: &[Hit],
    s: &mut PenetrationScratch,
    opts: &PenetrationOptions,
) -> Penetration {
    let mut sums = Sums::<L>::default();
    let mut to = Sink {
        sums: &mut sums,
        patches: &mut s.acc,
    };
    add_hits(ctx.simd, hits, ctx.a, ctx.b, &mut to);
    answer(ctx, ia, ib, &mut sums, s, opts, 0.0)
}
