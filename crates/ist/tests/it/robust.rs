//! Files, outputs and error texts of the command line, on inputs the tests write
//! themselves in a fresh temporary folder: no subcommand overwrites one of its inputs (the
//! same path, another spelling, a hard or symbolic link) and every output is written whole or
//! not at all; answers that are never silently wrong (`replay --query contact --csv`,
//! `--k 0`, `check` against another mesh, `replay --exact` with unrelated meshes); and error
//! texts that say what is wrong (the OS error once, the voxel size blamed for a huge voxel, a
//! tiny quaternion called too small to normalise, `demo` on one mesh twice refused before it
//! builds). docs/RELIABILITY.md, "Files and outputs", lists the same cases.

use crate::support;
use support::{code, ist, s, stderr, stdout, TempDir};

use innersphere::glam::DVec3;
use innersphere::shapes;
use std::path::Path;
use std::process::{Command, Output};

/// Runs `ist args`, asserts exit code `want`, returns stderr.
fn run(args: &[&str], want: i32) -> String {
    let out = ist(args);
    assert_eq!(
        code(&out),
        want,
        "ist {args:?}\nstdout: {}\nstderr: {}",
        stdout(&out),
        stderr(&out)
    );
    stderr(&out)
}

/// `mesh` as an OBJ, written here (coordinates printed in full).
fn write_obj(mesh: &innersphere::Mesh, path: &Path) {
    let mut text = String::new();
    for v in &mesh.vertices {
        text += &format!("v {} {} {}\n", v.x, v.y, v.z);
    }
    for t in &mesh.triangles {
        text += &format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    std::fs::write(path, text).unwrap();
}

/// A motion CSV of B translated along x through `xs`, written here.
fn write_motion(path: &Path, xs: &[f64]) {
    let mut text = String::from("t,tx,ty,tz,qw,qx,qy,qz\n");
    for (i, x) in xs.iter().enumerate() {
        text += &format!("{},{x},0,0,1,0,0,0\n", i as f64 * 1e-3);
    }
    std::fs::write(path, text).unwrap();
}

/// A folder with `box.obj` (the box ±(1, 0.6, 0.4)), `big.obj` (the same box twice as
/// large), `ball.obj` (a unit icosphere), the trees `box.ist` and `ball.ist`, and `m.csv`,
/// the ball moving along x from overlapping the box (frames 0–2) to 1 apart from it
/// (frames 3–4).
fn fixture(name: &str) -> TempDir {
    let dir = TempDir::new("ist-robust", name);
    let cuboid = shapes::cuboid(DVec3::new(1.0, 0.6, 0.4));
    write_obj(&cuboid, &dir.path("box.obj"));
    let mut big = cuboid.clone();
    for v in &mut big.vertices {
        *v *= 2.0;
    }
    write_obj(&big, &dir.path("big.obj"));
    write_obj(&shapes::icosphere(2), &dir.path("ball.obj"));
    for (mesh, tree) in [("box.obj", "box.ist"), ("ball.obj", "ball.ist")] {
        run(
            &[
                "build",
                s(&dir.path(mesh)),
                "-o",
                s(&dir.path(tree)),
                "--resolution",
                "16",
                "-q",
            ],
            0,
        );
    }
    write_motion(&dir.path("m.csv"), &[0.0, 0.5, 1.5, 3.0, 3.5]);
    dir
}

/// Runs `args`, which name `victim` as an output although it is an input: exit code 2, an
/// error that says so, and `victim` exactly as before.
fn refused(args: &[&str], victim: &Path) {
    let before = std::fs::read(victim).unwrap();
    let err = run(args, 2);
    assert!(
        err.contains("refusing to overwrite an input") || err.contains("two outputs are the same"),
        "ist {args:?}: {err}"
    );
    assert!(
        std::fs::read(victim).unwrap() == before,
        "ist {args:?} changed {}",
        victim.display()
    );
}

/// `build -o self.stl self.stl` must not replace the mesh with a tree, nor `export`,
/// `motion -o`/`--labels` and `replay --csv` write onto their inputs: each is refused.
#[test]
fn no_subcommand_overwrites_an_input() {
    let dir = fixture("inputs");
    let (box_obj, box_ist, ball_obj, ball_ist, m) = (
        dir.path("box.obj"),
        dir.path("box.ist"),
        dir.path("ball.obj"),
        dir.path("ball.ist"),
        dir.path("m.csv"),
    );
    refused(&["build", s(&box_obj), "-o", s(&box_obj), "-q"], &box_obj);
    // The same file spelt another way.
    let dotted = dir.0.join(".").join("box.obj");
    refused(&["build", s(&box_obj), "-o", s(&dotted), "-q"], &box_obj);
    #[cfg(unix)]
    {
        // A hard link and a symbolic link to the mesh.
        let hard = dir.path("hard.obj");
        std::fs::hard_link(&box_obj, &hard).unwrap();
        refused(&["build", s(&box_obj), "-o", s(&hard), "-q"], &box_obj);
        let soft = dir.path("soft.obj");
        std::os::unix::fs::symlink(&box_obj, &soft).unwrap();
        refused(&["build", s(&box_obj), "-o", s(&soft), "-q"], &box_obj);
    }
    refused(&["export", s(&box_ist), "-o", s(&box_ist)], &box_ist);
    let motion = |extra: &[&str]| {
        let mut a = vec!["motion", "--a", s(&box_obj), "--b", s(&ball_obj)];
        a.extend_from_slice(extra);
        a.iter().map(|x| x.to_string()).collect::<Vec<_>>()
    };
    let args = motion(&["-o", s(&box_obj)]);
    refused(
        &args.iter().map(String::as_str).collect::<Vec<_>>(),
        &box_obj,
    );
    let out = dir.path("out.csv");
    let args = motion(&["-o", s(&out), "--labels", s(&ball_obj)]);
    refused(
        &args.iter().map(String::as_str).collect::<Vec<_>>(),
        &ball_obj,
    );
    // Two outputs onto one file.
    std::fs::write(&out, "keep").unwrap();
    let args = motion(&["-o", s(&out), "--labels", s(&out)]);
    refused(&args.iter().map(String::as_str).collect::<Vec<_>>(), &out);
    let replay = |csv: &Path| {
        vec![
            "replay".to_string(),
            s(&box_ist).into(),
            s(&ball_ist).into(),
            "--motion".into(),
            s(&m).into(),
            "--exact".into(),
            s(&box_obj).into(),
            s(&ball_obj).into(),
            "--csv".into(),
            s(csv).into(),
        ]
    };
    for victim in [&m, &box_ist, &ball_ist, &box_obj, &ball_obj] {
        let args = replay(victim);
        refused(&args.iter().map(String::as_str).collect::<Vec<_>>(), victim);
    }
    // bench paper: an input inside the output folder under one of the names it writes.
    let paper = dir.path("paper");
    std::fs::create_dir_all(&paper).unwrap();
    let inside = paper.join("ours_vs_paper.csv");
    std::fs::copy(&m, &inside).unwrap();
    let args = [
        "bench",
        "paper",
        "--a",
        s(&box_obj),
        "--b",
        s(&ball_obj),
        "--motion",
        s(&inside),
        "--out",
        s(&paper),
    ];
    refused(&args, &inside);
    assert!(dir.temporaries().is_empty(), "{:?}", dir.temporaries());
}

/// Every output is written through a temporary file renamed into place: an existing output is
/// replaced whole, nothing temporary is left, and an output that cannot be written leaves
/// nothing and names the output (not a temporary file).
#[test]
fn outputs_are_replaced_whole_or_not_at_all() {
    let dir = fixture("atomic");
    let (box_obj, box_ist, ball_ist, m) = (
        dir.path("box.obj"),
        dir.path("box.ist"),
        dir.path("ball.ist"),
        dir.path("m.csv"),
    );
    let tree = dir.path("again.ist");
    std::fs::write(&tree, "an old file, longer than nothing").unwrap();
    run(
        &[
            "build",
            s(&box_obj),
            "-o",
            s(&tree),
            "--resolution",
            "16",
            "-q",
        ],
        0,
    );
    assert!(std::fs::read(&tree).unwrap() == std::fs::read(&box_ist).unwrap());
    let ply = dir.path("spheres.ply");
    run(&["export", s(&box_ist), "-o", s(&ply)], 0);
    assert!(std::fs::read_to_string(&ply).unwrap().starts_with("ply\n"));
    let csv = dir.path("frames.csv");
    run(
        &[
            "replay",
            s(&box_ist),
            s(&ball_ist),
            "--motion",
            s(&m),
            "--csv",
            s(&csv),
        ],
        0,
    );
    assert_eq!(std::fs::read_to_string(&csv).unwrap().lines().count(), 6);
    assert!(dir.temporaries().is_empty(), "{:?}", dir.temporaries());
    // A folder that does not exist: the error names the output and the folder.
    let nowhere = dir.path("no/such/folder/t.ist");
    let err = run(
        &[
            "build",
            s(&box_obj),
            "-o",
            s(&nowhere),
            "--resolution",
            "16",
            "-q",
        ],
        2,
    );
    assert!(err.contains(s(&nowhere)) && !err.contains(".tmp"), "{err}");
    assert!(!nowhere.exists());
}

/// A run whose write fails midway (here: the file size limit, `ulimit -f`, reached with
/// SIGXFSZ ignored, so that the write returns an error) leaves the previous output whole and
/// no temporary file (not an output truncated to the limit). With SIGXFSZ's default
/// action, which kills the process in the middle of the write (an interrupted run), the
/// previous output is whole too (only a hidden temporary file may stay behind).
#[cfg(unix)]
#[test]
fn a_failed_or_interrupted_write_leaves_the_old_output_whole() {
    use std::os::unix::process::CommandExt;
    let dir = fixture("failed-write");
    let (box_obj, box_ist, ball_ist) = (
        dir.path("box.obj"),
        dir.path("box.ist"),
        dir.path("ball.ist"),
    );
    let limit = 4096;
    let limited = |args: &[&str], ignore: bool| -> Output {
        let mut c = Command::new(env!("CARGO_BIN_EXE_ist"));
        c.args(args);
        // SAFETY: async-signal-safe libc calls only, between fork and exec.
        unsafe {
            c.pre_exec(move || {
                let lim = libc::rlimit {
                    rlim_cur: limit,
                    rlim_max: limit,
                };
                if libc::setrlimit(libc::RLIMIT_FSIZE, &lim) != 0 {
                    return Err(std::io::Error::last_os_error());
                }
                if ignore {
                    libc::signal(libc::SIGXFSZ, libc::SIG_IGN);
                }
                Ok(())
            });
        }
        c.output().expect("ist runs")
    };
    let old = std::fs::read(&ball_ist).unwrap();
    assert!(std::fs::read(&box_ist).unwrap().len() > 2 * limit as usize);
    let out_tree = dir.path("out.ist");
    let out_ply = dir.path("out.ply");
    for ignore in [true, false] {
        std::fs::write(&out_tree, &old).unwrap();
        std::fs::write(&out_ply, &old).unwrap();
        let runs = [
            vec![
                "build",
                s(&box_obj),
                "-o",
                s(&out_tree),
                "--resolution",
                "16",
                "-q",
            ],
            vec!["export", s(&box_ist), "-o", s(&out_ply)],
        ];
        for args in &runs {
            let out = limited(args, ignore);
            assert_ne!(out.status.code(), Some(0), "ist {args:?}");
            if ignore {
                assert_eq!(code(&out), 2, "ist {args:?}: {}", stderr(&out));
                let e = std::io::Error::from_raw_os_error(libc::EFBIG).to_string();
                assert!(stderr(&out).contains(&e), "ist {args:?}: {}", stderr(&out));
            }
        }
        for p in [&out_tree, &out_ply] {
            let now = std::fs::read(p).unwrap();
            assert!(
                now == old,
                "SIGXFSZ ignored: {ignore}: {} is {} bytes, was {}",
                p.display(),
                now.len(),
                old.len()
            );
        }
        if ignore {
            assert!(dir.temporaries().is_empty(), "{:?}", dir.temporaries());
        }
    }
}

/// The CSV cells of `column`.
fn column(csv: &str, name: &str) -> Vec<String> {
    let mut lines = csv.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let i = head
        .iter()
        .position(|h| *h == name)
        .unwrap_or_else(|| panic!("no column {name} in {head:?}"));
    lines
        .map(|l| l.split(',').nth(i).unwrap().to_string())
        .collect()
}

/// `replay --query contact --csv` writes the contact answer of every frame, not
/// `distance=0,contact=false`: each kind writes its own answer.
#[test]
fn replay_csv_rows_hold_each_kinds_own_answer() {
    let dir = fixture("replay-csv");
    let (box_ist, ball_ist, m, csv) = (
        dir.path("box.ist"),
        dir.path("ball.ist"),
        dir.path("m.csv"),
        dir.path("rows.csv"),
    );
    let overlapping = [true, true, true, false, false];
    for kind in ["contact", "multipoint", "penetration", "distance"] {
        run(
            &[
                "replay",
                s(&box_ist),
                s(&ball_ist),
                "--motion",
                s(&m),
                "--query",
                kind,
                "--csv",
                s(&csv),
            ],
            0,
        );
        let text = std::fs::read_to_string(&csv).unwrap();
        let head = text.lines().next().unwrap();
        // Only the kind that ran has answer columns.
        for other in ["contact", "multipoint", "penetration", "distance"] {
            let has = head.split(',').any(|h| h == format!("{other}_in_contact"));
            assert_eq!(has, other == kind, "{kind}: {head}");
        }
        let verdict = column(&text, &format!("{kind}_in_contact"));
        for (i, &want) in overlapping.iter().enumerate() {
            assert_eq!(verdict[i], want.to_string(), "{kind} frame {i}: {text}");
        }
    }
}

/// `query --query multipoint --k 0` must not say "separated by at least inf" for
/// overlapping bodies: k = 0 is refused (and in `replay`).
#[test]
fn k_zero_is_refused() {
    let dir = fixture("k0");
    let (box_ist, ball_ist, m) = (dir.path("box.ist"), dir.path("ball.ist"), dir.path("m.csv"));
    let err = run(
        &[
            "query",
            s(&box_ist),
            s(&ball_ist),
            "--query",
            "multipoint",
            "--k",
            "0",
        ],
        2,
    );
    assert!(err.contains("--k must be at least 1"), "{err}");
    let err = run(
        &[
            "replay",
            s(&box_ist),
            s(&ball_ist),
            "--motion",
            s(&m),
            "--k",
            "0",
        ],
        2,
    );
    assert!(err.contains("--k must be at least 1"), "{err}");
}

/// `check --mesh OTHER TREE` is not ok for a tree inside a larger mesh: a mesh whose
/// bounding box or volume is not the tree's source's is an error. The same mesh in another
/// format (here an ASCII STL) passes.
#[test]
fn check_refuses_a_mesh_the_tree_was_not_built_from() {
    let dir = fixture("check");
    let (box_ist, big_obj, ball_obj) = (
        dir.path("box.ist"),
        dir.path("big.obj"),
        dir.path("ball.obj"),
    );
    for other in [&big_obj, &ball_obj] {
        let err = run(&["check", s(&box_ist), "--mesh", s(other)], 2);
        assert!(
            err.contains("not the mesh the tree was built from") && err.contains("bounding box"),
            "{err}"
        );
    }
    // The box as an ASCII STL with f32-rounded coordinates.
    let m = shapes::cuboid(DVec3::new(1.0, 0.6, 0.4));
    let mut text = String::from("solid box\n");
    for t in 0..m.triangles.len() {
        text += "facet normal 0 0 0\nouter loop\n";
        for v in m.triangle(t) {
            text += &format!("vertex {} {} {}\n", v.x as f32, v.y as f32, v.z as f32);
        }
        text += "endloop\nendfacet\n";
    }
    text += "endsolid box\n";
    let stl = dir.path("box.stl");
    std::fs::write(&stl, text).unwrap();
    let out = ist(&["check", s(&box_ist), "--mesh", s(&stl)]);
    assert_eq!(code(&out), 0, "{}", stderr(&out));
    assert!(stdout(&out).starts_with("ok: "));
}

/// `replay --exact` with meshes that are not the trees' own warns (and runs); with the
/// right meshes it does not.
#[test]
fn replay_exact_with_unrelated_meshes_warns() {
    let dir = fixture("exact");
    let (box_ist, ball_ist, box_obj, ball_obj, big_obj, m) = (
        dir.path("box.ist"),
        dir.path("ball.ist"),
        dir.path("box.obj"),
        dir.path("ball.obj"),
        dir.path("big.obj"),
        dir.path("m.csv"),
    );
    let replay = |a: &Path, b: &Path| {
        run(
            &[
                "replay",
                s(&box_ist),
                s(&ball_ist),
                "--motion",
                s(&m),
                "--query",
                "distance",
                "--exact",
                s(a),
                s(b),
            ],
            0,
        )
    };
    let err = replay(&box_obj, &ball_obj);
    assert!(!err.contains("warning"), "{err}");
    let err = replay(&big_obj, &ball_obj);
    assert!(
        err.contains("warning: --exact")
            && err.contains("big.obj is not the mesh")
            && err.contains("box.ist"),
        "{err}"
    );
    // Swapped meshes: both warned about.
    let err = replay(&ball_obj, &box_obj);
    assert_eq!(err.matches("warning: --exact").count(), 2, "{err}");
}

/// The OS error of a missing input appears once, in every subcommand.
#[test]
fn a_missing_input_is_named_once_with_its_os_error_once() {
    let dir = fixture("missing");
    let (box_obj, box_ist, m) = (dir.path("box.obj"), dir.path("box.ist"), dir.path("m.csv"));
    let nope_mesh = dir.path("nope.stl");
    let nope_tree = dir.path("nope.ist");
    let nope_csv = dir.path("nope.csv");
    let out_ist = dir.path("x.ist");
    let out_csv = dir.path("x.csv");
    let cases: Vec<Vec<&str>> = vec![
        vec!["build", s(&nope_mesh), "-o", s(&out_ist)],
        vec!["inspect", s(&nope_mesh)],
        vec!["check", s(&nope_tree), "--mesh", s(&box_obj)],
        vec!["check", s(&box_ist), "--mesh", s(&nope_mesh)],
        vec!["export", s(&nope_tree)],
        vec!["query", s(&nope_tree), s(&box_ist)],
        vec![
            "motion",
            "--a",
            s(&nope_mesh),
            "--b",
            s(&box_obj),
            "-o",
            s(&out_csv),
        ],
        vec!["replay", s(&box_ist), s(&box_ist), "--motion", s(&nope_csv)],
        vec![
            "replay",
            s(&box_ist),
            s(&box_ist),
            "--motion",
            s(&m),
            "--exact",
            s(&nope_mesh),
            s(&box_obj),
        ],
        vec!["demo", "--a", s(&nope_mesh), "--b", s(&box_obj)],
        vec!["bench", "build", s(&nope_mesh)],
    ];
    let os = std::io::Error::from_raw_os_error(2).to_string();
    for args in cases {
        let err = run(&args, 2);
        assert_eq!(err.matches(&os).count(), 1, "ist {args:?}: {err}");
        assert!(err.contains("nope."), "ist {args:?}: {err}");
    }
}

/// A voxel larger than the mesh is blamed on the voxel size, not reported as "minimum radius
/// too large" (with the minimum radius 0).
#[test]
fn a_huge_voxel_blames_the_voxel_size() {
    let dir = fixture("voxel");
    let err = run(
        &[
            "build",
            s(&dir.path("box.obj")),
            "-o",
            s(&dir.path("t.ist")),
            "--voxel-size",
            "1e300",
            "-q",
        ],
        2,
    );
    assert!(
        err.contains("voxel size 1e300") && err.contains("too large for this mesh"),
        "{err}"
    );
    assert!(!err.contains("minimum radius"), "{err}");
    assert!(!dir.path("t.ist").exists());
}

/// A quaternion of length 1e-30 is too small to normalise (not "zero").
#[test]
fn a_tiny_quaternion_is_too_small_to_normalise() {
    let dir = fixture("quat");
    let t = dir.path("box.ist");
    let err = run(&["query", s(&t), s(&t), "--pose-b", "0 0 0 1e-30 0 0 0"], 2);
    assert!(err.contains("too small to normalise"), "{err}");
    assert!(err.contains("1e-30"), "{err}");
}

/// `demo --a X --b X`: the bodies coincide. The demo makes its motion from the meshes first,
/// so a pair that admits none fails before any build, and the generator says why: the same
/// mesh twice (one file, or a copy). With `--seconds 0` (build only) it is fine.
#[test]
fn demo_refuses_one_mesh_twice_before_building() {
    let dir = fixture("demo");
    let (box_obj, copy) = (dir.path("box.obj"), dir.path("copy.obj"));
    std::fs::copy(&box_obj, &copy).unwrap();
    for b in [&box_obj, &copy] {
        let err = run(
            &[
                "demo",
                "--a",
                s(&box_obj),
                "--b",
                s(b),
                "--resolution",
                "16",
            ],
            2,
        );
        assert!(err.contains("the same mesh"), "{err}");
        assert!(!err.contains("never touch"), "{err}");
        // Refused before building: nothing about trees or stages was printed.
        assert!(!err.contains("packing"), "{err}");
    }
    // `ist motion` says the same.
    let err = run(
        &[
            "motion",
            "--a",
            s(&box_obj),
            "--b",
            s(&copy),
            "-o",
            s(&dir.path("m2.csv")),
        ],
        2,
    );
    assert!(err.contains("the same mesh"), "{err}");
    run(
        &[
            "demo",
            "--a",
            s(&box_obj),
            "--b",
            s(&box_obj),
            "--resolution",
            "16",
            "--seconds",
            "0",
            "-q",
        ],
        0,
    );
}

/// Output names are honoured or refused before any work: a contact map named `.ply.gz` is
/// gzip, one named `.stl` is refused (it would hold PLY bytes), a tree named `.stl` is
/// refused, two spellings of one new path are one output, and a missing folder is found
/// before the meshes are read.
#[test]
fn output_names_are_honoured_or_refused_before_the_work() {
    let dir = fixture("names");
    let (box_obj, ball_obj, box_ist) = (
        dir.path("box.obj"),
        dir.path("ball.obj"),
        dir.path("box.ist"),
    );
    let map = |a: &Path, b: &Path| {
        vec![
            "occlusion-map".to_string(),
            s(&box_obj).into(),
            s(&ball_obj).into(),
            "--out-a".into(),
            s(a).into(),
            "--out-b".into(),
            s(b).into(),
        ]
    };
    let go =
        |v: Vec<String>, want: i32| run(&v.iter().map(String::as_str).collect::<Vec<_>>(), want);
    // `.ply.gz` is written compressed, and reads back as the same PLY.
    let (gz, plain) = (dir.path("a.ply.gz"), dir.path("b.ply"));
    go(map(&gz, &plain), 0);
    let bytes = std::fs::read(&gz).unwrap();
    assert_eq!(&bytes[..2], &[0x1f, 0x8b], "a .ply.gz contact map is gzip");
    // A contact map named as STL, a tree named as STL: refused, nothing written.
    let stl = dir.path("map.stl");
    let e = go(map(&stl, &dir.path("b2.ply")), 2);
    assert!(e.contains(".ply, .ply.gz"), "{e}");
    assert!(!stl.exists());
    let e = run(
        &["build", s(&box_obj), "-o", s(&dir.path("t.stl")), "-q"],
        2,
    );
    assert!(e.contains("tree file") && e.contains(".ist"), "{e}");
    let e = run(
        &[
            "export",
            s(&box_ist),
            "--format",
            "csv",
            "-o",
            s(&dir.path("s.ply")),
        ],
        2,
    );
    assert!(e.contains(".csv"), "{e}");
    // Two spellings of one path that does not exist yet.
    std::fs::create_dir_all(dir.path("out")).unwrap();
    let one = dir.path("out").join("q.ply");
    let other = dir
        .0
        .join(".")
        .join("out")
        .join("..")
        .join("out")
        .join("q.ply");
    let e = go(map(&one, &other), 2);
    assert!(e.contains("two outputs are the same"), "{e}");
    assert!(!one.exists());
    // A missing folder: refused at once, before the meshes are loaded.
    let missing = dir.path("nowhere").join("q.ply");
    let start = std::time::Instant::now();
    let e = go(map(&missing, &dir.path("b3.ply")), 2);
    assert!(e.contains("does not exist"), "{e}");
    assert!(start.elapsed().as_secs_f64() < 30.0);
    let e = run(
        &[
            "motion",
            "--a",
            s(&box_obj),
            "--b",
            s(&ball_obj),
            "-o",
            s(&dir.path("gone").join("m.csv")),
        ],
        2,
    );
    assert!(e.contains("does not exist"), "{e}");
}
