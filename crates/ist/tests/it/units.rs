//! `--unit`: a scan in metres (or cm, inches) is converted to millimetres as it is read, at
//! every command that takes a mesh, and gives the answers of the same scan in millimetres;
//! without it, the size of a dental body read in the wrong unit is named, with the unit
//! that fits.

use crate::support;
use support::{code, ist, s, stderr, stdout, TempDir};

use innersphere::{shapes, Mesh};
use serde_json::Value;

fn json(args: &[&str]) -> Value {
    let out = ist(args);
    assert_eq!(code(&out), 0, "ist {args:?}: {}", stderr(&out));
    serde_json::from_str(&stdout(&out)).unwrap()
}

fn scaled(m: &Mesh, f: f64) -> Mesh {
    Mesh {
        vertices: m.vertices.iter().map(|v| *v * f).collect(),
        triangles: m.triangles.clone(),
    }
}

#[test]
fn metre_scans_give_the_answers_of_the_same_scans_in_millimetres() {
    let dir = TempDir::new("units", "metres");
    let (a, b) = shapes::arch_pair(2, 8);
    let (a_mm, b_mm, a_m, b_m) = (
        dir.path("a_mm.stl"),
        dir.path("b_mm.stl"),
        dir.path("a_m.stl"),
        dir.path("b_m.stl"),
    );
    innersphere::mesh::save_stl(&a, &a_mm).unwrap();
    innersphere::mesh::save_stl(&b, &b_mm).unwrap();
    innersphere::mesh::save_stl(&scaled(&a, 1e-3), &a_m).unwrap();
    innersphere::mesh::save_stl(&scaled(&b, 1e-3), &b_m).unwrap();

    // The contact map: the same gaps, in mm (the f32 rounding of the metre file aside).
    let mm = json(&["occlusion-map", s(&a_mm), s(&b_mm), "--json"]);
    let m = json(&["occlusion-map", s(&a_m), s(&b_m), "--unit", "m", "--json"]);
    for k in ["a", "b"] {
        let (x, y) = (
            mm[k]["min_gap"].as_f64().unwrap(),
            m[k]["min_gap"].as_f64().unwrap(),
        );
        assert!((x - y).abs() < 1e-3, "{k}: {x} mm against {y}");
        assert_eq!(mm[k]["vertices_inside"], m[k]["vertices_inside"]);
    }

    // A tree of the metre file built in mm: the preset's voxel is 0.15 mm, the check passes
    // without --unit (the tree records the unit of its source), and it answers in mm.
    let (t_mm, t_m) = (dir.path("a_mm.ist"), dir.path("a_m.ist"));
    let build = |mesh: &std::path::Path, out: &std::path::Path, unit: &str| {
        json(&[
            "build",
            s(mesh),
            "-o",
            s(out),
            "--preset",
            "jaw-fast",
            "--unit",
            unit,
            "--json",
            "-q",
        ])
    };
    let r_mm = build(&a_mm, &t_mm, "mm");
    let r_m = build(&a_m, &t_m, "m");
    assert_eq!(r_m["voxel_size"], r_mm["voxel_size"], "{r_m}");
    let check = ist(&["check", s(&t_m), "--mesh", s(&a_m)]);
    assert_eq!(code(&check), 0, "{}", stderr(&check));
    let q = |t: &std::path::Path| {
        json(&["query", s(t), s(t), "--pose-b", "0 0 -20 1 0 0 0", "--json"])["distance"]
            .as_f64()
            .unwrap()
    };
    let (d_mm, d_m) = (q(&t_mm), q(&t_m));
    assert!((d_mm - d_m).abs() < 0.05, "{d_mm} mm against {d_m}");

    // The wafer from the metre scans, in mm.
    let out = dir.path("w.stl");
    let w = json(&[
        "splint",
        s(&a_m),
        s(&b_m),
        "--unit",
        "m",
        "--open",
        "3",
        "--voxel",
        "0.2",
        "-o",
        s(&out),
        "--json",
    ]);
    assert_eq!(w["fit"], true, "{w}");
    assert!(w["volume"].as_f64().unwrap() > 500.0, "{w}");

    // Without --unit: the dental preset warns, the splint refuses, each naming --unit m.
    let o = ist(&[
        "build",
        s(&a_m),
        "-o",
        s(&dir.path("x.ist")),
        "--preset",
        "jaw",
        "-q",
    ]);
    assert!(stderr(&o).contains("--unit m"), "{}", stderr(&o));
    let o = ist(&["splint", s(&a_m), s(&b_m), "-o", s(&out)]);
    assert_eq!(code(&o), 2);
    assert!(stderr(&o).contains("--unit m"), "{}", stderr(&o));
    // A unit that is none.
    let o = ist(&["inspect", s(&a_m), "--unit", "furlong"]);
    assert_eq!(code(&o), 2);
    assert!(stderr(&o).contains("mm, cm, m or in"), "{}", stderr(&o));
}
