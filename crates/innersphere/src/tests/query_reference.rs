//! Every query kind against the independent f64 reference (`reference/`), which shares no
//! code with the queries: hand-worked two-ball cases computed on paper, random poses of
//! generated trees, and motions that carry each query's pair from frame to frame.

use super::query_util;
use super::reference;

use glam::DVec3;
use innersphere::query::TraversalOptions;
use innersphere::{
    DistanceOptions, MultipointOptions, Pair, PenetrationOptions, Pose, SharedTree, Tracking,
};
use proptest::prelude::*;
use query_util::{motion, pair, pair_poses, pose, quat, trees};
use reference::checks::*;
use reference::{dv, hand_tree, RefPair};

/// Two unit balls 1.5 apart, worked on paper: lens volume `π(4r + d)(2r − d)²/12 = 11π/96`,
/// centroid half-way, normal +x, force `k·V` along +x; with A's centre of mass at (0, 0, 1)
/// and B's at (1.5, 1, 0) the torques are `−(g − c_A) × F = (0, kV, 0)` and
/// `(g − c_B) × F = (0, 0, kV)`.
#[test]
fn two_equal_balls_on_paper() {
    let a = hand_tree(&[([0.0, 0.0, 0.0], 1.0)], [0.0, 0.0, 1.0]);
    let b = hand_tree(&[([0.0, 0.0, 0.0], 1.0)], [0.0, 1.0, 0.0]);
    let pa = Pose::IDENTITY;
    let pb = Pose::from_translation(DVec3::new(1.5, 0.0, 0.0));
    let (k, v) = (2.0, 11.0 * std::f64::consts::PI / 96.0);
    let mut st = pair(&a, &b);
    let p = st.penetration_with(
        &pa,
        &pb,
        &PenetrationOptions {
            stiffness: k,
            safe_motion: false,
            ..Default::default()
        },
    );
    assert!((p.volume - v).abs() < 1e-12, "{}", p.volume);
    assert_eq!(p.pairs, 1);
    assert!((p.max_depth - 0.5).abs() < 1e-12);
    assert!(near(p.normal, DVec3::X, 1e-12));
    assert!(near(p.force, DVec3::new(k * v, 0.0, 0.0), 1e-12));
    assert!(
        near(p.torque_a, DVec3::new(0.0, k * v, 0.0), 1e-12),
        "{}",
        p.torque_a
    );
    assert!(
        near(p.torque_b, DVec3::new(0.0, 0.0, k * v), 1e-12),
        "{}",
        p.torque_b
    );
    assert_eq!(st.patches().len(), 1);
    assert!(near(
        st.patches()[0].point,
        DVec3::new(0.75, 0.0, 0.0),
        1e-12
    ));
    let r = RefPair::new(&a, &pa, &b, &pb).penetration(k, 0.0);
    assert!(
        (r.volume - v).abs() < 1e-12
            && near(dv(r.torque_a), p.torque_a, 1e-12)
            && near(dv(r.torque_b), p.torque_b, 1e-12)
    );
    let s = st.distance_with(
        &pa,
        &pb,
        &DistanceOptions {
            signed: true,
            ..Default::default()
        },
    );
    assert!((s.distance + 0.5).abs() < 1e-12);
    let c = st.contact(&pa, &pb).contact.expect("contact");
    assert!(near(c.point, DVec3::new(0.75, 0.0, 0.0), 1e-12) && (c.depth - 0.5).abs() < 1e-12);
}

