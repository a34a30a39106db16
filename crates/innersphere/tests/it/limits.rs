//! The accepted ranges (`docs/RELIABILITY.md`, "Limits"): coordinates beyond ±1e9 (or
//! non-finite) are refused by every loader with their line, triangle or vertex, and by the
//! build and the writers; meshes too small or too far from the origin for the tree's `f32`
//! are refused by the build; a tree that a build returns always reads back from its file.
//! The memory bounds of the readers are `tests/limits_memory.rs`.

use std::path::{Path, PathBuf};

use innersphere::build::{build_tree, BuildOptions, Resolution, MIN_EXTENT};
use innersphere::glam::DVec3;
use innersphere::mesh::{load, load_bytes, Format, MAX_COORDINATE};
use innersphere::progress::Silent;
use innersphere::tree::file;
use innersphere::{shapes, Error, Mesh, SphereTree};
use proptest::prelude::*;

fn tmp(name: &str) -> PathBuf {
    Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("limits_{}_{name}", std::process::id()))
}

fn opts(cells: u32) -> BuildOptions {
    BuildOptions {
        resolution: Resolution::Cells(cells),
        ..Default::default()
    }
}

/// The corners of a tetrahedron with one coordinate `x` given as text, and its faces.
const TETRA_FACES: [[usize; 3]; 4] = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];

fn tetra_corners(x: &str) -> [[String; 3]; 4] {
    let s = |v: &str| v.to_string();
    [
        [s("0"), s("0"), s("0")],
        [s(x), s("0"), s("0")],
        [s("0"), s("1"), s("0")],
        [s("0"), s("0"), s("1")],
    ]
}

/// The tetrahedron in `format` (ASCII variants) with `x` as the x coordinate of corner 1.
fn tetra_text(format: Format, x: &str) -> String {
    let c = tetra_corners(x);
    let v = |i: usize| c[i].join(" ");
    match format {
        Format::Stl => {
            let mut s = String::from("solid t\n");
            for f in TETRA_FACES {
                s += "facet normal 0 0 0\nouter loop\n";
                for i in f {
                    s += &format!("vertex {}\n", v(i));
                }
                s += "endloop\nendfacet\n";
            }
            s + "endsolid t\n"
        }
        Format::Obj => {
            let mut s: String = (0..4).map(|i| format!("v {}\n", v(i))).collect();
            for [a, b, c] in TETRA_FACES {
                s += &format!("f {} {} {}\n", a + 1, b + 1, c + 1);
            }
            s
        }
        Format::Off => {
            let mut s = String::from("OFF\n4 4 0\n");
            s += &(0..4).map(|i| format!("{}\n", v(i))).collect::<String>();
            for [a, b, c] in TETRA_FACES {
                s += &format!("3 {a} {b} {c}\n");
            }
            s
        }
        Format::Ply => {
            let mut s = String::from(
                "ply\nformat ascii 1.0\nelement vertex 4\nproperty double x\nproperty double y\n\
                 property double z\nelement face 4\nproperty list uchar int vertex_indices\nend_header\n",
            );
            s += &(0..4).map(|i| format!("{}\n", v(i))).collect::<String>();
            for [a, b, c] in TETRA_FACES {
                s += &format!("3 {a} {b} {c}\n");
            }
            s
        }
    }
}

/// The line of corner 1's x coordinate in [`tetra_text`].
fn tetra_line(format: Format) -> usize {
    match format {
        Format::Stl => 6, // solid, facet, outer loop, vertices 0, 2, 1 (the first face)
        Format::Obj => 2,
        Format::Off => 4,
        Format::Ply => 11, // nine header lines, then corners 0 and 1
    }
}

fn parse_message(r: innersphere::Result<Mesh>) -> String {
    match r {
        Err(Error::Parse { message, .. }) => message,
        other => panic!("expected a parse error, got {other:?}"),
    }
}

#[test]
fn coordinates_beyond_the_range_are_refused_with_their_line() {
    let formats = [Format::Stl, Format::Obj, Format::Off, Format::Ply];
    // Beyond f32 (1e39, 1e300), beyond the supported range but finite in f32 (2e9, -1e10),
    // and non-finite spellings that Rust's float parser accepts.
    for bad in ["1e39", "1e300", "-1e300", "2e9", "-1e10"] {
        for f in formats {
            let m = parse_message(load_bytes(tetra_text(f, bad).as_bytes(), f, Path::new("t")));
            let line = format!("line {}", tetra_line(f));
            assert!(
                m.contains(&line) && m.contains(bad) && m.contains("1e9"),
                "{f:?} {bad}: `{m}` should name {line}, the value and the range"
            );
        }
    }
    for bad in ["nan", "NaN", "inf", "-Infinity", "+inf", "1e400"] {
        for f in formats {
            let m = parse_message(load_bytes(tetra_text(f, bad).as_bytes(), f, Path::new("t")));
            assert!(
                m.contains(&format!("line {}", tetra_line(f))) && m.contains("non-finite"),
                "{f:?} {bad}: {m}"
            );
        }
    }
    // The bounds themselves are accepted.
    for ok in ["1e9", "-1e9", "1000000000.0"] {
        for f in formats {
            let m = load_bytes(tetra_text(f, ok).as_bytes(), f, Path::new("t"))
                .unwrap_or_else(|e| panic!("{f:?} {ok}: {e}"));
            let r = m.report();
            assert!(r.area.is_finite() && r.volume.is_finite(), "{r:?}");
        }
    }
}

