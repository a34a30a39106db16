//! Shared helpers of the query tests: small real trees from analytic solids (packing +
//! hierarchy, no mesh pipeline needed), random poses and generated motions.
#![allow(dead_code)]

use glam::{DQuat, DVec3};
use innersphere::build::{pack_signed_distance, tree_of_spheres, HierarchyOptions, PackingOptions};
use innersphere::progress::Silent;
use innersphere::tree::{SphereTree, TreeMeta};
use innersphere::{Pair, Pose};
use std::sync::OnceLock;

/// The tree of an analytic solid given by its signed distance (positive inside), sampled on
/// a grid of spacing `h` over `[lo, hi]`.
pub(crate) fn analytic_tree(
    lo: DVec3,
    hi: DVec3,
    h: f64,
    fanout: u32,
    com: DVec3,
    sdf: impl Fn(DVec3) -> f64,
) -> SphereTree {
    let spheres = pack_signed_distance(lo, hi, h, sdf, &PackingOptions::default()).unwrap();
    let meta = TreeMeta {
        center_of_mass: com.to_array(),
        ..TreeMeta::unmeasured(fanout, h, lo.to_array(), hi.to_array())
    };
    let opts = HierarchyOptions {
        fanout,
        ..Default::default()
    };
    tree_of_spheres(&spheres, &opts, meta, &Silent).unwrap().0
}

/// A box of half extents `half` centred at `c`.
pub(crate) fn box_tree(c: DVec3, half: DVec3, h: f64, fanout: u32) -> SphereTree {
    analytic_tree(c - half, c + half, h, fanout, c, move |p| {
        (half - (p - c).abs()).min_element()
    })
}

/// A ball.
pub(crate) fn ball_tree(c: DVec3, r: f64, h: f64, fanout: u32) -> SphereTree {
    analytic_tree(
        c - DVec3::splat(r),
        c + DVec3::splat(r),
        h,
        fanout,
        c,
        move |p| r - (p - c).length(),
    )
}

/// A torus around z.
pub(crate) fn torus_tree(major: f64, minor: f64, h: f64, fanout: u32) -> SphereTree {
    let e = DVec3::new(major + minor, major + minor, minor);
    analytic_tree(-e, e, h, fanout, DVec3::ZERO, move |p| {
        let q = DVec3::new((p.x * p.x + p.y * p.y).sqrt() - major, p.z, 0.0);
        minor - q.length()
    })
}

/// A few small trees of different shapes, fan-outs and depths (built once per test binary).
/// Their frames are deliberately offset from the shapes.
pub(crate) fn trees() -> &'static [SphereTree] {
    static T: OnceLock<Vec<SphereTree>> = OnceLock::new();
    T.get_or_init(|| {
        vec![
            box_tree(
                DVec3::new(0.3, -0.2, 0.1),
                DVec3::new(0.8, 0.5, 0.3),
                0.1,
                4,
            ),
            ball_tree(DVec3::new(-0.2, 0.4, 0.0), 0.6, 0.1, 2),
            torus_tree(0.6, 0.22, 0.075, 8),
            box_tree(
                DVec3::new(2.0, 1.0, -1.0),
                DVec3::new(0.3, 0.9, 0.4),
                0.09,
                3,
            ),
        ]
    })
}

/// A fresh [`Pair`] of copies of `a` and `b`.
pub(crate) fn pair(a: &SphereTree, b: &SphereTree) -> Pair {
    Pair::new(a.clone(), b.clone())
}

/// A unit quaternion from four numbers (normalized; identity when all are ~0).
pub(crate) fn quat(w: f64, x: f64, y: f64, z: f64) -> DQuat {
    let q = DQuat::from_xyzw(x, y, z, w);
    if q.length() < 1e-6 {
        DQuat::IDENTITY
    } else {
        q.normalize()
    }
}

/// A pose from a translation and four quaternion numbers.
pub(crate) fn pose(t: [f64; 3], q: [f64; 4]) -> Pose {
    Pose::new(DVec3::from_array(t), quat(q[0], q[1], q[2], q[3])).unwrap()
}

/// World poses of A and B so that B's root centre lands at `offset` (A's frame, relative to
/// A's root centre) under B's rotation: contacts, near misses and deep overlaps alike.
pub(crate) fn pair_poses(
    a: &SphereTree,
    b: &SphereTree,
    pose_a: Pose,
    rot_b: DQuat,
    offset: DVec3,
) -> (Pose, Pose) {
    let ca = a.sphere(0).0.as_dvec3();
    let cb = b.sphere(0).0.as_dvec3();
    // In A's frame: p' = rot_b·(p − cb) + ca + offset.
    let rel = Pose::new(ca + offset - rot_b * cb, rot_b).unwrap();
    (pose_a, pose_a.then(&rel))
}

/// A motion of B relative to A: `n` frames of B swinging through A along `dir` (scaled by
/// the root radii, so it goes from separated to touching to overlapping and back) while
/// turning about `axis` by `spin` radians per frame; A moves rigidly too.
pub(crate) fn motion(
    a: &SphereTree,
    b: &SphereTree,
    dir: DVec3,
    side: DVec3,
    axis: DVec3,
    spin: f64,
    n: usize,
) -> Vec<(Pose, Pose)> {
    let reach = (a.r[0] + b.r[0]) as f64 * 1.1;
    let dir = dir.try_normalize().unwrap_or(DVec3::X);
    let axis = axis.try_normalize().unwrap_or(DVec3::Z);
    (0..n)
        .map(|i| {
            let s = i as f64 / n as f64 * std::f64::consts::TAU;
            let offset = dir * reach * s.cos() + side * 0.3 * reach * (2.0 * s).sin();
            let rot_b = DQuat::from_axis_angle(axis, spin * i as f64);
            let pose_a = Pose::new(
                DVec3::new(0.1 * s.sin(), -0.2, 0.05 * i as f64 / n as f64),
                DQuat::from_rotation_z(0.3 * s.sin()),
            )
            .unwrap();
            pair_poses(a, b, pose_a, rot_b, offset)
        })
        .collect()
}

/// Relative tolerance helper: |x − y| ≤ rel·max(|x|,|y|) + abs.
pub(crate) fn close(x: f64, y: f64, rel: f64, abs: f64) -> bool {
    (x - y).abs() <= rel * x.abs().max(y.abs()) + abs
}
