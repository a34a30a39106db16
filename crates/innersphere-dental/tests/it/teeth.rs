//! Teeth-axes files against the arches they label (`contact_map::Teeth`,
//! `docs/OCCLUSION.md`): the generated arch pair with teeth files made from its tooth
//! placement (`Teeth::of_arch_pair`), written to files and read back through the one
//! reader; and the real jaw pair's own files (`#[ignore]`d: CI's `--ignored` pass).

use innersphere::glam::DVec3;
use innersphere::{shapes, Error, Mesh, Pose};
use innersphere_dental::contact_map::{check_pair, ArchContext, Jaw, Teeth};
use innersphere_testkit::data;
use std::path::{Path, PathBuf};

fn tmp(name: &str) -> PathBuf {
    Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("teeth_{}_{name}", std::process::id()))
}

/// `text` written to a file and loaded through [`Teeth::load`].
fn load(name: &str, text: &str) -> innersphere::Result<Teeth> {
    let p = tmp(name);
    std::fs::write(&p, text).unwrap();
    let r = Teeth::load(&p);
    std::fs::remove_file(&p).ok();
    r
}

fn refusal<T: std::fmt::Debug>(r: innersphere::Result<T>) -> String {
    match r {
        Err(e @ Error::Input { .. }) => e.to_string(),
        other => panic!("expected a refusal, got {other:?}"),
    }
}

