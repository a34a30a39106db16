//! The whole build, mesh → tree file, on generated meshes (always) and on the real closed
//! meshes (`--ignored`): the tree passes the independent check, the build is deterministic,
//! and bad inputs are clear errors.

use innersphere_testkit::data as common;

use glam::DVec3;
use innersphere::build::{build_tree, BuildOptions, Resolution};
use innersphere::progress::Silent;
use innersphere::tree::{check, file};
use innersphere::{shapes, Error, Mesh};
use proptest::prelude::*;

fn opts(cells: u32) -> BuildOptions {
    BuildOptions {
        resolution: Resolution::Cells(cells),
        ..Default::default()
    }
}

fn build_and_check(mesh: &Mesh, o: &BuildOptions) -> innersphere::SphereTree {
    let (tree, report) = build_tree(mesh, o, &Silent).unwrap();
    assert_eq!(report.spheres, tree.leaf_count());
    assert!(report.coverage > 0.3 && report.coverage < 1.0, "{report:?}");
    let c = check::check(&tree, mesh).unwrap();
    assert!(c.ok, "{c:?}");
    tree
}

#[test]
fn generated_meshes_build_valid_deterministic_trees() {
    for mesh in [
        shapes::icosphere(3),
        shapes::torus(1.0, 0.3, 48, 24),
        shapes::cuboid(DVec3::new(1.0, 0.5, 0.25)),
        shapes::molar(4, 0.0),
    ] {
        let a = build_and_check(&mesh, &opts(40));
        let (b, _) = build_tree(&mesh, &opts(40), &Silent).unwrap();
        assert_eq!(
            file::to_bytes(&a),
            file::to_bytes(&b),
            "build is not deterministic"
        );
    }
}

#[test]
fn built_trees_carry_a_stamp_and_unstamped_files_warn() {
    let (tree, _) = build_tree(&shapes::icosphere(2), &opts(24), &Silent).unwrap();
    let stamp = tree.meta.built_by.clone().expect("a built tree is stamped");
    assert_eq!(stamp.revision, innersphere::tree::BUILD_REVISION);
    assert_eq!(stamp.refine_steps, opts(24).packing.refine_steps);
    assert_eq!(tree.staleness(), None);
    let back = file::from_bytes(&file::to_bytes(&tree)).unwrap();
    assert_eq!(back.meta.built_by, Some(stamp.clone()));
    // A file written before the stamp existed (meta without `built_by`) still loads, with a
    // warning; so does one from an older revision.
    let mut old = tree.clone();
    old.meta.built_by = None;
    let bytes = file::to_bytes(&old);
    assert!(!String::from_utf8_lossy(&bytes).contains("built_by"));
    let back = file::from_bytes(&bytes).unwrap();
    assert!(back.staleness().unwrap().contains("no build stamp"));
    old.meta.built_by = Some(innersphere::tree::BuildStamp {
        revision: 1,
        ..stamp
    });
    let back = file::from_bytes(&file::to_bytes(&old)).unwrap();
    assert!(back.staleness().unwrap().contains("revision 1"));
}

#[test]
fn inward_facing_meshes_are_flipped_with_a_warning() {
    let mut mesh = shapes::icosphere(3);
    mesh.flip();
    let (tree, report) = build_tree(&mesh, &opts(32), &Silent).unwrap();
    assert!(report.warnings.iter().any(|w| w.contains("inward")));
    assert!(report.mesh_volume > 0.0);
    let mut outward = mesh.clone();
    outward.flip();
    assert!(check::check(&tree, &outward).unwrap().ok);
}

#[test]
fn open_meshes_build_with_a_warning_and_soups_are_errors() {
    let mut open = shapes::icosphere(3);
    open.triangles.truncate(open.triangles.len() - 3);
    let (_, report) = build_tree(&open, &opts(32), &Silent).unwrap();
    assert!(report.warnings.iter().any(|w| w.contains("not closed")));

    let soup: Vec<[DVec3; 3]> = (0..50)
        .map(|i| {
            let o = DVec3::new(
                i as f64 * 0.37 % 1.0,
                i as f64 * 0.61 % 1.0,
                i as f64 * 0.13 % 1.0,
            );
            [o, o + DVec3::X * 0.5, o + DVec3::Y * 0.5]
        })
        .collect();
    let err = build_tree(&Mesh::from_soup(&soup), &opts(32), &Silent).unwrap_err();
    assert!(matches!(err, Error::InvalidMesh(_)), "{err}");
}

