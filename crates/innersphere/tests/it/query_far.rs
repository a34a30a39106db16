//! Far and huge poses: every query kind answers any finite pose, to the documented tolerance,
//! with finite numbers and a bounded number of node-pair tests (a plain f32 search turns
//! exhaustive once B's rounding slack outgrows the leaves, and overflows beyond 10¹⁹).

use innersphere::glam::{DQuat, DVec3};
use innersphere::{
    build::Resolution, shapes, BuildOptions, MultipointOptions, Pair, Pose, SharedTree, SphereTree,
};
use proptest::prelude::*;

/// Length without overflow of the squares.
fn norm(v: DVec3) -> f64 {
    let m = v.abs().max_element();
    if m == 0.0 {
        return 0.0;
    }
    m * (v / m).length()
}

/// The f64 reference: the exact distance of the two leaf-sphere sets, A at `pa`, B at `pb`.
fn reference(a: &SphereTree, pa: &Pose, b: &SphereTree, pb: &Pose) -> f64 {
    let world = |t: &SphereTree, p: &Pose| -> Vec<(DVec3, f64)> {
        t.leaves()
            .map(|i| {
                let (c, r) = t.sphere(i);
                (p.transform_point(c.as_dvec3()), r as f64)
            })
            .collect()
    };
    let (la, lb) = (world(a, pa), world(b, pb));
    let mut best = f64::INFINITY;
    for &(ca, ra) in &la {
        for &(cb, rb) in &lb {
            best = best.min(norm(cb - ca) - ra - rb);
        }
    }
    best
}

fn tree(mesh: &innersphere::Mesh, cells: u32) -> SphereTree {
    let opts = BuildOptions {
        resolution: Resolution::Cells(cells),
        ..Default::default()
    };
    SphereTree::build(mesh, &opts).unwrap()
}

/// The rounding slack of the queries' f32 transform at relative translation length `t`.
fn slack(a: &SphereTree, b: &SphereTree, t: f64) -> f64 {
    let extent = |x: &SphereTree| {
        (0..x.len())
            .map(|i| {
                let (c, r) = x.sphere(i);
                (c.length() + r) as f64
            })
            .fold(0.0, f64::max)
    };
    16.0 * f32::EPSILON as f64 * (extent(a) + extent(b) + t)
}

/// Every query kind at `pb` (A at `pa`) against the reference.
fn check(pair: &mut Pair, a: &SphereTree, b: &SphereTree, pa: &Pose, pb: &Pose) {
    let d = reference(a, pa, b, pb);
    let t = norm(Pose::relative(pa, pb).translation);
    let s = slack(a, b, t);
    // The far tolerance (64 slacks), or the f32 rounding of a near query.
    let tol = 64.0 * s + 1e-9;
    let what = format!("|t| = {t:e}, reference distance {d:e}");
    let dist = pair.distance(pa, pb);
    assert!(
        dist.distance.is_finite() && dist.lower_bound.is_finite(),
        "{what}: {dist:?}"
    );
    assert!(
        dist.point_a.is_finite() && dist.point_b.is_finite() && dist.normal.is_finite(),
        "{what}: {dist:?}"
    );
    assert!(
        (dist.distance - d.max(0.0)).abs() <= tol,
        "{what}: {dist:?}"
    );
    assert!(dist.lower_bound <= d.max(0.0) + tol, "{what}: {dist:?}");
    assert!(dist.visits <= 100_000, "{what}: {} tests", dist.visits);
    let separated = d > tol;
    let c = pair.contact(pa, pb);
    assert!(
        c.distance.is_finite() && c.visits <= 100_000,
        "{what}: {c:?}"
    );
    if separated {
        assert!(!c.in_contact() && c.distance <= d + tol, "{what}: {c:?}");
    }
    let m = pair.multipoint(pa, pb, &MultipointOptions::default());
    assert!(
        m.distance.is_finite() && m.visits <= 100_000,
        "{what}: {m:?}"
    );
    if separated {
        assert_eq!(m.count, 0, "{what}");
        assert!(pair.contacts().is_empty());
    }
    let p = pair.penetration(pa, pb);
    assert!(
        p.distance.is_finite() && p.volume.is_finite() && p.force.is_finite(),
        "{what}: {p:?}"
    );
    assert!(p.visits <= 100_000, "{what}: {} tests", p.visits);
    if separated {
        assert_eq!((p.volume, p.patch_count), (0.0, 0), "{what}");
        assert!(
            pair.patches().is_empty() && p.distance <= d + tol,
            "{what}: {p:?}"
        );
    }
    let v = pair.penetration_within(pa, pb, 8_000);
    assert!(v.volume.is_finite() && v.upper_bound.is_finite(), "{what}");
    if separated {
        assert_eq!(v.volume, 0.0, "{what}");
    }
    for q in [
        pair.paper().distance_traversal(pa, pb, &Default::default()),
        pair.paper().backtracking(pa, pb, &Default::default()),
    ] {
        assert!(
            q.distance.is_finite() && q.visits <= 100_000,
            "{what}: {q:?}"
        );
        if separated {
            assert!(!q.in_contact() && q.distance <= d + tol, "{what}: {q:?}");
        }
    }
}

