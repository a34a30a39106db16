//! Penetration volume, force, torque and patches against the brute-force sum over all leaf
//! pairs, and the time-critical mode's bounds (found ≤ exact ≤ upper bound).

use super::query_util;

use glam::DVec3;
use innersphere::query::brute;
use innersphere::{PenetrationOptions, Tracking};
use proptest::prelude::*;
use query_util::*;

fn vec3() -> impl Strategy<Value = DVec3> {
    [-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64].prop_map(DVec3::from_array)
}

fn close_vec(x: DVec3, y: DVec3, scale: f64) -> bool {
    (x - y).length() <= 1e-9 * scale + 1e-12
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    /// Volume, pair count, deepest overlap, normal, force and torques equal the brute-force
    /// sums over all leaf pairs; the patches partition the pairs and the volume.
    #[test]
    fn penetration_equals_brute_force(
        ia in 0usize..4, ib in 0usize..4,
        qa in [-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64],
        qb in [-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64],
        off in vec3(),
        stiffness in 0.1..1000.0f64,
        max_patches in 0usize..6,
        patch_radius in prop_oneof![Just(0.0), 0.05..1.0f64],
        tracking in prop_oneof![Just(Tracking::Auto), Just(Tracking::Front), Just(Tracking::Traversal)],
    ) {
        let t = trees();
        let (a, b) = (&t[ia], &t[ib]);
        let scale = (a.r[0] + b.r[0]) as f64;
        let (pa, pb) = pair_poses(a, b, pose([1.0, 2.0, -0.5], qa), quat(qb[0], qb[1], qb[2], qb[3]), off * 0.9 * scale);
        let want = brute::penetration(a, &pa, b, &pb, stiffness);
        let mut pair = pair(a, b);
        let opts = PenetrationOptions { stiffness, max_patches, patch_radius, safe_motion: false, tracking, linearize: false };
        let p = pair.penetration_with(&pa, &pb, &opts);
        let patches = pair.patches();
        prop_assert_eq!(p.pairs, want.pairs);
        prop_assert!(close(p.volume, want.volume, 1e-10, 1e-15), "{} vs {}", p.volume, want.volume);
        prop_assert_eq!(p.max_depth, want.max_depth);
        let f = stiffness * want.volume;
        prop_assert!(close_vec(p.normal, want.normal, 1e-3 + 0.0 * f));
        prop_assert!(close_vec(p.force, want.force, f * 1e3), "{} vs {}", p.force, want.force);
        let tscale = f * 10.0 * scale * (1.0 + want.normal.length() * 1e3);
        prop_assert!(close_vec(p.torque_a, want.torque_a, tscale), "{} vs {}", p.torque_a, want.torque_a);
        prop_assert!(close_vec(p.torque_b, want.torque_b, tscale), "{} vs {}", p.torque_b, want.torque_b);
        if want.pairs > 0 {
            prop_assert!((p.force.length() - f).abs() <= 1e-9 * f + 1e-15);
            prop_assert!((p.normal.length() - 1.0).abs() < 1e-9 || p.force == DVec3::ZERO);
            prop_assert_eq!(p.distance, 0.0);
            prop_assert!(patches.len() <= max_patches);
            if max_patches > 0 {
                prop_assert!(!patches.is_empty());
                let pv: f64 = patches.iter().map(|q| q.volume).sum();
                let pn: u32 = patches.iter().map(|q| q.pairs).sum();
                prop_assert!(close(pv, p.volume, 1e-9, 1e-15));
                prop_assert_eq!(pn as usize, p.pairs);
                for q in patches {
                    prop_assert!(q.depth > 0.0 && q.depth <= p.max_depth);
                }
            }
        } else {
            prop_assert_eq!(p.volume, 0.0);
            prop_assert!(patches.is_empty());
            let (bd, _, _) = brute::min_distance(a, &pa, b, &pb);
            prop_assert!(p.distance <= bd);
        }
    }

    /// Time-critical mode: found ≤ exact ≤ upper bound for any budget, and an unlimited
    /// budget gives the exact volume.
    #[test]
    fn budgeted_volume_bounds(
        ia in 0usize..4, ib in 0usize..4,
        qb in [-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64],
        off in vec3(),
    ) {
        let t = trees();
        let (a, b) = (&t[ia], &t[ib]);
        let scale = (a.r[0] + b.r[0]) as f64;
        let (pa, pb) = pair_poses(a, b, Default::default(), quat(qb[0], qb[1], qb[2], qb[3]), off * 0.8 * scale);
        let mut pair = pair(a, b);
        let exact = pair.penetration_with(&pa, &pb, &PenetrationOptions { safe_motion: false, tracking: Tracking::Traversal, ..Default::default() }).volume;
        let tol = 1e-9 * exact + 1e-15;
        let mut last_visits = 0;
        for budget in [0u64, 1, 5, 20, 100, 400, 2000, 10_000, u64::MAX] {
            let r = pair.penetration_within(&pa, &pb, budget);
            prop_assert!(r.volume <= exact + tol, "budget {}: found {} > exact {}", budget, r.volume, exact);
            prop_assert!(exact <= r.upper_bound + tol, "budget {}: exact {} > upper {}", budget, exact, r.upper_bound);
            prop_assert!(r.volume <= r.upper_bound);
            prop_assert!(r.visits >= last_visits);
            last_visits = r.visits;
            if budget == u64::MAX {
                prop_assert!(r.complete);
                prop_assert!(close(r.volume, exact, 1e-10, 1e-15));
                prop_assert_eq!(r.upper_bound, r.volume);
            } else {
                // At most one refinement (≤ fan-out² tests) past the budget.
                prop_assert!(r.visits <= budget.max(1) + 64);
            }
        }
    }

    /// Along a motion, the kinetic front (tracking) gives the same overlapping pairs and
    /// volume as a traversal from the roots on every frame.
    #[test]
    fn tracked_penetration_equals_traversal_along_motions(
        ia in 0usize..4, ib in 0usize..4,
        dir in vec3(), side in vec3(), axis in vec3(),
        spin in -0.04..0.04f64,
    ) {
        let t = trees();
        let (a, b) = (&t[ia], &t[ib]);
        let frames = motion(a, b, dir, side, axis, spin, 120);
        let mut tracked = pair(a, b);
        let mut plain = pair(a, b);
        let topt = PenetrationOptions { tracking: Tracking::Front, ..Default::default() };
        let popt = PenetrationOptions { tracking: Tracking::Traversal, safe_motion: false, ..Default::default() };
        for (f, (pa, pb)) in frames.iter().enumerate() {
            let q = tracked.penetration_with(pa, pb, &topt);
            let (qv, qp, qf) = (q.volume, q.pairs, q.force);
            let r = plain.penetration_with(pa, pb, &popt);
            prop_assert_eq!(qp, r.pairs, "frame {}", f);
            prop_assert!(close(qv, r.volume, 1e-10, 1e-15), "frame {}: {} vs {}", f, qv, r.volume);
            prop_assert!((qf - r.force).length() <= 1e-8 * r.force.length() + 1e-15);
        }
    }

    /// The floor: the overlapping leaves are the brute-force set, and their sum alone is the
    /// query's answer (pairs, depth and patch count exact, sums to rounding); an index that is
    /// no leaf is refused.
    #[test]
    fn the_floor_sums_the_brute_force_leaves_to_the_query_answer(
        ia in 0usize..4, ib in 0usize..4,
        qa in [-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64],
        qb in [-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64],
        off in vec3(),
        linearize in any::<bool>(),
    ) {
        let t = trees();
        let (a, b) = (&t[ia], &t[ib]);
        let scale = (a.r[0] + b.r[0]) as f64;
        let (pa, pb) = pair_poses(a, b, pose([1.0, 2.0, -0.5], qa), quat(qb[0], qb[1], qb[2], qb[3]), off * 0.9 * scale);
        let mut pair = pair(a, b);
        let mut leaves = vec![[7, 7]];
        pair.overlapping_leaves(&pa, &pb, &mut leaves);
        let mut sorted: Vec<(u32, u32)> = leaves.iter().map(|&[i, j]| (i, j)).collect();
        sorted.sort_unstable();
        prop_assert_eq!(sorted, brute::overlapping_pairs(a, &pa, b, &pb));
        let opts = PenetrationOptions { linearize, safe_motion: false, ..Default::default() };
        let p = pair.penetration_with(&pa, &pb, &opts);
        let q = pair.penetration_of_leaves(&pa, &pb, &leaves, &opts).unwrap();
        prop_assert_eq!(q.pairs, p.pairs);
        prop_assert_eq!(q.max_depth, p.max_depth);
        prop_assert_eq!(q.patch_count, p.patch_count);
        prop_assert_eq!(q.visits, leaves.len() as u64);
        prop_assert!(close(q.volume, p.volume, 1e-12, 1e-15), "{} vs {}", q.volume, p.volume);
        prop_assert!(close(q.area, p.area, 1e-12, 1e-15));
        let f = p.force.length();
        prop_assert!((q.force - p.force).length() <= 1e-12 * f + 1e-15);
        prop_assert!((q.torque_b - p.torque_b).length() <= 1e-9 * f * scale + 1e-12);
        // Pairs that do not overlap add nothing.
        let n = (a.len() as u32 - 1, b.len() as u32 - 1);
        let leaf_a = (0..=n.0).filter(|&i| a.is_leaf(i as usize));
        let apart: Vec<[u32; 2]> = leaf_a
            .flat_map(|i| (0..=n.1).filter(|&j| b.is_leaf(j as usize)).map(move |j| [i, j]))
            .filter(|&[i, j]| !brute::leaves_overlap(a, i, &pa, b, j, &pb))
            .take(5)
            .collect();
        let r = pair.penetration_of_leaves(&pa, &pb, &[apart.clone(), leaves.clone(), apart].concat(), &opts).unwrap();
        prop_assert_eq!(r.pairs, p.pairs);
        prop_assert!(close(r.volume, p.volume, 1e-12, 1e-15));
        for bad in [[u32::MAX, 0], [0, u32::MAX], [n.0 + 1, 0]] {
            let mut l = leaves.clone();
            l.push(bad);
            prop_assert!(pair.penetration_of_leaves(&pa, &pb, &l, &opts).is_err());
        }
    }
}
