//! Poses within rounding distance of touching, where "the same answer as brute force"
//! matters most: B approaches A along the direction in which both roots are tangent to a
//! leaf (the root sphere touches its farthest leaf there), so that a root test and a leaf
//! test decide the same geometric contact with different f32 roundings. The offset is bisected
//! to where the leaf predicate (`|Δ|² < (ra + rb)²` on f32 centres, which defines every
//! query's answer) flips, and every query kind is compared with the brute-force scan over all
//! leaf pairs at a few rounding steps either side, with fresh pairs and with pairs carried
//! across the steps.

use super::query_util;

use glam::{DQuat, DVec3};
use innersphere::query::{brute, TraversalOptions};
use innersphere::{
    DistanceOptions, MultipointOptions, Pair, PenetrationOptions, Pose, SharedTree, SphereTree,
    Tracking,
};
use proptest::prelude::*;
use query_util::{box_tree, pair_poses, pose, trees};
use std::sync::OnceLock;

const NO_SKIP: TraversalOptions = TraversalOptions { safe_motion: false };

/// The unit direction (model frame) from the root's centre to the leaf that reaches
/// farthest from it: the root sphere is tangent to that leaf there.
fn support_direction(t: &SphereTree) -> DVec3 {
    let c0 = t.sphere(0).0.as_dvec3();
    let reach = |n: usize| (t.sphere(n).0.as_dvec3() - c0).length() + t.r[n] as f64;
    let far = t
        .leaves()
        .max_by(|&i, &j| reach(i).total_cmp(&reach(j)))
        .expect("a leaf");
    (t.sphere(far).0.as_dvec3() - c0).normalize()
}

/// Every query kind at one pose against the brute-force answer (leaf predicate in f32).
fn check_pose(
    a: &SphereTree,
    pa: &Pose,
    b: &SphereTree,
    pb: &Pose,
    st: &mut [Pair],
    what: &str,
) -> Result<(), TestCaseError> {
    let pairs = brute::overlapping_pairs(a, pa, b, pb);
    let (bd, _, _) = brute::min_distance(a, pa, b, pb);
    let touching = !pairs.is_empty();
    prop_assert_eq!(touching, bd < 0.0);
    let q = st[0].paper().distance_traversal(pa, pb, &NO_SKIP);
    prop_assert_eq!(q.in_contact(), touching, "{}: distance traversal", what);
    let q = st[1].paper().backtracking(pa, pb, &NO_SKIP);
    prop_assert_eq!(q.in_contact(), touching, "{}: backtracking", what);
    let q = st[2].contact(pa, pb);
    prop_assert_eq!(q.in_contact(), touching, "{}: contact", what);
    for (i, tracking) in [(3, false), (4, true)] {
        let opts = MultipointOptions {
            tracking,
            k: 4,
            split_depth: 3,
            reuse: true,
            safe_motion: false,
        };
        st[i].multipoint(pa, pb, &opts);
        prop_assert_eq!(
            !st[i].contacts().is_empty(),
            touching,
            "{}: multipoint {}",
            what,
            tracking
        );
    }
    for (i, tracking) in [(5, Tracking::Front), (6, Tracking::Traversal)] {
        let opts = PenetrationOptions {
            safe_motion: false,
            tracking,
            ..Default::default()
        };
        let p = st[i].penetration_with(pa, pb, &opts);
        prop_assert_eq!(p.pairs, pairs.len(), "{}: penetration {:?}", what, tracking);
    }
    let v = st[7].penetration_within(pa, pb, u64::MAX);
    prop_assert_eq!(v.volume > 0.0, touching, "{}: budgeted", what);
    for best_first in [false, true] {
        let opts = DistanceOptions {
            best_first,
            ..Default::default()
        };
        let p = st[8].distance_with(pa, pb, &opts);
        prop_assert_eq!(p.overlapping, touching, "{}: distance, overlapping", what);
        prop_assert_eq!(p.distance, bd.max(0.0), "{}: distance", what);
    }
    Ok(())
}

/// B's roots offset `d` from A's along `u` (A's frame), B turned so that its own support
/// direction faces A's.
fn poses_at(
    a: &SphereTree,
    b: &SphereTree,
    pa: Pose,
    rot: DQuat,
    u: DVec3,
    d: f64,
) -> (Pose, Pose) {
    pair_poses(a, b, pa, rot, u * d)
}

