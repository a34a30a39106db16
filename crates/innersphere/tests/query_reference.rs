//! Every query kind against the independent f64 reference (`reference/`), which shares no
//! code with the queries: hand-worked two-ball cases computed on paper, random poses of
//! generated trees, and motions that carry each query's coherent state from frame to frame.

mod query_util;
mod reference;

use glam::DVec3;
use innersphere::query::{
    backtracking, contact, distance_traversal, multipoint, penetration, penetration_budgeted,
    proximity, ContactOptions, ContactQuery, MultipointOptions, PairState, PenetrationOptions,
    Pose, ProximityOptions, Tracking,
};
use innersphere::SphereTree;
use proptest::prelude::*;
use query_util::{motion, pair_poses, pose, quat, trees};
use reference::{ancestor_at, dv, hand_tree, norm, RefPair};
use std::collections::BTreeSet;

const NO_SKIP: ContactOptions = ContactOptions { safe_motion: false };

fn near(x: DVec3, y: DVec3, tol: f64) -> bool {
    (x - y).length() <= tol
}

/// Exact proximity, every option, against the reference's minimum gap and closest points.
fn check_proximity(
    a: &SphereTree,
    pa: &Pose,
    b: &SphereTree,
    pb: &Pose,
    r: &RefPair,
    st: &mut PairState,
) -> Result<(), TestCaseError> {
    let (g, _, _) = r.min_gap();
    let eps = r.eps;
    for (signed, coherence, best_first) in [
        (false, false, false),
        (false, true, false),
        (false, false, true),
        (true, false, false),
        (true, true, true),
    ] {
        let opts = ProximityOptions {
            signed,
            coherence,
            best_first,
            ..Default::default()
        };
        let p = proximity(a, pa, b, pb, st, &opts);
        let want = if signed { g } else { g.max(0.0) };
        prop_assert!(
            (p.distance - want).abs() <= eps,
            "proximity {:?}: {} vs reference {}",
            opts,
            p.distance,
            want
        );
        if g.abs() > eps {
            prop_assert_eq!(p.overlapping, g < 0.0);
        }
        // The reported leaf pair attains the minimum (unsigned overlap: any overlapping pair).
        let pg = reference::gap(r.leaf_a(p.leaf_a), r.leaf_b(p.leaf_b));
        if signed || g > eps {
            prop_assert!((pg - g).abs() <= 2.0 * eps, "leaf pair gap {} vs {}", pg, g);
        } else {
            prop_assert!(pg < eps, "overlapping pair with gap {}", pg);
        }
        prop_assert!((p.pair_distance - pg).abs() <= eps);
        if !p.overlapping {
            let (qa, qb) = r.closest_points(p.leaf_a, p.leaf_b);
            prop_assert!(
                near(p.point_a, dv(qa), 4.0 * eps),
                "{} vs {:?}",
                p.point_a,
                qa
            );
            prop_assert!(
                near(p.point_b, dv(qb), 4.0 * eps),
                "{} vs {:?}",
                p.point_b,
                qb
            );
        }
    }
    Ok(())
}

/// A first-contact answer against the reference: contact exactly when a leaf pair overlaps
/// (outside the rounding band); the contact is a real overlapping pair with the reference's
/// point, normal and depth; without contact a lower bound on the gap.
fn check_contact(q: &ContactQuery, r: &RefPair, what: &str) -> Result<(), TestCaseError> {
    let (g, _, _) = r.min_gap();
    let eps = r.eps;
    if g < -eps {
        prop_assert!(q.in_contact(), "{}: missed an overlap of {}", what, -g);
    } else if g > eps {
        prop_assert!(!q.in_contact(), "{}: contact at gap {}", what, g);
    }
    match q.contact {
        Some(c) => {
            let pg = reference::gap(r.leaf_a(c.leaf_a), r.leaf_b(c.leaf_b));
            prop_assert!(pg < eps, "{}: contact pair has gap {}", what, pg);
            let (p, depth) = r.contact_point(c.leaf_a, c.leaf_b);
            prop_assert!(
                near(c.point, dv(p), 4.0 * eps),
                "{}: point {} vs {:?}",
                what,
                c.point,
                p
            );
            prop_assert!((c.depth - depth).abs() <= 2.0 * eps);
            let (x, y) = (r.leaf_a(c.leaf_a), r.leaf_b(c.leaf_b));
            let d = DVec3::from_array(y.c) - DVec3::from_array(x.c);
            if d.length() > 1e3 * eps {
                prop_assert!(near(c.normal, d.normalize(), 1e3 * eps / d.length()));
            }
            prop_assert_eq!(q.distance, 0.0);
        }
        None => prop_assert!(
            q.distance <= g.max(0.0) + eps,
            "{}: bound {} above {}",
            what,
            q.distance,
            g
        ),
    }
    Ok(())
}

