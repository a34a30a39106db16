//! The paper's traversals against brute force over leaf pairs: the distance traversal's
//! contact answer, backtracking equal to a full traversal on every frame of generated
//! motions, and the multipoint traversal's contact set.

use super::query_util;

use glam::DVec3;
use innersphere::query::{brute, TraversalOptions};
use innersphere::{MultipointOptions, SphereTree};
use proptest::prelude::*;
use query_util::*;
use std::collections::BTreeSet;

const NO_SKIP: TraversalOptions = TraversalOptions { safe_motion: false };

fn ancestor_at(t: &SphereTree, mut n: u32, d: u32) -> u32 {
    while t.depth[n as usize] as u32 > d {
        n = t.parent[n as usize];
    }
    n
}

fn vec3() -> impl Strategy<Value = DVec3> {
    [-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64].prop_map(DVec3::from_array)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// Contact iff some leaf pair overlaps; the contact's leaves overlap; without contact the
    /// distance is a lower bound of the brute-force minimum.
    #[test]
    fn distance_traversal_equals_brute_force(
        ia in 0usize..4, ib in 0usize..4,
        qb in [-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64],
        off in vec3(),
    ) {
        let t = trees();
        let (a, b) = (&t[ia], &t[ib]);
        let scale = (a.r[0] + b.r[0]) as f64;
        let (pa, pb) = pair_poses(a, b, pose([0.3, -1.0, 2.0], [1.0, 0.2, 0.0, 0.3]), quat(qb[0], qb[1], qb[2], qb[3]), off * 1.2 * scale);
        let (bd, _, _) = brute::min_distance(a, &pa, b, &pb);
        let mut st = pair(a, b);
        let q = st.paper().distance_traversal(&pa, &pb, &NO_SKIP);
        prop_assert_eq!(q.in_contact(), bd < 0.0);
        match q.contact {
            Some(c) => {
                prop_assert!(brute::leaves_overlap(a, c.leaf_a, &pa, b, c.leaf_b, &pb));
                prop_assert!(c.depth > -1e-6);
                prop_assert_eq!(q.distance, 0.0);
            }
            None => prop_assert!(q.distance >= 0.0 && q.distance <= bd, "{} > {}", q.distance, bd),
        }
    }


}
proptest! {
    #![proptest_config(ProptestConfig::with_cases(12))]

    /// Backtracking gives the same contact answer as the full traversal (and brute force) on
    /// every frame of a motion, with a valid contact or a valid lower bound; so does the
    /// kinetic-front contact query.
    #[test]
    fn backtracking_equals_full_traversal_along_motions(
        ia in 0usize..4, ib in 0usize..4,
        dir in vec3(), side in vec3(), axis in vec3(),
        spin in -0.04..0.04f64,
        frames in 60usize..160,
    ) {
        backtracking_equals_full_traversal_along_motions_case(ia, ib, dir, side, axis, spin, frames)?;
    }
}
proptest! {
    #![proptest_config(ProptestConfig::with_cases(12))]

    /// Multipoint: every contact is an overlapping leaf pair, at most one per split-depth
    /// pair, and as many as min(k, number of split-depth pairs holding an overlapping leaf
    /// pair) — on every frame, with and without reuse of last frame's contacts.
    #[test]
    fn multipoint_contact_sets_along_motions(
        ia in 0usize..4, ib in 0usize..4,
        dir in vec3(), side in vec3(), axis in vec3(),
        spin in -0.04..0.04f64,
        k in prop_oneof![Just(1usize), Just(2), Just(3), Just(16), Just(1000)],
        split in 0u32..8,
    ) {
        multipoint_contact_sets_along_motions_case(ia, ib, dir, side, axis, spin, k, split)?;
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// [`multipoint_contact_sets_along_motions`] with 48 cases.
    #[test]
    #[ignore = "heavy: 48 motions against brute force (about 4 s); CI runs it with --ignored"]
    fn multipoint_contact_sets_along_motions_heavy(
        ia in 0usize..4, ib in 0usize..4,
        dir in vec3(), side in vec3(), axis in vec3(),
        spin in -0.04..0.04f64,
        k in prop_oneof![Just(1usize), Just(2), Just(3), Just(16), Just(1000)],
        split in 0u32..8,
    ) {
        multipoint_contact_sets_along_motions_case(ia, ib, dir, side, axis, spin, k, split)?;
    }
}

/// One case of [`multipoint_contact_sets_along_motions`].
#[allow(clippy::too_many_arguments)]
fn multipoint_contact_sets_along_motions_case(
    ia: usize,
    ib: usize,
    dir: DVec3,
    side: DVec3,
    axis: DVec3,
    spin: f64,
    k: usize,
    split: u32,
) -> Result<(), TestCaseError> {
    let t = trees();
    let (a, b) = (&t[ia], &t[ib]);
    let motion = motion(a, b, dir, side, axis, spin, 50);
    let mut reuse = pair(a, b);
    let mut fresh = pair(a, b);
    let mut tracked = pair(a, b);
    for (f, (pa, pb)) in motion.iter().enumerate() {
        let pairs = brute::overlapping_pairs(a, pa, b, pb);
        let regions: BTreeSet<(u32, u32)> = pairs
            .iter()
            .map(|&(la, lb)| (ancestor_at(a, la, split), ancestor_at(b, lb, split)))
            .collect();
        let want = k.min(regions.len());
        for (st, reuse_on, tracking) in [
            (&mut reuse, true, false),
            (&mut fresh, false, false),
            (&mut tracked, true, true),
        ] {
            let opts = MultipointOptions {
                k,
                split_depth: split,
                reuse: reuse_on,
                safe_motion: false,
                tracking,
            };
            let r = st.multipoint(pa, pb, &opts);
            let contacts = st.contacts();
            prop_assert_eq!(contacts.len(), want, "frame {} reuse {}", f, reuse_on);
            prop_assert!(r.reused <= contacts.len());
            let mut seen = BTreeSet::new();
            for c in contacts {
                prop_assert!(brute::leaves_overlap(a, c.leaf_a, pa, b, c.leaf_b, pb));
                let key = (
                    ancestor_at(a, c.leaf_a, split),
                    ancestor_at(b, c.leaf_b, split),
                );
                prop_assert!(seen.insert(key), "two contacts below one split pair");
            }
            if contacts.is_empty() {
                let (bd, _, _) = brute::min_distance(a, pa, b, pb);
                prop_assert!(r.distance <= bd.max(0.0));
            }
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// [`backtracking_equals_full_traversal_along_motions`] with 48 cases.
    #[test]
    #[ignore = "heavy: 48 motions against brute force (about 6 s); CI runs it with --ignored"]
    fn backtracking_equals_full_traversal_along_motions_heavy(
        ia in 0usize..4, ib in 0usize..4,
        dir in vec3(), side in vec3(), axis in vec3(),
        spin in -0.04..0.04f64,
        frames in 60usize..160,
    ) {
        backtracking_equals_full_traversal_along_motions_case(ia, ib, dir, side, axis, spin, frames)?;
    }
}

/// One case of [`backtracking_equals_full_traversal_along_motions`].
#[allow(clippy::too_many_arguments)]
fn backtracking_equals_full_traversal_along_motions_case(
    ia: usize,
    ib: usize,
    dir: DVec3,
    side: DVec3,
    axis: DVec3,
    spin: f64,
    frames: usize,
) -> Result<(), TestCaseError> {
    let t = trees();
    let (a, b) = (&t[ia], &t[ib]);
    let motion = motion(a, b, dir, side, axis, spin, frames);
    let mut bt = pair(a, b);
    let mut full = pair(a, b);
    let mut front = pair(a, b);
    let mut contacts = 0;
    for (f, (pa, pb)) in motion.iter().enumerate() {
        let q = bt.paper().backtracking(pa, pb, &NO_SKIP);
        let r = full.paper().distance_traversal(pa, pb, &NO_SKIP);
        prop_assert_eq!(q.in_contact(), r.in_contact(), "frame {}", f);
        let t = front.contact(pa, pb);
        prop_assert_eq!(t.in_contact(), r.in_contact(), "front, frame {}", f);
        if let Some(c) = t.contact {
            prop_assert!(brute::leaves_overlap(a, c.leaf_a, pa, b, c.leaf_b, pb));
        } else {
            let (bd, _, _) = brute::min_distance(a, pa, b, pb);
            prop_assert!(t.distance <= bd, "front bound {} above {}", t.distance, bd);
        }
        let truth = !brute::overlapping_pairs(a, pa, b, pb).is_empty();
        prop_assert_eq!(q.in_contact(), truth, "frame {}", f);
        if let Some(c) = q.contact {
            contacts += 1;
            prop_assert!(brute::leaves_overlap(a, c.leaf_a, pa, b, c.leaf_b, pb));
        } else {
            let (bd, _, _) = brute::min_distance(a, pa, b, pb);
            prop_assert!(q.distance <= bd);
        }
    }
    // The motions pass through the other body, so contact happens.
    prop_assert!(contacts > 0);
    Ok(())
}