/// Trees far from their own frames' origins, on opposite sides: when they touch, the
/// relative translation is about as long as the two extents together, so the rounding of the
/// transform is as large as the slack must cover.
fn far_trees() -> &'static [SphereTree] {
    static T: OnceLock<Vec<SphereTree>> = OnceLock::new();
    T.get_or_init(|| {
        vec![
            box_tree(
                DVec3::new(60.0, 20.0, -10.0),
                DVec3::new(0.5, 0.3, 0.4),
                0.08,
                4,
            ),
            box_tree(
                DVec3::new(-60.0, -20.0, 10.0),
                DVec3::new(0.4, 0.4, 0.3),
                0.08,
                3,
            ),
        ]
    })
}

/// `t` mirrored through its frame's origin (every coordinate negated: exact in f32, so every
/// node still encloses its leaves bit for bit).
fn mirrored(t: &SphereTree) -> SphereTree {
    let mut m = t.clone();
    for v in [&mut m.x, &mut m.y, &mut m.z] {
        v.iter_mut().for_each(|c| *c = -*c);
    }
    m
}

/// Bisects B's offset along A's support direction to where the leaf predicate flips and
/// checks every query kind at rounding steps either side.
fn check_touching_offset(
    a: &SphereTree,
    b: &SphereTree,
    pa: Pose,
    spin: f64,
) -> Result<(), TestCaseError> {
    let ua = support_direction(a);
    let ub = support_direction(b);
    // B's support direction turned to face A's, then spun about the approach line.
    let rot = DQuat::from_axis_angle(ua, spin) * DQuat::from_rotation_arc(ub, -ua);
    let reach = (a.r[0] + b.r[0]) as f64;
    let touching = |d: f64| {
        let (pa, pb) = poses_at(a, b, pa, rot, ua, d);
        brute::min_distance(a, &pa, b, &pb).0 < 0.0
    };
    let (mut lo, mut hi) = (0.98 * reach, 1.1 * reach);
    // The first offset, coming in from outside, where some leaf pair overlaps (the tips of
    // the two bodies may hold no sphere).
    prop_assert!(!touching(hi));
    while !touching(lo) {
        prop_assert!(lo > 0.0, "no overlap along the approach");
        hi = lo;
        lo -= 0.02 * reach;
    }
    for _ in 0..80 {
        let mid = 0.5 * (lo + hi);
        if touching(mid) {
            lo = mid
        } else {
            hi = mid
        }
    }
    // Steps of about a quarter, one and four f32 roundings of the relative translation.
    let (_, pb) = poses_at(a, b, pa, rot, ua, hi);
    let t = Pose::relative(&pa, &pb).translation.length();
    let ulp = t.max(hi) * f32::EPSILON as f64;
    let (sa, sb) = (SharedTree::new(a.clone()), SharedTree::new(b.clone()));
    let mut carried: Vec<Pair> = (0..9).map(|_| Pair::new(&sa, &sb)).collect();
    for step in [0.25, 1.0, 4.0] {
        for k in -3i32..=3 {
            let d = if k < 0 { lo } else { hi } + k as f64 * step * ulp;
            let (pa, pb) = poses_at(a, b, pa, rot, ua, d);
            let mut fresh: Vec<Pair> = (0..9).map(|_| Pair::new(&sa, &sb)).collect();
            check_pose(a, &pa, b, &pb, &mut fresh, &format!("fresh, offset {d}"))?;
            check_pose(
                a,
                &pa,
                b,
                &pb,
                &mut carried,
                &format!("carried, offset {d}"),
            )?;
        }
    }
    Ok(())
}

/// A tree far from its frame's origin against its own mirror image, B unrotated: at the
/// touching offset the relative translation is as long as the two extents together, the most
/// the transform's rounding has to cover.
#[test]
fn a_far_tree_against_its_mirror_image() {
    for a in far_trees() {
        check_touching_offset(a, &mirrored(a), Pose::IDENTITY, 0.0).unwrap();
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(40))]

    /// The same for trees far from their frames' origins (A at the identity, so that the
    /// relative translation is long).
    #[test]
    fn far_from_the_origin_too(
        ia in 0usize..2,
        spin in 0.0..std::f64::consts::TAU,
    ) {
        let t = far_trees();
        check_touching_offset(&t[ia], &t[1 - ia], Pose::IDENTITY, spin)?;
    }

    /// Bisect to the touching offset; at rounding steps either side every query kind
    /// answers as the leaf predicate does.
    #[test]
    fn every_query_agrees_with_brute_force_at_the_touching_offset(
        ia in 0usize..4, ib in 0usize..4,
        qa in [-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64],
        ta in [-3.0..3.0f64, -3.0..3.0f64, -3.0..3.0f64],
        spin in 0.0..std::f64::consts::TAU,
    ) {
        let t = trees();
        check_touching_offset(&t[ia], &t[ib], pose(ta, qa), spin)?;
    }
}