#[test]
fn bad_inputs_and_absurd_options_are_clear_errors() {
    let mesh = shapes::icosphere(2);
    assert!(build_tree(&Mesh::default(), &opts(32), &Silent).is_err());
    let mut nan = mesh.clone();
    nan.vertices[3].x = f64::NAN;
    assert!(build_tree(&nan, &opts(32), &Silent).is_err());
    for bad in [
        BuildOptions {
            resolution: Resolution::Cells(1),
            ..Default::default()
        },
        BuildOptions {
            resolution: Resolution::Cells(100_000),
            ..Default::default()
        },
        BuildOptions {
            resolution: Resolution::VoxelSize(-1.0),
            ..Default::default()
        },
        BuildOptions {
            resolution: Resolution::VoxelSize(f64::NAN),
            ..Default::default()
        },
        BuildOptions {
            resolution: Resolution::VoxelSize(1e-9),
            ..Default::default()
        },
    ] {
        assert!(build_tree(&mesh, &bad, &Silent).is_err());
    }
    let mut o = opts(32);
    o.packing.min_radius = f64::NAN;
    assert!(build_tree(&mesh, &o, &Silent).is_err());
    let mut o = opts(32);
    o.hierarchy.fanout = 1;
    assert!(build_tree(&mesh, &o, &Silent).is_err());
    let mut o = opts(32);
    o.packing.min_radius = 10.0;
    assert!(
        build_tree(&mesh, &o, &Silent).is_err(),
        "no sphere fits: error, not an empty tree"
    );
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(10))]
    /// Random star-shaped closed meshes: every tree passes the independent check, for any
    /// fan-out, minimum radius and refinement.
    #[test]
    fn random_star_shapes_build_checked_trees(
        a in 0.2..0.6f64, f1 in 1.0..4.0f64, f2 in 1.0..4.0f64,
        cells in 16u32..40, fanout in 2u32..9, min_r in 0.0..0.05f64, refine in 0u32..6,
    ) {
        let mesh = shapes::radial(3, |v| 1.0 + a * (f1 * v.x).sin() * (f2 * v.y).cos());
        let mut o = opts(cells);
        o.hierarchy.fanout = fanout;
        o.packing.min_radius = min_r;
        o.packing.refine_steps = refine;
        build_and_check(&mesh, &o);
    }
}

#[test]
#[ignore = "real data: run with --ignored"]
fn every_closed_real_mesh_builds_a_checked_tree() {
    for rel in [
        "small/cube_cgal.stl",
        "small/torus_trimesh.stl",
        "small/knot1_cgal.stl",
        "small/eight_genus2_cgal.stl",
        "small/elephant_cgal.stl",
        "small/femur_cgal.stl",
        "small/teapot_closed_rainbow.stl",
        "small/dragon_small_rainbow.stl",
        "classic/bunny_closed_cgal.stl",
        "classic/armadillo_closed_43k.stl",
        "classic/dragon_closed_50k.stl",
        "jaw/ofj_p26_tooth03_upper_first_molar.stl",
        "jaw/ofj_p26_tooth30_lower_first_molar.stl",
    ] {
        let mesh = innersphere::mesh::io::load(&common::data(rel)).unwrap();
        let (tree, report) = build_tree(&mesh, &opts(64), &Silent).unwrap();
        assert!(report.warnings.is_empty(), "{rel}: {:?}", report.warnings);
        let c = check::check(&tree, &mesh).unwrap();
        assert!(c.ok, "{rel}: {c:?}");
        let back = file::from_bytes(&file::to_bytes(&tree)).unwrap();
        assert!(back == tree, "{rel}: the tree changed in a file round trip");
    }
}
