//! Broad phase and safe motion: skipping queries while the last proved separation cannot
//! have been closed never misses a contact that a full query finds, and the bound itself is
//! below the true separation.

use super::query_util;

use glam::DVec3;
use innersphere::query::{brute, TraversalOptions};
use innersphere::{MultipointOptions, PenetrationOptions, Tracking};
use proptest::prelude::*;
use query_util::*;

fn vec3() -> impl Strategy<Value = DVec3> {
    [-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64].prop_map(DVec3::from_array)
}

/// Root-sphere rejection: far apart, every query answers after one node-pair test.
#[test]
fn root_spheres_reject_far_pairs() {
    let t = trees();
    let (a, b) = (&t[0], &t[2]);
    let (pa, pb) = pair_poses(
        a,
        b,
        Default::default(),
        Default::default(),
        DVec3::new(10.0, 0.0, 0.0),
    );
    let mut st = pair(a, b);
    let off = TraversalOptions { safe_motion: false };
    assert_eq!(st.paper().distance_traversal(&pa, &pb, &off).visits, 1);
    assert_eq!(st.paper().backtracking(&pa, &pb, &off).visits, 1);
    let p = st.penetration_with(
        &pa,
        &pb,
        &PenetrationOptions {
            safe_motion: false,
            tracking: Tracking::Traversal,
            ..Default::default()
        },
    );
    assert_eq!((p.visits, p.volume), (1, 0.0));
    // And the next frame, barely moved, is skipped.
    let (pa2, pb2) = pair_poses(
        a,
        b,
        Default::default(),
        Default::default(),
        DVec3::new(9.99, 0.0, 0.0),
    );
    let q = st
        .paper()
        .distance_traversal(&pa2, &pb2, &TraversalOptions::default());
    assert!(q.skipped && q.distance > 5.0);
}
proptest! {
    #![proptest_config(ProptestConfig::with_cases(10))]

    /// Along motions, every contact query with the safe-motion skip on reports contact on
    /// exactly the frames where a full query (skip off) does; skipped frames really are
    /// separated, by at least the reported bound.
    #[test]
    fn safe_motion_never_misses_a_contact(
        ia in 0usize..4, ib in 0usize..4,
        dir in vec3(), side in vec3(), axis in vec3(),
        spin in -0.03..0.03f64,
        frames in 150usize..400,
        with_proximity in any::<bool>(),
    ) {
        safe_motion_never_misses_a_contact_case(ia, ib, dir, side, axis, spin, frames, with_proximity)?;
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(40))]

    /// [`safe_motion_never_misses_a_contact`] with 40 cases.
    #[test]
    #[ignore = "heavy: 40 motions (about 6 s); CI runs it with --ignored"]
    fn safe_motion_never_misses_a_contact_heavy(
        ia in 0usize..4, ib in 0usize..4,
        dir in vec3(), side in vec3(), axis in vec3(),
        spin in -0.03..0.03f64,
        frames in 150usize..400,
        with_proximity in any::<bool>(),
    ) {
        safe_motion_never_misses_a_contact_case(ia, ib, dir, side, axis, spin, frames, with_proximity)?;
    }
}

/// One case of [`safe_motion_never_misses_a_contact`].
#[allow(clippy::too_many_arguments)]
fn safe_motion_never_misses_a_contact_case(
    ia: usize,
    ib: usize,
    dir: DVec3,
    side: DVec3,
    axis: DVec3,
    spin: f64,
    frames: usize,
    with_proximity: bool,
) -> Result<(), TestCaseError> {
    let t = trees();
    let (a, b) = (&t[ia], &t[ib]);
    let motion = motion(a, b, dir, side, axis, spin, frames);
    let on = TraversalOptions { safe_motion: true };
    let off = TraversalOptions { safe_motion: false };
    let mut s_bt = pair(a, b);
    let mut s_dt = pair(a, b);
    let mut s_mp = pair(a, b);
    let mut s_pen = pair(a, b);
    let mut s_ref = pair(a, b);
    let mut s_front = pair(a, b);
    let mut s_pen_front = pair(a, b);
    let mut skipped = 0;
    for (f, (pa, pb)) in motion.iter().enumerate() {
        if with_proximity && f % 7 == 0 {
            // A distance query records its exact separation too.
            s_bt.distance(pa, pb);
        }
        let truth = s_ref.paper().distance_traversal(pa, pb, &off).in_contact();
        let bound = s_bt.safe_separation(pa, pb);
        let q = s_bt.paper().backtracking(pa, pb, &on);
        prop_assert_eq!(q.in_contact(), truth, "backtracking, frame {}", f);
        let (bd, _, _) = brute::min_distance(a, pa, b, pb);
        if let Some(s) = bound {
            prop_assert!(
                s <= bd.max(0.0) + 1e-12,
                "safe bound {} above the separation {}",
                s,
                bd
            );
        }
        if q.skipped {
            skipped += 1;
            prop_assert!(q.distance > 0.0 && q.distance <= bd);
        }
        prop_assert_eq!(
            s_dt.paper().distance_traversal(pa, pb, &on).in_contact(),
            truth,
            "distance traversal, frame {}",
            f
        );
        s_mp.multipoint(
            pa,
            pb,
            &MultipointOptions {
                k: 3,
                split_depth: 2,
                ..Default::default()
            },
        );
        prop_assert_eq!(
            !s_mp.contacts().is_empty(),
            truth,
            "multipoint, frame {}",
            f
        );
        let p = s_pen.penetration_with(
            pa,
            pb,
            &PenetrationOptions {
                tracking: Tracking::Traversal,
                ..Default::default()
            },
        );
        prop_assert_eq!(p.pairs > 0, truth, "penetration, frame {}", f);
        if p.skipped {
            prop_assert!(p.distance > 0.0 && p.distance <= bd);
        }
        let p = s_pen_front.penetration(pa, pb);
        prop_assert_eq!(p.pairs > 0, truth, "penetration (front), frame {}", f);
        let c = s_front.contact(pa, pb);
        prop_assert_eq!(c.in_contact(), truth, "front contact, frame {}", f);
        if !truth {
            prop_assert!(c.distance <= bd.max(0.0));
        }
    }
    // The motions are slow enough that separated stretches get skipped.
    prop_assert!(
        skipped > 0
            || motion
                .iter()
                .all(|(pa, pb)| brute::min_distance(a, pa, b, pb).0 < 0.05)
    );
    Ok(())
}
