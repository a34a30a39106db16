//! The linearised penalty wrench ([`ContactStiffness`]) against finite differences of the
//! force and torque, its symmetry and positive semi-definiteness, and the contact area.

use glam::{DQuat, DVec3};
use innersphere::{
    shapes, BuildOptions, ContactStiffness, Pair, PenetrationOptions, Pose, Resolution, SphereTree,
};
use proptest::prelude::*;
use std::sync::OnceLock;

/// Two 4 × 4 × 1 slabs, B resting 0.15 deep on A (z), each packed at 48 cells.
fn slabs() -> &'static (SphereTree, SphereTree) {
    static T: OnceLock<(SphereTree, SphereTree)> = OnceLock::new();
    T.get_or_init(|| {
        let opts = BuildOptions {
            resolution: Resolution::Cells(48),
            ..Default::default()
        };
        let m = shapes::cuboid(DVec3::new(2.0, 2.0, 0.5));
        let a = SphereTree::build(&m, &opts).unwrap();
        (a.clone(), a)
    })
}

fn on_top(dz: f64, rot: DQuat) -> Pose {
    Pose::new(DVec3::new(0.0, 0.0, 1.0 - dz), rot).unwrap()
}

fn quadratic(k: &[[f64; 6]; 6], x: [f64; 6]) -> f64 {
    (0..6)
        .map(|i| (0..6).map(|j| x[i] * k[i][j] * x[j]).sum::<f64>())
        .sum()
}

fn norm(k: &ContactStiffness) -> f64 {
    k.to_matrix6()
        .iter()
        .flatten()
        .map(|x| x.abs())
        .fold(0.0, f64::max)
}

#[test]
fn the_force_changes_as_the_stiffness_says() {
    let (a, b) = slabs();
    let mut pair = Pair::new(a.clone(), b.clone());
    let opts = PenetrationOptions {
        stiffness: 100.0,
        linearize: true,
        ..Default::default()
    };
    let pa = Pose::IDENTITY;
    let h = 1e-4;
    // Apart: no area, no stiffness (glam's default matrix is the identity, not zero).
    let apart = pair.penetration_with(&pa, &on_top(-0.1, DQuat::IDENTITY), &opts);
    assert_eq!(apart.area, 0.0);
    assert_eq!(norm(&apart.stiffness), 0.0);
    let w = pair.penetration_within_with(&pa, &on_top(-0.1, DQuat::IDENTITY), u64::MAX, &opts);
    assert!(w.complete);
    assert_eq!(norm(&w.stiffness), 0.0);
    // Unfinished, the node pairs left unrefined push as their bounds: never more than the
    // bound's force.
    let w = pair.penetration_within_with(&pa, &on_top(-0.1, DQuat::IDENTITY), 100, &opts);
    assert!(w.force.length() <= opts.stiffness * w.upper_bound * (1.0 + 1e-9));
    let mid = on_top(0.06, DQuat::IDENTITY);
    let p = pair.penetration_with(&pa, &mid, &opts);
    assert!(p.volume > 0.0 && p.area > 0.0);
    // Pushing B down (−z) by h raises the force along +z by about K_zz·h.
    let lo = pair.penetration_with(&pa, &on_top(0.06 + h, DQuat::IDENTITY), &opts);
    let hi = pair.penetration_with(&pa, &on_top(0.06 - h, DQuat::IDENTITY), &opts);
    let fd = (lo.force.z - hi.force.z) / (2.0 * h);
    let kzz = p.stiffness.linear.z_axis.z;
    assert!(
        (fd / kzz - 1.0).abs() < 0.15,
        "finite difference {fd} vs K_zz {kzz}"
    );
    // For a flat contact, the area is K_zz / stiffness.
    assert!(
        (kzz / (100.0 * p.area) - 1.0).abs() < 0.1,
        "{kzz} vs area {}",
        p.area
    );
    // Tilting B about x (about its centre of mass) turns a torque against it.
    let t = 1e-4;
    let mut tilt = |ang: f64| {
        let rot = DQuat::from_rotation_x(ang);
        // About the centre of mass: the centre of B's cuboid is its model origin.
        pair.penetration_with(&pa, &on_top(0.06, rot), &opts)
    };
    let (tp, tm) = (tilt(t), tilt(-t));
    let fd = -(tp.torque_b.x - tm.torque_b.x) / (2.0 * t);
    let kxx = p.stiffness.angular.x_axis.x;
    assert!(
        (fd / kxx - 1.0).abs() < 0.2,
        "finite difference {fd} vs K_θxθx {kxx}"
    );
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// At any overlapping pose the 6×6 stiffness is symmetric and positive semi-definite,
    /// the same whichever way the pair finds its leaf pairs, and the time-critical query
    /// with an unlimited budget gives the same one.
    #[test]
    fn the_stiffness_is_symmetric_and_positive(
        dz in 0.0f64..0.4,
        axis in (-1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0),
        angle in -0.3f64..0.3,
        shift in (-1.0f64..1.0, -1.0f64..1.0),
        x in prop::array::uniform6(-1.0f64..1.0),
    ) {
        let (a, b) = slabs();
        let axis = DVec3::new(axis.0, axis.1, axis.2);
        prop_assume!(axis.length() > 1e-3);
        let rot = DQuat::from_axis_angle(axis.normalize(), angle);
        let pb = Pose::new(DVec3::new(shift.0, shift.1, 1.0 - dz), rot).unwrap();
        let pa = Pose::new(DVec3::new(0.3, -0.2, 0.1), DQuat::from_rotation_z(0.4)).unwrap();
        let pb = pa.then(&pb);
        let mut pair = Pair::new(a.clone(), b.clone());
        let opts = PenetrationOptions { stiffness: 3.0, linearize: true, ..Default::default() };
        // Without linearize the sums are skipped: zero, and the rest unchanged.
        let plain = Pair::new(a.clone(), b.clone()).penetration_with(&pa, &pb, &PenetrationOptions { stiffness: 3.0, ..Default::default() });
        prop_assert_eq!(norm(&plain.stiffness), 0.0);
        let p = pair.penetration_with(&pa, &pb, &opts);
        prop_assert_eq!((plain.volume, plain.force, plain.area), (p.volume, p.force, 0.0));
        let k = p.stiffness.to_matrix6();
        let n = norm(&p.stiffness).max(1e-300);
        for (i, row) in k.iter().enumerate() {
            for (j, kij) in row.iter().enumerate() {
                prop_assert!((kij - k[j][i]).abs() <= 1e-9 * n, "K[{i}][{j}]");
            }
        }
        prop_assert!(quadratic(&k, x) >= -1e-9 * n, "xᵀKx = {}", quadratic(&k, x));
        let w = pair.penetration_within_with(&pa, &pb, u64::MAX, &opts);
        prop_assert!((w.volume - p.volume).abs() <= 1e-9 * p.volume.max(1e-12));
        prop_assert!((w.area - p.area).abs() <= 1e-9 * p.area.max(1e-12));
        prop_assert!((w.force - p.force).length() <= 1e-9 * p.force.length().max(1e-12));
        prop_assert!((w.torque_b - p.torque_b).length() <= 1e-9 * (p.torque_b.length() + n));
        let kw = w.stiffness.to_matrix6();
        for i in 0..6 {
            for j in 0..6 {
                prop_assert!((kw[i][j] - k[i][j]).abs() <= 1e-9 * n);
            }
        }
    }
}
