//! The C ABI called from Rust: the answers are the library's (penetration field by field,
//! bit for bit), the build options reach the build, every failure has its status and message,
//! the version and the identity pose are what they say. (The C program of `tests/c/run.sh`
//! checks the same from C, under the sanitizers.)

use innersphere::build::PackingOptions;
use innersphere::glam::DVec3;
use innersphere::{shapes, BuildOptions, Pair, Pose, Resolution, SphereTree};
use innersphere_c::*;
use std::ffi::{CStr, CString};
use std::path::{Path, PathBuf};

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("innersphere_c_abi_{}_{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn c(p: &Path) -> CString {
    CString::new(p.to_str().unwrap()).unwrap()
}

fn last_error() -> String {
    unsafe { CStr::from_ptr(ist_last_error()) }
        .to_string_lossy()
        .into_owned()
}

/// A 4 × 4 × 2 box mesh written as STL.
fn box_stl(d: &Path) -> PathBuf {
    let p = d.join("box.stl");
    innersphere::mesh::save_stl(&shapes::cuboid(DVec3::new(2.0, 2.0, 1.0)), &p).unwrap();
    p
}

#[test]
fn the_version_and_the_identity_are_what_they_say() {
    let v = unsafe { CStr::from_ptr(ist_version()) }.to_str().unwrap();
    assert_eq!(v, env!("CARGO_PKG_VERSION"));
    let id = ist_pose_identity();
    assert_eq!((id.t, id.q), ([0.0; 3], [1.0, 0.0, 0.0, 0.0]));
}

