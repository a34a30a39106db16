//! Exact distance ([`Pair::distance`](innersphere::Pair::distance)) against a brute-force scan over all leaf pairs, on random poses of small
//! trees, with and without tolerances, signed or not, and along motions (coherence).

use super::query_util;

use glam::DVec3;
use innersphere::query::brute;
use innersphere::DistanceOptions;
use proptest::prelude::*;
use query_util::*;

fn offset_strategy() -> impl Strategy<Value = DVec3> {
    // Offsets of B's root centre in units of the summed root radii: deep overlaps to clear
    // separation.
    (-1.3..1.3f64, -1.3..1.3f64, -1.3..1.3f64).prop_map(|(x, y, z)| DVec3::new(x, y, z))
}

fn quat_strategy() -> impl Strategy<Value = [f64; 4]> {
    [-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(96))]

    /// The distance equals the brute-force minimum over leaf pairs (bit for bit, same f32
    /// arithmetic); overlap is reported exactly when some leaf pair overlaps; the closest
    /// points are the reported pair's; signed mode gives minus the deepest overlap.
    #[test]
    fn proximity_equals_brute_force(
        ia in 0usize..4, ib in 0usize..4,
        qa in quat_strategy(), qb in quat_strategy(),
        ta in [-2.0..2.0f64, -2.0..2.0f64, -2.0..2.0f64],
        off in offset_strategy(),
    ) {
        let t = trees();
        let (a, b) = (&t[ia], &t[ib]);
        let scale = (a.r[0] + b.r[0]) as f64;
        let (pa, pb) = pair_poses(a, b, pose(ta, qa), quat(qb[0], qb[1], qb[2], qb[3]), off * scale);
        let (bd, _, _) = brute::min_distance(a, &pa, b, &pb);
        let mut pair = pair(a, b);
        for (coherence, best_first) in [(false, false), (true, false), (true, false), (false, true), (true, true)] {
            let opts = DistanceOptions { coherence, best_first, ..Default::default() };
            let p = pair.distance_with(&pa, &pb, &opts);
            prop_assert_eq!(p.overlapping, bd < 0.0);
            prop_assert_eq!(p.distance, bd.max(0.0));
            prop_assert_eq!(p.lower_bound, p.distance);
            prop_assert!(a.is_leaf(p.leaf_a as usize) && b.is_leaf(p.leaf_b as usize));
            if bd >= 0.0 {
                prop_assert_eq!(p.pair_distance, bd);
                let gap = (p.point_b - p.point_a).length();
                prop_assert!((gap - bd).abs() < 1e-4 * scale, "points {} apart, distance {}", gap, bd);
                prop_assert!(((p.point_b - p.point_a).normalize_or_zero() - p.normal).length() < 1e-3 || bd < 1e-4);
            } else {
                prop_assert!(brute::leaves_overlap(a, p.leaf_a, &pa, b, p.leaf_b, &pb));
                prop_assert!(p.pair_distance < 0.0);
            }
            let s = pair.distance_with(&pa, &pb, &DistanceOptions { signed: true, coherence, best_first, ..Default::default() });
            prop_assert_eq!(s.distance, bd);
            prop_assert_eq!(s.pair_distance, bd);
        }
    }

    /// With tolerances the answer is within them: true ≤ d ≤ true + max(abs, rel·true), and
    /// the lower bound is below the true distance.
    #[test]
    fn proximity_tolerances(
        ia in 0usize..4, ib in 0usize..4,
        qb in quat_strategy(),
        off in offset_strategy(),
        abs in 0.0..0.2f64, rel in 0.0..0.5f64,
        best_first in any::<bool>(),
    ) {
        let t = trees();
        let (a, b) = (&t[ia], &t[ib]);
        let scale = (a.r[0] + b.r[0]) as f64;
        let (pa, pb) = pair_poses(a, b, Default::default(), quat(qb[0], qb[1], qb[2], qb[3]), off * 1.5 * scale);
        let (bd, _, _) = brute::min_distance(a, &pa, b, &pb);
        let mut pair = pair(a, b);
        let opts = DistanceOptions { abs_tolerance: abs, rel_tolerance: rel, coherence: false, signed: false, best_first };
        let p = pair.distance_with(&pa, &pb, &opts);
        let truth = bd.max(0.0);
        let slop = 1e-6 * scale;
        prop_assert!(p.distance >= truth - slop, "{} < {}", p.distance, truth);
        prop_assert!(p.distance <= truth + abs.max(rel * truth) + slop, "{} vs {} (abs {}, rel {})", p.distance, truth, abs, rel);
        prop_assert!(p.lower_bound <= truth + slop);
        prop_assert!(p.lower_bound <= p.distance);
    }

    /// Along a motion with coherence (the pair carried from frame to frame) every frame
    /// still equals brute force.
    #[test]
    fn proximity_along_motions(
        ia in 0usize..4, ib in 0usize..4,
        dir in [-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64],
        side in [-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64],
        axis in [-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64],
        spin in -0.05..0.05f64,
    ) {
        let t = trees();
        let (a, b) = (&t[ia], &t[ib]);
        let frames = motion(a, b, DVec3::from_array(dir), DVec3::from_array(side), DVec3::from_array(axis), spin, 40);
        let mut pair = pair(a, b);
        for (pa, pb) in &frames {
            let (bd, _, _) = brute::min_distance(a, pa, b, pb);
            let p = pair.distance(pa, pb);
            prop_assert_eq!(p.distance, bd.max(0.0));
        }
    }
}