/// Two molars, each against the other and itself, at every power of ten from 1 to 10³⁰⁰
/// along a few directions, with A posed too.
#[test]
fn every_kind_answers_far_and_huge_poses_within_tolerance_and_bounded_work() {
    let a = tree(&shapes::molar(3, 0.0), 28);
    let b = tree(&shapes::molar(3, 0.7), 28);
    let pa = Pose::new(DVec3::new(0.3, -0.2, 0.1), DQuat::from_rotation_z(0.3)).unwrap();
    for (ta, tb) in [(&a, &b), (&a, &a)] {
        let mut pair = Pair::new(SharedTree::new(ta.clone()), SharedTree::new(tb.clone()));
        for dir in [
            DVec3::X,
            DVec3::new(1.0, -2.0, 0.5).normalize(),
            DVec3::new(-0.3, 0.1, -1.0).normalize(),
        ] {
            for k in (0..=300).step_by(4) {
                let len = 10f64.powi(k);
                let pb = Pose::new(dir * len, DQuat::from_rotation_y(0.1 * k as f64)).unwrap();
                check(&mut pair, ta, tb, &pa, &pb);
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]
    /// Random far poses (any direction, rotation and magnitude up to 10³⁰⁰, either body
    /// moved), on one pair carried across them so that coherence is exercised.
    #[test]
    fn random_far_poses(
        poses in prop::collection::vec(
            (-1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0, 0.0f64..300.0, any::<[u8; 4]>(), any::<bool>()),
            1..6,
        )
    ) {
        use std::sync::OnceLock;
        static TREES: OnceLock<(SphereTree, SphereTree)> = OnceLock::new();
        let (a, b) = TREES.get_or_init(|| {
            (tree(&shapes::molar(2, 0.0), 24), tree(&shapes::molar(2, 1.1), 24))
        });
        let mut pair = Pair::new(SharedTree::new(a.clone()), SharedTree::new(b.clone()));
        for (x, y, z, e, q, move_a) in poses {
            let dir = DVec3::new(x, y, z);
            prop_assume!(dir.length() > 1e-3);
            let t = dir.normalize() * 10f64.powf(e);
            let rot = DQuat::from_xyzw(
                q[0] as f64 - 127.5, q[1] as f64 - 127.5, q[2] as f64 - 127.5, q[3] as f64 + 1.0,
            )
            .normalize();
            let far = Pose::new(t, rot).unwrap();
            let (pa, pb) = if move_a { (far, Pose::IDENTITY) } else { (Pose::IDENTITY, far) };
            check(&mut pair, a, b, &pa, &pb);
        }
    }
}