#[test]
fn the_build_options_reach_the_build() {
    let d = dir("build");
    let mesh = c(&box_stl(&d));
    let build = |o: &ist_build_options| unsafe { ist_tree_build(mesh.as_ptr(), o) };
    let leaves = |o: &ist_build_options| {
        let t = build(o);
        assert!(!t.is_null(), "{o:?}: {}", last_error());
        let n = unsafe { ist_tree_leaf_count(t) };
        unsafe { ist_tree_free(t) };
        n
    };
    let def = ist_build_options_default();
    assert_eq!(
        (
            def.voxel_size,
            def.resolution,
            def.min_radius,
            def.refine_steps,
            def.max_spheres
        ),
        (0.0, 128, 0.0, 0, 0)
    );
    // Each field as the library's own build with the same options.
    let rust = |o: BuildOptions| {
        SphereTree::build(&shapes::cuboid(DVec3::new(2.0, 2.0, 1.0)), &o)
            .unwrap()
            .leaves()
            .count()
    };
    let cells = ist_build_options {
        resolution: 24,
        ..def
    };
    assert_eq!(
        leaves(&cells),
        rust(BuildOptions {
            resolution: Resolution::Cells(24),
            ..Default::default()
        })
    );
    let voxel = ist_build_options {
        voxel_size: 0.3,
        resolution: 24,
        ..def
    };
    assert_eq!(
        leaves(&voxel),
        rust(BuildOptions {
            resolution: Resolution::VoxelSize(0.3),
            ..Default::default()
        })
    );
    assert_ne!(leaves(&voxel), leaves(&cells));
    let packing = ist_build_options {
        resolution: 24,
        min_radius: 0.05,
        refine_steps: 2,
        max_spheres: 40,
        ..def
    };
    assert_eq!(
        leaves(&packing),
        rust(BuildOptions {
            resolution: Resolution::Cells(24),
            packing: PackingOptions {
                min_radius: 0.05,
                refine_steps: 2,
                max_spheres: 40,
            },
            ..Default::default()
        })
    );
    assert!(leaves(&packing) <= 40);
    // A unit: the file read as centimetres is the box ten times as large, in mm (the same
    // leaves at the same cell count, a voxel ten times as wide); an unknown unit is refused.
    let cm = ist_build_options {
        voxel_size: 3.0,
        unit: IST_UNIT_CM,
        ..def
    };
    assert_eq!(leaves(&cm), leaves(&voxel));
    let t = build(&cm);
    assert!(!t.is_null());
    let with = unsafe { ist_tree_with_mesh(t, mesh.as_ptr()) };
    assert!(
        !with.is_null(),
        "the mesh in the tree's recorded unit: {}",
        last_error()
    );
    unsafe {
        ist_tree_free(with);
        ist_tree_free(t);
    }
    assert!(build(&ist_build_options { unit: 7, ..def }).is_null());
    assert!(last_error().contains("IST_UNIT_MM"), "{}", last_error());
    // Neither a voxel size nor a resolution, or a negative voxel size: refused, saying why.
    for bad in [
        ist_build_options {
            voxel_size: 0.0,
            resolution: 0,
            ..def
        },
        ist_build_options {
            voxel_size: -1.0,
            resolution: 24,
            ..def
        },
        ist_build_options {
            voxel_size: f64::NAN,
            resolution: 24,
            ..def
        },
    ] {
        assert!(build(&bad).is_null(), "{bad:?}");
        assert!(
            last_error().contains("voxel_size > 0 or resolution > 0"),
            "{}",
            last_error()
        );
    }
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn every_failure_has_its_status_and_message() {
    let d = dir("errors");
    let mesh = c(&box_stl(&d));
    let o = ist_build_options {
        resolution: 16,
        ..ist_build_options_default()
    };
    unsafe {
        let t = ist_tree_build(mesh.as_ptr(), &o);
        assert!(!t.is_null());
        // A file that cannot be written: an I/O error naming it.
        let nowhere = c(&d.join("missing").join("t.ist"));
        assert_eq!(ist_tree_save(t, nowhere.as_ptr()), IST_ERR_IO);
        assert!(last_error().contains("missing"), "{}", last_error());
        assert_eq!(ist_last_status(), IST_ERR_IO);
        // NULL arguments.
        assert_eq!(
            ist_tree_save(std::ptr::null(), nowhere.as_ptr()),
            IST_ERR_NULL
        );
        assert!(last_error().contains("NULL"), "{}", last_error());
        assert!(ist_tree_load(std::ptr::null()).is_null());
        assert!(last_error().contains("NULL"), "{}", last_error());
        assert_eq!(ist_last_status(), IST_ERR_NULL);
        // A bad pose.
        let pair = ist_pair_new(t, t);
        let id = ist_pose_identity();
        let nan = ist_pose {
            t: [f64::NAN, 0.0, 0.0],
            q: [1.0, 0.0, 0.0, 0.0],
        };
        let mut r = ist_distance_result::default();
        assert_eq!(ist_distance(pair, &id, &nan, &mut r), IST_ERR_POSE);
        assert!(last_error().contains("NaN"), "{}", last_error());
        assert_eq!(ist_last_status(), IST_ERR_POSE);
        // A success leaves the last error as it was.
        let far = ist_pose {
            t: [10.0, 0.0, 0.0],
            q: [1.0, 0.0, 0.0, 0.0],
        };
        assert_eq!(ist_distance(pair, &id, &far, &mut r), IST_OK);
        assert!(last_error().contains("NaN"));
        assert_eq!(ist_last_status(), IST_ERR_POSE);
        assert!(r.distance > 5.0);
        // Bad options of a query: a status of their own.
        let mut p = ist_penetration_result::default();
        assert_eq!(
            ist_penetration_with_stiffness(pair, &id, &id, -1.0, &mut p),
            IST_ERR_INVALID_ARGUMENT
        );
        // A missing file, a corrupt tree file and a mesh that is not one: NULL, the reason
        // in the message and the status.
        assert!(ist_tree_load(c(&d.join("absent.ist")).as_ptr()).is_null());
        assert_eq!(ist_last_status(), IST_ERR_IO);
        let junk = d.join("junk.ist");
        std::fs::write(&junk, b"IST not really a tree").unwrap();
        assert!(ist_tree_load(c(&junk).as_ptr()).is_null());
        assert_eq!(ist_last_status(), IST_ERR_CORRUPT_TREE);
        let corrupt = last_error();
        let bad_mesh = d.join("bad.stl");
        std::fs::write(
            &bad_mesh,
            b"solid x\nfacet normal 0 0 1\n outer loop\n vertex 0 0",
        )
        .unwrap();
        assert!(ist_tree_build(c(&bad_mesh).as_ptr(), &o).is_null());
        assert_eq!(ist_last_status(), IST_ERR_MESH);
        assert!(
            !corrupt.is_empty() && last_error() != corrupt,
            "{corrupt} / {}",
            last_error()
        );
        ist_pair_free(pair);
        ist_tree_free(t);
    }
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn penetration_and_the_haptic_tool_pose_are_the_librarys_bit_for_bit() {
    let d = dir("answers");
    let opts = BuildOptions {
        resolution: Resolution::Cells(32),
        ..Default::default()
    };
    let (pa, pb) = (d.join("a.ist"), d.join("b.ist"));
    let ta = SphereTree::build(&shapes::cuboid(DVec3::new(3.0, 3.0, 0.5)), &opts).unwrap();
    let tb = SphereTree::build(&shapes::icosphere(3), &opts).unwrap();
    ta.save(&pa).unwrap();
    tb.save(&pb).unwrap();
    let mut rust = Pair::new(ta, tb);
    unsafe {
        let a = ist_tree_load(c(&pa).as_ptr());
        let b = ist_tree_load(c(&pb).as_ptr());
        let pair = ist_pair_new(a, b);
        let id = ist_pose_identity();
        for (k, z) in [1.45, 1.3, 1.1].into_iter().enumerate() {
            let q = innersphere::glam::DQuat::from_rotation_x(0.1 * k as f64);
            let pose = Pose {
                translation: DVec3::new(0.2, -0.1, z),
                rotation: q,
            };
            let cp = ist_pose {
                t: pose.translation.to_array(),
                q: [q.w, q.x, q.y, q.z],
            };
            let mut got = ist_penetration_result::default();
            assert_eq!(ist_penetration(pair, &id, &cp, &mut got), IST_OK);
            let want = rust.penetration(&Pose::IDENTITY, &pose);
            assert!(want.volume > 0.0);
            assert_eq!(got.volume.to_bits(), want.volume.to_bits());
            assert_eq!(got.max_depth.to_bits(), want.max_depth.to_bits());
            assert_eq!(got.normal, want.normal.to_array());
            assert_eq!(got.force, want.force.to_array());
            assert_eq!(got.torque_a, want.torque_a.to_array());
            assert_eq!(got.torque_b, want.torque_b.to_array());
            assert_eq!(got.patch_count, want.patch_count);
        }
        // The haptic tool's pose comes back as the loop has it.
        let mut hp = std::mem::zeroed::<ist_haptic_params>();
        assert_eq!(ist_haptic_params_default(IST_DEVICE_OMEGA, &mut hp), IST_OK);
        let start = ist_pose {
            t: [0.0, 0.0, 2.0],
            q: [1.0, 0.0, 0.0, 0.0],
        };
        hp.start = start;
        let h = ist_haptic_new(pair, &hp);
        assert!(!h.is_null());
        let turn = innersphere::glam::DQuat::from_rotation_z(0.01);
        let device = ist_pose {
            t: [0.01, 0.0, 2.0],
            q: [turn.w, turn.x, turn.y, turn.z],
        };
        let mut out = std::mem::zeroed::<ist_haptic_output>();
        for _ in 0..50 {
            assert_eq!(ist_haptic_tick(h, &device, 0.001, &mut out), IST_OK);
        }
        // Pulled towards the device: moved along x, turned about z, a unit quaternion.
        assert!(
            out.tool.t[0] > 0.005 && out.tool.t[0] < 0.0101,
            "{:?}",
            out.tool
        );
        let q = out.tool.q;
        assert!((q.iter().map(|x| x * x).sum::<f64>() - 1.0).abs() < 1e-12);
        assert!(
            q[3] > 0.0 && q[1].abs() < 1e-9 && q[2].abs() < 1e-9,
            "{q:?}"
        );
        ist_haptic_free(h);
        // Mesh contact: only in the collision thread, only with both trees' meshes.
        hp.mesh_contact = 1;
        assert!(ist_haptic_new(pair, &hp).is_null());
        assert!(
            last_error().contains("collision_thread"),
            "{}",
            last_error()
        );
        hp.collision_thread = 1;
        assert!(ist_haptic_new(pair, &hp).is_null());
        assert!(last_error().contains("meshes"), "{}", last_error());
        hp.mesh_contact = 2;
        assert!(ist_haptic_new(pair, &hp).is_null());
        assert!(last_error().contains("mesh_contact"), "{}", last_error());
        ist_pair_free(pair);
        ist_tree_free(a);
        ist_tree_free(b);
    }
    std::fs::remove_dir_all(&d).ok();
}