/// Multipoint against the reference: every contact a real overlapping pair with the
/// reference's point, at most one per split-depth pair, none missed while fewer than `k`.
#[allow(clippy::too_many_arguments)]
fn check_multipoint(
    a: &SphereTree,
    pa: &Pose,
    b: &SphereTree,
    pb: &Pose,
    r: &RefPair,
    st: &mut PairState,
    opts: &MultipointOptions,
) -> Result<(), TestCaseError> {
    let split = opts.split_depth;
    let region = |(la, lb): (u32, u32)| (ancestor_at(a, la, split), ancestor_at(b, lb, split));
    let sure: BTreeSet<_> = r.overlapping(-r.eps).into_iter().map(region).collect();
    let possible: BTreeSet<_> = r.overlapping(r.eps).into_iter().map(region).collect();
    let m = multipoint(a, pa, b, pb, st, opts);
    let mut seen = BTreeSet::new();
    for c in m.contacts {
        let pg = reference::gap(r.leaf_a(c.leaf_a), r.leaf_b(c.leaf_b));
        prop_assert!(pg < r.eps, "multipoint contact with gap {}", pg);
        let (p, depth) = r.contact_point(c.leaf_a, c.leaf_b);
        prop_assert!(near(c.point, dv(p), 4.0 * r.eps));
        prop_assert!((c.depth - depth).abs() <= 2.0 * r.eps);
        prop_assert!(
            seen.insert(region((c.leaf_a, c.leaf_b))),
            "two contacts below one split pair"
        );
    }
    prop_assert!(m.contacts.len() <= opts.k);
    prop_assert!(
        m.contacts.len() >= opts.k.min(sure.len()),
        "{} contacts, {} regions overlap",
        m.contacts.len(),
        sure.len()
    );
    prop_assert!(m.contacts.len() <= possible.len());
    if m.contacts.len() < opts.k {
        for key in &sure {
            prop_assert!(
                seen.contains(key),
                "split pair {:?} overlaps but has no contact",
                key
            );
        }
    }
    Ok(())
}