#[test]
fn binary_coordinates_beyond_the_range_name_their_triangle_or_vertex() {
    let m = Mesh {
        vertices: tetra_corners("1")
            .map(|c| {
                DVec3::new(
                    c[0].parse().unwrap(),
                    c[1].parse().unwrap(),
                    c[2].parse().unwrap(),
                )
            })
            .to_vec(),
        triangles: TETRA_FACES.map(|f| f.map(|i| i as u32)).to_vec(),
    };
    let stl = innersphere::mesh::io::to_stl_bytes(&m).unwrap();
    for bad in [3.0e38f32, 2e9, -1e12, f32::INFINITY, f32::NAN] {
        let mut b = stl.clone();
        // Triangle 2, corner 1, y.
        let at = 84 + 50 * 2 + 12 + 12 + 4;
        b[at..at + 4].copy_from_slice(&bad.to_le_bytes());
        let msg = parse_message(load_bytes(&b, Format::Stl, Path::new("b")));
        assert!(
            msg.contains("triangle 2") && msg.contains("corner 1") && msg.contains("y coordinate"),
            "{bad}: {msg}"
        );
    }
    let mut ply = String::from(
        "ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty double x\n\
         property double y\nproperty double z\nelement face 4\n\
         property list uchar int vertex_indices\nend_header\n",
    )
    .into_bytes();
    for (i, v) in m.vertices.iter().enumerate() {
        let z = if i == 3 { 1e300 } else { v.z };
        for x in [v.x, v.y, z] {
            ply.extend(x.to_le_bytes());
        }
    }
    for f in TETRA_FACES {
        ply.push(3);
        for i in f {
            ply.extend((i as i32).to_le_bytes());
        }
    }
    let msg = parse_message(load_bytes(&ply, Format::Ply, Path::new("b")));
    assert!(
        msg.contains("vertex 3") && msg.contains("z coordinate 1e300"),
        "{msg}"
    );
}

#[test]
fn a_file_beyond_the_range_does_not_load() {
    // What `ist inspect` and `ist build` load: refused with the file, line and range,
    // instead of a report with `null` area and volume.
    let path = tmp("big.stl");
    std::fs::write(&path, tetra_text(Format::Stl, "1e300")).unwrap();
    let e = load(&path).unwrap_err().to_string();
    std::fs::remove_file(&path).ok();
    assert!(
        e.contains("big.stl") && e.contains("line 6") && e.contains("1e9"),
        "{e}"
    );
}

#[test]
fn the_build_and_the_writers_refuse_meshes_beyond_the_range() {
    let mut m = shapes::cuboid(DVec3::ONE);
    m.vertices[5].y = 1e39;
    for r in [
        build_tree(&m, &opts(16), &Silent).map(drop),
        innersphere::mesh::io::to_obj_bytes(&m).map(drop),
        m.validate(),
    ] {
        match r {
            Err(Error::InvalidMesh(msg)) => assert!(
                msg.contains("vertex 5") && msg.contains("y coordinate") && msg.contains("1e9"),
                "{msg}"
            ),
            other => panic!("expected an invalid mesh, got {other:?}"),
        }
    }
}

#[test]
fn the_build_refuses_meshes_too_small_or_too_far_for_f32() {
    let cube = |half: f64, offset: f64| {
        let mut m = shapes::cuboid(DVec3::splat(half));
        for v in &mut m.vertices {
            *v += DVec3::new(offset, 0.0, 0.0);
        }
        m
    };
    let err = |m: &Mesh| match build_tree(m, &opts(16), &Silent) {
        Err(Error::InvalidMesh(msg)) => msg,
        other => panic!("expected an invalid mesh, got {:?}", other.map(|t| t.1)),
    };
    let small = err(&cube(MIN_EXTENT / 4.0, 0.0));
    assert!(small.contains("less than the supported 1e-6"), "{small}");
    // 1 unit across at 1e8 from the origin: f32 there is spaced 8 units apart.
    let far = err(&cube(0.5, 1e8));
    assert!(
        far.contains("spaced 8e0") && far.contains("voxel size"),
        "{far}"
    );
    // At 1e5, f32 is spaced 1/128: within a quarter voxel (1/64), but more than 1/32 of
    // it: a warning.
    let (_, report) = build_tree(&cube(0.5, 1e5), &opts(16), &Silent).unwrap();
    assert!(
        report.warnings.iter().any(|w| w.contains("f32")),
        "{:?}",
        report.warnings
    );
    // The extremes of the accepted range build: 2e9 across, and 1e-6 across.
    for m in [cube(MAX_COORDINATE, 0.0), cube(MIN_EXTENT / 2.0, 0.0)] {
        let (tree, report) = build_tree(&m, &opts(16), &Silent).unwrap();
        assert!(report.warnings.iter().all(|w| !w.contains("f32")));
        file::from_bytes(&file::to_checked_bytes(&tree).unwrap()).unwrap();
    }
}

