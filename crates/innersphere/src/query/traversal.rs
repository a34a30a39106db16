//! The paper's traversals (section III): the distance traversal (III-A), the backtracking
//! traversal (III-B, Algorithms 1–2) and the multipoint traversal (III-C).
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

use super::geometry::{make_contact, Contact};
use super::state::{pair_key, test_pair, Ctx, PairState, StackEntry, TbCache};
use super::Pose;
use crate::tree::NO_PARENT;
use crate::SphereTree;

/// Options of [`distance_traversal`] and [`backtracking`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactOptions {
    /// Skip the traversal (answer "no contact") while the last proved separation cannot have
    /// been closed by the relative motion since ([`PairState::safe_separation`]).
    pub safe_motion: bool,
}

impl Default for ContactOptions {
    fn default() -> Self {
        ContactOptions { safe_motion: true }
    }
}

/// Result of [`distance_traversal`] and [`backtracking`].
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct ContactQuery {
    /// The first overlapping leaf pair found, if any.
    pub contact: Option<Contact>,
    /// 0 with a contact; otherwise a proved lower bound on the distance between the two
    /// inner-sphere packings (the minimum over the separated pairs where the descent stopped,
    /// or the safe-motion bound when skipped).
    pub distance: f64,
    /// Node pairs tested.
    pub visits: u64,
    /// True when the safe-motion bound answered without a traversal.
    pub skipped: bool,
}

impl ContactQuery {
    /// True when the packings overlap.
    pub fn in_contact(&self) -> bool {
        self.contact.is_some()
    }
}

/// Options of [`multipoint`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MultipointOptions {
    /// At most this many contacts (no cap).
    pub k: usize,
    /// At most one contact below each traversal pair at this depth (pairs of nodes at this
    /// depth; a contact at a shallower leaf pair stands for itself).
    pub split_depth: u32,
    /// Keep last frame's contacts that still overlap and backtrack from the others.
    pub reuse: bool,
    /// Skip (answer "no contacts") while the last proved separation holds.
    pub safe_motion: bool,
}

impl Default for MultipointOptions {
    fn default() -> Self {
        MultipointOptions {
            k: 4,
            split_depth: 4,
            reuse: true,
            safe_motion: true,
        }
    }
}

/// Result of [`multipoint`]; the contacts are borrowed from the [`PairState`].
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct MultipointResult<'s> {
    /// Up to `k` contacts, at most one per split-depth pair; reused ones first.
    pub contacts: &'s [Contact],
    /// How many of them were last frame's contacts, still valid.
    pub reused: usize,
    /// 0 with contacts; otherwise a proved lower bound on the separation.
    pub distance: f64,
    /// Node pairs tested.
    pub visits: u64,
    /// True when the safe-motion bound answered without a traversal.
    pub skipped: bool,
}

/// Key that never matches a node pair.
const NO_PAIR: u64 = u64::MAX;

/// Refines the overlapping pair `e` into all child pairs (simultaneous descent), pushing the
/// overlapping ones that are neither `skip` nor excluded (exclusions are checked for pairs of
/// depth ≤ `split`), in reverse so that they pop in child order; separated ones lower
/// `min_sep`.
#[inline]
#[allow(clippy::too_many_arguments)]
fn expand_sim(
    ctx: &Ctx,
    tb: &mut TbCache,
    stack: &mut Vec<StackEntry>,
    excl: &[u64],
    split: u32,
    skip: u64,
    e: StackEntry,
    min_sep: &mut f32,
    visits: &mut u64,
) {
    let a = ctx.a;
    let b = ctx.b;
    let (ia, ib) = (e.a as usize, e.b as usize);
    let (fa, na) = if a.child_count[ia] != 0 {
        (a.first_child[ia] as usize, a.child_count[ia] as usize)
    } else {
        (ia, 1)
    };
    let (fb, nb) = if b.child_count[ib] != 0 {
        let f = b.first_child[ib] as usize;
        let n = b.child_count[ib] as usize;
        for j in f..f + n {
            tb.xf(&ctx.rel32, b, j);
        }
        (f, n)
    } else {
        (ib, 1)
    };
    let depth = e.depth + 1;
    let check = depth <= split && !excl.is_empty();
    let xs = &a.x[fa..fa + na];
    let ys = &a.y[fa..fa + na];
    let zs = &a.z[fa..fa + na];
    let rs = &a.r[fa..fa + na];
    let cs = &a.child_count[fa..fa + na];
    for j in (fb..fb + nb).rev() {
        let cb = tb.get(j);
        let rb = b.r[j];
        let jleaf = b.child_count[j] == 0;
        for k in (0..na).rev() {
            let leafs = jleaf && cs[k] == 0;
            let s = rs[k] + rb + if leafs { 0.0 } else { ctx.slack };
            let dx = xs[k] - cb[0];
            let dy = ys[k] - cb[1];
            let dz = zs[k] - cb[2];
            let d2 = dx * dx + dy * dy + dz * dz;
            if d2 < s * s {
                let key = pair_key((fa + k) as u32, j as u32);
                if key == skip || (check && excl.binary_search(&key).is_ok()) {
                    continue;
                }
                stack.push(StackEntry {
                    a: (fa + k) as u32,
                    b: j as u32,
                    depth,
                });
            } else {
                let lb = d2.sqrt() - s;
                if lb < *min_sep {
                    *min_sep = lb;
                }
            }
        }
        *visits += na as u64;
    }
}

