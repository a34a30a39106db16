//! The `ist` binary end to end on meshes the tests write themselves (an ASCII STL box and an
//! OBJ ball, in a fresh temporary folder): `inspect`, `build`, `check` (exit code 0 on a
//! tree and its mesh, 1 on a tree against another mesh), `query`, and exit code 2 on errors.

use innersphere::glam::DVec3;
use innersphere::shapes;
use innersphere::{DistanceOptions, Pair, Pose};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Half extents of the box mesh.
const HALF: DVec3 = DVec3::new(1.0, 0.6, 0.4);

/// A temporary folder, removed when dropped.
struct TempDir(PathBuf);

impl TempDir {
    fn new(name: &str) -> TempDir {
        let dir = std::env::temp_dir().join(format!("ist-cli-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        TempDir(dir)
    }

    fn path(&self, file: &str) -> PathBuf {
        self.0.join(file)
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Runs `ist` with `args`.
fn ist(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_ist"))
        .args(args)
        .output()
        .expect("ist runs")
}

fn code(out: &Output) -> i32 {
    out.status.code().expect("ist exited normally")
}

fn stdout(out: &Output) -> String {
    String::from_utf8(out.stdout.clone()).unwrap()
}

/// Runs `ist` with `args`, asserts exit code `want`, parses stdout as JSON.
fn ist_json(args: &[&str], want: i32) -> Value {
    let out = ist(args);
    assert_eq!(
        code(&out),
        want,
        "ist {args:?}\nstdout: {}\nstderr: {}",
        stdout(&out),
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_str(&stdout(&out)).unwrap_or_else(|e| panic!("ist {args:?}: {e}"))
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// The box `[-HALF, HALF]` as an ASCII STL, written here (not by the library's writer).
fn write_box_stl(path: &Path) {
    let m = shapes::cuboid(HALF);
    let mut text = String::from("solid box\n");
    for t in 0..m.triangles.len() {
        let [a, b, c] = m.triangle(t);
        let n = (b - a).cross(c - a).normalize();
        text += &format!("  facet normal {} {} {}\n    outer loop\n", n.x, n.y, n.z);
        for v in [a, b, c] {
            text += &format!("      vertex {} {} {}\n", v.x, v.y, v.z);
        }
        text += "    endloop\n  endfacet\n";
    }
    text += "endsolid box\n";
    std::fs::write(path, text).unwrap();
}

/// A unit icosphere (320 triangles, 162 vertices) as an OBJ, written here.
fn write_ball_obj(path: &Path) {
    let m = shapes::icosphere(2);
    let mut text = String::new();
    for v in &m.vertices {
        text += &format!("v {} {} {}\n", v.x, v.y, v.z);
    }
    for t in &m.triangles {
        text += &format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    std::fs::write(path, text).unwrap();
}

/// A folder with `box.stl`, `ball.obj` and their trees `box.ist`, `ball.ist` built by
/// `ist build`.
fn fixture(name: &str) -> TempDir {
    let dir = TempDir::new(name);
    write_box_stl(&dir.path("box.stl"));
    write_ball_obj(&dir.path("ball.obj"));
    for (mesh, tree) in [("box.stl", "box.ist"), ("ball.obj", "ball.ist")] {
        let (mesh, tree) = (dir.path(mesh), dir.path(tree));
        let r = ist_json(
            &[
                "build",
                s(&mesh),
                "-o",
                s(&tree),
                "--resolution",
                "20",
                "--json",
            ],
            0,
        );
        assert!(tree.is_file());
        assert_eq!(r["output"], s(&tree));
        let spheres = r["spheres"].as_u64().unwrap();
        assert!(spheres > 50, "{r}");
        assert!(r["nodes"].as_u64().unwrap() > spheres);
        let coverage = r["coverage"].as_f64().unwrap();
        assert!(coverage > 0.3 && coverage < 1.0, "{r}");
    }
    dir
}

#[test]
fn inspect_reports_the_meshes() {
    let dir = TempDir::new("inspect");
    let (stl, obj) = (dir.path("box.stl"), dir.path("ball.obj"));
    write_box_stl(&stl);
    write_ball_obj(&obj);
    let r = ist_json(&["inspect", s(&stl), "--json"], 0);
    assert_eq!(r["triangles"], 12, "{r}");
    assert_eq!(r["vertices"], 8, "the STL's corners are welded: {r}");
    assert_eq!(r["components"], 1);
    assert_eq!(r["boundary_edges"], 0);
    assert_eq!(r["watertight"], true);
    let volume = 8.0 * HALF.x * HALF.y * HALF.z;
    assert!(
        (r["volume"].as_f64().unwrap() - volume).abs() < 1e-12,
        "{r}"
    );
    let r = ist_json(&["inspect", s(&obj), "--json"], 0);
    assert_eq!(r["triangles"], 320, "{r}");
    assert_eq!(r["vertices"], 162);
    assert_eq!(r["oriented_closed"], true);
    // Without --json: one line per field.
    let out = ist(&["inspect", s(&stl)]);
    assert_eq!(code(&out), 0);
    assert!(stdout(&out)
        .lines()
        .any(|l| l.split_whitespace().collect::<Vec<_>>() == ["triangles", "12"]));
}

#[test]
fn check_passes_a_tree_on_its_mesh_and_fails_it_on_another() {
    let dir = fixture("check");
    let (box_stl, box_ist, ball_obj) = (
        dir.path("box.stl"),
        dir.path("box.ist"),
        dir.path("ball.obj"),
    );
    let good = ist_json(&["check", s(&box_ist), "--mesh", s(&box_stl), "--json"], 0);
    assert_eq!(good["ok"], true, "{good}");
    assert_eq!(good["max_protrusion"], 0.0);
    assert_eq!(good["centers_outside"], 0);
    assert_eq!(good["enclosure_violations"], 0);
    let tree = innersphere::tree::file::load(&box_ist).unwrap();
    assert_eq!(good["spheres"], tree.leaf_count());
    assert_eq!(good["nodes"], tree.len());
    let out = ist(&["check", s(&box_ist), "--mesh", s(&box_stl)]);
    assert_eq!(code(&out), 0);
    assert!(stdout(&out).starts_with("ok: "), "{}", stdout(&out));

    // The box's tree against the unit ball: its corners (1.23 from the centre) poke out.
    let bad = ist_json(&["check", s(&box_ist), "--mesh", s(&ball_obj), "--json"], 1);
    assert_eq!(bad["ok"], false, "{bad}");
    assert!(bad["max_protrusion"].as_f64().unwrap() > 0.1, "{bad}");
    assert!(bad["centers_outside"].as_u64().unwrap() > 0, "{bad}");
    let out = ist(&["check", s(&box_ist), "--mesh", s(&ball_obj)]);
    assert_eq!(code(&out), 1);
    assert!(stdout(&out).starts_with("FAILED: "), "{}", stdout(&out));
}

#[test]
fn query_gives_the_distance_of_the_posed_trees() {
    let dir = fixture("query");
    let (box_ist, ball_ist) = (dir.path("box.ist"), dir.path("ball.ist"));
    let (a, b) = (
        innersphere::tree::file::load(&box_ist).unwrap(),
        innersphere::tree::file::load(&ball_ist).unwrap(),
    );
    // The same query through the library, with the pose parsed from the same text.
    let library = |pose: &str, b: &innersphere::SphereTree| {
        let mut pair = Pair::new(a.clone(), b.clone());
        let opts = DistanceOptions {
            coherence: false,
            ..Default::default()
        };
        let pose: Pose = pose.parse().unwrap();
        pair.distance_with(&Pose::IDENTITY, &pose, &opts).distance
    };
    // The ball 3 along x: its surface is 1 from the box's +x face; the inner spheres lie
    // inside both meshes, less than a voxel diagonal (0.17) from their surfaces.
    let r = ist_json(
        &[
            "query",
            s(&box_ist),
            s(&ball_ist),
            "--pose-b",
            "3 0 0 1 0 0 0",
            "--json",
        ],
        0,
    );
    let d = r["distance"].as_f64().unwrap();
    assert!(d.is_finite() && (1.0..1.35).contains(&d), "{r}");
    assert_eq!(r["contact"], false);
    assert_eq!(d, library("3 0 0 1 0 0 0", &b));
    // The box against itself turned by 90° about z and moved 2 along x: the faces 0.4 apart
    // (unturned, they would touch).
    let turned = "2 0 0 0.7071067811865476 0 0 0.7071067811865476";
    let r = ist_json(
        &[
            "query",
            s(&box_ist),
            s(&box_ist),
            "--pose-b",
            turned,
            "--json",
        ],
        0,
    );
    let d = r["distance"].as_f64().unwrap();
    assert!((0.4..0.75).contains(&d), "{r}");
    assert_eq!(d, library(turned, &a));
    // Overlapping at the identity: contact at distance 0.
    let r = ist_json(&["query", s(&box_ist), s(&ball_ist), "--json"], 0);
    assert_eq!(r["contact"], true, "{r}");
    assert_eq!(r["distance"], 0.0);
}

#[test]
fn errors_exit_with_code_2() {
    let dir = fixture("errors");
    let missing = dir.path("missing.ist");
    let out = ist(&["check", s(&missing), "--mesh", s(&dir.path("box.stl"))]);
    assert_eq!(code(&out), 2);
    assert!(String::from_utf8_lossy(&out.stderr).starts_with("error: "));
    // A mesh is no tree file.
    let out = ist(&["query", s(&dir.path("box.stl")), s(&dir.path("ball.ist"))]);
    assert_eq!(code(&out), 2);
    // A pose of six numbers.
    let out = ist(&[
        "query",
        s(&dir.path("box.ist")),
        s(&dir.path("ball.ist")),
        "--pose-b",
        "1 0 0 1 0 0",
    ]);
    assert_eq!(code(&out), 2);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("expected 7 numbers"), "{err}");
}
