//! The splint on generated arches: one clean solid that keeps its clearance, carries the
//! occlusal surfaces, and fails cleanly on bad input. The same checks on the real jaw pair
//! are `innersphere-eval/tests/splint_jaw.rs`.

use innersphere::glam::DVec3;
use innersphere::{shapes, Mesh, Pose};
use innersphere_dental::splint::{self, SplintOptions};
use innersphere_testkit::splint::assert_seats;

fn options() -> SplintOptions {
    SplintOptions {
        voxel: 0.15,
        ..SplintOptions::default()
    }
}

#[test]
fn an_intermediate_splint_between_generated_arches_seats_on_both() {
    let (a, b) = shapes::arch_pair(3, 12);
    let opts = options();
    let pose = splint::opened(&a, &b, &Pose::IDENTITY, 3.0).unwrap();
    let s = splint::make(&a, &b, &pose, &opts).unwrap();
    assert_seats(&a, &b, &pose, &opts, &s);
    assert!(s.report.min_thickness >= opts.min_thickness - 2.0 * opts.voxel);
}

#[test]
fn a_final_splint_opens_the_bite_just_enough_for_its_material() {
    let (a, b) = shapes::arch_pair(3, 12);
    let opts = options();
    // The cusps interdigitate at the identity pose: no room for a wafer without opening.
    let o = splint::least_opening(&a, &b, &Pose::IDENTITY, &opts).unwrap();
    assert!(o > 0.0 && o < 5.0, "opening {o}");
    let pose = splint::opened(&a, &b, &Pose::IDENTITY, o).unwrap();
    let s = splint::make(&a, &b, &pose, &opts).unwrap();
    assert_seats(&a, &b, &pose, &opts, &s);
    assert!(s.report.perforated_area <= 0.01 * s.report.volume);
}

#[test]
fn bad_options_and_poses_are_refused_with_a_message() {
    let (a, b) = shapes::arch_pair(2, 8);
    for bad in [
        SplintOptions {
            clearance: f64::NAN,
            ..options()
        },
        SplintOptions {
            voxel: 0.0,
            ..options()
        },
        SplintOptions {
            min_thickness: -1.0,
            ..options()
        },
        SplintOptions {
            rim: 1e9,
            ..options()
        },
    ] {
        let e = splint::make(&a, &b, &Pose::IDENTITY, &bad).unwrap_err();
        assert!(e.to_string().contains("must be"), "{e}");
    }
    let nan = Pose {
        translation: DVec3::new(f64::NAN, 0.0, 0.0),
        ..Pose::IDENTITY
    };
    assert!(splint::make(&a, &b, &nan, &options()).is_err());
    assert!(splint::opened(&a, &b, &Pose::IDENTITY, f64::INFINITY).is_err());
    // B far away: no room is not the problem, but nothing lies between them either.
    let far = Pose::from_translation(DVec3::new(1e5, 0.0, 0.0));
    assert!(splint::make(&a, &b, &far, &options()).is_err());
    assert!(splint::make(&Mesh::default(), &b, &Pose::IDENTITY, &options()).is_err());
}

/// Bodies that cannot make a wafer are refused before the work, each with its reason (each
/// of these made a "wafer" before: a 98 mm block, one 200 mm sideways, one for B turned,
/// one for metre meshes with 100 % coverage, one with B swung through A).
#[test]
fn inputs_that_cannot_make_a_wafer_are_refused_with_the_reason() {
    let (a, b) = shapes::arch_pair(2, 8);
    let opts = options();
    let refused = |a: &Mesh, b: &Mesh, pose: Pose, why: &str| {
        let e = splint::make(a, b, &pose, &opts).unwrap_err().to_string();
        assert!(e.contains(why), "{why}: {e}");
    };
    let t = |x: f64, y: f64, z: f64| Pose::from_translation(DVec3::new(x, y, z));
    refused(&a, &b, t(0.0, 0.0, -100.0), "apart at their closest");
    refused(&a, &b, t(200.0, 0.0, 0.0), "apart at their closest");
    refused(&a, &b, t(0.0, 0.0, 5.0), "passes");
    for axis in [DVec3::Z, DVec3::X] {
        let turned = Pose {
            rotation: innersphere::glam::DQuat::from_axis_angle(axis, std::f64::consts::PI),
            translation: DVec3::new(0.0, 50.0, 0.0),
        };
        let e = splint::make(&a, &b, &turned, &opts)
            .unwrap_err()
            .to_string();
        assert!(e.contains("apart") || e.contains("passes"), "{axis}: {e}");
    }
    let scaled = |m: &Mesh, f: f64| Mesh {
        vertices: m.vertices.iter().map(|v| *v * f).collect(),
        triangles: m.triangles.clone(),
    };
    refused(
        &scaled(&a, 1e-3),
        &scaled(&b, 1e-3),
        Pose::IDENTITY,
        "--unit m",
    );
    refused(
        &scaled(&a, 1e3),
        &scaled(&b, 1e3),
        Pose::IDENTITY,
        "not a dental arch",
    );
    let flat = |m: &Mesh| Mesh {
        vertices: m
            .vertices
            .iter()
            .map(|v| DVec3::new(v.x, v.y, 0.2 * v.z.signum()))
            .collect(),
        triangles: m.triangles.clone(),
    };
    refused(&flat(&a), &b, Pose::IDENTITY, "flat");
    let one = Mesh {
        vertices: vec![
            DVec3::new(-20.0, 10.0, 5.0),
            DVec3::new(20.0, 10.0, 5.0),
            DVec3::new(0.0, 40.0, 5.0),
        ],
        triangles: vec![[0, 1, 2]],
    };
    assert!(splint::make(&one, &b, &Pose::IDENTITY, &opts).is_err());
    // Swung through A about the hinge, or opened beyond what a wafer is made at.
    for o in [-50.0, -5.0, 25.0] {
        let e = splint::make_opened(&a, &b, &Pose::IDENTITY, splint::Opening::By(o), &opts)
            .unwrap_err()
            .to_string();
        assert!(e.contains("opening must be within"), "{o}: {e}");
    }
}

