//! Multipoint contact (the paper's III-C): up to `k` contacts, at most one below each node
//! pair at a split depth, by the paper's traversal with reuse of last frame's contacts, or
//! (ours) picked from the kinetic front.

use super::kernel::geometry::{make_contact, Contact};
use super::kernel::info::TreeInfo;
use super::kernel::pair_key;
use super::kernel::separation::{record, safe_skip, SeparationRecord};
use super::kernel::Ctx;
use super::search::descent::{
    climb, insert_sorted, leave_below, resume, split_key, start, Descent, NO_PAIR,
};
use super::search::front::Front;

/// Contacts reserved per pair (64 KiB): `k` up to this allocates nothing.
pub(crate) const RESERVED_K: usize = 1024;

/// The scratch and coherence of multipoint: this frame's contacts, last frame's, and the
/// split-depth pairs already used.
#[derive(Debug)]
pub(crate) struct MultipointScratch {
    /// Sorted keys of traversal pairs excluded by the multipoint traversal.
    pub excluded: Vec<u64>,
    /// This frame's contacts.
    pub contacts: Vec<Contact>,
    /// Last frame's contact leaf pairs.
    pub prev: Vec<(u32, u32)>,
    /// Last frame's contacts that no longer overlap.
    pub stale: Vec<(u32, u32)>,
}

impl MultipointScratch {
    /// Reserved for `k` up to [`RESERVED_K`].
    pub(crate) fn new() -> MultipointScratch {
        MultipointScratch {
            // Stale contacts and found ones: at most 2k keys.
            excluded: Vec::with_capacity(2 * RESERVED_K),
            contacts: Vec::with_capacity(RESERVED_K),
            prev: Vec::with_capacity(RESERVED_K),
            stale: Vec::with_capacity(RESERVED_K),
        }
    }
}

/// Options of [`Pair::multipoint`](crate::Pair::multipoint).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MultipointOptions {
    /// `false` (default): the paper's traversal. `true` (ours): the contacts are picked from
    /// the kinetic front (all overlapping leaf pairs, kept up to date at the cost of what the
    /// motion changed): last frame's contacts that still overlap first, then the others in
    /// front order, at most one per split-depth pair. Same guarantees.
    pub tracking: bool,
    /// At most this many contacts (no cap; default 16, the same as `ist query` and `ist replay`).
    /// `k = 0` asks for none: no search runs, and the answer is no contacts with distance 0
    /// (no separation proved), never a claim that the bodies are apart.
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
            tracking: false,
            k: 16,
            split_depth: 4,
            reuse: true,
            safe_motion: true,
        }
    }
}

/// Result of [`Pair::multipoint`](crate::Pair::multipoint). The contacts themselves stay in
/// the pair until its next query: [`Pair::contacts`](crate::Pair::contacts).
///
/// Its serde form is the answer every door prints: `contact` (`count > 0`), then these
/// fields; the doors add the contacts as `contacts`.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
#[serde(remote = "Self")]
pub struct Multipoint {
    /// Number of contacts found (at most `k`), at most one per split-depth pair.
    pub count: usize,
    /// How many of them were last frame's contacts, still valid.
    pub reused: usize,
    /// 0 with contacts; otherwise a proved lower bound on the separation.
    pub distance: f64,
    /// Node pairs tested.
    pub visits: u64,
    /// True when the safe-motion bound answered without a traversal.
    pub skipped: bool,
}

impl serde::Serialize for Multipoint {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        // The derived fields (`remote = "Self"`) after `contact`.
        #[derive(serde::Serialize)]
        struct Form {
            contact: bool,
            #[serde(flatten, with = "Multipoint")]
            answer: Multipoint,
        }
        serde::Serialize::serialize(
            &Form {
                contact: self.count > 0,
                answer: *self,
            },
            s,
        )
    }
}

/// The paper's multipoint traversal (III-C): up to `k` contacts, at most one below each
/// traversal pair at the split depth.
///
/// Each frame: (1) last frame's contacts that still overlap are kept and their split-depth
/// pairs excluded; (2) from each stale one, backtrack within its split-depth pair for a
/// replacement (the pair is excluded afterwards, with or without one); (3) while fewer than
/// `k`, a traversal from the roots skipping excluded pairs; after each contact found the
/// search leaves that contact's split-depth pair.
#[allow(clippy::too_many_arguments)]
pub(crate) fn multipoint(
    ctx: &Ctx,
    ia: &TreeInfo,
    ib: &TreeInfo,
    desc: &mut Descent,
    front: &mut Front,
    sep: &mut Option<SeparationRecord>,
    s: &mut MultipointScratch,
    opts: &MultipointOptions,
) -> Multipoint {
    let k = opts.k;
    s.contacts.clear();
    s.excluded.clear();
    s.stale.clear();
    // With k = 0 nothing is searched, so nothing is proved: the lower bound is 0.
    let mut min_sep = if k == 0 { 0.0 } else { f32::INFINITY };
    let mut visits = 0u64;
    let mut reused = 0;
    let mut skip = false;
    if k > 0 && !opts.tracking && s.prev.is_empty() {
        if let Some(d) = safe_skip(ia, ib, *sep, ctx, opts.safe_motion) {
            min_sep = d as f32;
            skip = true;
        }
    }
    if k > 0 && opts.tracking {
        visits = front.update(ctx, ib);
        multipoint_pick(ctx, front, s, opts, &mut visits, &mut reused);
        min_sep = front.margin().max(0.0) as f32;
    } else if k > 0 && !skip {
        multipoint_search(ctx, desc, s, opts, &mut min_sep, &mut visits, &mut reused);
        if s.contacts.is_empty() {
            record(sep, ctx, min_sep.max(0.0) as f64);
        } else {
            *sep = None;
        }
    }
    s.prev.clear();
    s.prev
        .extend(s.contacts.iter().map(|c| (c.leaf_a, c.leaf_b)));
    let distance = if s.contacts.is_empty() {
        min_sep.max(0.0) as f64
    } else {
        0.0
    };
    Multipoint {
        count: s.contacts.len(),
        reused,
        distance,
        visits,
        skipped: skip,
    }
}