/// Penetration against the reference: pairs, volume, deepest overlap, normal, force, both
/// torques, and the patches' points (their volume-weighted sum is the volume's moment).
fn check_penetration(
    a: &SphereTree,
    pa: &Pose,
    b: &SphereTree,
    pb: &Pose,
    r: &RefPair,
    st: &mut PairState,
    opts: &PenetrationOptions,
) -> Result<(), TestCaseError> {
    let k = opts.stiffness;
    let want = r.penetration(k, 0.0);
    let sure = r.penetration(k, -r.eps).pairs;
    let possible = r.penetration(k, r.eps).pairs;
    let tol_v = r.volume_tolerance();
    let p = penetration(a, pa, b, pb, st, opts);
    prop_assert!(
        p.pairs >= sure && p.pairs <= possible,
        "{} pairs, reference {}..{}",
        p.pairs,
        sure,
        possible
    );
    prop_assert!(
        (p.volume - want.volume).abs() <= tol_v,
        "volume {} vs {} (tol {})",
        p.volume,
        want.volume,
        tol_v
    );
    prop_assert!((p.max_depth - want.max_depth).abs() <= 2.0 * r.eps);
    if want.pairs == 0 && sure == possible {
        prop_assert_eq!(p.volume, 0.0);
        prop_assert!(p.patches.is_empty());
        return Ok(());
    }
    // How far the sums may move: every pair's volume and direction within rounding.
    let vu_len = want.vu_len;
    let vu_tol = 2.0 * tol_v
        + r.pairs()
            .filter(|q| q.2 < r.eps)
            .map(|(x, y, _)| {
                let d = norm([y.c[0] - x.c[0], y.c[1] - x.c[1], y.c[2] - x.c[2]]);
                reference::lens(x.r, y.r, d).0 * (2.0 * r.eps / d).min(2.0)
            })
            .sum::<f64>();
    if vu_len < 1e3 * vu_tol {
        // Opposing contacts cancel: the normal is ill-conditioned; the volume checks stand.
        return Ok(());
    }
    let tol_n = 2.0 * vu_tol / vu_len;
    let tol_f = k * (tol_v + want.volume * tol_n);
    prop_assert!(
        near(p.normal, dv(want.normal), tol_n),
        "normal {} vs {:?}",
        p.normal,
        want.normal
    );
    prop_assert!(
        near(p.force, dv(want.force), tol_f),
        "force {} vs {:?} (tol {})",
        p.force,
        want.force,
        tol_f
    );
    let lever = r
        .a
        .iter()
        .chain(&r.b)
        .flat_map(|s| {
            [r.com_a, r.com_b].map(|c| norm([s.c[0] - c[0], s.c[1] - c[1], s.c[2] - c[2]]) + s.r)
        })
        .fold(0.0, f64::max);
    let tol_t = lever * (tol_f + k * want.volume / vu_len * vu_tol) + 1e-9 * want.torque_scale;
    prop_assert!(
        near(p.torque_a, dv(want.torque_a), tol_t),
        "torque A {} vs {:?} (tol {})",
        p.torque_a,
        want.torque_a,
        tol_t
    );
    prop_assert!(
        near(p.torque_b, dv(want.torque_b), tol_t),
        "torque B {} vs {:?} (tol {})",
        p.torque_b,
        want.torque_b,
        tol_t
    );
    if opts.max_patches > 0 {
        prop_assert!(!p.patches.is_empty() && p.patches.len() <= opts.max_patches);
        let moment = p
            .patches
            .iter()
            .fold(DVec3::ZERO, |s, q| s + q.point * q.volume);
        prop_assert!(
            near(moment, dv(want.moment), lever * 2.0 * tol_v + 1e-9),
            "patch moment {} vs {:?}",
            moment,
            want.moment
        );
        let pairs: u32 = p.patches.iter().map(|q| q.pairs).sum();
        prop_assert_eq!(pairs as usize, p.pairs);
        for q in p.patches {
            prop_assert!(q.depth > -r.eps && q.depth <= p.max_depth);
        }
    }
    Ok(())
}

