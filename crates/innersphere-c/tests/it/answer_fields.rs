//! The C result structs against the answers' serialized form, the field list every other door
//! prints (`ist query --json`, Python's dicts, the viewer): each field of a C struct in the
//! committed header is a key of its answer's serde form under the same name, or one of the
//! few C spellings listed here; each key the struct leaves out is listed as left out. A field
//! added to an answer fails here until C carries it or it is listed.

use innersphere::glam::DVec3;
use innersphere::{shapes, BuildOptions, Pair, Pose, Resolution, SharedTree, SphereTree};
use serde_json::Value;
use std::collections::BTreeSet;

/// The field names of `typedef struct NAME { … } NAME;` in the committed header.
fn header_fields(name: &str) -> Vec<String> {
    let header = include_str!("../../../../include/innersphere.h");
    let start = header
        .find(&format!("typedef struct {name} {{"))
        .unwrap_or_else(|| panic!("{name} is not in the header"));
    let body = &header[start..];
    let body = &body[..body.find(&format!("}} {name};")).expect("the struct ends")];
    let mut fields = Vec::new();
    let mut in_comment = false;
    for line in body.lines().skip(1) {
        let line = line.trim();
        if line.starts_with("/*") {
            in_comment = true;
        }
        if in_comment {
            in_comment = !line.ends_with("*/");
            continue;
        }
        if let Some(decl) = line.strip_suffix(';') {
            let last = decl.split_whitespace().last().expect("a declaration");
            fields.push(last.split('[').next().unwrap().to_string());
        }
    }
    fields
}

/// The keys of an answer's serde form.
fn keys<T: serde::Serialize>(answer: &T) -> BTreeSet<String> {
    match serde_json::to_value(answer).expect("answers serialize") {
        Value::Object(m) => m.keys().cloned().collect(),
        other => panic!("an answer is a record, not {other}"),
    }
}

/// Fails unless the C struct `c` spells the answer's keys `keys`: each C field a key or a
/// listed C spelling (`renamed`: C name → serialized key), each key a field or `left_out`.
fn assert_spells(c: &str, keys: &BTreeSet<String>, renamed: &[(&str, &str)], left_out: &[&str]) {
    let fields = header_fields(c);
    let mut covered = BTreeSet::new();
    for f in &fields {
        let key = renamed
            .iter()
            .find(|(cn, _)| cn == f)
            .map_or(f.as_str(), |(_, k)| k);
        assert!(
            keys.contains(key),
            "{c}.{f} is no key of its answer's serialized form {keys:?}"
        );
        covered.insert(key.to_string());
    }
    for k in keys {
        assert!(
            covered.contains(k) || left_out.contains(&k.as_str()),
            "{c} neither carries nor lists as left out the answer's `{k}`: add it to the C \
             struct (and the header) or to this test's list of keys C leaves out"
        );
    }
    for k in left_out {
        assert!(
            keys.contains(*k),
            "{c}: `{k}` is listed as left out but is no key"
        );
        assert!(
            !covered.contains(*k),
            "{c}: `{k}` is listed as left out but C carries it"
        );
    }
}

#[test]
fn every_c_result_struct_spells_its_answers_serialized_form() {
    let opts = BuildOptions {
        resolution: Resolution::Cells(16),
        ..Default::default()
    };
    let a = SphereTree::build(&shapes::cuboid(DVec3::new(3.0, 3.0, 0.5)), &opts).unwrap();
    let b = SphereTree::build(&shapes::icosphere(2), &opts).unwrap();
    let mut pair = Pair::new(a, b);
    let id = Pose::IDENTITY;
    let touching = Pose {
        translation: DVec3::new(0.0, 0.0, 1.2),
        ..Pose::IDENTITY
    };
    let d = pair.distance(&id, &touching);
    assert_spells(
        "ist_distance_result",
        &keys(&d),
        &[],
        &[
            "pair_distance",
            "lower_bound",
            "normal",
            "leaf_a",
            "leaf_b",
            "visits",
        ],
    );
    let p = pair.penetration(&id, &touching);
    assert!(p.pairs > 0, "the bodies touch");
    assert_spells(
        "ist_penetration_result",
        &keys(&p),
        &[],
        &[
            "contact",
            "pairs",
            "area",
            "stiffness",
            "distance",
            "visits",
            "skipped",
        ],
    );
    assert_spells("ist_patch", &keys(&pair.patches()[0]), &[], &[]);
    let w = pair.penetration_within(&id, &touching, 100);
    assert_spells(
        "ist_budgeted_result",
        &keys(&w),
        &[],
        &["area", "stiffness"],
    );
    pair.multipoint(&id, &touching, &Default::default());
    assert_spells("ist_contact_point", &keys(&pair.contacts()[0]), &[], &[]);
}

#[test]
fn the_mesh_answers_structs_spell_their_serialized_forms() {
    let opts = BuildOptions {
        resolution: Resolution::Cells(16),
        ..Default::default()
    };
    let (ma, mb) = (
        shapes::cuboid(DVec3::new(3.0, 3.0, 0.5)),
        shapes::icosphere(2),
    );
    let a = SharedTree::new(SphereTree::build(&ma, &opts).unwrap());
    let b = SharedTree::new(SphereTree::build(&mb, &opts).unwrap());
    let (a, b) = (a.with_mesh(&ma).unwrap(), b.with_mesh(&mb).unwrap());
    let apart = Pose {
        translation: DVec3::new(0.0, 0.0, 2.0),
        ..Pose::IDENTITY
    };
    let mut pair = Pair::new(a, b);
    let r = pair.refined_distance(&Pose::IDENTITY, &apart).unwrap();
    let touching = Pose {
        translation: DVec3::new(0.0, 0.0, 1.2),
        ..Pose::IDENTITY
    };
    let m = pair
        .mesh_penetration_with(&Pose::IDENTITY, &touching, &Default::default())
        .unwrap();
    assert!(m.contact, "the meshes overlap");
    assert_spells(
        "ist_mesh_penetration_result",
        &keys(&m),
        &[],
        &[
            "gradient",
            "rotation_gradient",
            "crossing_pairs",
            "stiffness",
        ],
    );
    let mut k = keys(&r);
    // C flattens the nested sphere distance to the one number it carries.
    k.insert("spheres.distance".into());
    assert_spells(
        "ist_refined_distance_result",
        &k,
        &[
            ("tri_a", "triangle_a"),
            ("tri_b", "triangle_b"),
            ("sphere_distance", "spheres.distance"),
        ],
        &["radius", "node_pairs", "triangle_pairs", "spheres"],
    );
}