/// Depth-first search over the stack until an overlapping leaf pair is popped.
#[allow(clippy::too_many_arguments)]
fn dfs_sim(
    ctx: &Ctx,
    tb: &mut TbCache,
    stack: &mut Vec<StackEntry>,
    excl: &[u64],
    split: u32,
    skip: u64,
    min_sep: &mut f32,
    visits: &mut u64,
) -> Option<StackEntry> {
    while let Some(e) = stack.pop() {
        if ctx.a.child_count[e.a as usize] == 0 && ctx.b.child_count[e.b as usize] == 0 {
            return Some(e);
        }
        expand_sim(ctx, tb, stack, excl, split, skip, e, min_sep, visits);
    }
    None
}

/// Ancestors of `n`, root first (`out[d]` is the ancestor at depth `d`).
fn chain(tree: &SphereTree, n: u32, out: &mut Vec<u32>) {
    out.clear();
    let mut n = n;
    loop {
        out.push(n);
        let p = tree.parent[n as usize];
        if p == NO_PARENT {
            break;
        }
        n = p;
    }
    out.reverse();
}

/// The ancestor of `n` at `depth` (`n` itself when it is not deeper).
fn ancestor_at(tree: &SphereTree, mut n: u32, depth: u32) -> u32 {
    while tree.depth[n as usize] as u32 > depth {
        n = tree.parent[n as usize];
    }
    n
}

/// Key of the traversal pair at `split` depth above leaf pair (`la`, `lb`).
fn split_key(a: &SphereTree, la: u32, b: &SphereTree, lb: u32, split: u32) -> u64 {
    pair_key(ancestor_at(a, la, split), ancestor_at(b, lb, split))
}

/// Inserts into a sorted vector; false when already present.
fn insert_sorted(v: &mut Vec<u64>, key: u64) -> bool {
    match v.binary_search(&key) {
        Ok(_) => false,
        Err(p) => {
            v.insert(p, key);
            true
        }
    }
}

/// The safe-motion answer, when enabled and positive.
fn safe_skip(st: &PairState, ctx: &Ctx, on: bool) -> Option<f64> {
    if !on {
        return None;
    }
    st.safe_separation_rel(&ctx.rel).filter(|&s| s > 0.0)
}

/// Root test, then a full traversal from the roots.
fn full(ctx: &Ctx, st: &mut PairState, min_sep: &mut f32, visits: &mut u64) -> Option<(u32, u32)> {
    st.stack.clear();
    let (ov, lb) = test_pair(ctx, 0, 0, st.tb.get(0));
    *visits += 1;
    if !ov {
        *min_sep = min_sep.min(lb);
        return None;
    }
    st.stack.push(StackEntry {
        a: 0,
        b: 0,
        depth: 0,
    });
    dfs_sim(
        ctx,
        &mut st.tb,
        &mut st.stack,
        &[],
        u32::MAX,
        NO_PAIR,
        min_sep,
        visits,
    )
    .map(|e| (e.a, e.b))
}