/// [`multipoint`] from the kinetic front: last frame's contacts that still overlap, then the
/// front's overlapping leaf pairs, at most one per split-depth pair.
fn multipoint_pick(
    ctx: &Ctx,
    front: &mut Front,
    s: &mut MultipointScratch,
    opts: &MultipointOptions,
    visits: &mut u64,
    reused: &mut usize,
) {
    let k = opts.k;
    let split = opts.split_depth;
    if opts.reuse {
        for idx in 0..s.prev.len() {
            if s.contacts.len() >= k {
                break;
            }
            let (la, lb) = s.prev[idx];
            let cb = ctx.xf(lb);
            let (ov, _) = ctx.test(la, lb, cb);
            *visits += 1;
            if ov && insert_sorted(&mut s.excluded, split_key(ctx, la, lb, split)) {
                s.contacts.push(make_contact(ctx.a, la, ctx.b, lb, cb));
                *reused += 1;
            }
        }
    }
    for h in front.hits.iter_mut() {
        if s.contacts.len() >= k {
            break;
        }
        if h.split != split {
            h.key = split_key(ctx, h.a, h.b, split);
            h.split = split;
        }
        if insert_sorted(&mut s.excluded, h.key) {
            s.contacts.push(make_contact(ctx.a, h.a, ctx.b, h.b, h.c));
        }
    }
}

/// The three stages of [`multipoint`]'s traversal.
fn multipoint_search(
    ctx: &Ctx,
    desc: &mut Descent,
    s: &mut MultipointScratch,
    opts: &MultipointOptions,
    min_sep: &mut f32,
    visits: &mut u64,
    reused: &mut usize,
) {
    let k = opts.k;
    let split = opts.split_depth;
    let c0 = ctx.xf(0);
    let (ov, lbr) = ctx.test(0, 0, c0);
    *visits += 1;
    if !ov {
        *min_sep = lbr;
        return;
    }
    // (1) Still valid contacts.
    if opts.reuse {
        for idx in 0..s.prev.len() {
            let (la, lb) = s.prev[idx];
            let cb = ctx.xf(lb);
            let (ov, d) = ctx.test(la, lb, cb);
            *visits += 1;
            if !ov {
                *min_sep = min_sep.min(d);
                s.stale.push((la, lb));
            } else if s.contacts.len() < k
                && insert_sorted(&mut s.excluded, split_key(ctx, la, lb, split))
            {
                s.contacts.push(make_contact(ctx.a, la, ctx.b, lb, cb));
                *reused += 1;
            }
        }
    }
    // (2) Backtrack from stale contacts within their split-depth pairs.
    for idx in 0..s.stale.len() {
        if s.contacts.len() >= k {
            break;
        }
        let (la, lb) = s.stale[idx];
        let key = split_key(ctx, la, lb, split);
        if s.excluded.binary_search(&key).is_ok() {
            continue;
        }
        let found = climb(ctx, desc, la, lb, split, min_sep, visits);
        insert_sorted(&mut s.excluded, key);
        if let Some(e) = found {
            s.contacts.push(make_contact(ctx.a, e.a, ctx.b, e.b, e.c));
        }
    }
    // (3) Search from the roots for the rest.
    if s.contacts.len() < k && s.excluded.binary_search(&pair_key(0, 0)).is_err() {
        start(ctx, desc, 0, 0, c0, 0);
        while let Some(e) = resume(ctx, desc, &s.excluded, split, NO_PAIR, min_sep, visits) {
            s.contacts.push(make_contact(ctx.a, e.a, ctx.b, e.b, e.c));
            insert_sorted(&mut s.excluded, split_key(ctx, e.a, e.b, split));
            if s.contacts.len() >= k {
                break;
            }
            leave_below(ctx, desc, split);
        }
    }
}

/// The answer at a far pose ([`far`](super::kernel::far)): no contacts (last frame's are
/// forgotten), the bodies at least the root spheres' separation apart.
pub(crate) fn separated(s: &mut MultipointScratch, separation: f64) -> Multipoint {
    s.contacts.clear();
    s.prev.clear();
    Multipoint {
        count: 0,
        reused: 0,
        distance: separation,
        visits: 1,
        skipped: false,
    }
}
