//! The counting global allocator and the query-kind matrix of the allocation tests: every
//! query kind and option of the public API run along motions, their allocations counted per
//! thread. Shared by `query_alloc.rs` and the jaw test of `innersphere-eval`
//! (`tests/query_alloc_jaw.rs`, which needs its generated motions).
//!
//! `INNERSPHERE_ALLOC_TRACE=1` prints a backtrace of every counted allocation.

use innersphere::query::TraversalOptions;
use innersphere::{
    DistanceOptions, MultipointOptions, Pair, PenetrationOptions, Pose, RefineOptions, SharedTree,
    Tracking,
};
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

/// A global allocator that counts, on each thread, the allocations made while [`counted`]
/// runs there: declare it in a test binary with
/// `#[global_allocator] static A: Counting = Counting;`.
pub struct Counting;

// Both the switch and the counts are per thread: the test harness runs tests on parallel
// threads, and a count shared between them would see the other tests' allocations.
thread_local! {
    static COUNTING: Cell<bool> = const { Cell::new(false) };
    static TRACE: Cell<bool> = const { Cell::new(false) };
    static ALLOCS: Cell<u64> = const { Cell::new(0) };
    static BYTES: Cell<u64> = const { Cell::new(0) };
}

fn note(bytes: usize) {
    if COUNTING.with(|c| c.get()) {
        ALLOCS.with(|n| n.set(n.get() + 1));
        BYTES.with(|n| n.set(n.get() + bytes as u64));
        if TRACE.with(|t| t.get()) {
            // Capturing allocates: not counted.
            COUNTING.with(|c| c.set(false));
            eprintln!(
                "allocation of {bytes} bytes:\n{}",
                std::backtrace::Backtrace::force_capture()
            );
            COUNTING.with(|c| c.set(true));
        }
    }
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, l: Layout) -> *mut u8 {
        note(l.size());
        unsafe { System.alloc(l) }
    }
    unsafe fn alloc_zeroed(&self, l: Layout) -> *mut u8 {
        note(l.size());
        unsafe { System.alloc_zeroed(l) }
    }
    unsafe fn realloc(&self, p: *mut u8, l: Layout, n: usize) -> *mut u8 {
        note(n.saturating_sub(l.size()));
        unsafe { System.realloc(p, l, n) }
    }
    unsafe fn dealloc(&self, p: *mut u8, l: Layout) {
        unsafe { System.dealloc(p, l) }
    }
}

/// (allocations, bytes) made by `f` on this thread; `f`'s result.
pub fn counted<R>(f: impl FnOnce() -> R) -> (u64, u64, R) {
    TRACE.with(|t| t.set(std::env::var_os("INNERSPHERE_ALLOC_TRACE").is_some()));
    ALLOCS.with(|n| n.set(0));
    BYTES.with(|n| n.set(0));
    COUNTING.with(|c| c.set(true));
    let r = f();
    COUNTING.with(|c| c.set(false));
    (ALLOCS.with(|n| n.get()), BYTES.with(|n| n.get()), r)
}

/// One query kind with its options.
#[derive(Debug, Clone, Copy)]
pub enum Kind {
    Distance(DistanceOptions),
    DistanceTraversal(TraversalOptions),
    Backtracking(TraversalOptions),
    /// [`Pair::contact`] takes no options.
    Contact,
    Multipoint(MultipointOptions),
    Penetration(PenetrationOptions),
    Budgeted(u64),
    /// Run only on trees with their meshes ([`SharedTree::with_mesh`]); skipped on others.
    Refined(RefineOptions),
}

/// Every query kind and option of the public API (all combinations that change the path a
/// query takes through its scratch memory).
pub fn kinds() -> Vec<Kind> {
    let mut v = Vec::new();
    for best_first in [false, true] {
        for coherence in [true, false] {
            for signed in [false, true] {
                v.push(Kind::Distance(DistanceOptions {
                    best_first,
                    coherence,
                    signed,
                    ..Default::default()
                }));
            }
        }
        for (rel_tolerance, abs_tolerance) in [(0.1, 0.0), (0.0, 0.01), (0.1, 0.01)] {
            v.push(Kind::Distance(DistanceOptions {
                best_first,
                rel_tolerance,
                abs_tolerance,
                ..Default::default()
            }));
        }
    }
    for safe_motion in [true, false] {
        let o = TraversalOptions { safe_motion };
        v.extend([Kind::DistanceTraversal(o), Kind::Backtracking(o)]);
    }
    v.push(Kind::Contact);
    for tracking in [false, true] {
        for k in [1, 16, 256] {
            for split_depth in [0, 2, 5, 9, 40] {
                v.push(Kind::Multipoint(MultipointOptions {
                    tracking,
                    k,
                    split_depth,
                    ..Default::default()
                }));
            }
            for (reuse, safe_motion) in [(false, true), (true, false), (false, false)] {
                v.push(Kind::Multipoint(MultipointOptions {
                    tracking,
                    k,
                    split_depth: 4,
                    reuse,
                    safe_motion,
                }));
            }
        }
    }
    for tracking in [Tracking::Auto, Tracking::Front, Tracking::Traversal] {
        for safe_motion in [true, false] {
            for (max_patches, patch_radius) in [(0, 0.0), (8, 0.0), (64, 1e-3)] {
                v.push(Kind::Penetration(PenetrationOptions {
                    tracking,
                    safe_motion,
                    max_patches,
                    patch_radius,
                    stiffness: 2.0,
                    // Both ways, without multiplying the cases.
                    linearize: max_patches == 8,
                }));
            }
        }
    }
    for budget in [0, 10, 200, 1000, 10_000, 100_000, u64::MAX] {
        v.push(Kind::Budgeted(budget));
    }
    for (radius_scale, rel_tolerance, max_node_pairs) in [
        (0.5, 1e-3, 4096),
        (1.0, 0.0, 4096),
        (3.0, 0.0, 16),
        (0.0, 0.5, 1),
    ] {
        v.push(Kind::Refined(RefineOptions {
            radius_scale,
            rel_tolerance,
            max_node_pairs,
            ..Default::default()
        }));
    }
    v
}

