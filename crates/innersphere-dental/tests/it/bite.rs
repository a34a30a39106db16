//! The bite as the planners ask for it (`innersphere_dental::bite`), on generated arches: it is the
//! occlusion (with the temporomandibular joints) or the free occlusion (many starts) run
//! with the frame, the joints and the defaults it documents; its JSON says what it found
//! and what it ran with.

use glam::DVec3;
use innersphere::{shapes, BuildOptions, Pair, Pose, Resolution, SharedTree, SphereTree};
use innersphere_dental::{
    bite, frame_of, occlude, occlude_free, BiteOptions, FreeOcclusionOptions, Joints,
    OcclusionOptions, OcclusionStatus, CONDYLE_HALF_SPAN,
};
use serde_json::Value;
use std::sync::OnceLock;

/// Generated upper (A) and lower (B) arches of 8 teeth, in their bite at the identity.
fn arches() -> &'static (SharedTree, SharedTree) {
    static T: OnceLock<(SharedTree, SharedTree)> = OnceLock::new();
    T.get_or_init(|| {
        let (upper, lower) = shapes::arch_pair(2, 8);
        let opts = BuildOptions {
            resolution: Resolution::Cells(96),
            ..Default::default()
        };
        let build = |m| SharedTree::new(SphereTree::build(m, &opts).unwrap());
        (build(&upper), build(&lower))
    })
}

/// B 1.5 mm open along the pair's up.
fn open(up: DVec3) -> Pose {
    Pose::from_translation(-1.5 * up)
}

fn num(v: &Value) -> f64 {
    v.as_f64().unwrap()
}

fn array(v: &Value) -> Vec<f64> {
    v.as_array().unwrap().iter().map(num).collect()
}

#[test]
fn the_bite_with_the_joints_is_the_occlusion_with_the_frame_and_joints_it_reports() {
    let (a, b) = arches();
    let frame = frame_of(a.tree(), b.tree()).unwrap();
    let from = open(frame.up);
    let opts = BiteOptions {
        max_seconds: 10.0,
        force: 8.0,
        ..Default::default()
    };
    let got = bite(a, b, &from, &opts).unwrap();
    // What it documents it runs: the pair's up, the force asked for (closing at 5 mm/s:
    // the damping 8 N / 5 mm/s), 10 N/mm³, the joints held where the condyles are at the
    // reference.
    let closing = OcclusionOptions {
        axis: frame.up,
        force: 8.0,
        damping: 1.6,
        contact_stiffness: 10.0,
        max_seconds: 10.0,
        joints: Some(Joints::temporomandibular(&frame, &Pose::IDENTITY, 20.0)),
        ..OcclusionOptions::default()
    };
    assert_eq!(got.closing, closing);
    assert_eq!(got.frame, frame);
    assert!(got.candidates.is_empty());
    let mut pair = Pair::new(a.clone(), b.clone());
    let want = occlude(&mut pair, &Pose::IDENTITY, &from, &closing).unwrap();
    assert_eq!(got.occlusion, want);
    // It closed: in contact, at rest, back near the scanned bite.
    let o = &got.occlusion;
    assert!(
        o.converged() && o.volume > 0.0 && !o.patches.is_empty(),
        "{o:?}"
    );
    let closed = o.pose.translation.dot(frame.up);
    assert!((-0.5..0.5).contains(&closed), "{closed} mm along up");
    // The JSON says the same.
    let j = got.to_json();
    assert_eq!(array(&j["pose"]), o.pose.to_array());
    assert_eq!(j["converged"], true);
    assert_eq!(j["status"], "converged");
    assert!(j["closings"].is_null());
    assert_eq!(j["steps"].as_u64().unwrap() as usize, o.steps);
    assert_eq!(num(&j["seconds"]), o.seconds);
    assert_eq!(num(&j["volume"]), o.volume);
    assert_eq!(num(&j["max_depth"]), o.max_depth);
    let patches = j["patches"].as_array().unwrap();
    assert_eq!(patches.len(), o.patches.len());
    for (p, q) in patches.iter().zip(&o.patches) {
        assert_eq!(array(&p["point"]), q.point.to_array());
        assert_eq!(array(&p["normal"]), q.normal.to_array());
        assert_eq!((num(&p["volume"]), num(&p["depth"])), (q.volume, q.depth));
    }
    assert_eq!(array(&j["axis"]), o.axis.to_array());
    assert_eq!(
        (num(&j["force"]), num(&j["contact_stiffness"])),
        (8.0, 10.0)
    );
    let joints = closing.joints.unwrap();
    for k in 0..2 {
        assert_eq!(
            array(&j["joints"]["points"][k]),
            joints.points[k].to_array()
        );
        assert_eq!(
            array(&j["joints"]["anchors"][k]),
            joints.anchors[k].to_array()
        );
    }
    assert_eq!(num(&j["joints"]["stiffness"]), 20.0);
    for (key, v) in [
        ("up", frame.up),
        ("left", frame.left),
        ("anterior", frame.anterior),
        ("incisal", frame.incisal),
        ("hinge", frame.hinge),
    ] {
        assert_eq!(array(&j["frame"][key]), v.to_array(), "{key}");
    }
    assert_eq!(num(&j["frame"]["scale"]), frame.scale);
    assert!(j["candidates"].is_null());
}

