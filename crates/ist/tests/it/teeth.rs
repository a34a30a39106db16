//! Teeth-axes files at every door that takes them (`occlusion-map --teeth-a/--teeth-b`,
//! `occlude --landmarks`; `view --teeth-a/-b` goes through the same library check,
//! `innersphere_view::Scene::check_teeth`): bounded reading (`/dev/zero`, a sparse 100 MB
//! file) and the same refusals with the same messages, on the generated arch pair and teeth
//! files made from its tooth placement.

use crate::support;
use support::{code, ist, s, stderr, stdout, TempDir};

use innersphere::shapes;
use innersphere_dental::contact_map::Teeth;
use std::path::{Path, PathBuf};

struct Arches {
    dir: TempDir,
    upper: PathBuf,
    lower: PathBuf,
    teeth_upper: PathBuf,
    teeth_lower: PathBuf,
}

fn arches(name: &str) -> Arches {
    let dir = TempDir::new("ist-teeth", name);
    let (upper, lower) = shapes::arch_pair(1, 10);
    let (tu, tl) = Teeth::of_arch_pair(10);
    let a = Arches {
        upper: dir.path("upper.stl"),
        lower: dir.path("lower.stl"),
        teeth_upper: dir.path("upper.json"),
        teeth_lower: dir.path("lower.json"),
        dir,
    };
    innersphere::mesh::save_stl(&upper, &a.upper).unwrap();
    innersphere::mesh::save_stl(&lower, &a.lower).unwrap();
    std::fs::write(&a.teeth_upper, tu.to_json()).unwrap();
    std::fs::write(&a.teeth_lower, tl.to_json()).unwrap();
    a
}

