//! "Converged" means at rest in contact, on generated bodies: a converged bite is checked in
//! contact by the exact mesh distance and balanced by its own forces summed here; closings
//! that go through A, away from it or rest open say so; inputs that cannot make a bite are
//! refused with a sentence naming the limit (none of them with the old "dynamics became
//! non-finite").

use glam::{DQuat, DVec3};
use innersphere::exact::{self, ExactMesh, ExactScratch};
use innersphere::query::PenetrationOptions;
use innersphere::{shapes, BuildOptions, Mesh, Pair, Pose, Resolution, SharedTree, SphereTree};
use innersphere_dental::{
    bite, frame_of, occlude, BiteOptions, Joints, OcclusionOptions, OcclusionStatus,
};
use std::sync::OnceLock;

/// Generated upper (A) and lower (B) arches of 8 teeth in their bite at the identity: the
/// meshes (exact, for the checks) and their trees.
struct Arches {
    exact: (ExactMesh, ExactMesh),
    trees: (SharedTree, SharedTree),
}

fn arches() -> &'static Arches {
    static T: OnceLock<Arches> = OnceLock::new();
    T.get_or_init(|| {
        let (upper, lower) = shapes::arch_pair(2, 8);
        Arches {
            exact: (
                ExactMesh::new(&upper).unwrap(),
                ExactMesh::new(&lower).unwrap(),
            ),
            trees: (build(&upper, 96), build(&lower, 96)),
        }
    })
}

fn build(m: &Mesh, cells: u32) -> SharedTree {
    let opts = BuildOptions {
        resolution: Resolution::Cells(cells),
        ..Default::default()
    };
    SharedTree::new(SphereTree::build(m, &opts).unwrap())
}

/// B's centre of mass at `pose` against A's, along `axis` (positive: B beyond A).
fn beyond(a: &SharedTree, b: &SharedTree, pose: &Pose, axis: DVec3) -> f64 {
    (pose.transform_point(b.info().center_of_mass) - a.info().center_of_mass).dot(axis)
}

/// The answer `pose` of a converged bite, checked with what shares nothing with the
/// closing: the exact meshes touch there and are not sunk into each other, and the forces
/// on B (the closing force, the contact's, the joints' springs summed here) balance.
fn assert_rests_in_contact(pose: &Pose, force: f64, stiffness: f64, joints: Option<&Joints>) {
    let Arches {
        exact: (ea, eb),
        trees: (a, b),
    } = arches();
    let frame = frame_of(a.tree(), b.tree()).unwrap();
    let mut scratch = ExactScratch::new();
    let d = exact::distance(ea, &Pose::IDENTITY, eb, pose, &mut scratch);
    assert!(d.intersecting, "not in contact: {} mm apart", d.distance);
    let p = Pair::new(a.clone(), b.clone()).penetration_with(
        &Pose::IDENTITY,
        pose,
        &PenetrationOptions {
            stiffness,
            ..Default::default()
        },
    );
    // Not sunk in: the meshes overlap by no more than the spheres do plus the depth of the
    // spheres below each surface (up to a voxel each).
    let depth = exact::penetration_depth(ea, &Pose::IDENTITY, eb, pose, &mut scratch);
    let slack = a.tree().meta.voxel_size + b.tree().meta.voxel_size;
    assert!(
        depth <= p.max_depth + slack,
        "sunk {depth} mm into A (spheres {} mm)",
        p.max_depth
    );
    // Balanced: the contact's force and the joints' springs carry the closing force.
    let springs: DVec3 = joints.map_or(DVec3::ZERO, |j| {
        j.points
            .iter()
            .zip(&j.anchors)
            .map(|(p, anchor)| (*anchor - pose.transform_point(*p)) * j.stiffness)
            .sum()
    });
    let net = frame.up * force + p.force + springs;
    assert!(
        net.length() <= 0.05 * force,
        "net force {net} N of {force} N"
    );
    // And on the near side of A.
    assert!(beyond(a, b, pose, frame.up) < 0.0);
}

