//! Issue 25, the library's side of the command line's cases: multipoint with `k = 0` claims
//! no separation.

use innersphere::build::{build_tree, BuildOptions, Resolution};
use innersphere::glam::DVec3;
use innersphere::progress::Silent;
use innersphere::{shapes, Mesh, MultipointOptions, Pair, Pose, SphereTree};

fn box_mesh() -> Mesh {
    shapes::cuboid(DVec3::new(1.0, 0.6, 0.4))
}

fn tree_of(mesh: &Mesh) -> SphereTree {
    let opts = BuildOptions {
        resolution: Resolution::Cells(16),
        ..Default::default()
    };
    build_tree(mesh, &opts, &Silent).unwrap().0
}

/// `MultipointOptions { k: 0 }` answered "no contacts, separated by at least inf" for
/// overlapping bodies; with nothing searched, nothing is proved: distance 0.
#[test]
fn multipoint_with_k_zero_claims_no_separation() {
    let t = tree_of(&box_mesh());
    let mut pair = Pair::new(t.clone(), t);
    for x in [0.0, 0.5, 5.0] {
        let pose = Pose::from_translation(DVec3::new(x, 0.0, 0.0));
        for (reuse, safe_motion, tracking) in [
            (false, false, false),
            (true, true, false),
            (false, false, true),
        ] {
            let opts = MultipointOptions {
                k: 0,
                reuse,
                safe_motion,
                tracking,
                ..Default::default()
            };
            let m = pair.multipoint(&Pose::IDENTITY, &pose, &opts);
            assert_eq!(m.count, 0);
            assert!(pair.contacts().is_empty());
            assert_eq!(m.distance, 0.0, "x = {x}: {m:?}");
        }
    }
    // k = 1 still answers.
    let m = pair.multipoint(
        &Pose::IDENTITY,
        &Pose::IDENTITY,
        &MultipointOptions {
            k: 1,
            ..Default::default()
        },
    );
    assert_eq!(m.count, 1);
}