#[test]
fn the_condyles_sit_either_side_of_the_hinge_held_where_the_reference_puts_them() {
    let (a, b) = arches();
    let frame = frame_of(a.tree(), b.tree()).unwrap();
    let reference = Pose::new(
        DVec3::new(0.5, -1.0, 2.0),
        glam::DQuat::from_rotation_x(0.1),
    )
    .unwrap();
    let j = Joints::temporomandibular(&frame, &reference, 35.0);
    let half = frame.left * CONDYLE_HALF_SPAN * frame.scale;
    assert!((j.points[0] - (frame.hinge + half)).length() < 1e-12);
    assert!((j.points[1] - (frame.hinge - half)).length() < 1e-12);
    assert_eq!(j.anchors, j.points.map(|p| reference.transform_point(p)));
    assert_eq!(j.stiffness, 35.0);
    // The frame's up points from the lower arch to the upper one.
    let centre = |t: &SharedTree| t.info().center_of_mass;
    assert!(frame.up.dot(centre(a) - centre(b)) > 0.0);
}

#[test]
fn the_free_bite_is_the_free_occlusion_with_the_spread_it_documents() {
    let (a, b) = arches();
    let frame = frame_of(a.tree(), b.tree()).unwrap();
    let from = open(frame.up);
    let axis = (frame.up + 0.05 * frame.anterior).normalize();
    let opts = BiteOptions {
        free: true,
        axis: Some(axis),
        starts: 6,
        spread: 0.8,
        seed: 7,
        max_seconds: 10.0,
        ..Default::default()
    };
    let got = bite(a, b, &from, &opts).unwrap();
    let closing = OcclusionOptions {
        axis,
        force: 5.0,
        contact_stiffness: 1000.0,
        max_seconds: 10.0,
        joints: None,
        ..OcclusionOptions::default()
    };
    assert_eq!(got.closing, closing);
    let want = occlude_free(
        a,
        b,
        &Pose::IDENTITY,
        &from,
        &FreeOcclusionOptions {
            closing,
            lateral: frame.left,
            starts: 6,
            spread: 0.8,
            spread_angle: 1.6f64.to_radians(),
            seed: 7,
            ..FreeOcclusionOptions::default()
        },
    )
    .unwrap();
    assert_eq!(got.candidates, want.candidates);
    assert_eq!(got.occlusion, want.closing);
    assert_eq!(got.closings.as_ref(), Some(&want.closings));
    assert!(!got.candidates.is_empty());
    assert_eq!(got.occlusion.pose, got.candidates[0].pose);
    let j = got.to_json();
    assert!(j["joints"].is_null());
    assert_eq!(num(&j["contact_stiffness"]), 1000.0);
    let c = j["candidates"].as_array().unwrap();
    assert_eq!(c.len(), got.candidates.len());
    for (v, k) in c.iter().zip(&got.candidates) {
        assert_eq!(array(&v["pose"]), k.pose.to_array());
        assert_eq!(v["starts"].as_u64().unwrap() as usize, k.starts);
        assert_eq!(v["contacts"].as_u64().unwrap() as usize, k.contacts);
        assert_eq!(
            v["contacts_left"].as_u64().unwrap() as usize,
            k.lateral_side
        );
        assert_eq!(v["contacts_right"].as_u64().unwrap() as usize, k.other_side);
        assert_eq!(num(&v["contact_area"]), k.contact_area);
        assert_eq!(num(&v["volume"]), k.volume);
        assert_eq!(num(&v["lateral_stiffness"]), k.lateral_stiffness);
    }
}

#[test]
fn a_free_bite_where_no_closing_converges_answers_with_the_starts_own_closing() {
    let (a, b) = arches();
    let frame = frame_of(a.tree(), b.tree()).unwrap();
    // 25 mm open with a tenth of a second to close: no closing reaches A.
    let from = Pose::from_translation(-25.0 * frame.up);
    let opts = BiteOptions {
        free: true,
        axis: Some(frame.up * 3.0),
        starts: 3,
        max_seconds: 0.1,
        ..Default::default()
    };
    let got = bite(a, b, &from, &opts).unwrap();
    assert!(got.candidates.is_empty());
    // Every start accounted for: three closings out of time.
    let closings = got.closings.as_ref().unwrap();
    assert_eq!(closings[&OcclusionStatus::TimeLimit], 3, "{closings:?}");
    assert_eq!(closings.values().sum::<usize>(), 3);
    // The answer is the start's own closing: 100 steps of 1 ms at 5 mm/s along up.
    let o = &got.occlusion;
    assert_eq!((o.status, o.steps), (OcclusionStatus::TimeLimit, 100));
    assert!(!o.converged());
    let moved = o.pose.translation - from.translation;
    assert!((moved.dot(frame.up) - 0.5).abs() < 0.01, "{moved}");
    assert!(moved.reject_from(frame.up).length() < 1e-9, "{moved}");
    assert_eq!((o.volume, o.max_depth), (0.0, 0.0));
    assert!(o.patches.is_empty());
    assert!((o.axis - frame.up).length() < 1e-12, "{}", o.axis);
    let j = got.to_json();
    assert_eq!(j["status"], "time_limit");
    assert_eq!(j["converged"], false);
    assert_eq!(
        j["closings"],
        serde_json::json!({"converged": 0, "no_contact": 0, "time_limit": 3,
                           "passed_through": 0, "escaped": 0})
    );
}