#[test]
fn generated_arches_and_their_files() {
    let (upper, lower) = shapes::arch_pair(1, 12);
    let (tu, tl) = Teeth::of_arch_pair(12);
    assert_eq!(tu.teeth.first().unwrap().number, 3);
    assert_eq!(tl.teeth.last().unwrap().number, 30);
    let (tu, tl) = (
        load("upper.json", &tu.to_json()).unwrap(),
        load("lower.json", &tl.to_json()).unwrap(),
    );
    let (fu, fl) = check_pair(&upper, Some(&tu), &lower, Some(&tl), &Pose::IDENTITY).unwrap();
    for (f, n) in [
        (fu.unwrap(), upper.vertices.len()),
        (fl.unwrap(), lower.vertices.len()),
    ] {
        assert!(f.warnings.is_empty(), "{:?}", f.warnings);
        // Every crown is labelled: each tooth has about its share of the vertices.
        for &c in &f.vertices {
            assert!(c * 12 > n / 2, "{:?} of {n}", f.vertices);
        }
    }

    // A key given twice: the last one would have won silently.
    let mut text = tl.to_json();
    text.insert_str(1, r#""21": {"c": [0, 0, 0]},"#);
    let e = refusal(load("dup.json", &text));
    assert!(e.contains("the key \"21\" appears twice"), "{e}");

    // The other arch's file, swapped or twice.
    let e = refusal(check_pair(
        &upper,
        Some(&tl),
        &lower,
        Some(&tu),
        &Pose::IDENTITY,
    ));
    assert!(e.contains("lie inside the opposing arch"), "{e}");
    let e = refusal(check_pair(&upper, None, &lower, Some(&tu), &Pose::IDENTITY));
    assert!(
        e.contains("this looks like the other arch's teeth file"),
        "{e}"
    );
    let e = refusal(check_pair(
        &upper,
        Some(&tu),
        &lower,
        Some(&tu),
        &Pose::IDENTITY,
    ));
    assert!(e.contains("need one upper and one lower teeth file"), "{e}");

    // In metres for a mesh in millimetres.
    let metres = load("m.json", &tl.scaled(0.001).unwrap().to_json()).unwrap();
    let e = refusal(check_pair(
        &upper,
        None,
        &lower,
        Some(&metres),
        &Pose::IDENTITY,
    ));
    assert!(e.contains("likely in metres"), "{e}");

    // Both arches in one file.
    let mut mixed = tl.clone();
    mixed.teeth.push(tu.teeth[0]);
    let mixed = load("mixed.json", &mixed.to_json()).unwrap();
    let e = refusal(check_pair(
        &upper,
        None,
        &lower,
        Some(&mixed),
        &Pose::IDENTITY,
    ));
    assert!(
        e.contains("mixes upper teeth (1–16: 3) and lower teeth"),
        "{e}"
    );
}

/// The pose at which B is checked is B's pose in A's frame: B moved away and its teeth with
/// it still fit; the other arch's file found where B is.
#[test]
fn the_opposing_arch_is_where_the_pose_puts_it() {
    let (upper, lower) = shapes::arch_pair(1, 10);
    let (tu, tl) = Teeth::of_arch_pair(10);
    let pose = Pose::new(
        DVec3::new(3.0, -40.0, 20.0),
        innersphere::glam::DQuat::from_rotation_z(0.7),
    )
    .unwrap();
    // B's mesh and teeth in B's own frame: the inverse pose of the bite.
    let inv = pose.inverse();
    let moved = Mesh {
        vertices: lower
            .vertices
            .iter()
            .map(|v| inv.transform_point(*v))
            .collect(),
        triangles: lower.triangles.clone(),
    };
    let mut tl_moved = tl.clone();
    for t in &mut tl_moved.teeth {
        t.centre = inv.transform_point(t.centre);
    }
    let mut tu_moved = tu.clone();
    for t in &mut tu_moved.teeth {
        t.centre = inv.transform_point(t.centre);
    }
    check_pair(&upper, Some(&tu), &moved, Some(&tl_moved), &pose).unwrap();
    let e = refusal(check_pair(&upper, None, &moved, Some(&tu_moved), &pose));
    assert!(
        e.contains("this looks like the other arch's teeth file"),
        "{e}"
    );
    // A known arch.
    let e = refusal(tu.check_against(&ArchContext {
        arch: &lower,
        opposing: None,
        jaw: Some(Jaw::Lower),
    }));
    assert!(
        e.contains("holds upper teeth (1–16), but the arch it is given for is the lower one"),
        "{e}"
    );
}

fn real() -> (Mesh, Mesh, Teeth, Teeth) {
    let mesh = |f: &str| Mesh::load(data(&format!("jaw/ofj_p26_{f}_teeth.stl.gz"))).unwrap();
    let teeth = |f: &str| Teeth::load(&data(&format!("jaw/ofj_p26_teeth_axes_{f}.json"))).unwrap();
    (
        mesh("maxilla"),
        mesh("mandible"),
        teeth("maxilla"),
        teeth("mandible"),
    )
}

#[test]
#[ignore = "real data: CI runs it with --ignored"]
fn the_real_teeth_files_fit_their_arches_and_only_theirs() {
    let (maxilla, mandible, upper, lower) = real();
    assert_eq!((upper.teeth.len(), lower.teeth.len()), (15, 14));
    let t = std::time::Instant::now();
    let (fu, fl) = check_pair(
        &maxilla,
        Some(&upper),
        &mandible,
        Some(&lower),
        &Pose::IDENTITY,
    )
    .unwrap();
    eprintln!(
        "both real files checked in {:.3} s",
        t.elapsed().as_secs_f64()
    );
    let (fu, fl) = (fu.unwrap(), fl.unwrap());
    assert_eq!((fu.jaw, fl.jaw), (Jaw::Upper, Jaw::Lower));
    assert!(fu.warnings.is_empty() && fl.warnings.is_empty());
    assert!(fu.vertices.iter().chain(&fl.vertices).all(|&c| c > 1000));
    // The regions are what the per-tooth list used before the checks.
    assert_eq!(fu.regions, upper.regions(&maxilla.vertices));
    assert_eq!(fl.regions, lower.regions(&mandible.vertices));

    for (what, r) in [
        (
            "swapped",
            check_pair(
                &maxilla,
                Some(&lower),
                &mandible,
                Some(&upper),
                &Pose::IDENTITY,
            ),
        ),
        (
            "upper for B",
            check_pair(&maxilla, None, &mandible, Some(&upper), &Pose::IDENTITY),
        ),
        (
            "lower for A",
            check_pair(&maxilla, Some(&lower), &mandible, None, &Pose::IDENTITY),
        ),
    ] {
        let e = refusal(r);
        eprintln!("{what}: {e}");
        assert!(
            e.contains("this looks like the other arch's teeth file"),
            "{what}: {e}"
        );
    }
    for (factor, unit) in [
        (0.001, "metres"),
        (0.1, "centimetres"),
        (1.0 / 25.4, "inches"),
    ] {
        let e = refusal(check_pair(
            &maxilla,
            Some(&upper.scaled(factor).unwrap()),
            &mandible,
            None,
            &Pose::IDENTITY,
        ));
        eprintln!("{unit}: {e}");
        assert!(e.contains(&format!("likely in {unit}")), "{e}");
    }
}
