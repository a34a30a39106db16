//! The `ist` binary end to end on meshes the tests write themselves (an ASCII STL box and an
//! OBJ ball, in a fresh temporary folder): `inspect`, `build`, `check` (exit code 0 on a
//! tree and its mesh, 2 on a tree against another mesh), `query`, and exit code 2 on errors;
//! then the edges a user meets: presets, the inspect verdict, errors that name the file once
//! and say what to do, JSON that ends with a newline, progress on stderr when piped, and the
//! same defaults for the same option in `query` and `replay`.

use crate::support;
use support::{code, ist, s, stderr, stdout, TempDir};

use innersphere::glam::DVec3;
use innersphere::shapes;
use innersphere::{DistanceOptions, Pair, Pose};
use serde_json::Value;
use std::path::Path;

/// Half extents of the box mesh.
const HALF: DVec3 = DVec3::new(1.0, 0.6, 0.4);

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
    let dir = TempDir::new("ist-cli", name);
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
    let dir = TempDir::new("ist-cli", "inspect");
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

    // The box's tree against the unit ball: not the mesh it was built from (by the bounding
    // box and volume the tree keeps), an error before any sphere is checked. (The library's
    // check of the spheres against another mesh, exit code 1, is the core's src/tests/check_negative.rs.)
    for json in [true, false] {
        let mut args = vec!["check", s(&box_ist), "--mesh", s(&ball_obj)];
        if json {
            args.push("--json");
        }
        let out = ist(&args);
        assert_eq!(code(&out), 2, "{}", stderr(&out));
        assert!(stdout(&out).is_empty());
        assert!(
            stderr(&out).contains("not the mesh the tree was built from"),
            "{}",
            stderr(&out)
        );
    }
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

/// `--query refined-distance` finds each tree's mesh from its file (or takes --meshes) and
/// gives the meshes' exact distance here (the balls hold the few large triangles); without
/// the meshes, or with another body's, it says what to give.
#[test]
fn query_refines_the_distance_to_the_meshes() {
    let dir = fixture("refined");
    let (box_ist, ball_ist) = (dir.path("box.ist"), dir.path("ball.ist"));
    let pose = "3 0.1 0 1 0 0 0";
    let exact = {
        let load = |f: &str| {
            innersphere::exact::ExactMesh::new(&innersphere::Mesh::load(dir.path(f)).unwrap())
                .unwrap()
        };
        let (a, b) = (load("box.stl"), load("ball.obj"));
        let mut scratch = innersphere::exact::ExactScratch::new();
        innersphere::exact::distance(
            &a,
            &Pose::IDENTITY,
            &b,
            &pose.parse().unwrap(),
            &mut scratch,
        )
        .distance
    };
    let q = |extra: &[&str], want: i32| {
        let mut args = vec![
            "query",
            s(&box_ist),
            s(&ball_ist),
            "--pose-b",
            pose,
            "--query",
            "refined-distance",
            "--json",
        ];
        args.extend_from_slice(extra);
        ist_json(&args, want)
    };
    let r = q(&[], 0);
    let d = r["distance"].as_f64().unwrap();
    assert!((d - exact).abs() <= 1e-9, "refined {d}, exact {exact}: {r}");
    assert!(d < r["spheres"]["distance"].as_f64().unwrap(), "{r}");
    assert_eq!(
        (
            r["refined"].clone(),
            r["contact"].clone(),
            r["complete"].clone()
        ),
        (true.into(), false.into(), true.into())
    );
    assert!(r["triangle_a"].as_u64().unwrap() < 12, "{r}");
    let given = q(
        &[
            "--meshes",
            s(&dir.path("box.stl")),
            s(&dir.path("ball.obj")),
        ],
        0,
    );
    assert_eq!(given["distance"], r["distance"]);
    // Another body's mesh, a bad margin, and replay's refined kind without meshes.
    let out = ist(&[
        "query",
        s(&box_ist),
        s(&ball_ist),
        "--query",
        "refined-distance",
        "--meshes",
        s(&dir.path("ball.obj")),
        s(&dir.path("ball.obj")),
    ]);
    assert_eq!(code(&out), 2);
    assert!(stderr(&out).contains("not the mesh"), "{}", stderr(&out));
    let out = ist(&[
        "query",
        s(&box_ist),
        s(&ball_ist),
        "--query",
        "refined-distance",
        "--refine-margin=-1",
    ]);
    assert_eq!(code(&out), 2);
    assert!(stderr(&out).contains("--refine-margin"), "{}", stderr(&out));
    std::fs::write(
        dir.path("m.csv"),
        "t,tx,ty,tz,qw,qx,qy,qz\n0,3,0,0,1,0,0,0\n",
    )
    .unwrap();
    let out = ist(&[
        "replay",
        s(&box_ist),
        s(&ball_ist),
        "--motion",
        s(&dir.path("m.csv")),
        "--query",
        "refined-distance",
    ]);
    assert_eq!(code(&out), 2);
    assert!(stderr(&out).contains("--exact"), "{}", stderr(&out));
}

/// `ist bench batch` times every batch kind, the refined distance with the meshes its trees
/// name (or `--meshes`), and every thread count answers the same bits; another body's mesh
/// and an unknown kind are errors.
#[test]
fn bench_batch_runs_every_kind_with_the_same_answers_on_any_thread_count() {
    let dir = fixture("bench-batch");
    let (box_ist, ball_ist) = (dir.path("box.ist"), dir.path("ball.ist"));
    let bench = |query: &str, extra: &[&str], want: i32| {
        let mut args = vec![
            "bench",
            "batch",
            s(&box_ist),
            s(&ball_ist),
            "--poses",
            "40",
            "--mm",
            "3",
            "--query",
            query,
            "--threads",
            "1,2",
            "--repeat",
            "1",
            "--json",
        ];
        args.extend_from_slice(extra);
        ist_json(&args, want)
    };
    for query in ["distance", "refined-distance", "contact", "penetration"] {
        let rows = bench(query, &[], 0);
        let rows = rows.as_array().unwrap();
        assert_eq!(rows.len(), 2, "{query}: {rows:?}");
        assert!(rows.iter().all(|r| r["same_answers"] == true), "{query}");
    }
    let (box_stl, ball_obj) = (dir.path("box.stl"), dir.path("ball.obj"));
    let given = [s(&box_stl), s(&ball_obj)];
    bench("refined-distance", &["--meshes", given[0], given[1]], 0);
    let out = ist(&[
        "bench",
        "batch",
        s(&box_ist),
        s(&ball_ist),
        "--poses",
        "4",
        "--query",
        "refined-distance",
        "--meshes",
        given[1],
        given[1],
    ]);
    assert_eq!(code(&out), 2);
    assert!(stderr(&out).contains("not the mesh"), "{}", stderr(&out));
    let out = ist(&[
        "bench",
        "batch",
        s(&box_ist),
        s(&ball_ist),
        "--query",
        "volume",
    ]);
    assert_eq!(code(&out), 2);
    assert!(
        stderr(&out).contains("refined-distance"),
        "{}",
        stderr(&out)
    );
}

