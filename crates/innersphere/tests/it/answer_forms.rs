//! The serialized form of every answer type: the keys each door prints (`ist query --json`,
//! Python's `to_dict`, the viewer), in order, and the values under the renamed keys. A new
//! field of an answer shows here first.

use glam::{DMat3, DVec3};
use innersphere::{
    BudgetedVolume, Contact, ContactResult, ContactStiffness, Distance, MeshPenetration,
    Multipoint, Patch, Penetration, RefinedDistance,
};
use serde_json::{json, Value};

/// The keys of a record, sorted (as `serde_json` keeps them).
fn keys(v: &Value) -> Vec<&str> {
    v.as_object()
        .expect("an answer serializes as a record")
        .keys()
        .map(String::as_str)
        .collect()
}

/// Fails unless the record `v` has exactly the keys `want`.
fn keys_are<const N: usize>(v: &Value, mut want: [&str; N]) {
    want.sort_unstable();
    assert_eq!(keys(v), want, "{v}");
}

fn form<T: serde::Serialize>(t: &T) -> Value {
    serde_json::to_value(t).expect("answers serialize")
}

fn distance(overlapping: bool) -> Distance {
    Distance {
        distance: 0.25,
        pair_distance: 0.25,
        lower_bound: 0.25,
        overlapping,
        point_a: DVec3::new(1.0, 2.0, 3.0),
        point_b: DVec3::new(1.0, 2.0, 3.25),
        normal: DVec3::Z,
        leaf_a: 7,
        leaf_b: 9,
        visits: 41,
    }
}

#[test]
fn a_distance_says_contact_for_overlapping() {
    let v = form(&distance(true));
    keys_are(
        &v,
        [
            "distance",
            "pair_distance",
            "lower_bound",
            "contact",
            "point_a",
            "point_b",
            "normal",
            "leaf_a",
            "leaf_b",
            "visits",
        ],
    );
    assert_eq!(v["contact"], json!(true));
    assert_eq!(v["point_b"], json!([1.0, 2.0, 3.25]));
    assert_eq!(form(&distance(false))["contact"], json!(false));
}

#[test]
fn a_contact_result_is_one_flat_record_with_nulls_when_apart() {
    let c = Contact {
        leaf_a: 3,
        leaf_b: 5,
        point: DVec3::X,
        normal: DVec3::Y,
        depth: 0.5,
    };
    let hit = ContactResult {
        contact: Some(c),
        distance: 0.0,
        visits: 12,
        skipped: false,
    };
    let v = form(&hit);
    let want = [
        "contact", "point", "normal", "depth", "leaf_a", "leaf_b", "distance", "visits", "skipped",
    ];
    keys_are(&v, want);
    assert_eq!(v["contact"], json!(true));
    assert_eq!(v["point"], json!([1.0, 0.0, 0.0]));
    assert_eq!(
        (v["leaf_a"].clone(), v["depth"].clone()),
        (json!(3), json!(0.5))
    );
    let apart = form(&ContactResult {
        contact: None,
        distance: 1.5,
        visits: 3,
        skipped: true,
    });
    keys_are(&apart, want);
    assert_eq!(apart["contact"], json!(false));
    for k in ["point", "normal", "depth", "leaf_a", "leaf_b"] {
        assert!(apart[k].is_null(), "{k}: {apart}");
    }
    assert_eq!(apart["distance"], json!(1.5));
}

#[test]
fn a_multipoint_and_a_penetration_say_contact_first() {
    let m = Multipoint {
        count: 2,
        reused: 1,
        distance: 0.0,
        visits: 80,
        skipped: false,
    };
    let v = form(&m);
    keys_are(
        &v,
        [
            "contact", "count", "reused", "distance", "visits", "skipped",
        ],
    );
    assert_eq!(v["contact"], json!(true));
    assert_eq!(form(&Multipoint { count: 0, ..m })["contact"], json!(false));

    let p = Penetration {
        volume: 0.125,
        pairs: 4,
        max_depth: 0.1,
        normal: DVec3::Z,
        force: DVec3::new(0.0, 0.0, 0.25),
        torque_a: DVec3::X,
        torque_b: DVec3::NEG_X,
        patch_count: 1,
        area: 0.0,
        stiffness: ContactStiffness {
            linear: DMat3::IDENTITY,
            ..Default::default()
        },
        distance: 0.0,
        visits: 99,
        skipped: false,
    };
    let v = form(&p);
    keys_are(
        &v,
        [
            "contact",
            "volume",
            "pairs",
            "max_depth",
            "normal",
            "force",
            "torque_a",
            "torque_b",
            "patch_count",
            "area",
            "stiffness",
            "distance",
            "visits",
            "skipped",
        ],
    );
    assert_eq!(v["contact"], json!(true));
    assert_eq!(v["torque_b"], json!([-1.0, 0.0, 0.0]));
    keys_are(&v["stiffness"], ["linear", "coupling", "angular"]);
    assert_eq!(
        form(&Penetration { pairs: 0, ..p })["contact"],
        json!(false)
    );
}

#[test]
fn a_refined_distance_names_its_triangles_and_nests_the_spheres() {
    let r = RefinedDistance {
        distance: 0.2,
        point_a: DVec3::ZERO,
        point_b: DVec3::Z,
        tri_a: 11,
        tri_b: u32::MAX,
        refined: true,
        intersecting: false,
        complete: true,
        radius: 0.3,
        node_pairs: 5,
        triangle_pairs: 6,
        spheres: distance(false),
    };
    let v = form(&r);
    keys_are(
        &v,
        [
            "distance",
            "point_a",
            "point_b",
            "triangle_a",
            "triangle_b",
            "refined",
            "contact",
            "complete",
            "radius",
            "node_pairs",
            "triangle_pairs",
            "spheres",
        ],
    );
    assert_eq!(v["triangle_a"], json!(11));
    assert!(v["triangle_b"].is_null());
    assert_eq!(v["spheres"], form(&distance(false)));
}

#[test]
fn a_budgeted_volume_and_a_patch_keep_their_field_names() {
    let w = BudgetedVolume {
        volume: 1.0,
        upper_bound: 2.0,
        visits: 3,
        complete: false,
        max_depth: 0.5,
        normal: DVec3::Z,
        force: DVec3::Z,
        torque_b: DVec3::X,
        area: 0.0,
        stiffness: ContactStiffness::default(),
    };
    keys_are(
        &form(&w),
        [
            "volume",
            "upper_bound",
            "visits",
            "complete",
            "max_depth",
            "normal",
            "force",
            "torque_b",
            "area",
            "stiffness",
        ],
    );
    let q = Patch {
        point: DVec3::X,
        normal: DVec3::Z,
        depth: 0.1,
        volume: 0.01,
        pairs: 3,
    };
    keys_are(&form(&q), ["point", "normal", "depth", "volume", "pairs"]);
}

#[test]
fn a_mesh_penetration_keeps_its_field_names() {
    keys_are(
        &form(&MeshPenetration::default()),
        [
            "contact",
            "volume",
            "normal",
            "force",
            "torque_a",
            "torque_b",
            "gradient",
            "rotation_gradient",
            "area",
            "max_depth",
            "patch_count",
            "stiffness",
            "crossing_pairs",
        ],
    );
}
