//! The library's side of the command line's answers and messages: multipoint with `k = 0` claims
//! no separation, a tree knows whether a mesh is the one it was built from, a huge voxel
//! blames the voxel size, a tiny quaternion is called too small to normalise. (Outputs never
//! overwriting inputs and atomic writes: the unit tests of `innersphere::output`.)

use innersphere::build::{build_tree, BuildOptions, Resolution};
use innersphere::glam::DVec3;
use innersphere::progress::Silent;
use innersphere::tree::check::{check_built_from, source_mismatch};
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

#[test]
fn a_tree_knows_the_mesh_it_was_built_from() {
    let mesh = box_mesh();
    let tree = tree_of(&mesh);
    assert_eq!(source_mismatch(&tree, &mesh), None);
    assert!(check_built_from(&tree, &mesh).unwrap().ok);
    // Coordinates rounded to f32 (an STL) or to 6 significant digits (a text format).
    let mut rounded = mesh.clone();
    for v in &mut rounded.vertices {
        *v = v.as_vec3().as_dvec3();
    }
    assert_eq!(source_mismatch(&tree, &rounded), None);
    let mut printed = mesh.clone();
    for v in &mut printed.vertices {
        for c in [&mut v.x, &mut v.y, &mut v.z] {
            *c = format!("{:.5e}", *c).parse().unwrap();
        }
    }
    assert_eq!(source_mismatch(&tree, &printed), None);
    // The box moved by 1e-3 of its size, scaled by 1.001, twice as large, and a ball.
    let mut moved = mesh.clone();
    for v in &mut moved.vertices {
        v.x += 2e-3;
    }
    let mut scaled = mesh.clone();
    for v in &mut scaled.vertices {
        *v *= 1.001;
    }
    let mut big = mesh.clone();
    for v in &mut big.vertices {
        *v *= 2.0;
    }
    for (name, other) in [
        ("moved", moved),
        ("scaled", scaled),
        ("big", big),
        ("ball", shapes::icosphere(2)),
    ] {
        let why = source_mismatch(&tree, &other).unwrap_or_else(|| panic!("{name} passed"));
        assert!(why.contains("bounding box"), "{name}: {why}");
        let e = check_built_from(&tree, &other).unwrap_err().to_string();
        assert!(
            e.contains("not the mesh the tree was built from"),
            "{name}: {e}"
        );
    }
    // The same bounding box, another volume: one corner of the box pushed in along x (the
    // other corners keep the box).
    let mut dented = mesh.clone();
    let corner = dented
        .vertices
        .iter()
        .position(|v| v.x > 0.0 && v.y > 0.0 && v.z > 0.0)
        .unwrap();
    dented.vertices[corner].x = 0.99;
    assert_eq!(dented.bbox(), mesh.bbox());
    let why = source_mismatch(&tree, &dented).unwrap();
    assert!(why.contains("volume"), "{why}");
}

#[test]
fn a_voxel_larger_than_the_mesh_blames_the_voxel_size() {
    for h in [1e300, 1e10, 2.0] {
        let opts = BuildOptions {
            resolution: Resolution::VoxelSize(h),
            ..Default::default()
        };
        match build_tree(&box_mesh(), &opts, &Silent) {
            // A single voxel at the centre may still hold one sphere.
            Ok(_) => assert!(h < 10.0, "{h}"),
            Err(e) => {
                let e = e.to_string();
                assert!(e.contains("voxel size is too large"), "{h}: {e}");
                assert!(!e.contains("minimum radius"), "{h}: {e}");
            }
        }
    }
    // A minimum radius larger than the mesh is still blamed as such.
    let mut opts = BuildOptions {
        resolution: Resolution::Cells(16),
        ..Default::default()
    };
    opts.packing.min_radius = 5.0;
    let e = build_tree(&box_mesh(), &opts, &Silent)
        .unwrap_err()
        .to_string();
    assert!(e.contains("minimum radius is too large"), "{e}");
}

#[test]
fn a_tiny_quaternion_is_too_small_to_normalise() {
    for text in [
        "0 0 0 1e-30 0 0 0",
        "0 0 0 0 0 0 0",
        "0 0 0 1e-13 1e-13 0 0",
    ] {
        let e = text.parse::<Pose>().unwrap_err().to_string();
        assert!(e.contains("too small to normalise"), "{text}: {e}");
        assert!(!e.contains("zero"), "{text}: {e}");
    }
    let e = "0 0 0 1e200 1e200 0 0"
        .parse::<Pose>()
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("cannot be normalised") && e.contains("overflows"),
        "{e}"
    );
}