/// Balls of radii 2 and 1 whose centres are 2.5 apart along +y (B turned 90° about z):
/// the circle of intersection at `x0 = (d² + ra² − rb²)/2d = 1.85`, caps of heights 0.15 and
/// 0.35, volume `π(ra + rb − d)²(d² + 2d(ra + rb) − 3(ra − rb)²)/12d = 73π/480`, centroid
/// `(Va·ga + Vb·gb)/V = 1.7787671232876712` from A's centre (cap centroids
/// `3(2r − h)²/4(3r − h)`). With the centres of mass at (1, 0, 0) for A and (0, 2.5, 0.5) for
/// B: torque on A `(0, 0, kV)`, on B `(kV/2, 0, 0)`.
#[test]
fn unequal_balls_on_paper() {
    let a = hand_tree(&[([0.0, 0.0, 0.0], 2.0)], [1.0, 0.0, 0.0]);
    let b = hand_tree(&[([0.3, 0.0, 0.0], 1.0)], [0.3, 0.0, 0.5]);
    let pa = Pose::IDENTITY;
    let pb = Pose::new(
        DVec3::new(0.0, 2.2, 0.0),
        glam::DQuat::from_rotation_z(std::f64::consts::FRAC_PI_2),
    )
    .unwrap();
    let (k, v, g) = (1.0, 73.0 * std::f64::consts::PI / 480.0, 1.7787671232876712);
    let mut st = pair(&a, &b);
    let p = st.penetration_with(
        &pa,
        &pb,
        &PenetrationOptions {
            stiffness: k,
            safe_motion: false,
            ..Default::default()
        },
    );
    // B's centre went through an f32 transform: 1e-6 covers it.
    assert!((p.volume - v).abs() < 1e-6, "{} vs {v}", p.volume);
    assert!((p.max_depth - 0.5).abs() < 1e-6);
    assert!(near(p.normal, DVec3::Y, 1e-6));
    assert!(
        near(p.torque_a, DVec3::new(0.0, 0.0, k * v), 1e-6),
        "{}",
        p.torque_a
    );
    assert!(
        near(p.torque_b, DVec3::new(0.5 * k * v, 0.0, 0.0), 1e-6),
        "{}",
        p.torque_b
    );
    assert!(
        near(st.patches()[0].point, DVec3::new(0.0, g, 0.0), 1e-6),
        "{}",
        st.patches()[0].point
    );
    let (rv, rg) = reference::lens(2.0, 1.0, 2.5);
    assert!(
        (rv - v).abs() < 1e-12 && (rg - g).abs() < 1e-12,
        "{rv} {rg}"
    );
    let r = RefPair::new(&a, &pa, &b, &pb).penetration(k, 0.0);
    assert!(near(dv(r.moment) / r.volume, DVec3::new(0.0, g, 0.0), 1e-6));
}

/// The reference's lens against the cap formulas in limits: disjoint, containment, equal.
#[test]
fn reference_lens_limits() {
    let pi = std::f64::consts::PI;
    assert_eq!(reference::lens(1.0, 1.0, 2.0).0, 0.0);
    let (v, g) = reference::lens(2.0, 0.5, 0.7);
    assert!((v - 4.0 / 3.0 * pi * 0.125).abs() < 1e-12 && (g - 0.7).abs() < 1e-12);
    let (v, g) = reference::lens(0.5, 2.0, 0.7);
    assert!((v - 4.0 / 3.0 * pi * 0.125).abs() < 1e-12 && g.abs() < 1e-12);
    let (v, _) = reference::lens(1.0, 1.0, 0.0);
    assert!((v - 4.0 / 3.0 * pi).abs() < 1e-12);
}

/// Two unit balls exactly 2 apart (every number exact in f32) touch without overlapping:
/// no contact, no volume, distance 0; concentric balls overlap with the smaller ball's volume
/// and no direction, so the force and torques are zero, not NaN.
#[test]
fn touching_and_concentric_balls() {
    let a = hand_tree(&[([0.0; 3], 1.0)], [0.0; 3]);
    let b = hand_tree(&[([0.0; 3], 1.0)], [0.0; 3]);
    let pa = Pose::IDENTITY;
    let pb = Pose::from_translation(DVec3::new(2.0, 0.0, 0.0));
    let mut st = pair(&a, &b);
    let opts = PenetrationOptions {
        safe_motion: false,
        ..Default::default()
    };
    let p = st.penetration_with(&pa, &pb, &opts);
    assert_eq!((p.pairs, p.volume), (0, 0.0));
    assert!(innersphere::query::brute::overlapping_pairs(&a, &pa, &b, &pb).is_empty());
    assert!(!st.contact(&pa, &pb).in_contact());
    let q = st.distance_with(
        &pa,
        &pb,
        &DistanceOptions {
            signed: true,
            ..Default::default()
        },
    );
    assert_eq!((q.distance, q.overlapping), (0.0, false));
    let small = hand_tree(&[([0.0; 3], 0.5)], [0.0; 3]);
    let mut st = pair(&a, &small);
    let p = st.penetration_with(&pa, &pa, &opts);
    assert_eq!(p.pairs, 1);
    assert!((p.volume - std::f64::consts::PI / 6.0).abs() < 1e-12);
    for v in [p.normal, p.force, p.torque_a, p.torque_b] {
        assert_eq!(v, DVec3::ZERO);
    }
}

