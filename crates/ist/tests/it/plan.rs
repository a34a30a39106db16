//! `ist plan` on generated arches: from the scans to the wafers and the report, the same
//! bytes run after run (the report's "Made" line aside), the same plan from scans in metres,
//! and an output folder that is the plan's own.

use crate::support;
use support::{code, ist, s, stderr, stdout, TempDir};

use innersphere::mesh::Unit;
use innersphere::{shapes, Mesh};
use innersphere_dental::contact_map::Teeth;
use std::path::Path;

/// Every file of `dir` by name, with the report's "Made" line taken out.
fn outputs(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut files: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| {
            let e = e.unwrap();
            let name = e.file_name().to_string_lossy().into_owned();
            let mut bytes = std::fs::read(e.path()).unwrap();
            if name == "report.html" {
                let text = String::from_utf8(bytes).unwrap();
                bytes = text
                    .lines()
                    .filter(|l| !l.starts_with("<p>Made "))
                    .collect::<Vec<_>>()
                    .join("\n")
                    .into_bytes();
            }
            (name, bytes)
        })
        .collect();
    files.sort();
    files
}

fn json(out: &std::process::Output) -> serde_json::Value {
    serde_json::from_str(&stdout(out)).unwrap_or_else(|e| panic!("{e}: {}", stderr(out)))
}

