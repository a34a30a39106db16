//! Exact proximity of the two inner-sphere packings: best-first branch and bound over both
//! trees.

use super::geometry::{direction, leaf_pair};
use super::heap::Entry;
use super::state::{expand_larger, test_pair, PairState};
use super::Pose;
use crate::SphereTree;
use glam::DVec3;

/// Options of [`proximity`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProximityOptions {
    /// Stop once the answer is proved within this absolute distance of the minimum (as PQP
    /// and FCL offer); 0 = exact.
    pub abs_tolerance: f64,
    /// Stop once the answer is proved within this fraction of the minimum; 0 = exact.
    pub rel_tolerance: f64,
    /// When the packings overlap: `false` (default) stops at the first overlapping leaf pair
    /// found and reports `distance = 0`; `true` finds the most deeply overlapping leaf pair
    /// and reports `distance = −(its overlap)` (slower: every overlapping node pair deeper
    /// than that must be refined).
    pub signed: bool,
    /// Start from last query's closest leaf pair (an upper bound before the search starts).
    pub coherence: bool,
}

impl Default for ProximityOptions {
    fn default() -> Self {
        ProximityOptions {
            abs_tolerance: 0.0,
            rel_tolerance: 0.0,
            signed: false,
            coherence: true,
        }
    }
}

/// Result of [`proximity`].
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Proximity {
    /// Minimum distance between the two inner-sphere packings (the unions of the leaf
    /// spheres): `min |cb − ca| − ra − rb` over all leaf pairs. When the packings overlap it
    /// is 0, or with [`ProximityOptions::signed`] minus the deepest leaf-pair overlap. With
    /// tolerances: `true ≤ distance ≤ true + max(abs, rel·true)`.
    pub distance: f64,
    /// `|cb − ca| − ra − rb` of the reported leaf pair (negative when it overlaps).
    pub pair_distance: f64,
    /// A proved lower bound on the exact answer (equal to `distance` without tolerances).
    pub lower_bound: f64,
    /// True when the packings overlap.
    pub overlapping: bool,
    /// Closest point on A's leaf sphere (world): `ca + ra·n`.
    pub point_a: DVec3,
    /// Closest point on B's leaf sphere (world): `cb − rb·n`.
    pub point_b: DVec3,
    /// World unit direction from A's leaf centre to B's.
    pub normal: DVec3,
    /// The leaf of A (node index).
    pub leaf_a: u32,
    /// The leaf of B (node index).
    pub leaf_b: u32,
    /// Node pairs whose distance was computed.
    pub visits: u64,
}

/// Exact minimum distance between the inner-sphere packings of `a` at `pose_a` and `b` at
/// `pose_b` (world poses), with the closest points and the leaf pair.
///
/// Best-first branch and bound: a priority queue of node pairs keyed by the lower bound
/// `|ca − cb| − ra − rb`, refining the larger sphere first, pruning pairs that cannot beat
/// the best leaf pair so far (seeded with last query's pair). Records the separation for the
/// safe-motion skip of the contact queries.
pub fn proximity(
    a: &SphereTree,
    pose_a: &Pose,
    b: &SphereTree,
    pose_b: &Pose,
    st: &mut PairState,
    opts: &ProximityOptions,
) -> Proximity {
    let ctx = st.begin(a, pose_a, b, pose_b);
    let abs = opts.abs_tolerance.max(0.0) as f32;
    let rel = opts.rel_tolerance.max(0.0) as f32;
    let signed = opts.signed;
    // A pair whose lower bound is `lb` cannot improve `ub` by more than the tolerance.
    let done = |lb: f32, ub: f32| ub - lb <= abs.max(rel * lb.max(0.0));
    let mut ub = f32::INFINITY;
    let mut best = (0u32, 0u32);
    let mut visits = 0u64;
    if opts.coherence {
        if let Some((la, lb)) = st.prox_pair {
            let cb = st.tb.xf(&ctx.rel32, b, lb as usize);
            let (_, d) = test_pair(&ctx, la as usize, lb as usize, cb);
            ub = d;
            best = (la, lb);
            visits += 1;
        }
    }
    st.heap.clear();
    let (_, root_lb) = test_pair(&ctx, 0, 0, st.tb.get(0));
    visits += 1;
    let key_of = |d: f32, s: f32| if signed || d > 0.0 { d } else { -1.0 / s };
    if a.is_leaf(0) && b.is_leaf(0) {
        if root_lb < ub {
            ub = root_lb;
            best = (0, 0);
        }
    } else {
        let l = if signed { root_lb } else { root_lb.max(0.0) };
        if !done(l, ub) {
            st.heap.push(Entry {
                key: key_of(root_lb, a.r[0] + b.r[0] + ctx.slack),
                a: 0,
                b: 0,
            });
        }
    }
    let mut lower = f32::INFINITY;
    let heap = &mut st.heap;
    while let Some(e) = heap.pop() {
        let elb = if signed { e.key } else { e.key.max(0.0) };
        if done(elb, ub) {
            lower = elb;
            break;
        }
        expand_larger(&ctx, &mut st.tb, e.a, e.b, |i, j, _cb, d2, s, leafs| {
            visits += 1;
            let d = d2.sqrt() - s;
            if leafs {
                if d < ub {
                    ub = d;
                    best = (i, j);
                }
            } else {
                let l = if signed { d } else { d.max(0.0) };
                if !done(l, ub) {
                    heap.push(Entry {
                        key: key_of(d, s),
                        a: i,
                        b: j,
                    });
                }
            }
        });
    }
    let lower = lower.min(ub);
    st.prox_pair = Some(best);
    let (la, lb) = best;
    let cb = st.tb.xf(&ctx.rel32, b, lb as usize);
    let (ca, ra, cbd, rb) = leaf_pair(a, la, b, lb, cb);
    let (mut n, _) = direction(ca, cbd);
    if n == DVec3::ZERO {
        n = DVec3::X;
    }
    let overlapping = ub < 0.0;
    if overlapping {
        st.separation = None;
    } else {
        st.record_separation(&ctx, lower as f64);
    }
    Proximity {
        distance: if signed {
            ub as f64
        } else {
            ub.max(0.0) as f64
        },
        pair_distance: ub as f64,
        lower_bound: if signed {
            lower as f64
        } else {
            lower.max(0.0) as f64
        },
        overlapping,
        point_a: pose_a.transform_point(ca + n * ra),
        point_b: pose_a.transform_point(cbd - n * rb),
        normal: pose_a.transform_vector(n),
        leaf_a: la,
        leaf_b: lb,
        visits,
    }
}