/// Lenses where the circle of intersection lies behind one centre (a large ball mostly
/// inside a larger one), at several scales: volume and centroid against the reference.
#[test]
fn lenses_with_the_circle_behind_a_centre() {
    for (ra, rb, d) in [
        (10.0, 15.0, 6.0),
        (15.0, 10.0, 6.0),
        (3.0, 3.5, 0.6),
        (0.2, 0.3, 0.11),
    ] {
        let a = hand_tree(&[([0.0; 3], ra)], [0.0; 3]);
        let b = hand_tree(&[([0.0; 3], rb)], [0.0; 3]);
        let (pa, pb) = (
            Pose::IDENTITY,
            Pose::from_translation(DVec3::new(0.0, 0.0, d)),
        );
        let (v, g) = reference::lens(ra, rb, d);
        assert!(
            (innersphere::query::lens_volume(ra, rb, d) - v).abs() < 1e-9 * v,
            "{ra} {rb} {d}"
        );
        let opts = PenetrationOptions {
            max_patches: 1,
            safe_motion: false,
            ..Default::default()
        };
        let mut st = pair(&a, &b);
        let p = st.penetration_with(&pa, &pb, &opts);
        assert!((p.volume - v).abs() < 1e-7 * v, "{} vs {v}", p.volume);
        assert!(
            near(
                st.patches()[0].point,
                DVec3::new(0.0, 0.0, g),
                1e-7 * (ra + rb)
            ),
            "{} vs {g}",
            st.patches()[0].point
        );
    }
}