/// The same arch turned about the insertion axis (B's front towards A's back) is refused by
/// the arches' own anterior directions.
#[test]
fn an_arch_turned_about_the_insertion_axis_is_refused() {
    let (a, b) = shapes::arch_pair(2, 8);
    // The arch spans y 8–43: turned by π about z through its middle.
    let turned = Pose {
        rotation: innersphere::glam::DQuat::from_rotation_z(std::f64::consts::PI),
        translation: DVec3::new(0.0, 2.0 * 25.3, 0.0),
    };
    let e = splint::make(&a, &b, &turned, &options())
        .unwrap_err()
        .to_string();
    assert!(e.contains("point") && e.contains("apart"), "{e}");
}

/// A voxel size whose grid would not fit the splint's memory is refused at once, naming the
/// voxel size that fits (a bound on bytes: 0.042 mm aborted in the surface extraction).
#[test]
fn a_voxel_too_fine_for_memory_is_refused_with_one_that_fits() {
    let (a, b) = shapes::arch_pair(2, 8);
    let big = |m: &Mesh| Mesh {
        vertices: m.vertices.iter().map(|v| *v * 2.5).collect(),
        triangles: m.triangles.clone(),
    };
    let opts = SplintOptions {
        voxel: 0.01,
        ..options()
    };
    let e = splint::make(&big(&a), &big(&b), &Pose::IDENTITY, &opts)
        .unwrap_err()
        .to_string();
    // Refused before the columns' work, from the least grid any wafer needs.
    assert!(e.contains("GB") && e.contains("or more is needed"), "{e}");
}

/// An open pair (the arches 4 mm apart, teeth with roots) and arches with open boundaries
/// and +y up get a wafer that seats and covers their occlusal surfaces (coverage was 0 for
/// any pair more than 3.5 mm open).
#[test]
fn open_pairs_open_meshes_and_any_up_axis_get_a_wafer_that_seats() {
    let (a, b) = shapes::arch_pair(3, 12);
    let opts = options();
    let open = Pose::from_translation(DVec3::new(0.0, 0.0, -4.0));
    let s = splint::make(&a, &b, &open, &opts).unwrap();
    assert_seats(&a, &b, &open, &opts, &s);
    // The roots' ends cut off: open boundaries.
    let cut = |m: &Mesh, keep: &dyn Fn(f64) -> bool| {
        let mut m = m.clone();
        m.triangles
            .retain(|t| keep(t.iter().map(|&i| m.vertices[i as usize].z).sum::<f64>() / 3.0));
        m
    };
    let (ao, bo) = (cut(&a, &|z| z < 9.0), cut(&b, &|z| z > -4.0));
    assert!(!ao.report().watertight && !bo.report().watertight);
    let s = splint::make(&ao, &bo, &open, &opts).unwrap();
    assert_seats(&ao, &bo, &open, &opts, &s);
    // +y up: the same pair turned so that the insertion axis is y.
    let q = innersphere::glam::DQuat::from_rotation_x(-std::f64::consts::FRAC_PI_2);
    let turn = |m: &Mesh| Mesh {
        vertices: m.vertices.iter().map(|v| q * *v).collect(),
        triangles: m.triangles.clone(),
    };
    let (ay, by) = (turn(&a), turn(&b));
    let pose = splint::opened(&ay, &by, &Pose::IDENTITY, 3.0).unwrap();
    let s = splint::make(&ay, &by, &pose, &opts).unwrap();
    assert_seats(&ay, &by, &pose, &opts, &s);
    let axis = DVec3::from_array(s.report.insertion_axis);
    assert!(axis.dot(DVec3::Y) > 0.95, "{axis}");
}

#[test]
fn a_splints_report_is_the_same_bits_on_any_number_of_threads() {
    // The coverages summed vertex areas in a parallel reduction whose grouping followed the
    // scheduling: `ist splint` and Python's `splint` differed in the last bit under load.
    let (a, b) = shapes::arch_pair(3, 12);
    let opts = options();
    let pose = splint::opened(&a, &b, &Pose::IDENTITY, 3.0).unwrap();
    let on = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let mut r = pool.install(|| splint::make(&a, &b, &pose, &opts).unwrap().report);
        // Everything but the wall times.
        r.seconds = 0.0;
        r.stage_seconds = Default::default();
        r
    };
    let one = on(1);
    for threads in [2, 3, 4, 7] {
        let r = on(threads);
        assert_eq!(
            (r.coverage_a.to_bits(), r.coverage_b.to_bits()),
            (one.coverage_a.to_bits(), one.coverage_b.to_bits()),
            "{threads} threads"
        );
        assert_eq!(format!("{r:?}"), format!("{one:?}"), "{threads} threads");
    }
}

/// Arches with their bone (each one closed surface of teeth and bone): the intermediate and
/// the final wafer seat and carry both occlusal surfaces (`--ignored`: the arches have half a
/// million triangles each).
#[test]
#[ignore]
fn wafers_between_arches_with_bone_seat_on_both() {
    let (a, b) = shapes::arch_pair_with_bone(3, 12);
    let opts = options();
    for opening in [splint::Opening::By(3.0), splint::Opening::Auto] {
        let s = splint::make_opened(&a, &b, &Pose::IDENTITY, opening, &opts).unwrap();
        let pose = Pose::from_array(s.report.pose).unwrap();
        assert_seats(&a, &b, &pose, &opts, &s);
    }
}