/// Runs `ist args`, asserts exit code 2 and returns stderr.
fn refused(args: &[&str]) -> String {
    let out = ist(args);
    let err = stderr(&out);
    assert_eq!(
        code(&out),
        2,
        "ist {args:?}\nstdout: {}\nstderr: {err}",
        stdout(&out)
    );
    assert!(err.starts_with("error: "), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    err
}

fn sparse(path: &Path, bytes: u64) {
    std::fs::File::create(path).unwrap().set_len(bytes).unwrap();
}

#[test]
fn occlusion_map_reads_teeth_bounded_and_refuses_what_does_not_fit() {
    let w = arches("map");
    let map = |ta: &Path, tb: &Path| -> Vec<String> {
        [
            "occlusion-map",
            s(&w.upper),
            s(&w.lower),
            "--teeth-a",
            s(ta),
            "--teeth-b",
            s(tb),
        ]
        .map(String::from)
        .to_vec()
    };
    let run = |args: Vec<String>| refused(&args.iter().map(String::as_str).collect::<Vec<_>>());

    // The arches' own files: every tooth listed with all its vertices (42 at this size).
    let mut args = map(&w.teeth_upper, &w.teeth_lower);
    args.push("--json".into());
    let out = ist(&args.iter().map(String::as_str).collect::<Vec<_>>());
    assert_eq!(code(&out), 0, "{}", stderr(&out));
    assert!(!stderr(&out).contains("warning"), "{}", stderr(&out));
    let r: serde_json::Value = serde_json::from_str(&stdout(&out)).unwrap();
    for (k, first) in [("a", 4), ("b", 20)] {
        let teeth = r[k]["teeth"].as_array().unwrap();
        assert_eq!(teeth.len(), 10, "{r}");
        assert_eq!(teeth[0]["tooth"], first, "{r}");
        assert!(
            teeth.iter().all(|t| t["vertices"].as_u64().unwrap() == 42),
            "{r}"
        );
    }

    // Bounded: a device, and a sparse 100 MB file refused unread; the limit named.
    for dev in ["/dev/zero", "/dev/urandom"] {
        if Path::new(dev).exists() {
            let e = run(map(&w.teeth_upper, Path::new(dev)));
            assert!(
                e.contains(dev) && e.contains("1048576 bytes (1 MiB)"),
                "{e}"
            );
        }
    }
    let big = w.dir.path("big.json");
    sparse(&big, 100 << 20);
    let e = run(map(&big, &w.teeth_lower));
    assert!(
        e.contains("the file has 104857600 bytes, more than the 1048576-byte (1 MiB) limit for a teeth-axes JSON file"),
        "{e}"
    );

    // A key twice.
    let dup = w.dir.path("dup.json");
    let text = std::fs::read_to_string(&w.teeth_lower).unwrap();
    std::fs::write(&dup, text.replacen('{', r#"{"25": {"c": [0, 0, 0]}, "#, 1)).unwrap();
    let e = run(map(&w.teeth_upper, &dup));
    assert!(e.contains("the key \"25\" appears twice"), "{e}");

    // The other arch's files, swapped; one arch twice; both arches in one file.
    let e = run(map(&w.teeth_lower, &w.teeth_upper));
    assert!(
        e.contains("this looks like the other arch's teeth file"),
        "{e}"
    );
    let e = run(map(&w.teeth_upper, &w.teeth_upper));
    assert!(e.contains("need one upper and one lower teeth file"), "{e}");
    let mixed = w.dir.path("mixed.json");
    let upper_text = std::fs::read_to_string(&w.teeth_upper).unwrap();
    std::fs::write(
        &mixed,
        text.replacen('{', &format!("{},", &upper_text[..upper_text.len() - 1]), 1),
    )
    .unwrap();
    let e = run(map(&w.teeth_upper, &mixed));
    assert!(e.contains("mixes upper teeth (1–16: 4, 5"), "{e}");

    // In metres for meshes in millimetres.
    let (_, tl) = Teeth::of_arch_pair(10);
    let metres = w.dir.path("metres.json");
    std::fs::write(&metres, tl.scaled(0.001).unwrap().to_json()).unwrap();
    let e = run(map(&w.teeth_upper, &metres));
    assert!(e.contains("likely in metres"), "{e}");
}

#[test]
fn occlude_landmarks_go_through_the_same_reader_and_checks() {
    let w = arches("occlude");
    let (ta, tb) = (w.dir.path("upper.ist"), w.dir.path("lower.ist"));
    for (m, t) in [(&w.upper, &ta), (&w.lower, &tb)] {
        let out = ist(&["build", s(m), "-o", s(t), "--resolution", "48", "--quiet"]);
        assert_eq!(code(&out), 0, "{}", stderr(&out));
    }
    let occlude = |landmarks: &Path| -> Vec<String> {
        [
            "occlude",
            s(&ta),
            s(&tb),
            "--from",
            "0 0 -1 1 0 0 0",
            "--max-seconds",
            "0.05",
            "--landmarks",
            s(landmarks),
            "--json",
        ]
        .map(String::from)
        .to_vec()
    };
    let run = |args: Vec<String>| refused(&args.iter().map(String::as_str).collect::<Vec<_>>());
    // B's own file: landmarks named by tooth, plus the incisal point.
    let args = occlude(&w.teeth_lower);
    let out = ist(&args.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(code(&out) == 0 || code(&out) == 1, "{}", stderr(&out));
    let v: serde_json::Value = serde_json::from_str(&stdout(&out)).unwrap();
    let names: Vec<&str> = v["landmark_errors"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| e["landmark"].as_str().unwrap())
        .collect();
    assert_eq!(names.len(), 11, "{names:?}");
    assert_eq!(names[0], "incisal");
    assert!(
        names.contains(&"tooth 20") && names.contains(&"tooth 29"),
        "{names:?}"
    );

    // The refusals of occlusion-map, with its messages.
    for dev in ["/dev/zero", "/dev/urandom"] {
        if Path::new(dev).exists() {
            let e = run(occlude(Path::new(dev)));
            assert!(e.contains("1048576 bytes (1 MiB)"), "{e}");
        }
    }
    let big = w.dir.path("big.json");
    sparse(&big, 100 << 20);
    let e = run(occlude(&big));
    assert!(e.contains("refused unread"), "{e}");
    let keyed = w.dir.path("keys.json");
    std::fs::write(&keyed, r#"{"incisal": {"c": [0, 40, 1]}}"#).unwrap();
    let e = run(occlude(&keyed));
    assert!(e.contains("\"incisal\" is no tooth number"), "{e}");
    // The other arch's file: the trees' own meshes (their recorded source) tell.
    let e = run(occlude(&w.teeth_upper));
    assert!(
        e.contains("this looks like the other arch's teeth file"),
        "{e}"
    );
}