#[test]
fn a_case_from_scans_to_wafers_the_same_run_after_run_and_in_metres() {
    let dir = TempDir::new("ist-plan", "case");
    let (upper, lower) = shapes::arch_pair(2, 10);
    let (tu, tl) = Teeth::of_arch_pair(10);
    // The scans in metres (OBJ keeps every digit), and the same read in mm written again.
    let metres = |m: &Mesh| Mesh {
        vertices: m.vertices.iter().map(|v| *v * 1e-3).collect(),
        triangles: m.triangles.clone(),
    };
    for (m, name) in [(&upper, "upper"), (&lower, "lower")] {
        let path_m = dir.path(&format!("{name}_m.obj"));
        innersphere::mesh::save(&metres(m), &path_m).unwrap();
        let in_mm = Mesh::load_in(&path_m, Unit::M).unwrap();
        innersphere::mesh::save(&in_mm, &dir.path(&format!("{name}.obj"))).unwrap();
    }
    std::fs::write(dir.path("upper.json"), tu.to_json()).unwrap();
    std::fs::write(dir.path("lower.json"), tl.to_json()).unwrap();
    std::fs::write(dir.path("upper_m.json"), tu.scaled(1e-3).unwrap().to_json()).unwrap();
    std::fs::write(dir.path("lower_m.json"), tl.scaled(1e-3).unwrap().to_json()).unwrap();
    let case = |suffix: &str, unit: &str| {
        format!(
            r#"{{"version": 1, "upper": "upper{suffix}.obj", "lower": "lower{suffix}.obj", "unit": "{unit}",
                "teeth_upper": "upper{suffix}.json", "teeth_lower": "lower{suffix}.json",
                "bite": {{"method": "joints"}},
                "splints": [{{"name": "final", "open": "auto"}}, {{"name": "intermediate", "open": 3, "voxel": 0.2}}]}}"#
        )
    };
    std::fs::write(dir.path("case.json"), case("", "mm")).unwrap();
    std::fs::write(dir.path("case_m.json"), case("_m", "m")).unwrap();

    let run = |case: &str, out: &str| {
        let o = ist(&[
            "plan",
            s(&dir.path(case)),
            "-o",
            s(&dir.path(out)),
            "--json",
        ]);
        assert_eq!(code(&o), 0, "{}", stderr(&o));
        json(&o)
    };
    let first = run("case.json", "out1");
    let again = run("case.json", "out2");
    let in_m = run("case_m.json", "out_m");

    // The plan: a bite on the joints near the scanned one (the generated pair interlocks at
    // the identity), a contact map per tooth, two wafers fit for a lab.
    let bite = &first["bite"];
    assert_eq!(bite["status"], "converged");
    let pose: Vec<f64> = serde_json::from_value(bite["pose"].clone()).unwrap();
    assert!(pose[..3].iter().all(|x| x.abs() < 0.5), "{pose:?}");
    for arch in ["upper", "lower"] {
        let m = &first["map"][arch];
        assert_eq!(m["teeth"].as_array().unwrap().len(), 10, "{m}");
        assert_eq!(m["regions"].as_array().unwrap().len(), 5);
        let share = m["balance"]["left_share"].as_f64().unwrap();
        assert!((0.3..0.7).contains(&share), "a symmetric pair: {share}");
    }
    let splints = first["splints"].as_array().unwrap();
    assert_eq!(splints.len(), 2);
    for w in splints {
        let r = &w["report"];
        assert_eq!(r["fit"], true, "{r}");
        assert!(r["triangles"].as_u64().unwrap() <= 300_000);
        assert_eq!(r["self_intersections"], 0);
        assert!(dir
            .path(&format!("out1/{}", w["file"].as_str().unwrap()))
            .is_file());
    }
    // The final wafer was simplified (the surface nets gave more than the cap).
    assert!(
        splints[0]["report"]["extracted_triangles"]
            .as_u64()
            .unwrap()
            > 300_000
    );
    assert!(first["fit"].as_bool().unwrap());

    // The same bytes run after run, and from the scans in metres.
    let (o1, o2, om) = (
        outputs(&dir.path("out1")),
        outputs(&dir.path("out2")),
        outputs(&dir.path("out_m")),
    );
    let names: Vec<&str> = o1.iter().map(|f| f.0.as_str()).collect();
    assert_eq!(
        names,
        [
            "case.json",
            "final.3mf",
            "final.stl",
            "intermediate.3mf",
            "intermediate.stl",
            "lower_map.ply",
            "plan-files.txt",
            "report.html",
            "upper_map.ply"
        ]
    );
    for ((n1, b1), (n2, b2)) in o1.iter().zip(&o2) {
        assert_eq!(n1, n2);
        assert!(b1 == b2, "{n1} differs between two runs");
    }
    for ((n1, b1), (nm, bm)) in o1.iter().zip(&om) {
        assert_eq!(n1, nm);
        if n1.ends_with(".stl") || n1.ends_with(".3mf") || n1.ends_with(".ply") {
            assert!(b1 == bm, "{n1} differs from the plan in metres");
        }
    }
    assert_eq!(first["bite"]["pose"], in_m["bite"]["pose"]);
    assert_eq!(first["bite"]["pose"], again["bite"]["pose"]);
    assert_eq!(in_m["unit"], "m");

    // The report stands alone: pictures inside, no scripts, no links out.
    let report = std::fs::read_to_string(dir.path("out1/report.html")).unwrap();
    assert!(report.matches("data:image/png;base64,").count() >= 5);
    assert!(!report.contains("<script") && !report.contains("http"));
    assert!(report.contains(first["inputs"][0]["blake3"].as_str().unwrap()));

    // The saved case replays to the same files.
    let replay = ist(&[
        "plan",
        s(&dir.path("out1/case.json")),
        "-o",
        s(&dir.path("out3")),
    ]);
    assert_eq!(code(&replay), 0, "{}", stderr(&replay));
    let o3 = outputs(&dir.path("out3"));
    for ((n1, b1), (n3, b3)) in o1.iter().zip(&o3) {
        assert_eq!(n1, n3);
        assert!(b1 == b3 || n1 == "case.json", "{n1} differs when replayed");
    }

    // The folder is the plan's own: a plan with one wafer fewer removes the other's file,
    // and a file of the user's is kept.
    std::fs::write(dir.path("out1/notes.txt"), "mine").unwrap();
    std::fs::write(
        dir.path("one.json"),
        case("", "mm").replace(r#", {"name": "intermediate", "open": 3, "voxel": 0.2}"#, ""),
    )
    .unwrap();
    let o = ist(&["plan", s(&dir.path("one.json")), "-o", s(&dir.path("out1"))]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    assert!(!dir.path("out1/intermediate.stl").exists());
    assert!(!dir.path("out1/intermediate.3mf").exists());
    assert!(dir.path("out1/final.stl").is_file());
    assert_eq!(
        std::fs::read_to_string(dir.path("out1/notes.txt")).unwrap(),
        "mine"
    );

    // A folder of someone else's files is refused, untouched.
    std::fs::create_dir_all(dir.path("theirs")).unwrap();
    std::fs::write(dir.path("theirs/final.stl"), "precious").unwrap();
    let o = ist(&[
        "plan",
        s(&dir.path("one.json")),
        "-o",
        s(&dir.path("theirs")),
    ]);
    assert_eq!(code(&o), 2);
    assert!(stderr(&o).contains("no plan wrote"), "{}", stderr(&o));
    assert_eq!(
        std::fs::read_to_string(dir.path("theirs/final.stl")).unwrap(),
        "precious"
    );
}

#[test]
fn a_case_that_cannot_be_planned_is_refused_before_any_work() {
    let dir = TempDir::new("ist-plan", "refused");
    for (text, says) in [
        (
            r#"{"version": 1, "upper": "u.stl"}"#,
            "missing field `lower`",
        ),
        (
            r#"{"version": 1, "upper": "u.stl", "lower": "l.stl", "splints": [{"name": "../x", "open": 1}]}"#,
            "name",
        ),
        (
            r#"{"version": 1, "upper": "missing.stl", "lower": "l.stl"}"#,
            "missing.stl",
        ),
        ("\u{0}\u{0}", "NUL byte"),
    ] {
        std::fs::write(dir.path("c.json"), text).unwrap();
        let o = ist(&["plan", s(&dir.path("c.json")), "-o", s(&dir.path("out"))]);
        assert_eq!(code(&o), 2, "{text}");
        assert!(stderr(&o).contains(says), "{text}: {}", stderr(&o));
        assert!(!dir.path("out").exists(), "{text}");
    }
}

/// Crowns without roots (open scans): the bite, the map and the intermediate wafer are made;
/// the final wafer, for which the arches leave no room, is reported with the reason, not
/// written, and the exit code says a wafer is missing.
#[test]
fn a_wafer_the_arches_cannot_make_is_reported_and_the_rest_written() {
    let dir = TempDir::new("ist-plan", "open");
    let (upper, lower) = shapes::arch_pair(3, 12);
    // The root ends cut off, as `write_arches` cuts them: open boundaries.
    let cut = |m: &Mesh, keep: &dyn Fn(f64) -> bool| {
        let mut m = m.clone();
        m.triangles
            .retain(|t| keep(t.iter().map(|&i| m.vertices[i as usize].z).sum::<f64>() / 3.0));
        m
    };
    innersphere::mesh::save(&cut(&upper, &|z| z < 9.0), &dir.path("upper.stl")).unwrap();
    innersphere::mesh::save(&cut(&lower, &|z| z > -4.0), &dir.path("lower.stl")).unwrap();
    std::fs::write(
        dir.path("case.json"),
        r#"{"version": 1, "upper": "upper.stl", "lower": "lower.stl",
            "splints": [{"name": "final", "open": "auto"}, {"name": "intermediate", "open": 3}]}"#,
    )
    .unwrap();
    let o = ist(&[
        "plan",
        s(&dir.path("case.json")),
        "-o",
        s(&dir.path("out")),
        "--json",
    ]);
    assert_eq!(code(&o), 3, "{}", stderr(&o));
    let p = json(&o);
    assert_eq!(p["bite"]["status"], "converged");
    let w = &p["splints"];
    assert!(w[0]["report"].is_null() && w[0]["file"].is_null());
    assert!(w[0]["error"].as_str().unwrap().contains("room"), "{}", w[0]);
    assert_eq!(w[1]["report"]["fit"], true, "{}", w[1]);
    assert!(dir.path("out/intermediate.stl").is_file());
    assert!(!dir.path("out/final.stl").exists());
    let report = std::fs::read_to_string(dir.path("out/report.html")).unwrap();
    assert!(report.contains("NOT made"));
}