/// A tree of two leaves and a root, against the reference under a rotation: the rotation's
/// direction and the leaf order matter.
#[test]
fn rotated_two_leaf_trees() {
    let a = hand_tree(
        &[([-1.0, 0.0, 0.0], 1.0), ([1.0, 0.0, 0.0], 1.0)],
        [0.0, 0.5, 0.0],
    );
    let b = hand_tree(
        &[
            ([0.0, -0.6, 0.0], 0.6),
            ([0.0, 0.6, 0.0], 0.6),
            ([0.0, 0.0, 0.9], 0.3),
        ],
        [0.0, 0.0, 0.2],
    );
    for i in 0..40 {
        let s = i as f64 * 0.37;
        let pa = pose([0.2 * s.sin(), 0.1, -0.3], [1.0, 0.1 * s, 0.3, -0.2]);
        let pb = pose(
            [1.8 * s.cos(), 0.9 * s.sin(), 0.3 * (2.0 * s).sin()],
            [0.4, 1.0, -0.3 * s, 0.2],
        );
        check_all(&a, &pa, &b, &pb, 1).unwrap();
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// Random poses of generated trees: every query kind and option against the reference.
    #[test]
    fn every_query_equals_the_reference(
        ia in 0usize..4, ib in 0usize..4,
        qa in [-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64],
        qb in [-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64],
        ta in [-2.0..2.0f64, -2.0..2.0f64, -2.0..2.0f64],
        off in [-1.2..1.2f64, -1.2..1.2f64, -1.2..1.2f64],
        split in 0u32..6,
    ) {
        let t = trees();
        let (a, b) = (&t[ia], &t[ib]);
        let s = (a.r[0] + b.r[0]) as f64;
        let (pa, pb) = pair_poses(a, b, pose(ta, qa), quat(qb[0], qb[1], qb[2], qb[3]), DVec3::from_array(off) * s);
        check_all(a, &pa, b, &pb, split)?;
    }

    /// Two balls of any size from 1e-2 to 1e2 at any overlap: volume, deepest overlap and
    /// the lens centroid (the one patch's point) against the reference's integration.
    #[test]
    fn two_balls_at_every_scale(
        la in -2.0..2.0f64, lb in -2.0..2.0f64,
        frac in 0.0..1.0f64,
        dir in [-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64],
    ) {
        let (ra, rb) = (10f64.powf(la), 10f64.powf(lb));
        let u = DVec3::from_array(dir).try_normalize().unwrap_or(DVec3::X);
        // From full containment (d = 0) to just touching (d = ra + rb).
        let d = frac * (ra + rb);
        let a = hand_tree(&[([0.0; 3], ra)], [0.0; 3]);
        let b = hand_tree(&[([0.0; 3], rb)], [0.0; 3]);
        let (pa, pb) = (Pose::IDENTITY, Pose::from_translation(u * d));
        let r = RefPair::new(&a, &pa, &b, &pb);
        let want = r.penetration(1.0, 0.0);
        let opts = PenetrationOptions { max_patches: 1, safe_motion: false, ..Default::default() };
        let mut st = pair(&a, &b);
        let p = st.penetration_with(&pa, &pb, &opts);
        let tol = r.volume_tolerance() + 1e-9 * want.volume;
        prop_assert!((p.volume - want.volume).abs() <= tol, "volume {} vs {} (ra {}, rb {}, d {})", p.volume, want.volume, ra, rb, d);
        if want.volume > 1e3 * tol {
            let g = dv(want.moment) / want.volume;
            prop_assert!(near(st.patches()[0].point, g, 1e-6 * (ra + rb)), "centroid {} vs {} (ra {}, rb {}, d {})", st.patches()[0].point, g, ra, rb, d);
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(6))]

    /// Along motions, with each query's state carried from frame to frame (coherence,
    /// fronts, backtracking, safe motion): every frame against the reference. A few motions
    /// here; [`coherent_queries_along_many_motions`] runs 48 (CI, `--ignored`).
    #[test]
    fn coherent_queries_along_motions_equal_the_reference(
        ia in 0usize..4, ib in 0usize..4,
        dir in [-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64],
        side in [-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64],
        axis in [-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64],
        spin in -0.05..0.05f64,
        split in 0u32..6,
    ) {
        coherent_case(ia, ib, dir, side, axis, spin, split)?;
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// [`coherent_queries_along_motions_equal_the_reference`] along 48 motions.
    #[test]
    #[ignore = "heavy: 48 motions against the f64 reference (about 20 s); CI runs it with --ignored"]
    fn coherent_queries_along_many_motions(
        ia in 0usize..4, ib in 0usize..4,
        dir in [-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64],
        side in [-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64],
        axis in [-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64],
        spin in -0.05..0.05f64,
        split in 0u32..6,
    ) {
        coherent_case(ia, ib, dir, side, axis, spin, split)?;
    }
}

/// One motion of [`coherent_queries_along_motions_equal_the_reference`].
fn coherent_case(
    ia: usize,
    ib: usize,
    dir: [f64; 3],
    side: [f64; 3],
    axis: [f64; 3],
    spin: f64,
    split: u32,
) -> Result<(), TestCaseError> {
    let t = trees();
    let (a, b) = (&t[ia], &t[ib]);
    let frames = motion(
        a,
        b,
        DVec3::from_array(dir),
        DVec3::from_array(side),
        DVec3::from_array(axis),
        spin,
        48,
    );
    let (sa, sb) = (SharedTree::new(a.clone()), SharedTree::new(b.clone()));
    let mut st: Vec<Pair> = (0..8).map(|_| Pair::new(&sa, &sb)).collect();
    let safe = TraversalOptions { safe_motion: true };
    for (pa, pb) in &frames {
        let r = RefPair::new(a, pa, b, pb);
        check_proximity(&mut st[0], pa, pb, &r)?;
        check_contact(
            &st[1].paper().backtracking(pa, pb, &safe),
            &r,
            "backtracking",
        )?;
        check_contact(&st[2].contact(pa, pb), &r, "contact")?;
        check_contact(
            &st[3].paper().distance_traversal(pa, pb, &safe),
            &r,
            "distance traversal",
        )?;
        for (i, tracking) in [(4, false), (5, true)] {
            let opts = MultipointOptions {
                tracking,
                k: 6,
                split_depth: split,
                reuse: true,
                safe_motion: true,
            };
            check_multipoint(&mut st[i], pa, pb, &r, &opts)?;
        }
        for (i, tracking) in [(6, Tracking::Front), (7, Tracking::Traversal)] {
            let opts = PenetrationOptions {
                stiffness: 10.0,
                max_patches: 4,
                patch_radius: 0.0,
                safe_motion: true,
                tracking,
                linearize: true,
            };
            check_penetration(&mut st[i], pa, pb, &r, &opts)?;
        }
    }
    Ok(())
}
