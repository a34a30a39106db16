//! Occlusion on generated bodies: a peg closed into a ring from several open starts ends in
//! the same seat, the free search from many starts seats it, bad options are refused, and a
//! closing out of time stops at its step limit.

// The haptic crate's test helpers (the slab, the block, the serial lock).
use crate::haptic_util;

use glam::{DQuat, DVec3};
use haptic_util::{build, on_slab, serial, slab_and_block};
use innersphere::{shapes, Pair, PenetrationOptions, Pose};
use innersphere_dental::{
    occlude, occlude_free, FreeOcclusionOptions, Joints, OcclusionOptions, OcclusionStatus,
};

#[test]
fn occlusion_of_a_peg_in_a_ring_ends_in_the_same_seat() {
    let _serial = serial();
    // A ring (A, hole radius 1 mm) and an egg-shaped peg (B, 2.8 mm wide, 6 mm long) pushed
    // up (+z) into the hole: it seats centred and upright, whatever its start.
    let a = build(&shapes::torus(2.0, 1.0, 96, 48), 64);
    let b = build(&shapes::ellipsoid(DVec3::new(1.4, 1.4, 3.0), 5), 48);
    let starts = [
        Pose::from_translation(DVec3::new(0.0, 0.0, -5.0)),
        Pose::from_translation(DVec3::new(0.3, -0.2, -6.0)),
        Pose::new(DVec3::new(-0.3, 0.2, -5.5), DQuat::from_rotation_x(0.05)).unwrap(),
        Pose::new(DVec3::new(0.1, 0.3, -5.0), DQuat::from_rotation_y(-0.05)).unwrap(),
    ];
    let opts = OcclusionOptions {
        axis: DVec3::Z,
        force: 5.0,
        contact_stiffness: 20.0,
        ..Default::default()
    };
    let mut ends = vec![];
    for s in &starts {
        let mut pair = Pair::new(a.clone(), b.clone());
        let o = occlude(&mut pair, &Pose::IDENTITY, s, &opts).unwrap();
        assert!(
            o.converged(),
            "from {s:?}: not at rest after {} steps ({:?})",
            o.steps,
            o.pose
        );
        assert!(o.volume > 0.0 && o.max_depth > 0.0 && !o.patches.is_empty());
        // At rest the contact carries the closing force.
        let f = o.volume * opts.contact_stiffness;
        assert!((f / opts.force - 1.0).abs() < 0.05, "{f} N of contact");
        ends.push(o.pose);
    }
    // The peg's axis (its tip and its foot) ends in the same place from every start (the
    // turn about its own axis is a symmetry of the peg).
    let probes = [DVec3::new(0.0, 0.0, 3.0), DVec3::new(0.0, 0.0, -3.0)];
    for e in &ends {
        for p in probes {
            let d = (e.transform_point(p) - ends[0].transform_point(p)).length();
            assert!(d < 0.01, "{d} mm apart: {e:?} vs {:?}", ends[0]);
        }
        assert_seated(e);
    }
}

/// The peg's pose `e` is centred in the ring and upright to the packing's resolution: its
/// centre within half the ring's voxel (6 mm / 64) of the axis, its own axis within 2° of the
/// ring's. (The packing of a symmetric shape is not symmetric — the greedy packing runs in
/// blocks — and spheres inside the surface by up to a quarter voxel tilt a peg seated on a
/// 1 mm ring by up to about 2°.)
fn assert_seated(e: &Pose) {
    let off = e.transform_point(DVec3::ZERO).truncate().length();
    let tilt = e
        .rotation
        .mul_vec3(DVec3::Z)
        .angle_between(DVec3::Z)
        .to_degrees();
    assert!(off < 0.5 * 6.0 / 64.0, "{off} mm off centre: {e:?}");
    assert!(tilt < 2.0, "tilted {tilt}°: {e:?}");
}