#[test]
fn the_tree_writer_refuses_what_the_reader_would_refuse() {
    let tree = SphereTree::build(&shapes::icosphere(2), &opts(12)).unwrap();
    let leaf = tree.leaves().next().unwrap();
    let mut broken: Vec<(&str, SphereTree)> = Vec::new();
    let mut t = tree.clone();
    t.r[leaf] = f32::INFINITY;
    broken.push(("non-finite", t));
    let mut t = tree.clone();
    t.x[0] = f32::NAN;
    broken.push(("non-finite", t));
    let mut t = tree.clone();
    t.meta.mesh_volume = f64::NAN;
    broken.push(("mesh_volume", t));
    let mut t = tree.clone();
    t.meta.bbox_max[2] = f64::INFINITY;
    broken.push(("bbox_max", t));
    for (what, t) in broken {
        // The unchecked bytes are refused by the reader ...
        assert!(file::from_bytes(&file::to_bytes(&t)).is_err(), "{what}");
        // ... so the writer refuses them, and writes no file.
        let path = tmp("broken.ist");
        match t.save(&path) {
            Err(Error::CorruptTree(m)) => assert!(m.contains(what), "{what}: {m}"),
            other => panic!("{what}: expected a refusal, got {other:?}"),
        }
        assert!(!path.exists(), "{what}: a file was written");
        assert!(file::to_checked_bytes(&t).is_err());
    }
    let path = tmp("good.ist");
    tree.save(&path).unwrap();
    assert_eq!(SphereTree::load(&path).unwrap(), tree);
    std::fs::remove_file(path).ok();
}

/// A small closed mesh of the given kind, with half-sizes in `half`.
fn small_mesh(kind: usize, half: DVec3) -> Mesh {
    match kind {
        0 => shapes::cuboid(half),
        1 => shapes::ellipsoid(half, 1),
        _ => {
            let mut m = shapes::cuboid(half);
            // A wedge: the top face pulled in along x (still closed and convex).
            for v in &mut m.vertices {
                if v.z > 0.0 {
                    v.x *= 0.3;
                }
            }
            m
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(96))]

    /// A build never returns a tree that its own file reader rejects: random small meshes at
    /// scales from 1e-7 to 1e300 and offsets up to 1e5 times their size either build a tree
    /// that survives `to_bytes` → `from_bytes` and `validate_structure`, or are a clear error;
    /// within the accepted range (|coordinate| ≤ 1e9, extent ≥ 1e-6, near the origin) they
    /// always build.
    #[test]
    fn builds_always_read_back(
        kind in 0usize..3,
        half in (0.5f64..1.0, 0.5f64..1.0, 0.5f64..1.0),
        log_scale in prop_oneof![3 => -6.0f64..9.0, 2 => 9.0f64..300.0, 1 => -7.0f64..-6.0],
        offset_size in prop_oneof![Just(0.0), Just(3.0), Just(1e3), Just(1e5)],
        direction in (-1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0),
        cells in 8u32..17,
    ) {
        let scale = 10f64.powf(log_scale);
        let offset = DVec3::from(direction) * offset_size * scale;
        let mut m = small_mesh(kind, DVec3::from(half));
        for v in &mut m.vertices {
            *v = *v * scale + offset;
        }
        let (lo, hi) = m.bbox();
        let within = lo.abs().max(hi.abs()).max_element() <= MAX_COORDINATE
            && (hi - lo).max_element() >= MIN_EXTENT
            && offset_size <= 3.0;
        match build_tree(&m, &opts(cells), &Silent) {
            Ok((tree, _)) => {
                let bytes = file::to_bytes(&tree);
                let back = file::from_bytes(&bytes);
                prop_assert!(back.is_ok(), "scale {scale:e}: {:?}", back.err());
                let back = back.unwrap();
                prop_assert!(back.validate_structure().is_ok());
                prop_assert_eq!(file::to_checked_bytes(&back).unwrap(), bytes);
            }
            Err(e @ (Error::InvalidMesh(_) | Error::InvalidOption(_))) => {
                prop_assert!(!within, "scale {scale:e}, offset {offset:?}: {e}");
            }
            Err(e) => prop_assert!(false, "unexpected error kind: {e}"),
        }
    }
}