/// Climbs from the stale leaf pair (`la`, `lb`) toward the root (Algorithms 1–2): the leaf
/// pair itself, then each traversal pair above it from level `top − 1` down to `stop`, each
/// searched without the already visited child pair. Leaves the chains in `st.anc_*`.
fn climb(
    ctx: &Ctx,
    st: &mut PairState,
    la: u32,
    lb: u32,
    stop: u32,
    min_sep: &mut f32,
    visits: &mut u64,
) -> Option<(u32, u32)> {
    let (a, b) = (ctx.a, ctx.b);
    let cb = st.tb.xf(&ctx.rel32, b, lb as usize);
    let (ov, d) = test_pair(ctx, la as usize, lb as usize, cb);
    *visits += 1;
    if ov {
        return Some((la, lb));
    }
    *min_sep = min_sep.min(d);
    chain(a, la, &mut st.anc_a);
    chain(b, lb, &mut st.anc_b);
    let da = st.anc_a.len() - 1;
    let db = st.anc_b.len() - 1;
    let top = da.max(db);
    let path = |anc_a: &[u32], anc_b: &[u32], k: usize| (anc_a[k.min(da)], anc_b[k.min(db)]);
    for k in (stop as usize..top).rev() {
        let (pa, pb) = path(&st.anc_a, &st.anc_b, k);
        let cb = st.tb.xf(&ctx.rel32, b, pb as usize);
        let (ov, d) = test_pair(ctx, pa as usize, pb as usize, cb);
        *visits += 1;
        if !ov {
            *min_sep = min_sep.min(d);
            continue;
        }
        let (na, nb) = path(&st.anc_a, &st.anc_b, k + 1);
        st.stack.clear();
        st.stack.push(StackEntry {
            a: pa,
            b: pb,
            depth: k as u32,
        });
        let skip = pair_key(na, nb);
        if let Some(e) = dfs_sim(
            ctx,
            &mut st.tb,
            &mut st.stack,
            &[],
            u32::MAX,
            skip,
            min_sep,
            visits,
        ) {
            return Some((e.a, e.b));
        }
    }
    None
}

/// Result of a contact traversal, recording the separation for the safe-motion skip.
fn finish(
    ctx: &Ctx,
    st: &mut PairState,
    found: Option<(u32, u32)>,
    min_sep: f32,
    visits: u64,
) -> ContactQuery {
    match found {
        Some((la, lb)) => {
            st.separation = None;
            let cb = st.tb.get(lb as usize);
            ContactQuery {
                contact: Some(make_contact(ctx.a, la, ctx.b, lb, cb, &ctx.pose_a)),
                distance: 0.0,
                visits,
                skipped: false,
            }
        }
        None => {
            let d = min_sep.max(0.0) as f64;
            st.record_separation(ctx, d);
            ContactQuery {
                contact: None,
                distance: d,
                visits,
                skipped: false,
            }
        }
    }
}

fn skipped(d: f64) -> ContactQuery {
    ContactQuery {
        contact: None,
        distance: d,
        visits: 0,
        skipped: true,
    }
}

/// The paper's distance traversal (III-A): from the roots, descend while the spheres
/// overlap, stop at the first overlapping leaf pair (the contact) or when every branch has
/// reached a separated pair (no contact; `distance` = the smallest separation seen there).
pub fn distance_traversal(
    a: &SphereTree,
    pose_a: &Pose,
    b: &SphereTree,
    pose_b: &Pose,
    st: &mut PairState,
    opts: &ContactOptions,
) -> ContactQuery {
    let ctx = st.begin(a, pose_a, b, pose_b);
    if let Some(d) = safe_skip(st, &ctx, opts.safe_motion) {
        return skipped(d);
    }
    let mut min_sep = f32::INFINITY;
    let mut visits = 0;
    let found = full(&ctx, st, &mut min_sep, &mut visits);
    finish(&ctx, st, found, min_sep, visits)
}

/// The paper's backtracking traversal (III-B, Algorithms 1–2): restart from the previous
/// frame's contact pair; if it no longer overlaps, search the traversal pair above it, then
/// climb toward the root, each time skipping the subtree pair already searched. Without a
/// previous contact it is the full distance traversal. Same contact answer as
/// [`distance_traversal`] on every frame.
pub fn backtracking(
    a: &SphereTree,
    pose_a: &Pose,
    b: &SphereTree,
    pose_b: &Pose,
    st: &mut PairState,
    opts: &ContactOptions,
) -> ContactQuery {
    let ctx = st.begin(a, pose_a, b, pose_b);
    if let Some(d) = safe_skip(st, &ctx, opts.safe_motion) {
        return skipped(d);
    }
    let mut min_sep = f32::INFINITY;
    let mut visits = 0;
    let found = match st.bt_pair {
        None => full(&ctx, st, &mut min_sep, &mut visits),
        Some((la, lb)) => {
            // Broad phase first.
            let (ov, lbr) = test_pair(&ctx, 0, 0, st.tb.get(0));
            visits += 1;
            if ov {
                climb(&ctx, st, la, lb, 0, &mut min_sep, &mut visits)
            } else {
                min_sep = lbr;
                None
            }
        }
    };
    if found.is_some() {
        st.bt_pair = found;
    }
    finish(&ctx, st, found, min_sep, visits)
}