/// A free peg closed from starts spread around its start: every start seats it centred and
/// upright in the ring, the candidates account for every start, the same seed gives the same
/// answer, and bad options are refused.
#[test]
fn free_occlusion_from_many_starts_seats_the_peg() {
    let _serial = serial();
    let a = build(&shapes::torus(2.0, 1.0, 96, 48), 64);
    let b = build(&shapes::ellipsoid(DVec3::new(1.4, 1.4, 3.0), 5), 48);
    let opts = FreeOcclusionOptions {
        closing: OcclusionOptions {
            axis: DVec3::Z,
            force: 5.0,
            contact_stiffness: 20.0,
            ..Default::default()
        },
        lateral: DVec3::X,
        starts: 8,
        spread: 0.4,
        spread_angle: 0.05,
        ..Default::default()
    };
    let from = Pose::from_translation(DVec3::new(0.2, -0.1, -5.0));
    let f = occlude_free(&a, &b, &Pose::IDENTITY, &from, &opts).unwrap();
    assert!(
        f.closing.converged() && f.closings[&OcclusionStatus::Converged] == 8,
        "{f:?}"
    );
    assert_eq!(f.candidates.iter().map(|c| c.starts).sum::<usize>(), 8);
    assert_eq!(f.closing.pose, f.candidates[0].pose);
    for c in &f.candidates {
        // The turn about its own axis is a symmetry of the peg: its axis is what must agree.
        assert_seated(&c.pose);
        assert!(
            c.contacts > 0 && c.lateral_side > 0 && c.other_side > 0,
            "{c:?}"
        );
        assert!(
            c.contact_area > 0.0 && c.volume > 0.0 && c.lateral_stiffness > 0.0,
            "{c:?}"
        );
        assert_eq!(c.contacts, c.lateral_side + c.other_side, "{c:?}");
        // The contact at the candidate, with the closing's stiffness: its area, volume and
        // least stiffness across the closing axis (z), lateral x and anterior y.
        let p = Pair::new(a.clone(), b.clone()).penetration_with(
            &Pose::IDENTITY,
            &c.pose,
            &PenetrationOptions {
                stiffness: 20.0,
                linearize: true,
                ..Default::default()
            },
        );
        assert_eq!((c.contact_area, c.volume), (p.area, p.volume));
        let m = p.stiffness.linear;
        let (xx, yy, xy) = (m.x_axis.x, m.y_axis.y, 0.5 * (m.y_axis.x + m.x_axis.y));
        let least = 0.5 * (xx + yy) - (0.25 * (xx - yy).powi(2) + xy * xy).sqrt();
        assert!(
            (c.lateral_stiffness - least).abs() <= 1e-9 * least.abs(),
            "{} against {least}",
            c.lateral_stiffness
        );
    }
    let closing = &f.closing;
    assert_eq!(closing.patches.len(), f.candidates[0].contacts);
    assert_eq!(
        f,
        occlude_free(&a, &b, &Pose::IDENTITY, &from, &opts).unwrap()
    );
    let joints = Joints {
        points: [DVec3::ZERO; 2],
        anchors: [DVec3::ZERO; 2],
        stiffness: 1.0,
    };
    for bad in [
        FreeOcclusionOptions {
            closing: OcclusionOptions {
                joints: Some(joints),
                ..opts.closing
            },
            ..opts
        },
        FreeOcclusionOptions { starts: 0, ..opts },
        FreeOcclusionOptions {
            spread: f64::NAN,
            ..opts
        },
        FreeOcclusionOptions {
            lateral: DVec3::Z,
            ..opts
        },
        FreeOcclusionOptions {
            closing: OcclusionOptions {
                force: -1.0,
                ..opts.closing
            },
            ..opts
        },
    ] {
        assert!(
            occlude_free(&a, &b, &Pose::IDENTITY, &from, &bad).is_err(),
            "{bad:?}"
        );
    }
    // A start with a non-finite translation, or rotation, alone.
    for start in [
        Pose {
            translation: DVec3::new(0.0, f64::NAN, 0.0),
            ..from
        },
        Pose {
            rotation: DQuat::from_xyzw(0.0, 0.0, f64::INFINITY, 1.0),
            ..from
        },
    ] {
        let e = occlude_free(&a, &b, &Pose::IDENTITY, &start, &opts).unwrap_err();
        assert!(e.to_string().contains("start pose must be finite"), "{e}");
    }
}

#[test]
fn occlusion_refuses_bad_options() {
    let _serial = serial();
    let (a, b) = slab_and_block();
    let base = OcclusionOptions::default();
    for o in [
        OcclusionOptions { force: 0.0, ..base },
        OcclusionOptions {
            axis: DVec3::ZERO,
            ..base
        },
        OcclusionOptions {
            step: f64::NAN,
            ..base
        },
        OcclusionOptions {
            max_seconds: 1e9,
            step: 1e-6,
            ..base
        },
    ] {
        let mut pair = Pair::new(a.clone(), b.clone());
        assert!(
            occlude(&mut pair, &Pose::IDENTITY, &on_slab(-1.0), &o).is_err(),
            "{o:?}"
        );
    }
    // A joint stiffness below 0 or not finite.
    for stiffness in [-1.0, f64::INFINITY, f64::NAN] {
        let o = OcclusionOptions {
            joints: Some(Joints {
                points: [DVec3::X, -DVec3::X],
                anchors: [DVec3::X, -DVec3::X],
                stiffness,
            }),
            ..base
        };
        let mut pair = Pair::new(a.clone(), b.clone());
        let e = occlude(&mut pair, &Pose::IDENTITY, &on_slab(-1.0), &o).unwrap_err();
        assert!(e.to_string().contains("joint stiffness"), "{e}");
    }
    // An axis with one NaN component is refused as an axis, before any step (it was taken
    // for a direction, and the dynamics failed later with a message about them).
    let o = OcclusionOptions {
        axis: DVec3::new(f64::NAN, 0.0, 1.0),
        ..base
    };
    let mut pair = Pair::new(a.clone(), b.clone());
    let e = occlude(&mut pair, &Pose::IDENTITY, &on_slab(-1.0), &o).unwrap_err();
    assert!(e.to_string().contains("closing axis"), "{e}");
}

/// Out of time, the occlusion stops after the steps the time allows (rounded up), not one
/// more, and says it did not come to rest.
#[test]
fn an_occlusion_out_of_time_stops_at_its_step_limit() {
    let _serial = serial();
    let (a, b) = slab_and_block();
    let o = OcclusionOptions {
        max_seconds: 0.0105,
        ..OcclusionOptions::default()
    };
    let mut pair = Pair::new(a.clone(), b.clone());
    let r = occlude(&mut pair, &Pose::IDENTITY, &on_slab(-1.0), &o).unwrap();
    assert_eq!(r.status, OcclusionStatus::TimeLimit);
    assert_eq!(r.steps, 11);
    assert!((r.seconds - 0.011).abs() < 1e-15, "{}", r.seconds);
}