/// Every query kind and option at one pose, each with a fresh state.
fn check_all(
    a: &SphereTree,
    pa: &Pose,
    b: &SphereTree,
    pb: &Pose,
    split: u32,
) -> Result<(), TestCaseError> {
    let r = RefPair::new(a, pa, b, pb);
    check_proximity(a, pa, b, pb, &r, &mut PairState::new(a, b))?;
    for safe_motion in [false, true] {
        let o = ContactOptions { safe_motion };
        check_contact(
            &distance_traversal(a, pa, b, pb, &mut PairState::new(a, b), &o),
            &r,
            "distance traversal",
        )?;
        check_contact(
            &backtracking(a, pa, b, pb, &mut PairState::new(a, b), &o),
            &r,
            "backtracking",
        )?;
        check_contact(
            &contact(a, pa, b, pb, &mut PairState::new(a, b), &o),
            &r,
            "contact",
        )?;
    }
    for tracking in [false, true] {
        for k in [1, 3, 16, 1000] {
            let opts = MultipointOptions {
                tracking,
                k,
                split_depth: split,
                reuse: true,
                safe_motion: false,
            };
            check_multipoint(a, pa, b, pb, &r, &mut PairState::new(a, b), &opts)?;
        }
    }
    for tracking in [Tracking::Auto, Tracking::Front, Tracking::Traversal] {
        for max_patches in [0, 1, 5] {
            let opts = PenetrationOptions {
                stiffness: 3.5,
                max_patches,
                patch_radius: 0.0,
                safe_motion: false,
                tracking,
            };
            check_penetration(a, pa, b, pb, &r, &mut PairState::new(a, b), &opts)?;
        }
    }
    // One patch: its point is the centroid of the whole intersection.
    let opts = PenetrationOptions {
        max_patches: 1,
        safe_motion: false,
        ..Default::default()
    };
    let mut st = PairState::new(a, b);
    let p = penetration(a, pa, b, pb, &mut st, &opts);
    let want = r.penetration(1.0, 0.0);
    if let [q] = p.patches {
        if want.volume > 1e3 * r.volume_tolerance() {
            let g = dv(want.moment) / want.volume;
            prop_assert!(
                near(q.point, g, 1e-3 * norm(want.moment) / want.volume + 1e-6),
                "patch point {} vs {}",
                q.point,
                g
            );
        }
    }
    // The time-critical volume brackets the reference's.
    let tol_v = r.volume_tolerance();
    for budget in [1u64, 16, 256, u64::MAX] {
        let v = penetration_budgeted(a, pa, b, pb, &mut PairState::new(a, b), budget);
        prop_assert!(
            v.volume <= want.volume + tol_v,
            "budget {}: found {} > {}",
            budget,
            v.volume,
            want.volume
        );
        prop_assert!(
            v.upper_bound >= want.volume - tol_v,
            "budget {}: bound {} < {}",
            budget,
            v.upper_bound,
            want.volume
        );
        if budget == u64::MAX {
            prop_assert!(v.complete && (v.volume - want.volume).abs() <= tol_v);
        }
    }
    Ok(())
}

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
    let mut st = PairState::new(&a, &b);
    let p = penetration(
        &a,
        &pa,
        &b,
        &pb,
        &mut st,
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
    assert_eq!(p.patches.len(), 1);
    assert!(near(p.patches[0].point, DVec3::new(0.75, 0.0, 0.0), 1e-12));
    let r = RefPair::new(&a, &pa, &b, &pb).penetration(k, 0.0);
    assert!(
        (r.volume - v).abs() < 1e-12
            && near(dv(r.torque_a), p.torque_a, 1e-12)
            && near(dv(r.torque_b), p.torque_b, 1e-12)
    );
    let s = proximity(
        &a,
        &pa,
        &b,
        &pb,
        &mut st,
        &ProximityOptions {
            signed: true,
            ..Default::default()
        },
    );
    assert!((s.distance + 0.5).abs() < 1e-12);
    let c = contact(&a, &pa, &b, &pb, &mut st, &NO_SKIP)
        .contact
        .expect("contact");
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
    let mut st = PairState::new(&a, &b);
    let p = penetration(
        &a,
        &pa,
        &b,
        &pb,
        &mut st,
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
        near(p.patches[0].point, DVec3::new(0.0, g, 0.0), 1e-6),
        "{}",
        p.patches[0].point
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

    /// Along motions, with each query's state carried from frame to frame (coherence,
    /// fronts, backtracking, safe motion): every frame against the reference.
    #[test]
    fn coherent_queries_along_motions_equal_the_reference(
        ia in 0usize..4, ib in 0usize..4,
        dir in [-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64],
        side in [-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64],
        axis in [-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64],
        spin in -0.05..0.05f64,
        split in 0u32..6,
    ) {
        let t = trees();
        let (a, b) = (&t[ia], &t[ib]);
        let frames = motion(a, b, DVec3::from_array(dir), DVec3::from_array(side), DVec3::from_array(axis), spin, 48);
        let mut st: Vec<PairState> = (0..8).map(|_| PairState::new(a, b)).collect();
        let safe = ContactOptions { safe_motion: true };
        for (pa, pb) in &frames {
            let r = RefPair::new(a, pa, b, pb);
            check_proximity(a, pa, b, pb, &r, &mut st[0])?;
            check_contact(&backtracking(a, pa, b, pb, &mut st[1], &safe), &r, "backtracking")?;
            check_contact(&contact(a, pa, b, pb, &mut st[2], &safe), &r, "contact")?;
            check_contact(&distance_traversal(a, pa, b, pb, &mut st[3], &safe), &r, "distance traversal")?;
            for (i, tracking) in [(4, false), (5, true)] {
                let opts = MultipointOptions { tracking, k: 6, split_depth: split, reuse: true, safe_motion: true };
                check_multipoint(a, pa, b, pb, &r, &mut st[i], &opts)?;
            }
            for (i, tracking) in [(6, Tracking::Front), (7, Tracking::Traversal)] {
                let opts = PenetrationOptions { stiffness: 10.0, max_patches: 4, patch_radius: 0.0, safe_motion: true, tracking };
                check_penetration(a, pa, b, pb, &r, &mut st[i], &opts)?;
            }
        }
    }
}
