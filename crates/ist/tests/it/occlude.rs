//! `ist occlude` on generated arches and bodies the tests write themselves: "converged"
//! (exit 0) only at rest in contact, checked with the exact mesh distance; a distinct status
//! word and exit code otherwise (out of time 1, through A 4); refusals (exit 2) with the
//! limit named for what cannot make a bite (a force or stiffness out of range, an arch
//! against its own copy, a start far away or beside A, a spread beyond a bite search); and
//! `--free` accounting for every start.

use crate::support;
use support::{code, ist, s, stderr, stdout, TempDir};

use innersphere::exact::{self, ExactMesh, ExactScratch};
use innersphere::glam::DVec3;
use innersphere::{shapes, Mesh, Pose};
use serde_json::Value;
use std::path::Path;

/// `mesh` as an OBJ, written here.
fn write_obj(mesh: &Mesh, path: &Path) {
    let mut text = String::new();
    for v in &mesh.vertices {
        text += &format!("v {} {} {}\n", v.x, v.y, v.z);
    }
    for t in &mesh.triangles {
        text += &format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    std::fs::write(path, text).unwrap();
}

/// Writes `mesh` as `name.obj` and builds `name.ist` at `cells` voxels along its longest
/// side; the tree's path.
fn tree(dir: &TempDir, name: &str, mesh: &Mesh, cells: u32) -> String {
    let (obj, ist_path) = (
        dir.path(&format!("{name}.obj")),
        dir.path(&format!("{name}.ist")),
    );
    write_obj(mesh, &obj);
    let cells = cells.to_string();
    let out = ist(&[
        "build",
        s(&obj),
        "-o",
        s(&ist_path),
        "--resolution",
        &cells,
        "--quiet",
    ]);
    assert_eq!(code(&out), 0, "{}", stderr(&out));
    s(&ist_path).to_string()
}

/// Runs `ist occlude a b --from from extra…`, asserts exit code `want`; stdout and stderr.
fn occlude(a: &str, b: &str, from: &str, extra: &[&str], want: i32) -> (String, String) {
    let mut args = vec!["occlude", a, b, "--from", from];
    args.extend_from_slice(extra);
    let out = ist(&args);
    assert_eq!(
        code(&out),
        want,
        "ist {args:?}\nstdout: {}\nstderr: {}",
        stdout(&out),
        stderr(&out)
    );
    (stdout(&out), stderr(&out))
}

fn pose_of(v: &Value) -> Pose {
    let p: Vec<f64> = v["pose"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    Pose::from_array(p.try_into().unwrap()).unwrap()
}

#[test]
fn converged_means_at_rest_in_contact_and_every_other_end_has_its_word_and_code() {
    let dir = TempDir::new("ist-occlude", "statuses");
    let (upper, lower) = shapes::arch_pair(2, 8);
    let a = tree(&dir, "upper", &upper, 96);
    let b = tree(&dir, "lower", &lower, 96);
    // The arches' up is +z: B 2 mm open.
    let open = "0.2 -0.2 -2 1 0 0 0";
    // Converged (exit 0): at rest, and in contact by the exact meshes.
    let (out, _) = occlude(&a, &b, open, &["--json"], 0);
    let v: Value = serde_json::from_str(&out).unwrap();
    assert_eq!(
        (v["status"].as_str(), v["converged"].as_bool()),
        (Some("converged"), Some(true))
    );
    assert!(v["closings"].is_null() && v["candidates"].is_null(), "{v}");
    let (ea, eb) = (
        ExactMesh::new(&upper).unwrap(),
        ExactMesh::new(&lower).unwrap(),
    );
    let d = exact::distance(
        &ea,
        &Pose::IDENTITY,
        &eb,
        &pose_of(&v),
        &mut ExactScratch::new(),
    );
    assert!(d.intersecting, "{} mm apart", d.distance);
    // The human text leads with the same word.
    let (out, _) = occlude(&a, &b, open, &[], 0);
    assert!(out.starts_with("converged after"), "{out}");
    // Out of time (exit 1): still moving, 2 mm open.
    let (out, _) = occlude(&a, &b, open, &["--max-seconds", "0.05", "--json"], 1);
    let v: Value = serde_json::from_str(&out).unwrap();
    assert_eq!(
        (v["status"].as_str(), v["converged"].as_bool()),
        (Some("time_limit"), Some(false))
    );
    let d = exact::distance(
        &ea,
        &Pose::IDENTITY,
        &eb,
        &pose_of(&v),
        &mut ExactScratch::new(),
    );
    assert!(d.distance > 0.3, "{} mm apart", d.distance);
    let (out, _) = occlude(&a, &b, open, &["--max-seconds", "0.05"], 1);
    assert!(out.starts_with("time_limit after 50 steps"), "{out}");
    // Free: every start accounted for, in the JSON and the text.
    let free = ["--free", "--starts", "6", "--spread", "1"];
    let (out, _) = occlude(&a, &b, open, &[&free[..], &["--json"]].concat(), 0);
    let v: Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["status"], "converged");
    let closings = v["closings"].as_object().unwrap();
    let words = [
        "converged",
        "no_contact",
        "time_limit",
        "passed_through",
        "escaped",
    ];
    assert_eq!(
        closings.keys().collect::<Vec<_>>().len(),
        words.len(),
        "{v}"
    );
    let total: u64 = words.iter().map(|w| closings[*w].as_u64().unwrap()).sum();
    assert_eq!(total, 6, "{v}");
    let in_candidates: u64 = v["candidates"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["starts"].as_u64().unwrap())
        .sum();
    assert_eq!(in_candidates, closings["converged"].as_u64().unwrap());
    let (out, _) = occlude(&a, &b, open, &free, 0);
    assert!(out.contains("starts: 6 ("), "{out}");
    // --help names every status with its exit code.
    let help = stdout(&ist(&["occlude", "--help"]));
    for (word, code) in [
        ("converged", 0),
        ("time_limit", 1),
        ("no_contact", 3),
        ("passed_through", 4),
        ("escaped", 5),
    ] {
        let line = help.lines().find(|l| l.trim_start().starts_with(word));
        let line = line.unwrap_or_else(|| panic!("{word} not in --help:\n{help}"));
        assert!(line.contains(&format!(" {code} ")), "{line}");
    }
}

/// The repros of the planning tools' review: each was "converged" (exit 0), or a message
/// about non-finite dynamics; each is refused now (exit 2) with the limit named.
#[test]
fn what_cannot_make_a_bite_is_refused_with_the_limit_named() {
    let dir = TempDir::new("ist-occlude", "refused");
    let (upper, lower) = shapes::arch_pair(2, 8);
    let a = tree(&dir, "upper", &upper, 96);
    let b = tree(&dir, "lower", &lower, 96);
    let open = "0.2 -0.2 -2 1 0 0 0";
    let free = ["--free", "--starts", "4"];
    let cases: Vec<(&str, &str, &str, Vec<&str>, &str)> = vec![
        // 3 mm open and "converged" at 0.001 N; through A and 261 mm away at 2000 N.
        (
            &a,
            &b,
            open,
            vec!["--force", "0.001"],
            "the closing force must be 0.5 to 1000 N",
        ),
        (
            &a,
            &b,
            open,
            vec!["--force", "2000"],
            "the closing force must be 0.5 to 1000 N",
        ),
        (
            &a,
            &b,
            open,
            vec!["--force", "100"],
            "more than the 2 mm³ the contact holds",
        ),
        (
            &a,
            &b,
            open,
            vec!["--force", "1e300"],
            "the closing force must be 0.5 to 1000 N",
        ),
        (
            &a,
            &b,
            open,
            vec!["--contact-stiffness", "1e300"],
            "at most 100000 N/mm³",
        ),
        (
            &a,
            &b,
            open,
            vec!["--joint-stiffness", "1e300"],
            "0 to 10000 N/mm",
        ),
        (
            &a,
            &b,
            open,
            vec!["--max-seconds", "1e7"],
            "the time limit must be",
        ),
        // An arch against its own copy: "converged" 38 mm away.
        (
            &a,
            &a,
            open,
            vec![],
            "the two arches do not face each other",
        ),
        (
            &a,
            &a,
            open,
            free.to_vec(),
            "Is B the lower arch, and is it in A's frame?",
        ),
        // Far, beside, turned over, beyond.
        (
            &a,
            &b,
            "0 0 -1e15 1 0 0 0",
            vec![],
            "a bite closes from at most 30 mm open",
        ),
        (
            &a,
            &b,
            "0 0 -40 1 0 0 0",
            free.to_vec(),
            "a bite closes from at most 30 mm open",
        ),
        (
            &a,
            &b,
            "60 0 -3 1 0 0 0",
            vec![],
            "the arches lie side by side",
        ),
        (
            &a,
            &b,
            "0 0 -2 0 1 0 0",
            vec![],
            "turns B 180° from A's frame",
        ),
        (
            &a,
            &b,
            "0 0 20 1 0 0 0",
            vec![],
            "beyond A's along the closing axis",
        ),
        (
            &a,
            &b,
            open,
            vec!["--reference", "1e300 0 0 1 0 0 0"],
            "the reference pose",
        ),
        // A search far beyond a bite's: 9 of 10 starts used to be dropped silently.
        (
            &a,
            &b,
            open,
            [&free[..], &["--spread", "1000"]].concat(),
            "the spread must be at most 10 mm",
        ),
        (
            &a,
            &b,
            open,
            vec!["--free", "--starts", "5000"],
            "the starts must be 1 to 1000",
        ),
    ];
    for (a, b, from, extra, want) in cases {
        let (_, e) = occlude(a, b, from, &extra, 2);
        assert!(e.contains(want), "{from} {extra:?}: {e}");
        assert!(!e.contains("non-finite"), "{e}");
    }
}

/// A needle closed onto a foil within every limit (20 N on 10 N/mm³: 2 mm³ at rest, where
/// the two overlap by 0.4 mm³ at most): it goes through, and says so (exit 4), stopped at
/// once on the far side.
#[test]
fn a_needle_through_a_foil_is_passed_through_with_its_exit_code() {
    let dir = TempDir::new("ist-occlude", "needle");
    let foil = tree(
        &dir,
        "foil",
        &shapes::cuboid(DVec3::new(10.0, 10.0, 0.25)),
        128,
    );
    let mut needle = shapes::ellipsoid(DVec3::new(0.5, 0.5, 5.0), 3);
    for v in &mut needle.vertices {
        v.z -= 5.5;
    }
    let needle = tree(&dir, "needle", &needle, 48);
    let args = [
        "--free",
        "--starts",
        "1",
        "--force",
        "20",
        "--contact-stiffness",
        "10",
        "--json",
    ];
    let (out, _) = occlude(&foil, &needle, "0 0 0 1 0 0 0", &args, 4);
    let v: Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["status"], "passed_through", "{v}");
    assert_eq!(v["converged"], false);
    assert_eq!(v["closings"]["passed_through"], 1, "{v}");
    assert!(v["candidates"].as_array().unwrap().is_empty());
    // The needle's centre (5.5 mm below its model origin) just past the foil's.
    let centre = pose_of(&v).transform_point(DVec3::new(0.0, 0.0, -5.5));
    assert!(centre.z > 0.0 && centre.z < 0.1, "{centre}");
    let (out, _) = occlude(&foil, &needle, "0 0 0 1 0 0 0", &args[..7], 4);
    assert!(out.starts_with("passed_through after"), "{out}");
    assert!(
        out.contains("starts: 1 (1 passed_through); candidates: 0"),
        "{out}"
    );
}

/// Options that cannot make a bite are refused before the bodies are read or built: on the
/// real jaws `--force 2000` was refused only after both trees were built (3.3 s). Here the
/// bodies do not even exist, and the message names the option, not a missing file.
#[test]
fn options_are_refused_before_the_bodies_are_loaded() {
    let dir = TempDir::new("occlude", "options-first");
    let (a, b) = (dir.path("missing_a.stl"), dir.path("missing_b.stl"));
    for (extra, says) in [
        (&["--force", "2000"][..], "the closing force must be"),
        (
            &["--free", "--spread", "1000"][..],
            "the spread must be at most",
        ),
    ] {
        let (_, err) = occlude(s(&a), s(&b), "0 0 -3 1 0 0 0", extra, 2);
        assert!(err.contains(says) && !err.contains("missing_a"), "{err}");
    }
}