#[test]
fn errors_exit_with_code_2() {
    let dir = fixture("errors");
    let missing = dir.path("missing.ist");
    let out = ist(&["check", s(&missing), "--mesh", s(&dir.path("box.stl"))]);
    assert_eq!(code(&out), 2);
    assert!(String::from_utf8_lossy(&out.stderr).starts_with("error: "));
    // A mesh is no tree file (for `export`; `query` builds it).
    let out = ist(&["export", s(&dir.path("box.stl"))]);
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

/// Writes `mesh` as an OBJ (the library's writer; the box and ball above are written by hand).
fn write_obj(mesh: &innersphere::Mesh, path: &Path) {
    innersphere::mesh::save_obj(mesh, path).unwrap();
}

#[test]
fn a_mesh_where_a_tree_belongs_and_a_tree_where_a_mesh_belongs_say_so() {
    let dir = fixture("hints");
    let (box_stl, box_ist) = (dir.path("box.stl"), dir.path("box.ist"));
    // A mesh given as a tree, in every subcommand that reads trees.
    // (`query`, `replay`, `haptic`, `occlude` and `view` take meshes too: see
    // `meshes_open_directly_through_the_build_cache`.)
    for args in [
        vec!["check", s(&box_stl), "--mesh", s(&box_stl)],
        vec!["export", s(&box_stl)],
    ] {
        let out = ist(&args);
        assert_eq!(code(&out), 2, "{args:?}");
        let err = stderr(&out);
        assert!(
            err.starts_with(&format!(
                "error: {} is a mesh, not a tree file: run `ist build` on it first",
                s(&box_stl)
            )),
            "{args:?}: {err}"
        );
        assert_eq!(
            err.matches(s(&box_stl)).count(),
            1,
            "the file named once: {err}"
        );
    }
    // A tree given as a mesh.
    let not_written = dir.path("x.ist");
    for args in [
        vec!["inspect", s(&box_ist)],
        vec!["build", s(&box_ist), "-o", s(&not_written)],
        vec!["check", s(&box_ist), "--mesh", s(&box_ist)],
    ] {
        let out = ist(&args);
        assert_eq!(code(&out), 2, "{args:?}");
        let err = stderr(&out);
        assert!(
            err.starts_with(&format!(
                "error: {} is an Inner Sphere Tree file, not a mesh: give a mesh file here",
                s(&box_ist)
            )),
            "{args:?}: {err}"
        );
        assert_eq!(err.matches(s(&box_ist)).count(), 1, "{err}");
    }
    // A missing file: named once, with the operating system's reason once.
    let missing = dir.path("missing.ist");
    let err = stderr(&ist(&["check", s(&missing), "--mesh", s(&box_stl)]));
    assert_eq!(err.matches(s(&missing)).count(), 1, "{err}");
    assert_eq!(err.matches("os error").count(), 1, "{err}");
    assert!(!not_written.exists());
}

#[test]
fn inspect_ends_with_a_verdict_that_matches_what_build_does() {
    let dir = TempDir::new("ist-cli", "verdict");
    let closed = shapes::cuboid(HALF);
    let mut inward = closed.clone();
    inward.flip();
    let mut open = shapes::icosphere(2);
    open.triangles.truncate(open.triangles.len() - 3);
    let soup = innersphere::Mesh::from_soup(
        &(0..30)
            .map(|i| {
                let o = DVec3::splat(i as f64 * 2.0);
                [o, o + DVec3::X, o + DVec3::Y]
            })
            .collect::<Vec<_>>(),
    );
    for (name, mesh, verdict, line_start, builds) in [
        (
            "closed",
            &closed,
            "closed",
            "verdict: closed and consistently oriented: build uses the exact inside test",
            true,
        ),
        (
            "inward",
            &inward,
            "closed_inward",
            "verdict: closed but facing inward",
            true,
        ),
        ("open", &open, "open", "verdict: open (", true),
        ("soup", &soup, "soup", "verdict: a triangle soup (", false),
    ] {
        let path = dir.path(&format!("{name}.obj"));
        write_obj(mesh, &path);
        let out = ist(&["inspect", s(&path)]);
        assert_eq!(code(&out), 0);
        let text = stdout(&out);
        let last = text.lines().last().unwrap();
        assert!(last.starts_with(line_start), "{name}: {last}");
        let r = ist_json(&["inspect", s(&path), "--json"], 0);
        assert_eq!(r["verdict"], verdict, "{name}: {r}");
        assert_eq!(
            format!("verdict: {}", r["verdict_text"].as_str().unwrap()),
            last
        );
        // What the verdict promises is what build does.
        let tree = dir.path(&format!("{name}.ist"));
        let out = ist(&[
            "build",
            s(&path),
            "-o",
            s(&tree),
            "--resolution",
            "16",
            "--json",
        ]);
        assert_eq!(code(&out) == 0, builds, "{name}: {}", stderr(&out));
        if builds {
            let r: Value = serde_json::from_str(&stdout(&out)).unwrap();
            let method = if name == "open" {
                "winding_number"
            } else {
                "closed_exact"
            };
            assert_eq!(r["inside_method"], method, "{name}");
            let warned_flip = r["warnings"]
                .as_array()
                .unwrap()
                .iter()
                .any(|w| w.as_str().unwrap().contains("flipped"));
            assert_eq!(warned_flip, name == "inward", "{name}: {r}");
        } else {
            assert!(
                stderr(&out).contains("encloses no volume"),
                "{}",
                stderr(&out)
            );
        }
    }
}

/// The build options `ist build` reports in its JSON.
fn built_options(mesh: &Path, tree: &Path, extra: &[&str]) -> Value {
    let mut args = vec!["build", s(mesh), "-o", s(tree), "--json", "--quiet"];
    args.extend_from_slice(extra);
    ist_json(&args, 0)["options"].clone()
}

#[test]
fn presets_are_computed_from_the_mesh_and_flags_override_their_fields() {
    let dir = TempDir::new("ist-cli", "preset");
    let (stl, tree) = (dir.path("box.stl"), dir.path("box.ist"));
    write_box_stl(&stl); // 2 x 1.2 x 0.8: read as millimetres, a small tooth
                         // The jaw preset: absolute millimetres.
    let o = built_options(&stl, &tree, &["--preset", "jaw"]);
    assert_eq!(o["preset"], "jaw", "{o}");
    assert_eq!(o["voxel_size"], 0.1);
    assert_eq!(o["min_radius"], 0.05);
    assert_eq!(o["refine_steps"], 8);
    assert_eq!(o["fanout"], 4);
    let o = built_options(&stl, &tree, &["--preset", "jaw-fast"]);
    assert_eq!(
        (o["voxel_size"].as_f64(), o["min_radius"].as_f64()),
        (Some(0.15), Some(0.05))
    );
    // An explicit flag replaces that one field and keeps the others.
    let o = built_options(
        &stl,
        &tree,
        &["--preset", "jaw", "--refine-steps", "2", "--fanout", "8"],
    );
    assert_eq!(o["voxel_size"], 0.1);
    assert_eq!(o["min_radius"], 0.05);
    assert_eq!(o["refine_steps"], 2);
    assert_eq!(o["fanout"], 8);
    // The unit-free fine preset scales with the mesh: voxel = longest side / 384; with
    // --resolution the grid is the flag's, the minimum radius still the preset's.
    let o = built_options(&stl, &tree, &["--preset", "fine", "--resolution", "20"]);
    assert_eq!(o["preset"], "fine");
    assert_eq!(o["resolution"], 20);
    assert_eq!(o["voxel_size"], Value::Null);
    assert_eq!(
        o["min_radius"].as_f64().unwrap(),
        2.0 * HALF.x / 384.0 / 2.0
    );
    assert_eq!(o["refine_steps"], 8);
    let o = built_options(&stl, &tree, &["--preset", "fast"]);
    assert_eq!(o["resolution"], 64);
    assert_eq!(
        (o["min_radius"].as_f64(), o["refine_steps"].as_u64()),
        (Some(0.0), Some(0))
    );
    // Without a preset: the defaults, and no preset named.
    let o = built_options(&stl, &tree, &["--resolution", "20"]);
    assert_eq!(o["preset"], Value::Null);
    assert_eq!(o["refine_steps"], 0);
    // The same box in metres is refused by the millimetre presets, with the reason.
    let tiny = dir.path("tiny.obj");
    let mut m = shapes::cuboid(HALF);
    m.vertices.iter_mut().for_each(|v| *v *= 1e-3);
    write_obj(&m, &tiny);
    let out = ist(&["build", s(&tiny), "-o", s(&tree), "--preset", "jaw"]);
    assert_eq!(code(&out), 2);
    let err = stderr(&out);
    assert!(err.contains("preset jaw is in millimetres"), "{err}");
    assert_eq!(err.matches(s(&tiny)).count(), 1, "{err}");
    // An unknown preset is a usage error listing the names.
    let out = ist(&["build", s(&stl), "-o", s(&tree), "--preset", "coarse"]);
    assert_eq!(code(&out), 2);
    assert!(stderr(&out).contains("jaw-fast"), "{}", stderr(&out));
}

#[test]
fn build_reports_its_stages_on_stderr_when_not_on_a_terminal() {
    let dir = TempDir::new("ist-cli", "stages");
    let (stl, tree) = (dir.path("box.stl"), dir.path("box.ist"));
    write_box_stl(&stl);
    // The test captures stdout and stderr through pipes: no terminal.
    let out = ist(&["build", s(&stl), "-o", s(&tree), "--resolution", "20"]);
    assert_eq!(code(&out), 0);
    let err = stderr(&out);
    for stage in ["distance field", "packing spheres", "clustering (BNG)"] {
        assert!(err.contains(&format!("] {stage} ...")), "{stage}: {err}");
        assert!(
            err.contains(&format!("] {stage}: done in ")),
            "{stage}: {err}"
        );
    }
    assert!(!err.contains('\r'), "no bar drawing in a log: {err:?}");
    assert!(
        stdout(&out).contains("spheres"),
        "the report stays on stdout"
    );
    // With --json the report is on stdout and the stages still on stderr.
    let out = ist(&[
        "build",
        s(&stl),
        "-o",
        s(&tree),
        "--resolution",
        "20",
        "--json",
    ]);
    assert!(stderr(&out).contains("packing spheres"));
    serde_json::from_str::<Value>(&stdout(&out)).unwrap();
    // --quiet: nothing at all on stderr for a clean mesh.
    let out = ist(&[
        "build",
        s(&stl),
        "-o",
        s(&tree),
        "--resolution",
        "20",
        "--quiet",
    ]);
    assert_eq!(code(&out), 0);
    assert_eq!(stderr(&out), "");
}

#[test]
fn every_json_output_ends_with_a_newline() {
    let dir = fixture("json");
    let (box_stl, box_ist, ball_obj, ball_ist) = (
        dir.path("box.stl"),
        dir.path("box.ist"),
        dir.path("ball.obj"),
        dir.path("ball.ist"),
    );
    let motion = dir.path("m.csv");
    let out = ist(&[
        "motion",
        "--a",
        s(&box_stl),
        "--b",
        s(&ball_obj),
        "-o",
        s(&motion),
        "--seconds",
        "0.05",
    ]);
    assert_eq!(code(&out), 0, "{}", stderr(&out));
    let tree2 = dir.path("again.ist");
    let runs: Vec<Vec<&str>> = vec![
        vec!["inspect", s(&box_stl)],
        vec![
            "build",
            s(&box_stl),
            "-o",
            s(&tree2),
            "--resolution",
            "12",
            "--quiet",
        ],
        vec!["check", s(&box_ist), "--mesh", s(&box_stl)],
        vec!["query", s(&box_ist), s(&ball_ist), "--query", "distance"],
        vec!["query", s(&box_ist), s(&ball_ist), "--query", "contact"],
        vec!["query", s(&box_ist), s(&ball_ist), "--query", "multipoint"],
        vec!["query", s(&box_ist), s(&ball_ist), "--query", "penetration"],
        vec!["replay", s(&box_ist), s(&ball_ist), "--motion", s(&motion)],
        vec!["bench", "build", s(&box_stl), "--resolution", "12"],
        vec!["demo", "--resolution", "12", "--seconds", "0", "--quiet"],
    ];
    for mut args in runs {
        args.push("--json");
        let out = ist(&args);
        assert_eq!(code(&out), 0, "{args:?}: {}", stderr(&out));
        let text = stdout(&out);
        assert!(
            text.ends_with("}\n") || text.ends_with("]\n"),
            "{args:?}: {text:?}"
        );
        assert!(!text.ends_with("\n\n"), "{args:?}");
        serde_json::from_str::<Value>(&text).unwrap_or_else(|e| panic!("{args:?}: {e}"));
    }
}

/// The default of `--option` in `ist SUBCOMMAND --help`.
fn default_of(subcommand: &[&str], option: &str) -> String {
    let mut args = subcommand.to_vec();
    args.push("--help");
    let help = stdout(&ist(&args));
    let start = help
        .find(&format!("--{option} <"))
        .unwrap_or_else(|| panic!("{subcommand:?} has no --{option}: {help}"));
    let rest = &help[start..];
    let end = rest.find("\n  -").unwrap_or(rest.len());
    let entry = &rest[..end];
    let d = entry
        .find("[default: ")
        .unwrap_or_else(|| panic!("--{option} shows no default: {entry}"));
    entry[d + 10..].split(']').next().unwrap().to_string()
}

#[test]
fn query_and_replay_share_their_defaults() {
    for option in ["k", "split-depth"] {
        assert_eq!(
            default_of(&["query"], option),
            default_of(&["replay"], option),
            "--{option}"
        );
    }
    // The benchmarks' k = 16.
    assert_eq!(default_of(&["query"], "k"), "16");
    // And the default is what runs: the box against itself touches everywhere.
    let dir = fixture("k");
    let box_ist = dir.path("box.ist");
    let r = ist_json(
        &[
            "query",
            s(&box_ist),
            s(&box_ist),
            "--query",
            "multipoint",
            "--json",
        ],
        0,
    );
    assert_eq!(r["contacts"].as_array().unwrap().len(), 16, "{r}");
}

#[test]
fn printed_numbers_say_their_units() {
    let dir = fixture("units");
    let (box_stl, box_ist, ball_ist) = (
        dir.path("box.stl"),
        dir.path("box.ist"),
        dir.path("ball.ist"),
    );
    let out = stdout(&ist(&[
        "build",
        s(&box_stl),
        "-o",
        s(&dir.path("b.ist")),
        "--resolution",
        "12",
    ]));
    assert!(out.contains("model units"), "{out}");
    assert!(out.contains(" units³"), "{out}");
    assert!(out.contains("cells of 0.166667 units"), "{out}");
    let out = stdout(&ist(&[
        "query",
        s(&box_ist),
        s(&ball_ist),
        "--pose-b",
        "3 0 0 1 0 0 0",
    ]));
    assert!(
        out.starts_with("distance 1.") && out.contains(" units (separated)") && out.contains(" µs"),
        "{out}"
    );
    let out = stdout(&ist(&[
        "query",
        s(&box_ist),
        s(&ball_ist),
        "--pose-b",
        "3 0 0 1 0 0 0",
        "--query",
        "contact",
    ]));
    assert!(out.contains("separated by at least"), "{out}");
    assert!(
        out.contains("a proved lower bound, not the distance"),
        "{out}"
    );
    for (kind, lower) in [
        ("distance", false),
        ("contact", true),
        ("multipoint", true),
        ("penetration", true),
    ] {
        let r = ist_json(
            &[
                "query",
                s(&box_ist),
                s(&ball_ist),
                "--pose-b",
                "3 0 0 1 0 0 0",
                "--query",
                kind,
                "--json",
            ],
            0,
        );
        assert_eq!(r["distance_is_lower_bound"], lower, "{kind}: {r}");
        assert!(r["distance"].as_f64().unwrap() > 0.5, "{kind}: {r}");
    }
    let out = stdout(&ist(&[
        "query",
        s(&box_ist),
        s(&ball_ist),
        "--query",
        "penetration",
    ]));
    assert!(
        out.starts_with("penetration volume ") && out.contains(" units³"),
        "{out}"
    );
    assert!(out.contains("N for N/mm³"), "{out}");
    let help = stdout(&ist(&["query", "--help"]));
    assert!(
        help.contains("force per unit of penetration volume"),
        "{help}"
    );
    assert!(help.contains("N/mm³"), "{help}");
    let help = stdout(&ist(&["build", "--help"]));
    assert!(help.contains("mm for the jaw scans"), "{help}");
}

#[test]
fn haptic_and_occlude_run_on_generated_bodies_and_refuse_bad_input() {
    let dir = TempDir::new("cli", "haptic");
    let (box_stl, ball_obj) = (dir.path("box.stl"), dir.path("ball.obj"));
    write_box_stl(&box_stl);
    write_ball_obj(&ball_obj);
    let (ta, tb) = (dir.path("box.ist"), dir.path("ball.ist"));
    for (m, t) in [(&box_stl, &ta), (&ball_obj, &tb)] {
        let out = ist(&["build", s(m), "-o", s(t), "--resolution", "24", "--quiet"]);
        assert_eq!(code(&out), 0, "{}", stderr(&out));
    }
    // The ball (B) pressed from 2 mm above the box's centre to 1.2 (0.2 mm into its top).
    let dev = dir.path("dev.csv");
    let mut text = String::from("t,tx,ty,tz,qw,qx,qy,qz\n");
    for i in 0..=300 {
        let t = i as f64 / 1000.0;
        text += &format!("{t},0,0,{},1,0,0,0\n", 2.0 - 0.8 * (t / 0.3));
    }
    std::fs::write(&dev, text).unwrap();
    let (trace, plot) = (dir.path("trace.csv"), dir.path("plot.png"));
    let v = ist_json(
        &[
            "haptic",
            s(&ta),
            s(&tb),
            "--device",
            s(&dev),
            "--trace",
            s(&trace),
            "--plot",
            s(&plot),
            "--json",
        ],
        0,
    );
    assert_eq!(v["ticks"], 301);
    for key in [
        "deadline_misses",
        "compute_p50_us",
        "compute_p99_us",
        "compute_max_us",
        "budgeted_ticks",
        "max_force_n",
        "max_torque_nmm",
        "max_depth_mm",
        "max_volume_mm3",
        "energy_to_user_max_j",
        "max_force_step_n",
    ] {
        assert!(v[key].is_number(), "{key}: {v}");
    }
    assert!(v["max_force_n"].as_f64().unwrap() > 0.0, "{v}");
    assert!(v["energy_to_user_max_j"].as_f64().unwrap() <= 1e-12, "{v}");
    let rows = std::fs::read_to_string(&trace).unwrap();
    assert_eq!(rows.lines().count(), 302);
    assert!(rows.starts_with("t,dev_tx"));
    assert!(std::fs::metadata(&plot).unwrap().len() > 1000);
    // The collision thread, in real time: its figures beside the servo's.
    let v = ist_json(
        &[
            "haptic",
            s(&ta),
            s(&tb),
            "--device",
            s(&dev),
            "--realtime",
            "--collision-thread",
            "--collision-delay-us",
            "500",
            "--json",
        ],
        0,
    );
    assert_eq!(v["collision_thread"], true, "{v}");
    assert_eq!(v["collision_delay_us"], 500.0, "{v}");
    for key in ["collision_rate_hz", "collision_p99_us", "model_age_p99_us"] {
        assert!(v[key].as_f64().unwrap() > 0.0, "{key}: {v}");
    }
    assert!(v["max_force_n"].as_f64().unwrap() > 0.0, "{v}");
    assert!(v["energy_to_user_max_j"].as_f64().unwrap() <= 1e-9, "{v}");
    // Bad input: a clear error (exit 2), never a panic; the device file is not overwritten.
    for args in [
        vec!["haptic", s(&ta), s(&tb), "--device", s(&dev), "--rate", "0"],
        vec![
            "haptic",
            s(&ta),
            s(&tb),
            "--device",
            s(&dev),
            "--stiffness",
            "99",
        ],
        vec![
            "haptic",
            s(&ta),
            s(&tb),
            "--device",
            s(&dev),
            "--trace",
            s(&dev),
        ],
        vec!["haptic", s(&ta), s(&tb), "--device", s(&box_stl)],
        // The collision thread runs in real time only; its delay needs it.
        vec![
            "haptic",
            s(&ta),
            s(&tb),
            "--device",
            s(&dev),
            "--collision-thread",
        ],
        vec![
            "haptic",
            s(&ta),
            s(&tb),
            "--device",
            s(&dev),
            "--collision-delay-us",
            "100",
        ],
        vec![
            "haptic",
            s(&ta),
            s(&tb),
            "--device",
            s(&dev),
            "--realtime",
            "--collision-thread",
            "--collision-delay-us",
            "-5",
        ],
        vec![
            "occlude",
            s(&ta),
            s(&tb),
            "--from",
            "0 0 2 1 0 0 0",
            "--force",
            "-1",
        ],
        vec!["occlude", s(&ta), s(&tb), "--from", "0 0 nan 1 0 0 0"],
    ] {
        let out = ist(&args);
        assert_eq!(code(&out), 2, "ist {args:?}: {}", stderr(&out));
        assert!(stderr(&out).contains("error"), "{}", stderr(&out));
    }
    assert!(std::fs::read_to_string(&dev).unwrap().starts_with("t,tx"));
    // A low rate, a trace longer than is kept, a negative joint stiffness: a
    // sentence with plain numbers, exit 2, at once.
    let long = dir.path("long.csv");
    std::fs::write(
        &long,
        "t,tx,ty,tz,qw,qx,qy,qz\n0,0,0,2,1,0,0,0\n49999,0,0,2,1,0,0,0\n",
    )
    .unwrap();
    for (args, want) in [
        (
            vec!["haptic", s(&ta), s(&tb), "--device", s(&dev), "--rate", "1"],
            "from 100 Hz",
        ),
        (
            vec![
                "haptic",
                s(&ta),
                s(&tb),
                "--device",
                s(&long),
                "--trace",
                s(&trace),
            ],
            "keeps every tick",
        ),
        (
            vec![
                "occlude",
                s(&ta),
                s(&tb),
                "--from",
                "0 0 2 1 0 0 0",
                "--joint-stiffness=-1",
            ],
            "the joint stiffness must be finite and 0 to 10000 N/mm",
        ),
    ] {
        let t = std::time::Instant::now();
        let out = ist(&args);
        let e = stderr(&out);
        assert_eq!(code(&out), 2, "ist {args:?}: {e}");
        assert!(e.contains(want), "ist {args:?}: {e}");
        assert!(!e.contains("DVec3") && !e.contains("Joints {"), "{e}");
        assert!(
            t.elapsed().as_secs() < 10,
            "ist {args:?} took {:?}",
            t.elapsed()
        );
    }
    // A box and a ball in the same place do not face each other: no bite to close (the
    // closings themselves are tested on generated arches in tests/occlude.rs).
    let out = ist(&[
        "occlude",
        s(&ta),
        s(&tb),
        "--from",
        "0 0 2 1 0 0 0",
        "--free",
    ]);
    assert_eq!(code(&out), 2, "{}", stderr(&out));
    assert!(
        stderr(&out).contains("do not face each other"),
        "{}",
        stderr(&out)
    );
}

/// The vertices and `gap`s of a contact-map PLY written by `ist occlusion-map`.
fn read_gap_ply(path: &Path) -> Vec<(DVec3, f64, [u8; 3])> {
    let bytes = std::fs::read(path).unwrap();
    let end = b"end_header\n";
    let h = bytes.windows(end.len()).position(|w| w == end).unwrap() + end.len();
    let header = String::from_utf8_lossy(&bytes[..h]);
    assert!(header.contains("property float gap"), "{header}");
    let n: usize = header
        .lines()
        .find_map(|l| l.strip_prefix("element vertex "))
        .unwrap()
        .parse()
        .unwrap();
    let f = |o: usize| f32::from_le_bytes(bytes[o..o + 4].try_into().unwrap()) as f64;
    (0..n)
        .map(|i| {
            let o = h + 19 * i;
            let rgb = [bytes[o + 16], bytes[o + 17], bytes[o + 18]];
            (DVec3::new(f(o), f(o + 4), f(o + 8)), f(o + 12), rgb)
        })
        .collect()
}

#[test]
fn occlusion_map_writes_the_signed_gaps_of_both_meshes() {
    use innersphere::mesh::closest::point_triangle_distance_sq;
    let dir = TempDir::new("cli", "occlusion-map");
    let (box_stl, ball) = (dir.path("box.stl"), dir.path("ball.obj"));
    write_box_stl(&box_stl);
    let ball_mesh = shapes::icosphere(3);
    write_obj(&ball_mesh, &ball);
    let teeth = dir.path("teeth.json");
    std::fs::write(&teeth, r#"{"30": {"c": [0, 0, 0]}}"#).unwrap();
    let (pa, pb) = (dir.path("a.ply"), dir.path("b.ply"));
    // The ball (radius 1) centred 1.2 along x: it overlaps the box's face x = 1 by 0.8.
    let c = DVec3::new(1.2, 0.0, 0.0);
    let r = ist_json(
        &[
            "occlusion-map",
            s(&box_stl),
            s(&ball),
            "--pose",
            "1.2 0 0 1 0 0 0",
            "--out-a",
            s(&pa),
            "--out-b",
            s(&pb),
            "--teeth-b",
            s(&teeth),
            "--json",
        ],
        0,
    );
    let box_mesh = shapes::cuboid(HALF);
    let ball_at: Vec<[DVec3; 3]> = (0..ball_mesh.triangles.len())
        .map(|t| ball_mesh.triangle(t).map(|v| v + c))
        .collect();
    let box_tris: Vec<[DVec3; 3]> = (0..box_mesh.triangles.len())
        .map(|t| box_mesh.triangle(t))
        .collect();
    let brute = |p: DVec3, tris: &[[DVec3; 3]]| {
        tris.iter()
            .map(|t| point_triangle_distance_sq(p, t[0], t[1], t[2]))
            .fold(f64::INFINITY, f64::min)
            .sqrt()
    };
    let inside_box = |p: DVec3| (p.abs() - HALF).max_element() < -1e-3;
    let outside_box = |p: DVec3| (p.abs() - HALF).max_element() > 1e-3;
    for (ply, tris, inside, outside) in [
        (
            &pa,
            &ball_at,
            &(|p: DVec3| (p - c).length() < 0.98) as &dyn Fn(DVec3) -> bool,
            &(|p: DVec3| (p - c).length() > 1.001) as &dyn Fn(DVec3) -> bool,
        ),
        (
            &pb,
            &box_tris,
            &inside_box as &dyn Fn(DVec3) -> bool,
            &outside_box as &dyn Fn(DVec3) -> bool,
        ),
    ] {
        let v = read_gap_ply(ply);
        assert!(v.len() >= 8);
        let (mut n_in, mut n_out) = (0, 0);
        for (p, g, rgb) in v {
            // f32 in the file: 1e-4 of the exact f64 gap.
            assert!(
                (g.abs() - brute(p, tris)).abs() <= 1e-4,
                "{p}: {g} vs {}",
                brute(p, tris)
            );
            if inside(p) {
                assert!(g < 0.0, "{p}: {g}");
                n_in += 1;
            } else if outside(p) {
                assert!(g > 0.0, "{p}: {g}");
                n_out += 1;
            }
            assert_eq!(
                rgb,
                innersphere_dental::contact_map::gap_colour(g as f32 as f64)
            );
        }
        assert!(n_in > 0 && n_out > 0, "{}", ply.display());
    }
    assert!(r["a"]["min_gap"].as_f64().unwrap() < 0.0, "{r}");
    assert!(r["b"]["vertices_inside"].as_u64().unwrap() > 0, "{r}");
    let t = &r["b"]["teeth"][0];
    assert_eq!(t["tooth"], 30);
    assert!(
        t["spots"].as_u64().unwrap() >= 1 && t["area_within_0_1"].as_f64().unwrap() > 0.0,
        "{r}"
    );
    assert!(r["a"]["teeth"].is_null());
    // Units in --help; bad input is a clear error.
    let help = stdout(&ist(&["occlusion-map", "--help"]));
    assert!(help.contains("mm") && help.contains("negative"), "{help}");
    for bad in [
        vec![
            "occlusion-map",
            s(&box_stl),
            s(&ball),
            "--out-a",
            s(&box_stl),
        ],
        vec!["occlusion-map", s(&box_stl), s(&ball), "--pose", "1 2 3"],
        vec![
            "occlusion-map",
            s(&box_stl),
            s(&ball),
            "--pose",
            "nan 0 0 1 0 0 0",
        ],
        vec![
            "occlusion-map",
            s(&box_stl),
            s(&ball),
            "--teeth-a",
            s(&box_stl),
        ],
        vec!["occlusion-map", s(&box_stl), s(&dir.path("none.stl"))],
    ] {
        let out = ist(&bad);
        assert_eq!(code(&out), 2, "{bad:?}: {}", stdout(&out));
        assert!(stderr(&out).starts_with("error: "), "{bad:?}");
    }
    // Far poses: refused at once with the range (1e17 ran for hours, 1e300 wrote `inf`).
    for far in ["1e17 0 0 1 0 0 0", "1e300 0 0 1 0 0 0", "0 -2e9 0 1 0 0 0"] {
        let ply = dir.path("far.ply");
        let out = ist(&[
            "occlusion-map",
            s(&box_stl),
            s(&ball),
            "--pose",
            far,
            "--out-b",
            s(&ply),
        ]);
        assert_eq!(code(&out), 2, "{far}: {}", stdout(&out));
        assert!(
            stderr(&out).contains("beyond the supported"),
            "{far}: {}",
            stderr(&out)
        );
        assert!(!ply.exists());
    }
}

/// `ist splint` between generated arches: a watertight STL that `ist inspect` calls closed
/// and consistently oriented, JSON with the measurements; bad input is a clear error.
#[test]
fn splint_writes_a_closed_wafer_and_refuses_bad_input() {
    let dir = TempDir::new("cli", "splint");
    let (upper, lower) = shapes::arch_pair(2, 10);
    let (a, b) = (dir.path("upper.stl"), dir.path("lower.stl"));
    innersphere::mesh::save_stl(&upper, &a).unwrap();
    innersphere::mesh::save_stl(&lower, &b).unwrap();
    let out = dir.path("splint.stl");
    let r = ist_json(
        &[
            "splint",
            s(&a),
            s(&b),
            "--open",
            "3",
            "--voxel",
            "0.2",
            "-o",
            s(&out),
            "--json",
        ],
        0,
    );
    assert_eq!(r["opened"], 3.0);
    assert!(
        r["watertight"] == true && r["manifold"] == true && r["bodies"] == 1,
        "{r}"
    );
    assert!(r["volume"].as_f64().unwrap() > 0.0);
    let inspect = ist_json(&["inspect", s(&out), "--json"], 0);
    assert_eq!(inspect["watertight"], true, "{inspect}");
    assert_eq!(inspect["winding_consistent"], true);
    assert_eq!(inspect["components"], 1);
    assert_eq!(inspect["triangles"], r["triangles"]);
    assert_eq!(r["fit"], true, "{r}");
    // `-o x.obj` writes OBJ (it wrote STL bytes).
    let obj = dir.path("splint.obj");
    ist_json(
        &[
            "splint",
            s(&a),
            s(&b),
            "--open",
            "3",
            "--voxel",
            "0.2",
            "-o",
            s(&obj),
            "--json",
        ],
        0,
    );
    let text = std::fs::read_to_string(&obj).unwrap();
    assert!(
        text.starts_with("# written by innersphere\nv "),
        "{}",
        &text[..80]
    );
    // `-o x.3mf` writes 3MF: a zip (its local-file magic), the same wafer.
    let three = dir.path("splint.3mf");
    ist_json(
        &[
            "splint",
            s(&a),
            s(&b),
            "--open",
            "3",
            "--voxel",
            "0.2",
            "-o",
            s(&three),
            "--json",
        ],
        0,
    );
    assert!(std::fs::read(&three).unwrap().starts_with(b"PK\x03\x04"));
    // A name that promises another format is refused before the work.
    let o = ist(&["splint", s(&a), s(&b), "-o", s(&dir.path("splint.ply"))]);
    assert_eq!(code(&o), 2);
    assert!(stderr(&o).contains(".3mf"), "{}", stderr(&o));
    // An unfit wafer (at the interlocking bite, no room for the plate: coverage falls short)
    // exits 3, says which guarantee failed, and is not written unless --keep-unfit.
    let unfit = dir.path("unfit.stl");
    let o = ist(&["splint", s(&a), s(&b), "--voxel", "0.2", "-o", s(&unfit)]);
    assert_eq!(code(&o), 3, "{}", stderr(&o));
    assert!(
        stderr(&o).contains("NOT fit to print") && stderr(&o).contains("coverage"),
        "{}",
        stderr(&o)
    );
    assert!(!unfit.exists());
    let o = ist(&[
        "splint",
        s(&a),
        s(&b),
        "--voxel",
        "0.2",
        "-o",
        s(&unfit),
        "--keep-unfit",
    ]);
    assert_eq!(code(&o), 3);
    assert!(unfit.exists());
    let help = stdout(&ist(&["splint", "--help"]));
    assert!(
        help.contains("mm") && help.contains("auto") && help.contains("Exit codes"),
        "{help}"
    );
    for bad in [
        vec!["splint", s(&a), s(&b), "-o", s(&a)],
        vec!["splint", s(&a), s(&b), "--open", "wide", "-o", s(&out)],
        vec!["splint", s(&a), s(&b), "--voxel", "0", "-o", s(&out)],
        vec!["splint", s(&a), s(&b), "--clearance", "nan", "-o", s(&out)],
        vec![
            "splint",
            s(&a),
            s(&b),
            "--pose",
            "nan 0 0 1 0 0 0",
            "-o",
            s(&out),
        ],
        vec!["splint", s(&a), s(&dir.path("none.stl")), "-o", s(&out)],
        vec![
            "splint",
            s(&a),
            s(&b),
            "--pose",
            "0 0 -100 1 0 0 0",
            "-o",
            s(&out),
        ],
        vec!["splint", s(&a), s(&b), "--open", "-50", "-o", s(&out)],
        vec!["splint", s(&a), s(&b), "-o", s(&dir.path("splint.ply"))],
    ] {
        let o = ist(&bad);
        assert_eq!(code(&o), 2, "{bad:?}: {}", stdout(&o));
        assert!(stderr(&o).starts_with("error: "), "{bad:?}: {}", stderr(&o));
    }
}

/// A mesh where a tree is expected (`query`, `replay`): built with the preset and cached in
/// $IST_CACHE; the same answer as the tree `ist build` makes; a second run reads the cache; a
/// truncated entry is rebuilt, never trusted; `--no-cache` writes nothing; two processes
/// building the same meshes at once both succeed and leave one entry per mesh.
#[test]
fn meshes_open_directly_through_the_build_cache() {
    use std::process::Command;
    let dir = fixture("bodies");
    let (box_stl, ball_obj) = (dir.path("box.stl"), dir.path("ball.obj"));
    let (box_t, ball_t) = (dir.path("box-fast.ist"), dir.path("ball-fast.ist"));
    for (m, t) in [(&box_stl, &box_t), (&ball_obj, &ball_t)] {
        ist_json(
            &["build", s(m), "-o", s(t), "--preset", "fast", "--json"],
            0,
        );
    }
    let cache = dir.path("cache");
    let run = |args: &[&str], cache: &Path| {
        Command::new(env!("CARGO_BIN_EXE_ist"))
            .args(args)
            .env("IST_CACHE", cache)
            .output()
            .expect("ist runs")
    };
    let pose = "2.5 0.1 0 1 0 0 0";
    let query = |a: &Path, b: &Path, extra: &[&str]| {
        let mut v = vec!["query", s(a), s(b), "--pose-b", pose, "--json"];
        v.extend_from_slice(extra);
        v.into_iter().map(str::to_string).collect::<Vec<_>>()
    };
    fn args(v: &[String]) -> Vec<&str> {
        v.iter().map(String::as_str).collect()
    }
    let want = ist_json(&args(&query(&box_t, &ball_t, &[])), 0)["distance"].clone();
    let by_mesh = query(&box_stl, &ball_obj, &["--preset", "fast"]);
    // The cache's entries, in its own subfolder (beside its tag).
    let entries = |c: &Path| {
        let mut v: Vec<String> = std::fs::read_dir(c.join("innersphere-trees-v1"))
            .map(|r| {
                r.filter_map(|e| e.ok())
                    .map(|e| e.file_name().to_string_lossy().into_owned())
                    .filter(|n| n != "CACHEDIR.TAG")
                    .collect()
            })
            .unwrap_or_default();
        v.sort();
        v
    };
    for (round, says) in [(0, "built"), (1, "read from the cache")] {
        let out = run(&args(&by_mesh), &cache);
        assert_eq!(code(&out), 0, "{}", stderr(&out));
        let err = stderr(&out);
        assert_eq!(err.matches(says).count(), 2, "round {round}: {err}");
        assert!(err.contains("preset fast"), "{err}");
        let r: Value = serde_json::from_str(&stdout(&out)).unwrap();
        assert_eq!(r["distance"], want, "round {round}");
    }
    assert_eq!(entries(&cache).len(), 2);
    // A mesh and a tree mixed.
    let out = run(
        &args(&query(&box_t, &ball_obj, &["--preset", "fast"])),
        &cache,
    );
    let r: Value = serde_json::from_str(&stdout(&out)).unwrap();
    assert_eq!(r["distance"], want);
    // Truncated entries are rebuilt, and the answer stays.
    for e in entries(&cache) {
        let p = cache.join("innersphere-trees-v1").join(e);
        let bytes = std::fs::read(&p).unwrap();
        std::fs::write(&p, &bytes[..bytes.len() / 3]).unwrap();
    }
    let out = run(&args(&by_mesh), &cache);
    assert_eq!(
        stderr(&out)
            .matches("was not used: it failed the tree file's checks")
            .count(),
        2,
        "{}",
        stderr(&out)
    );
    let r: Value = serde_json::from_str(&stdout(&out)).unwrap();
    assert_eq!(r["distance"], want);
    // Without the recommendation's preset: it says which it chose and why.
    let out = run(&args(&query(&box_stl, &ball_obj, &[])), &cache);
    assert_eq!(code(&out), 0);
    assert!(
        stderr(&out).contains("preset fine, the recommendation"),
        "{}",
        stderr(&out)
    );
    // --no-cache writes nothing.
    let none = dir.path("none");
    let out = run(
        &args(&query(
            &box_stl,
            &ball_obj,
            &["--preset", "fast", "--no-cache"],
        )),
        &none,
    );
    assert_eq!(code(&out), 0);
    assert!(!none.exists());
    // Two processes at once on an empty cache: both succeed, one entry per mesh.
    let racing = dir.path("racing");
    let children: Vec<_> = (0..2)
        .map(|_| {
            Command::new(env!("CARGO_BIN_EXE_ist"))
                .args(args(&by_mesh))
                .env("IST_CACHE", &racing)
                .stdout(std::process::Stdio::piped())
                .stderr(std::process::Stdio::piped())
                .spawn()
                .unwrap()
        })
        .collect();
    for c in children {
        let out = c.wait_with_output().unwrap();
        assert_eq!(code(&out), 0, "{}", stderr(&out));
        let r: Value = serde_json::from_str(&stdout(&out)).unwrap();
        assert_eq!(r["distance"], want);
    }
    assert_eq!(entries(&racing).len(), 2, "{:?}", entries(&racing));
    assert!(entries(&racing)
        .iter()
        .all(|e| e.ends_with(".ist") && !e.starts_with('.')));
    // A cache folder that cannot be made: the command still answers, and says why.
    let blocked = dir.path("box.stl").join("cache");
    let out = run(&args(&by_mesh), &blocked);
    assert_eq!(code(&out), 0, "{}", stderr(&out));
    assert!(stderr(&out).contains("cannot be used"), "{}", stderr(&out));
    let r: Value = serde_json::from_str(&stdout(&out)).unwrap();
    assert_eq!(r["distance"], want);
    // A tree `ist build` writes remembers its mesh (path and content hash); a changed file
    // is told apart.
    let copy = dir.path("copy.stl");
    std::fs::copy(&box_stl, &copy).unwrap();
    let copy_t = dir.path("copy.ist");
    ist_json(
        &[
            "build",
            s(&copy),
            "-o",
            s(&copy_t),
            "--preset",
            "fast",
            "--json",
        ],
        0,
    );
    let src = innersphere::tree::file::load(&copy_t)
        .unwrap()
        .meta
        .source
        .expect("remembered");
    assert_eq!(Path::new(&src.path), copy.canonicalize().unwrap());
    assert_eq!(
        src.hash,
        innersphere::Mesh::load(&copy).unwrap().content_hash()
    );
    assert!(src.load().is_ok());
    std::fs::write(
        &copy,
        std::fs::read_to_string(&box_stl)
            .unwrap()
            .replace("0.6", "0.7"),
    )
    .unwrap();
    assert!(src.load().unwrap_err().to_string().contains("another mesh"));
    // replay takes meshes too.
    let motion = dir.path("m.csv");
    std::fs::write(
        &motion,
        "t,tx,ty,tz,qw,qx,qy,qz\n0,2.5,0.1,0,1,0,0,0\n0.001,2.4,0.1,0,1,0,0,0\n",
    )
    .unwrap();
    let out = run(
        &[
            "replay",
            s(&box_stl),
            s(&ball_obj),
            "--preset",
            "fast",
            "--motion",
            s(&motion),
            "--query",
            "distance",
            "--json",
        ],
        &cache,
    );
    assert_eq!(code(&out), 0, "{}", stderr(&out));
    assert!(stderr(&out).contains("read from the cache"));
}
