//! Comparisons of every query kind with [`RefPair`](super::RefPair), for the test files that
//! use the reference: each returns the first disagreement as a proptest failure.

use super::{ancestor_at, dv, norm, RefPair};
use glam::DVec3;
use innersphere::query::TraversalOptions;
use innersphere::{
    ContactResult, DistanceOptions, MultipointOptions, Pair, PenetrationOptions, Pose, SharedTree,
    SphereTree, Tracking,
};
use proptest::prelude::*;
use std::collections::BTreeSet;

pub(crate) const NO_SKIP: TraversalOptions = TraversalOptions { safe_motion: false };

pub(crate) fn near(x: DVec3, y: DVec3, tol: f64) -> bool {
    (x - y).length() <= tol
}

/// Exact distance, every option, against the reference's minimum gap and closest points.
pub(crate) fn check_proximity(
    pair: &mut Pair,
    pa: &Pose,
    pb: &Pose,
    r: &RefPair,
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
        let opts = DistanceOptions {
            signed,
            coherence,
            best_first,
            ..Default::default()
        };
        let p = pair.distance_with(pa, pb, &opts);
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
        let pg = super::gap(r.leaf_a(p.leaf_a), r.leaf_b(p.leaf_b));
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
pub(crate) fn check_contact(
    q: &ContactResult,
    r: &RefPair,
    what: &str,
) -> Result<(), TestCaseError> {
    let (g, _, _) = r.min_gap();
    let eps = r.eps;
    if g < -eps {
        prop_assert!(q.in_contact(), "{}: missed an overlap of {}", what, -g);
    } else if g > eps {
        prop_assert!(!q.in_contact(), "{}: contact at gap {}", what, g);
    }
    match q.contact {
        Some(c) => {
            let pg = super::gap(r.leaf_a(c.leaf_a), r.leaf_b(c.leaf_b));
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
pub(crate) fn check_multipoint(
    pair: &mut Pair,
    pa: &Pose,
    pb: &Pose,
    r: &RefPair,
    opts: &MultipointOptions,
) -> Result<(), TestCaseError> {
    let split = opts.split_depth;
    let (a, b) = (pair.tree_a().tree().clone(), pair.tree_b().tree().clone());
    let region = |(la, lb): (u32, u32)| (ancestor_at(&a, la, split), ancestor_at(&b, lb, split));
    let sure: BTreeSet<_> = r.overlapping(-r.eps).into_iter().map(region).collect();
    let possible: BTreeSet<_> = r.overlapping(r.eps).into_iter().map(region).collect();
    pair.multipoint(pa, pb, opts);
    let contacts = pair.contacts();
    let mut seen = BTreeSet::new();
    for c in contacts {
        let pg = super::gap(r.leaf_a(c.leaf_a), r.leaf_b(c.leaf_b));
        prop_assert!(pg < r.eps, "multipoint contact with gap {}", pg);
        let (p, depth) = r.contact_point(c.leaf_a, c.leaf_b);
        prop_assert!(near(c.point, dv(p), 4.0 * r.eps));
        prop_assert!((c.depth - depth).abs() <= 2.0 * r.eps);
        prop_assert!(
            seen.insert(region((c.leaf_a, c.leaf_b))),
            "two contacts below one split pair"
        );
    }
    prop_assert!(contacts.len() <= opts.k);
    prop_assert!(
        contacts.len() >= opts.k.min(sure.len()),
        "{} contacts, {} regions overlap",
        contacts.len(),
        sure.len()
    );
    prop_assert!(contacts.len() <= possible.len());
    if contacts.len() < opts.k {
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
pub(crate) fn check_penetration(
    pair: &mut Pair,
    pa: &Pose,
    pb: &Pose,
    r: &RefPair,
    opts: &PenetrationOptions,
) -> Result<(), TestCaseError> {
    let k = opts.stiffness;
    let want = r.penetration(k, 0.0);
    let sure = r.penetration(k, -r.eps).pairs;
    let possible = r.penetration(k, r.eps).pairs;
    let tol_v = r.volume_tolerance();
    let p = pair.penetration_with(pa, pb, opts);
    let patches = pair.patches();
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
        prop_assert!(patches.is_empty());
        return Ok(());
    }
    // How far the sums may move: every pair's volume and direction within rounding.
    let vu_len = want.vu_len;
    let vu_tol = 2.0 * tol_v
        + r.pairs()
            .filter(|q| q.2 < r.eps)
            .map(|(x, y, _)| {
                let d = norm([y.c[0] - x.c[0], y.c[1] - x.c[1], y.c[2] - x.c[2]]);
                super::lens(x.r, y.r, d).0 * (2.0 * r.eps / d).min(2.0)
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
        prop_assert!(!patches.is_empty() && patches.len() <= opts.max_patches);
        let moment = patches
            .iter()
            .fold(DVec3::ZERO, |s, q| s + q.point * q.volume);
        prop_assert!(
            near(moment, dv(want.moment), lever * 2.0 * tol_v + 1e-9),
            "patch moment {} vs {:?}",
            moment,
            want.moment
        );
        let pairs: u32 = patches.iter().map(|q| q.pairs).sum();
        prop_assert_eq!(pairs as usize, p.pairs);
        for q in patches {
            prop_assert!(q.depth > -r.eps && q.depth <= p.max_depth);
        }
    }
    Ok(())
}

/// Every query kind and option at one pose, each with a fresh pair.
pub(crate) fn check_all(
    a: &SphereTree,
    pa: &Pose,
    b: &SphereTree,
    pb: &Pose,
    split: u32,
) -> Result<(), TestCaseError> {
    let r = RefPair::new(a, pa, b, pb);
    let (sa, sb) = (SharedTree::new(a.clone()), SharedTree::new(b.clone()));
    let fresh = || Pair::new(&sa, &sb);
    check_proximity(&mut fresh(), pa, pb, &r)?;
    for safe_motion in [false, true] {
        let o = TraversalOptions { safe_motion };
        check_contact(
            &fresh().paper().distance_traversal(pa, pb, &o),
            &r,
            "distance traversal",
        )?;
        check_contact(
            &fresh().paper().backtracking(pa, pb, &o),
            &r,
            "backtracking",
        )?;
        check_contact(&fresh().contact(pa, pb), &r, "contact")?;
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
            check_multipoint(&mut fresh(), pa, pb, &r, &opts)?;
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
                linearize: max_patches == 1,
            };
            check_penetration(&mut fresh(), pa, pb, &r, &opts)?;
        }
    }
    // One patch: its point is the centroid of the whole intersection.
    let opts = PenetrationOptions {
        max_patches: 1,
        safe_motion: false,
        ..Default::default()
    };
    let mut pair = fresh();
    pair.penetration_with(pa, pb, &opts);
    let want = r.penetration(1.0, 0.0);
    if let [q] = pair.patches() {
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
        let v = fresh().penetration_within(pa, pb, budget);
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