#[test]
fn a_converged_bite_rests_in_contact_with_the_joints_and_free() {
    let Arches { trees: (a, b), .. } = arches();
    let frame = frame_of(a.tree(), b.tree()).unwrap();
    let from = Pose::from_translation(-2.0 * frame.up + 0.3 * frame.left);
    let got = bite(a, b, &from, &BiteOptions::default()).unwrap();
    assert_eq!(got.occlusion.status, OcclusionStatus::Converged);
    assert_rests_in_contact(&got.occlusion.pose, 5.0, 10.0, got.closing.joints.as_ref());
    let opts = BiteOptions {
        free: true,
        starts: 6,
        spread: 1.0,
        ..Default::default()
    };
    let got = bite(a, b, &from, &opts).unwrap();
    assert_eq!(got.occlusion.status, OcclusionStatus::Converged);
    assert_rests_in_contact(&got.occlusion.pose, 5.0, 1000.0, None);
    // Every start accounted for, and every candidate a converged rest in contact.
    let closings = got.closings.unwrap();
    assert_eq!(closings.values().sum::<usize>(), 6, "{closings:?}");
    assert_eq!(
        got.candidates.iter().map(|c| c.starts).sum::<usize>(),
        closings[&OcclusionStatus::Converged]
    );
    for c in &got.candidates {
        assert_rests_in_contact(&c.pose, 5.0, 1000.0, None);
    }
}

/// The largest force the contact holds (1000 N on a 500 N/mm³ contact, 2 mm³ at rest)
/// still ends at rest in contact, on the near side of A, not through it.
#[test]
fn the_largest_force_within_the_limits_rests_in_contact() {
    let Arches { trees: (a, b), .. } = arches();
    let frame = frame_of(a.tree(), b.tree()).unwrap();
    let from = Pose::from_translation(-2.0 * frame.up);
    let opts = BiteOptions {
        force: 1000.0,
        contact_stiffness: Some(500.0),
        ..Default::default()
    };
    let got = bite(a, b, &from, &opts).unwrap();
    assert_eq!(got.occlusion.status, OcclusionStatus::Converged);
    assert_rests_in_contact(
        &got.occlusion.pose,
        1000.0,
        500.0,
        got.closing.joints.as_ref(),
    );
}

/// A needle pushed through a foil within every limit (20 N on a 10 N/mm³ contact: 2 mm³ at
/// rest, but the foil and the needle overlap by at most 0.4 mm³): the closing says it
/// passed through, and stops there.
#[test]
fn a_needle_through_a_foil_passed_through_and_stops() {
    let foil = build(&shapes::cuboid(DVec3::new(10.0, 10.0, 0.25)), 128);
    let needle = build(&shapes::ellipsoid(DVec3::new(0.5, 0.5, 5.0), 3), 48);
    let from = Pose::from_translation(DVec3::new(0.0, 0.0, -6.0));
    let opts = OcclusionOptions {
        axis: DVec3::Z,
        force: 20.0,
        damping: 4.0,
        max_seconds: 20.0,
        ..Default::default()
    };
    let mut pair = Pair::new(foil.clone(), needle.clone());
    let o = occlude(&mut pair, &Pose::IDENTITY, &from, &opts).unwrap();
    assert_eq!(o.status, OcclusionStatus::PassedThrough, "{o:?}");
    assert!(!o.converged());
    // Its centre just beyond the foil's: stopped at once, not flown on for 20 s.
    let past = beyond(&foil, &needle, &o.pose, DVec3::Z);
    assert!(past > 0.0 && past < 0.1, "{past} mm past the foil");
    assert!(o.steps < 3000, "{} steps", o.steps);
}

/// Pushed away from A (no joints), B escapes; held open by joints on the line through its
/// centre of mass, it rests open: neither is converged.
#[test]
fn a_closing_away_from_a_escapes_and_one_held_open_rests_without_contact() {
    let Arches {
        exact: (ea, eb),
        trees: (a, b),
    } = arches();
    let frame = frame_of(a.tree(), b.tree()).unwrap();
    let from = Pose::from_translation(-3.0 * frame.up);
    let away = OcclusionOptions {
        axis: -frame.up,
        force: 20.0,
        max_seconds: 10.0,
        ..Default::default()
    };
    let mut pair = Pair::new(a.clone(), b.clone());
    let o = occlude(&mut pair, &Pose::IDENTITY, &from, &away).unwrap();
    assert_eq!(o.status, OcclusionStatus::Escaped, "{o:?}");
    // Farther than its start's distance to A's centre plus both bodies' radii, just.
    let radius = |t: &SharedTree| {
        let i = t.info();
        (i.root_center - i.center_of_mass).length() + i.radius
    };
    let com = |p: &Pose| p.transform_point(b.info().center_of_mass);
    let reach = (com(&from) - a.info().center_of_mass).length() + radius(a) + radius(b);
    let moved = (com(&o.pose) - com(&from)).length();
    assert!(
        moved > reach && moved < reach + 0.1,
        "{moved} against {reach}"
    );
    // Held open: two stiff joints either side of B's centre of mass, where they are.
    let c = b.info().center_of_mass;
    let points = [c + frame.left * 10.0, c - frame.left * 10.0];
    let held = OcclusionOptions {
        axis: frame.up,
        joints: Some(Joints {
            points,
            anchors: points.map(|p| from.transform_point(p)),
            stiffness: 1000.0,
        }),
        ..Default::default()
    };
    let o = occlude(&mut pair, &Pose::IDENTITY, &from, &held).unwrap();
    assert_eq!(o.status, OcclusionStatus::NoContact, "{o:?}");
    let d = exact::distance(ea, &Pose::IDENTITY, eb, &o.pose, &mut ExactScratch::new());
    assert!(d.distance > 2.5, "{} mm apart", d.distance);
}