/// The paper's multipoint traversal (III-C): up to `k` contacts, at most one below each
/// traversal pair at the split depth.
///
/// Each frame: (1) last frame's contacts that still overlap are kept and their split-depth
/// pairs excluded; (2) from each stale one, backtrack within its split-depth pair for a
/// replacement (the pair is excluded afterwards, with or without one); (3) while fewer than
/// `k`, a traversal from the roots skipping excluded pairs; after each contact found the
/// search leaves that contact's split-depth pair.
pub fn multipoint<'s>(
    a: &SphereTree,
    pose_a: &Pose,
    b: &SphereTree,
    pose_b: &Pose,
    st: &'s mut PairState,
    opts: &MultipointOptions,
) -> MultipointResult<'s> {
    let ctx = st.begin(a, pose_a, b, pose_b);
    let k = opts.k;
    let split = opts.split_depth;
    st.contacts.clear();
    st.excluded.clear();
    st.stale.clear();
    let mut min_sep = f32::INFINITY;
    let mut visits = 0u64;
    let mut reused = 0;
    let done = |st: &'s mut PairState, min_sep: f32, visits, reused, skipped| {
        st.mp_prev.clear();
        st.mp_prev
            .extend(st.contacts.iter().map(|c| (c.leaf_a, c.leaf_b)));
        let distance = if st.contacts.is_empty() {
            min_sep.max(0.0) as f64
        } else {
            0.0
        };
        MultipointResult {
            contacts: &st.contacts,
            reused,
            distance,
            visits,
            skipped,
        }
    };
    if k == 0 {
        return done(st, 0.0, 0, 0, false);
    }
    if st.mp_prev.is_empty() {
        if let Some(d) = safe_skip(st, &ctx, opts.safe_motion) {
            return done(st, d as f32, 0, 0, true);
        }
    }
    let (ov, lbr) = test_pair(&ctx, 0, 0, st.tb.get(0));
    visits += 1;
    if !ov {
        st.record_separation(&ctx, lbr as f64);
        return done(st, lbr, visits, 0, false);
    }
    // (1) Still valid contacts.
    if opts.reuse {
        for idx in 0..st.mp_prev.len() {
            let (la, lb) = st.mp_prev[idx];
            let cb = st.tb.xf(&ctx.rel32, b, lb as usize);
            let (ov, d) = test_pair(&ctx, la as usize, lb as usize, cb);
            visits += 1;
            if !ov {
                min_sep = min_sep.min(d);
                st.stale.push((la, lb));
            } else if st.contacts.len() < k
                && insert_sorted(&mut st.excluded, split_key(a, la, b, lb, split))
            {
                st.contacts.push(make_contact(a, la, b, lb, cb, pose_a));
                reused += 1;
            }
        }
    }
    // (2) Backtrack from stale contacts within their split-depth pairs.
    for idx in 0..st.stale.len() {
        if st.contacts.len() >= k {
            break;
        }
        let (la, lb) = st.stale[idx];
        let key = split_key(a, la, b, lb, split);
        if st.excluded.binary_search(&key).is_ok() {
            continue;
        }
        let found = climb(&ctx, st, la, lb, split, &mut min_sep, &mut visits);
        insert_sorted(&mut st.excluded, key);
        if let Some((fa, fb)) = found {
            let cb = st.tb.get(fb as usize);
            st.contacts.push(make_contact(a, fa, b, fb, cb, pose_a));
        }
    }
    // (3) Search from the roots for the rest.
    if st.contacts.len() < k && st.excluded.binary_search(&pair_key(0, 0)).is_err() {
        st.stack.clear();
        st.stack.push(StackEntry {
            a: 0,
            b: 0,
            depth: 0,
        });
        while let Some(e) = dfs_sim(
            &ctx,
            &mut st.tb,
            &mut st.stack,
            &st.excluded,
            split,
            NO_PAIR,
            &mut min_sep,
            &mut visits,
        ) {
            let cb = st.tb.get(e.b as usize);
            st.contacts.push(make_contact(a, e.a, b, e.b, cb, pose_a));
            insert_sorted(&mut st.excluded, split_key(a, e.a, b, e.b, split));
            if st.contacts.len() >= k {
                break;
            }
            while st.stack.last().is_some_and(|t| t.depth > split) {
                st.stack.pop();
            }
        }
    }
    if st.contacts.is_empty() {
        st.record_separation(&ctx, min_sep.max(0.0) as f64);
    } else {
        st.separation = None;
    }
    done(st, min_sep, visits, reused, false)
}
