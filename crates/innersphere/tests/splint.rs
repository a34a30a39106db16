//! The splint on generated arches: one clean solid that keeps its clearance, carries the
//! occlusal surfaces, and fails cleanly on bad input. The same checks on the real jaw pair
//! are `innersphere-eval/tests/splint_jaw.rs`.

use innersphere::glam::DVec3;
use innersphere::splint::{self, SplintOptions};
use innersphere::{shapes, Mesh, Pose};
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