/// Runs query `kind` once on `pair`; a checksum of its answer, so that nothing is optimized
/// away.
pub fn run(kind: &Kind, pair: &mut Pair, pa: &Pose, pb: &Pose) -> f64 {
    match kind {
        Kind::Distance(o) => {
            let p = pair.distance_with(pa, pb, o);
            p.distance + p.lower_bound + p.leaf_a as f64
        }
        Kind::DistanceTraversal(o) => pair.paper().distance_traversal(pa, pb, o).distance,
        Kind::Backtracking(o) => pair.paper().backtracking(pa, pb, o).distance,
        Kind::Contact => {
            let c = pair.contact(pa, pb);
            c.distance + c.contact.map_or(0.0, |c| c.depth)
        }
        Kind::Multipoint(o) => {
            let m = pair.multipoint(pa, pb, o);
            let contacts = pair.contacts();
            contacts.len() as f64 + m.distance + contacts.last().map_or(0.0, |c| c.depth)
        }
        Kind::Penetration(o) => {
            let p = pair.penetration_with(pa, pb, o);
            p.volume + p.distance + pair.patches().len() as f64 + p.torque_a.x
        }
        Kind::Budgeted(budget) => {
            let r = pair.penetration_within(pa, pb, *budget);
            r.volume + r.upper_bound
        }
        Kind::Refined(o) => {
            if pair.tree_a().mesh().is_none() || pair.tree_b().mesh().is_none() {
                return 0.0;
            }
            match pair.refined_distance_with(pa, pb, o) {
                Ok(r) => r.distance + r.point_a.x + r.node_pairs as f64,
                Err(_) => f64::NAN,
            }
        }
    }
}

/// Allocations of one query kind along two motions.
#[derive(Debug, Default, Clone, Copy)]
pub struct Counts {
    /// The first frame of a fresh pair.
    pub first: u64,
    /// The rest of the first motion.
    pub cold: u64,
    /// The whole second motion, after the first.
    pub warm: u64,
}

impl Counts {
    pub fn total(&self) -> u64 {
        self.first + self.cold + self.warm
    }
}

/// Counts the allocations of `kind` on a fresh pair of `a` and `b` along `m1` and then `m2`.
pub fn count_kind(
    kind: &Kind,
    a: &SharedTree,
    b: &SharedTree,
    m1: &[(Pose, Pose)],
    m2: &[(Pose, Pose)],
) -> Counts {
    let mut pair = Pair::new(a, b);
    let along = |pair: &mut Pair, m: &[(Pose, Pose)]| -> f64 {
        m.iter().map(|(pa, pb)| run(kind, pair, pa, pb)).sum()
    };
    let (first, _, x) = counted(|| along(&mut pair, &m1[..1]));
    let (cold, _, y) = counted(|| along(&mut pair, &m1[1..]));
    let (warm, _, z) = counted(|| along(&mut pair, m2));
    assert!(!(x + y + z).is_nan());
    Counts { first, cold, warm }
}

/// Asserts that every query kind allocates nothing along `m1` from a fresh pair and along
/// `m2` after it, and along `m2` from a fresh pair and `m1` after it (a fresh [`Pair`] of
/// `a` and `b` per kind and order).
pub fn assert_allocation_free(
    label: &str,
    a: &SharedTree,
    b: &SharedTree,
    m1: &[(Pose, Pose)],
    m2: &[(Pose, Pose)],
) {
    let mut bad = Vec::new();
    for kind in kinds() {
        for (x, y) in [(m1, m2), (m2, m1)] {
            let c = count_kind(&kind, a, b, x, y);
            if c.total() > 0 {
                bad.push(format!("{kind:?}: {c:?}"));
            }
        }
    }
    assert!(
        bad.is_empty(),
        "{label}: {} query kinds allocated:\n{}",
        bad.len(),
        bad.join("\n")
    );
}
