//! Every query against brute force on trees built from real meshes (`../shared/data/small`
//! and the opposing molar pair of the jaw data set). Ignored by default:
//! `cargo test -p innersphere --release --lib -- --ignored query_real`.

use super::data as common;
use super::query_util;
use super::reference;

use glam::{DQuat, DVec3};
use innersphere::build::{build_tree, BuildOptions, Resolution};
use innersphere::progress::Silent;
use innersphere::query::{brute, TraversalOptions};
use innersphere::{
    MultipointOptions, Pair, PenetrationOptions, Pose, SharedTree, SphereTree, Tracking,
};
use query_util::{close, motion, pair_poses};
use reference::checks::{check_contact, check_multipoint, check_penetration};
use reference::RefPair;

fn tree(rel: &str, cells: u32) -> SphereTree {
    let mesh = innersphere::mesh::io::load(&common::data(rel)).unwrap();
    let opts = BuildOptions {
        resolution: Resolution::Cells(cells),
        ..Default::default()
    };
    build_tree(&mesh, &opts, &Silent).unwrap().0
}

/// Deterministic pseudo-random numbers in [-1, 1).
fn rng(seed: u64) -> impl FnMut() -> f64 {
    let mut s = seed.wrapping_mul(0x9E3779B97F4A7C15) | 1;
    move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }
}

/// Checks every query kind against brute force at one pose pair, and with `reference` also
/// against the independent f64 reference (slower); the pairs `st` carry coherence.
fn check_pose(
    a: &SphereTree,
    b: &SphereTree,
    pa: &Pose,
    pb: &Pose,
    st: &mut [Pair; 4],
    reference: bool,
) {
    let (bd, _, _) = brute::min_distance(a, pa, b, pb);
    let pairs = brute::overlapping_pairs(a, pa, b, pb);
    let p = st[0].distance(pa, pb);
    assert_eq!(p.distance, bd.max(0.0));
    let off = TraversalOptions { safe_motion: false };
    assert_eq!(
        st[1].paper().distance_traversal(pa, pb, &off).in_contact(),
        !pairs.is_empty()
    );
    assert_eq!(
        st[2].paper().backtracking(pa, pb, &off).in_contact(),
        !pairs.is_empty()
    );
    assert_eq!(st[3].contact(pa, pb).in_contact(), !pairs.is_empty());
    let want = brute::penetration(a, pa, b, pb, 2.0);
    let q = st[1].penetration_with(
        pa,
        pb,
        &PenetrationOptions {
            stiffness: 2.0,
            safe_motion: false,
            tracking: Tracking::Traversal,
            ..Default::default()
        },
    );
    assert_eq!(q.pairs, want.pairs);
    assert!(close(q.volume, want.volume, 1e-10, 1e-18));
    assert!((q.force - want.force).length() <= 1e-7 * want.force.length() + 1e-18);
    let t = st[3].penetration_with(
        pa,
        pb,
        &PenetrationOptions {
            stiffness: 2.0,
            ..Default::default()
        },
    );
    assert_eq!(t.pairs, want.pairs);
    assert!(close(t.volume, want.volume, 1e-10, 1e-18));
    for budget in [10, 1000, u64::MAX] {
        let r = st[1].penetration_within(pa, pb, budget);
        assert!(r.volume <= want.volume * (1.0 + 1e-9) + 1e-18);
        assert!(want.volume <= r.upper_bound * (1.0 + 1e-9) + 1e-18);
    }
    st[2].multipoint(
        pa,
        pb,
        &MultipointOptions {
            k: 8,
            split_depth: 3,
            safe_motion: false,
            ..Default::default()
        },
    );
    assert_eq!(st[2].contacts().is_empty(), pairs.is_empty());
    if !reference {
        return;
    }
    // The independent reference: contacts, multipoint's contact set, penetration's force,
    // torques and patches, with the pairs carried along.
    let r = RefPair::new(a, pa, b, pb);
    check_contact(&st[3].contact(pa, pb), &r, "contact").unwrap();
    let opts = MultipointOptions {
        k: 8,
        split_depth: 3,
        safe_motion: false,
        tracking: true,
        ..Default::default()
    };
    check_multipoint(&mut st[2], pa, pb, &r, &opts).unwrap();
    let opts = PenetrationOptions {
        stiffness: 2.0,
        safe_motion: false,
        max_patches: 6,
        ..Default::default()
    };
    check_penetration(&mut st[3], pa, pb, &r, &opts).unwrap();
}

#[test]
#[ignore = "real data: run with --ignored"]
fn small_meshes_random_poses_equal_brute_force() {
    let names = [
        "small/knot1_cgal.stl",
        "small/eight_genus2_cgal.stl",
        "small/femur_cgal.stl",
        "small/torus_trimesh.stl",
    ];
    let trees: Vec<SharedTree> = names.iter().map(|n| SharedTree::new(tree(n, 40))).collect();
    let mut r = rng(7);
    for (i, sa) in trees.iter().enumerate() {
        for (j, sb) in trees.iter().enumerate() {
            let (a, b) = (&**sa.tree(), &**sb.tree());
            let scale = (a.r[0] + b.r[0]) as f64;
            let mut st: [Pair; 4] = std::array::from_fn(|_| Pair::new(sa, sb));
            for _ in 0..12 {
                let q = DQuat::from_xyzw(r(), r(), r(), r()).normalize();
                let off = DVec3::new(r(), r(), r()) * scale * 0.9;
                let pose_a =
                    Pose::new(DVec3::new(r(), r(), r()), DQuat::from_rotation_y(r())).unwrap();
                let (pa, pb) = pair_poses(a, b, pose_a, q, off);
                check_pose(a, b, &pa, &pb, &mut st, true);
            }
            let frames = motion(
                a,
                b,
                DVec3::new(r(), r(), r()),
                DVec3::new(r(), r(), r()),
                DVec3::new(r(), r(), r()),
                0.02,
                60,
            );
            for (f, (pa, pb)) in frames.iter().enumerate() {
                check_pose(a, b, pa, pb, &mut st, f % 10 == 0);
            }
            eprintln!("{} vs {}: ok", names[i], names[j]);
        }
    }
}

#[test]
#[ignore = "real data: run with --ignored"]
fn opposing_molars_in_the_bite_and_along_a_motion() {
    let sa = SharedTree::new(tree("jaw/ofj_p26_tooth03_upper_first_molar.stl", 48));
    let sb = SharedTree::new(tree("jaw/ofj_p26_tooth30_lower_first_molar.stl", 48));
    let (a, b) = (&**sa.tree(), &**sb.tree());
    // Both are in the same frame: the bite pose is the identity.
    let mut st: [Pair; 4] = std::array::from_fn(|_| Pair::new(&sa, &sb));
    let id = Pose::IDENTITY;
    check_pose(a, b, &id, &id, &mut st, true);
    // Open and close the bite: B moves down and back up along z with a small rotation.
    for f in 0..120 {
        let s = f as f64 / 120.0 * std::f64::consts::TAU;
        let pb = Pose::new(
            DVec3::new(0.1 * s.sin(), 0.0, -1.0 + s.cos()),
            DQuat::from_rotation_x(0.02 * s.sin()),
        )
        .unwrap();
        check_pose(a, b, &id, &pb, &mut st, f % 8 == 0);
    }
}