/// Refused before any closing, with the limit named; never the old "dynamics became
/// non-finite", never a "converged" answer far from A.
#[test]
fn what_cannot_make_a_bite_is_refused_with_the_limit_named() {
    let Arches { trees: (a, b), .. } = arches();
    let frame = frame_of(a.tree(), b.tree()).unwrap();
    let (up, left) = (frame.up, frame.left);
    let open = Pose::from_translation(-2.0 * up);
    let base = BiteOptions::default();
    let free = BiteOptions {
        free: true,
        starts: 4,
        ..base
    };
    let cases: Vec<(BiteOptions, Pose, &str)> = vec![
        (
            BiteOptions {
                force: 0.001,
                ..base
            },
            open,
            "the closing force must be 0.5 to 1000 N",
        ),
        (
            BiteOptions {
                force: 2000.0,
                ..base
            },
            open,
            "the closing force must be 0.5 to 1000 N",
        ),
        (
            BiteOptions {
                force: 1e300,
                ..free
            },
            open,
            "the closing force must be 0.5 to 1000 N",
        ),
        (
            BiteOptions {
                force: 100.0,
                ..base
            },
            open,
            "rests on 10 mm³ of overlap, more than the 2 mm³",
        ),
        (
            BiteOptions {
                contact_stiffness: Some(1e300),
                ..base
            },
            open,
            "the contact stiffness must be positive and at most 100000 N/mm³",
        ),
        (
            BiteOptions {
                joint_stiffness: 1e300,
                ..base
            },
            open,
            "the joint stiffness must be finite and 0 to 10000 N/mm",
        ),
        (
            BiteOptions {
                max_seconds: 1e7,
                ..base
            },
            open,
            "the time limit must be 0.001 to 60 s",
        ),
        (
            BiteOptions {
                spread: 1000.0,
                ..free
            },
            open,
            "the spread must be at most 10 mm",
        ),
        (
            BiteOptions {
                starts: 5000,
                ..free
            },
            open,
            "the starts must be 1 to 1000",
        ),
        (
            base,
            Pose::from_translation(-40.0 * up),
            "at most 30 mm open",
        ),
        (
            free,
            Pose::from_translation(-1e15 * up),
            "at most 30 mm open",
        ),
        (
            base,
            Pose::from_translation(-3.0 * up + 60.0 * left),
            "the arches lie side by side",
        ),
        (
            free,
            Pose::new(-2.0 * up, DQuat::from_axis_angle(up, std::f64::consts::PI)).unwrap(),
            "the start turns B 180° from A's frame",
        ),
        (
            base,
            Pose::from_translation(20.0 * up),
            "beyond A's along the closing axis",
        ),
        (
            BiteOptions {
                axis: Some(left),
                ..base
            },
            open,
            "the closing axis is 90° from the arches' occlusal axis",
        ),
        (
            BiteOptions {
                reference: Pose::from_translation(DVec3::new(1e300, 0.0, 0.0)),
                ..base
            },
            open,
            "the reference pose",
        ),
    ];
    for (opts, from, want) in cases {
        let e = bite(a, b, &from, &opts).unwrap_err().to_string();
        assert!(e.contains(want), "{opts:?} from {from:?}: {e}");
        assert!(!e.contains("non-finite"), "{e}");
    }
}

/// An arch against its own copy (both upper arches: they do not face each other) is
/// refused, with the joints and free; it used to close "converged" 38 mm from the bite.
#[test]
fn an_arch_against_its_own_copy_is_refused() {
    let Arches { trees: (a, _), .. } = arches();
    let from = Pose::from_translation(DVec3::new(0.2, -0.2, -3.0));
    for free in [false, true] {
        let opts = BiteOptions {
            free,
            starts: 4,
            ..Default::default()
        };
        let e = bite(a, a, &from, &opts).unwrap_err().to_string();
        assert!(
            e.contains("the two arches do not face each other")
                && e.contains("Is B the lower arch, and is it in A's frame?"),
            "{e}"
        );
    }
}
