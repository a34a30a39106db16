//! Mesh loading, saving and the defect report.
//!
//! Tests on the real data in `../shared/data` are `#[ignore]`d; run them with
//! `cargo test -p innersphere --release --test it -- --include-ignored mesh_io::`.

use innersphere_testkit::data as common;

use std::path::{Path, PathBuf};
use std::time::Instant;

use innersphere::glam::DVec3;
use innersphere::mesh::io::{to_obj_bytes, to_stl_bytes};
use innersphere::mesh::{load, load_bytes, save_obj, save_stl, Format, MeshReport};
use innersphere::{Error, Mesh};
use proptest::prelude::*;

const FORMATS: [Format; 4] = [Format::Stl, Format::Obj, Format::Ply, Format::Off];

fn tmp(name: &str) -> PathBuf {
    Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("mesh_io_{}_{name}", std::process::id()))
}

fn parse(text: &str, format: Format) -> innersphere::Result<Mesh> {
    load_bytes(text.as_bytes(), format, Path::new("test-input"))
}

fn parse_ok(bytes: &[u8], format: Format) -> Mesh {
    match load_bytes(bytes, format, Path::new("test-input")) {
        Ok(m) => m,
        Err(e) => panic!("{format:?} input did not load: {e}"),
    }
}

/// Asserts a parse error (not an invalid-mesh error) whose message contains `needle`.
fn assert_parse_error(result: innersphere::Result<Mesh>, needle: &str) {
    match result {
        Err(Error::Parse { message, .. }) => {
            assert!(
                message.contains(needle),
                "message `{message}` lacks `{needle}`"
            )
        }
        other => panic!("expected a parse error containing `{needle}`, got {other:?}"),
    }
}

/// The 2x2x2 cube centred at the origin, outward, as 12 triangles (welded).
fn cube() -> Mesh {
    let corner = |i: u32| {
        DVec3::new(
            if i & 1 == 0 { -1.0 } else { 1.0 },
            if i & 2 == 0 { -1.0 } else { 1.0 },
            if i & 4 == 0 { -1.0 } else { 1.0 },
        )
    };
    let quads: [[u32; 4]; 6] = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    let soup: Vec<[DVec3; 3]> = quads
        .iter()
        .flat_map(|q| {
            [
                [corner(q[0]), corner(q[1]), corner(q[2])],
                [corner(q[0]), corner(q[2]), corner(q[3])],
            ]
        })
        .collect();
    Mesh::from_soup(&soup)
}

/// A closed UV sphere with irregular (non-f32) coordinates, welded.
fn sphere(n: usize) -> Mesh {
    let p = |i: usize, j: usize| {
        if i == 0 {
            return DVec3::Z;
        }
        if i == n {
            return -DVec3::Z;
        }
        let th = std::f64::consts::PI * i as f64 / n as f64;
        let ph = std::f64::consts::TAU * (j % (2 * n)) as f64 / (2 * n) as f64;
        DVec3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos()) * 1.234_567_890_123
    };
    let mut soup = Vec::new();
    for i in 0..n {
        for j in 0..2 * n {
            let (a, b, c, d) = (p(i, j), p(i + 1, j), p(i + 1, j + 1), p(i, j + 1));
            if i != 0 {
                soup.push([a, b, d]);
            }
            if i != n - 1 {
                soup.push([b, c, d]);
            }
        }
    }
    Mesh::from_soup(&soup)
}

fn round_to_f32(m: &Mesh) -> Mesh {
    let soup: Vec<[DVec3; 3]> = (0..m.triangles.len())
        .map(|t| m.triangle(t).map(|v| v.as_vec3().as_dvec3()))
        .collect();
    Mesh::from_soup(&soup)
}

const CUBE_QUADS_OBJ: &str = "\
# a cube of quads, with texture and normal references
mtllib cube.mtl
o cube
v -1 -1 -1
v 1 -1 -1
v -1 1 -1
v 1 1 -1
v -1 -1 1
v 1 -1 1 # trailing comment
v -1 1 1
v 1 1 1
vt 0 0
vn 0 0 1
usemtl red
s off
f 1/1/1 3/1/1 4/1/1 2/1/1
f 5//1 6//1 8//1 7//1
f 1 2 6 5
f 3 7 8 4
f -8 -4 -2 -6
f 2/1 4/1 8/1 6/1
";

const CUBE_OFF: &str = "\
OFF
# the cube
8 6 12

-1 -1 -1
 1 -1 -1
-1  1 -1
 1  1 -1
-1 -1  1
 1 -1  1
-1  1  1
 1  1  1
4 0 2 3 1
4 4 5 7 6
4 0 1 5 4
4 2 6 7 3
4 0 4 6 2
4 1 3 7 5 255 0 0
";

const CUBE_PLY_ASCII: &str = "\
ply
format ascii 1.0
comment made by hand
element vertex 8
property float x
property float y
property float z
property uchar red
element face 7
property list uchar int vertex_indices
property uchar flags
element edge 1
property int vertex1
property int vertex2
end_header
-1 -1 -1 0
1 -1 -1 0
-1 1 -1 0
1 1 -1 0
-1 -1 1 0
1 -1 1 0
-1 1 1 0
1 1 1 9
4 0 2 3 1 0
4 4 5 7 6 0
4 0 1 5 4 0
4 2 6 7 3 0
3 0 4 6 0
3 0 6 2 0
4 1 3 7 5 0
0 1
";

const CUBE_QUADS: [[u32; 4]; 6] = [
    [0, 2, 3, 1],
    [4, 5, 7, 6],
    [0, 1, 5, 4],
    [2, 6, 7, 3],
    [0, 4, 6, 2],
    [1, 3, 7, 5],
];

/// A binary PLY of the cube: double x/y/z plus a float property, faces as uchar/uint lists.
fn cube_ply_binary(big_endian: bool) -> Vec<u8> {
    let fmt = if big_endian {
        "binary_big_endian"
    } else {
        "binary_little_endian"
    };
    let mut out = format!(
        "ply\r\nformat {fmt} 1.0\r\nelement vertex 8\r\nproperty double x\r\nproperty float confidence\r\n\
         property double y\r\nproperty double z\r\nelement face 6\r\n\
         property list uchar uint vertex_indices\r\nend_header\r\n"
    )
    .into_bytes();
    let f64b = |x: f64| {
        if big_endian {
            x.to_be_bytes()
        } else {
            x.to_le_bytes()
        }
    };
    for i in 0..8u32 {
        let c = |bit: u32| if i & bit == 0 { -1.0 } else { 1.0 };
        out.extend(f64b(c(1)));
        let conf = 0.5f32;
        out.extend(if big_endian {
            conf.to_be_bytes()
        } else {
            conf.to_le_bytes()
        });
        out.extend(f64b(c(2)));
        out.extend(f64b(c(4)));
    }
    for q in CUBE_QUADS {
        out.push(4);
        for i in q {
            out.extend(if big_endian {
                i.to_be_bytes()
            } else {
                i.to_le_bytes()
            });
        }
    }
    out
}

fn ascii_stl(tris: &[[[f64; 3]; 3]]) -> String {
    let mut s = String::from("solid a name with spaces\n");
    for t in tris {
        s += "  facet normal 0 0 0\n    outer loop\n";
        for v in t {
            s += &format!("      vertex {} {} {}\n", v[0], v[1], v[2]);
        }
        s += "    endloop\n  endfacet\n";
    }
    s + "endsolid a name with spaces\n"
}

fn assert_closed_cube(m: &Mesh) {
    let r = m.report();
    assert_eq!((r.vertices, r.triangles, r.components), (8, 12, 1), "{r:?}");
    assert_eq!(
        (
            r.boundary_edges,
            r.nonmanifold_edges,
            r.degenerate_triangles
        ),
        (0, 0, 0)
    );
    assert!(
        r.watertight && r.winding_consistent && r.oriented_closed,
        "{r:?}"
    );
    assert!((r.volume - 8.0).abs() < 1e-12, "volume {}", r.volume);
    assert_eq!((r.bbox_min, r.bbox_max), ([-1.0; 3], [1.0; 3]));
}

// ---------------------------------------------------------------------------------------
// Round trips

#[test]
fn stl_round_trip_rounds_to_f32() {
    let m = sphere(12);
    let path = tmp("sphere.stl");
    save_stl(&m, &path).expect("save");
    let back = load(&path).expect("load");
    assert_eq!(back, round_to_f32(&m));
    let r = back.report();
    assert!(r.watertight && r.winding_consistent && r.components == 1);
    assert!(r.volume > 0.0);
    // The header must not look like ASCII STL.
    let bytes = std::fs::read(&path).expect("read back");
    assert!(!bytes.starts_with(b"solid"));
    assert_eq!(bytes.len(), 84 + 50 * m.triangles.len());
    std::fs::remove_file(path).ok();
}

#[test]
fn obj_round_trip_is_exact() {
    let m = sphere(9);
    let path = tmp("sphere.obj");
    save_obj(&m, &path).expect("save");
    assert_eq!(load(&path).expect("load"), m);
    std::fs::remove_file(path).ok();
}

#[test]
fn gzip_round_trips() {
    let m = sphere(7);
    for name in ["sphere.stl.gz", "sphere.OBJ.GZ"] {
        let path = tmp(name);
        if name.contains(".stl") {
            save_stl(&m, &path).expect("save");
        } else {
            save_obj(&m, &path).expect("save");
        }
        let bytes = std::fs::read(&path).expect("read back");
        assert_eq!(&bytes[..2], &[0x1f, 0x8b], "{name} is not gzip");
        let back = load(&path).expect("load");
        let expected = if name.contains(".stl") {
            round_to_f32(&m)
        } else {
            m.clone()
        };
        assert_eq!(back, expected, "{name}");
        std::fs::remove_file(path).ok();
    }
}

#[test]
fn unwritable_meshes_are_refused() {
    let mut m = cube();
    m.vertices[3].x = 1e300; // finite, but not as f32, and beyond the supported range
    assert!(matches!(to_stl_bytes(&m), Err(Error::InvalidMesh(_))));
    // Neither format writes what no loader would read back.
    assert!(matches!(to_obj_bytes(&m), Err(Error::InvalidMesh(_))));
    m.vertices[3].x = innersphere::mesh::MAX_COORDINATE;
    assert!(to_obj_bytes(&m).is_ok() && to_stl_bytes(&m).is_ok());
    m.vertices[3].x = f64::NAN;
    assert!(matches!(to_obj_bytes(&m), Err(Error::InvalidMesh(_))));
    m.vertices[3].x = 1.0;
    m.triangles[0][0] = 99;
    assert!(matches!(to_obj_bytes(&m), Err(Error::InvalidMesh(_))));
    assert!(matches!(
        save_stl(&m, &tmp("never_written.stl")),
        Err(Error::InvalidMesh(_))
    ));
}

#[test]
fn corrupt_gzip_is_an_error() {
    let path = tmp("corrupt.stl.gz");
    let mut bytes = {
        let p = tmp("ok.stl.gz");
        save_stl(&cube(), &p).expect("save");
        let b = std::fs::read(&p).expect("read");
        std::fs::remove_file(p).ok();
        b
    };
    bytes.truncate(bytes.len() / 2);
    std::fs::write(&path, &bytes).expect("write");
    assert_parse_error(load(&path), "gzip");
    std::fs::write(&path, b"plain text, not gzip").expect("write");
    assert_parse_error(load(&path), "gzip");
    std::fs::remove_file(path).ok();
}

#[test]
fn bad_paths() {
    assert!(matches!(
        load(Path::new("model.3ds")),
        Err(Error::UnsupportedFormat(_))
    ));
    assert!(matches!(
        load(Path::new("model.gz")),
        Err(Error::UnsupportedFormat(_))
    ));
    assert!(matches!(
        load(&tmp("does_not_exist.stl")),
        Err(Error::Io { .. })
    ));
}

// ---------------------------------------------------------------------------------------
// Hand-written files of each format

#[test]
fn ascii_stl_welds_and_accepts_crlf_and_case() {
    let tris = [
        [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        [[1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]],
        // -0.0 is the same point as 0.0.
        [[-0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.5e-3]],
    ];
    let text = ascii_stl(&tris);
    let m = parse(&text, Format::Stl).expect("ascii stl");
    assert_eq!((m.vertices.len(), m.triangles.len()), (5, 3));
    let crlf = text.replace('\n', "\r\n").replace("vertex", "VERTEX");
    assert_eq!(parse(&crlf, Format::Stl).expect("crlf"), m);
    let r = m.report();
    assert_eq!(r.boundary_edges, 5);
    assert!(!r.watertight);
}

#[test]
fn ascii_stl_cube() {
    let c = cube();
    let tris: Vec<[[f64; 3]; 3]> = (0..12)
        .map(|t| c.triangle(t).map(|v| v.to_array()))
        .collect();
    let m = parse(&ascii_stl(&tris), Format::Stl).expect("cube");
    assert_eq!(m, c);
    assert_closed_cube(&m);
}

#[test]
fn ascii_stl_errors() {
    let good = ascii_stl(&[[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]]);
    assert_parse_error(
        parse(
            &good.replace("vertex 1 0 0", "vertex 1 zero 0"),
            Format::Stl,
        ),
        "line 5: `zero` is not a number",
    );
    assert_parse_error(
        parse(&good.replace("vertex 1 0 0\n", ""), Format::Stl),
        "2 vertices",
    );
    let cut = &good[..good.find("endloop").expect("has endloop")];
    assert_parse_error(parse(cut, Format::Stl), "inside a facet");
    assert_parse_error(
        parse(&good.replace("outer", "banana"), Format::Stl),
        "unexpected `banana`",
    );
}

#[test]
fn binary_stl_with_solid_header_is_binary() {
    let m = cube();
    let mut bytes = to_stl_bytes(&m).expect("stl bytes");
    bytes[..20].copy_from_slice(b"solid cube-ish thing");
    assert_eq!(parse_ok(&bytes, Format::Stl), m);
}

#[test]
fn lying_binary_stl_headers_are_errors() {
    // 100 bytes claiming 4e9 triangles, with and without a `solid` header.
    let mut bytes = vec![0u8; 100];
    bytes[80..84].copy_from_slice(&4_000_000_000u32.to_le_bytes());
    assert_parse_error(
        load_bytes(&bytes, Format::Stl, Path::new("x")),
        "claims 4000000000",
    );
    bytes[..5].copy_from_slice(b"solid");
    assert_parse_error(
        load_bytes(&bytes, Format::Stl, Path::new("x")),
        "claims 4000000000",
    );
    // Truncated by one byte, and one byte too long.
    let good = to_stl_bytes(&cube()).expect("stl bytes");
    assert_parse_error(
        load_bytes(&good[..good.len() - 1], Format::Stl, Path::new("x")),
        "truncated",
    );
    let mut long = good.clone();
    long.push(0);
    assert_parse_error(load_bytes(&long, Format::Stl, Path::new("x")), "claims 12");
    // Too short for a header at all.
    assert_parse_error(
        load_bytes(&good[..50], Format::Stl, Path::new("x")),
        "too short",
    );
}

#[test]
fn obj_quads_comments_and_negative_indices() {
    let m = parse(CUBE_QUADS_OBJ, Format::Obj).expect("obj");
    assert_closed_cube(&m);
}

#[test]
fn obj_errors() {
    assert_parse_error(
        parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", Format::Obj),
        "line 4",
    );
    assert_parse_error(
        parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 0\n", Format::Obj),
        "out of range",
    );
    assert_parse_error(
        parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -4\n", Format::Obj),
        "out of range",
    );
    assert_parse_error(
        parse("v 0 0 0\nv 1 0 0\nf 1 2\n", Format::Obj),
        "fewer than 3",
    );
    assert_parse_error(parse("v 0 0\n", Format::Obj), "three coordinates");
    assert_parse_error(
        parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 x 3\n", Format::Obj),
        "bad vertex",
    );
}

#[test]
fn ply_ascii_with_extra_properties_and_elements() {
    let m = parse(CUBE_PLY_ASCII, Format::Ply).expect("ascii ply");
    assert_closed_cube(&m);
}

#[test]
fn ply_binary_both_endians() {
    let le = parse_ok(&cube_ply_binary(false), Format::Ply);
    let be = parse_ok(&cube_ply_binary(true), Format::Ply);
    assert_closed_cube(&le);
    assert_eq!(le, be);
}

#[test]
fn ply_errors() {
    let bin = cube_ply_binary(false);
    assert_parse_error(
        load_bytes(&bin[..bin.len() - 3], Format::Ply, Path::new("x")),
        "end of data",
    );
    let lying =
        String::from_utf8_lossy(&bin).replace("element vertex 8", "element vertex 4000000000");
    assert_parse_error(parse(&lying, Format::Ply), "claims 4000000000");
    assert_parse_error(
        parse(
            &CUBE_PLY_ASCII.replace("4 1 3 7 5 0", "4 1 3 7 8 0"),
            Format::Ply,
        ),
        "vertex 8",
    );
    assert_parse_error(
        parse(
            &CUBE_PLY_ASCII.replace("4 1 3 7 5 0", "4 1 3 7 -5 0"),
            Format::Ply,
        ),
        "not a valid",
    );
    assert_parse_error(
        parse(&CUBE_PLY_ASCII.replace("end_header\n", ""), Format::Ply),
        "header",
    );
    assert_parse_error(
        parse(&CUBE_PLY_ASCII.replace("ascii", "utf8"), Format::Ply),
        "format",
    );
    assert_parse_error(
        parse(
            &CUBE_PLY_ASCII.replace("property float z\n", ""),
            Format::Ply,
        ),
        "z",
    );
    assert_parse_error(parse("plyx\n", Format::Ply), "ply");
}

#[test]
fn off_quads_comments_and_colours() {
    let m = parse(CUBE_OFF, Format::Off).expect("off");
    assert_closed_cube(&m);
    let coff = CUBE_OFF
        .replace("OFF\n", "COFF\n")
        .replace("-1 -1 -1\n", "-1 -1 -1 0.5 0.5 0.5 1\n");
    assert_eq!(parse(&coff, Format::Off).expect("coff"), m);
    let one_line_header = CUBE_OFF.replace("OFF\n# the cube\n8 6 12", "OFF 8 6 12");
    assert_eq!(
        parse(&one_line_header, Format::Off).expect("one-line header"),
        m
    );
}

#[test]
fn off_errors() {
    let lying = CUBE_OFF.replace("8 6 12", "1000000000 6 12");
    assert_parse_error(parse(&lying, Format::Off), "claims 1000000000 vertices");
    let lying = CUBE_OFF.replace("8 6 12", "8 1000000000 12");
    assert_parse_error(parse(&lying, Format::Off), "1000000000 faces");
    let out_of_range = CUBE_OFF.replace("4 1 3 7 5", "4 1 3 7 8");
    assert_parse_error(parse(&out_of_range, Format::Off), "bad vertex index `8`");
    let short_face = CUBE_OFF.replace("4 1 3 7 5 255 0 0", "9 1 3 7 5");
    assert_parse_error(parse(&short_face, Format::Off), "declares 9");
    let truncated = &CUBE_OFF[..CUBE_OFF.find("4 0 2 3 1").expect("has faces")];
    assert_parse_error(parse(truncated, Format::Off), "0 of 6 faces");
    assert_parse_error(parse("4OFF\n1 1 0\n", Format::Off), "unsupported");
    assert_parse_error(parse("OFF BINARY\n", Format::Off), "binary");
    assert_parse_error(parse("PLY\n", Format::Off), "expected `OFF`");
}

#[test]
fn non_finite_coordinates_are_rejected() {
    let stl = ascii_stl(&[[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]])
        .replace("vertex 1 0 0", "vertex nan 0 0");
    assert_parse_error(parse(&stl, Format::Stl), "non-finite");
    let mut bin = to_stl_bytes(&cube()).expect("stl bytes");
    bin[84 + 12..84 + 16].copy_from_slice(&f32::INFINITY.to_le_bytes());
    assert_parse_error(load_bytes(&bin, Format::Stl, Path::new("x")), "non-finite");
    let obj = "v inf 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    assert_parse_error(parse(obj, Format::Obj), "non-finite");
    let off = CUBE_OFF.replace("-1 -1 -1\n", "-1 NaN -1\n");
    assert_parse_error(parse(&off, Format::Off), "non-finite");
    let ply = CUBE_PLY_ASCII.replace("1 1 1 9", "1 -inf 1 9");
    assert_parse_error(parse(&ply, Format::Ply), "non-finite");
    let mut bin = cube_ply_binary(false);
    let at = bin.len() - 6 * 17 - 28; // x of the last vertex
    bin[at..at + 8].copy_from_slice(&f64::NAN.to_le_bytes());
    assert_parse_error(load_bytes(&bin, Format::Ply, Path::new("x")), "non-finite");
}

#[test]
fn empty_inputs_are_errors() {
    for f in FORMATS {
        let r = load_bytes(b"", f, Path::new("empty"));
        assert!(
            matches!(r, Err(Error::Parse { .. } | Error::InvalidMesh(_))),
            "{f:?}: {r:?}"
        );
    }
    let no_triangles = [
        (Format::Stl, "solid empty\nendsolid empty\n"),
        (Format::Obj, "v 0 0 0\nv 1 0 0\nv 0 1 0\n"),
        (Format::Off, "OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n"),
        (
            Format::Ply,
            "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\n\
             property float z\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n",
        ),
    ];
    for (f, text) in no_triangles {
        let r = parse(text, f);
        assert!(matches!(r, Err(Error::InvalidMesh(_))), "{f:?}: {r:?}");
    }
}

#[test]
fn report_serializes_to_json() {
    let r = MeshReport::of(&cube());
    let json = serde_json::to_value(&r).expect("json");
    assert_eq!(json["triangles"], 12);
    assert_eq!(json["watertight"], true);
    assert_eq!(json["bbox_max"], serde_json::json!([1.0, 1.0, 1.0]));
}

// ---------------------------------------------------------------------------------------
// No panics on any input

/// Valid files of every format (binary and ASCII variants) to mutate.
fn samples() -> Vec<(Format, Vec<u8>)> {
    let c = cube();
    let tris: Vec<[[f64; 3]; 3]> = (0..12)
        .map(|t| c.triangle(t).map(|v| v.to_array()))
        .collect();
    vec![
        (Format::Stl, to_stl_bytes(&c).expect("stl")),
        (Format::Stl, ascii_stl(&tris).into_bytes()),
        (Format::Obj, CUBE_QUADS_OBJ.as_bytes().to_vec()),
        (Format::Obj, to_obj_bytes(&c).expect("obj")),
        (Format::Ply, CUBE_PLY_ASCII.as_bytes().to_vec()),
        (Format::Ply, cube_ply_binary(false)),
        (Format::Ply, cube_ply_binary(true)),
        (Format::Off, CUBE_OFF.as_bytes().to_vec()),
    ]
}

fn load_any(bytes: &[u8], format: Format) {
    // Any outcome but a panic (or an abort) is fine; a success must be a valid mesh.
    if let Ok(m) = load_bytes(bytes, format, Path::new("fuzz")) {
        assert!(m.validate().is_ok());
        let _ = m.report();
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..400)) {
        for f in FORMATS {
            load_any(&bytes, f);
        }
    }

    #[test]
    fn random_text_never_panics(
        lines in proptest::collection::vec(
            "(v|f|vertex|facet|OFF|ply|element|property|end_header|[0-9 ./-]){0,6}", 0..24)
    ) {
        let text = lines.join("\n");
        for f in FORMATS {
            load_any(text.as_bytes(), f);
        }
    }

    #[test]
    fn mutated_and_truncated_files_never_panic(
        which in 0usize..8,
        cut in 0.0f64..1.0,
        edits in proptest::collection::vec((0.0f64..1.0, any::<u8>()), 0..6),
        fix_stl_count in any::<bool>(),
    ) {
        let samples = samples();
        let (format, mut bytes) = samples[which % samples.len()].clone();
        for (at, byte) in edits {
            let i = ((bytes.len() as f64 * at) as usize).min(bytes.len() - 1);
            bytes[i] = byte;
        }
        let keep = (bytes.len() as f64 * cut) as usize;
        bytes.truncate(keep.max(1));
        if fix_stl_count && format == Format::Stl && bytes.len() >= 84 {
            // Make the count agree with the length so that the binary path is taken.
            let n = ((bytes.len() - 84) / 50) as u32;
            bytes.truncate(84 + 50 * n as usize);
            bytes[80..84].copy_from_slice(&n.to_le_bytes());
        }
        load_any(&bytes, format);
    }
}

// ---------------------------------------------------------------------------------------
// Real data (../shared/data)

struct Expected {
    file: &'static str,
    v: usize,
    f: usize,
    watertight: bool,
    /// `None` where the data README does not say.
    winding_consistent: Option<bool>,
    boundary: usize,
    nonmanifold: usize,
    components: usize,
    volume: Option<f64>,
    extents: [f64; 3],
}

const fn closed(
    file: &'static str,
    v: usize,
    f: usize,
    components: usize,
    volume: f64,
    extents: [f64; 3],
) -> Expected {
    Expected {
        file,
        v,
        f,
        watertight: true,
        winding_consistent: Some(true),
        boundary: 0,
        nonmanifold: 0,
        components,
        volume: Some(volume),
        extents,
    }
}

const fn open(
    file: &'static str,
    v: usize,
    f: usize,
    boundary: usize,
    components: usize,
    extents: [f64; 3],
) -> Expected {
    Expected {
        file,
        v,
        f,
        watertight: false,
        winding_consistent: None,
        boundary,
        nonmanifold: 0,
        components,
        volume: None,
        extents,
    }
}

/// The table of `shared/data/README.md` (trimesh 5.2.0 after welding). NaN extents: not given.
const EXPECTED: &[Expected] = &[
    closed(
        "jaw/ofj_p26_maxilla_teeth.stl.gz",
        223758,
        447456,
        15,
        7777.1,
        [57.3, 51.5, 21.8],
    ),
    closed(
        "jaw/ofj_p26_mandible_teeth.stl.gz",
        220148,
        440232,
        16,
        7607.1,
        [76.2, 52.2, 24.5],
    ),
    closed(
        "jaw/ofj_p26_tooth03_upper_first_molar.stl",
        20138,
        40272,
        1,
        777.6,
        [10.9, 11.2, 17.4],
    ),
    closed(
        "jaw/ofj_p26_tooth30_lower_first_molar.stl",
        22522,
        45040,
        1,
        845.4,
        [13.6, 11.1, 17.4],
    ),
    closed(
        "classic/bunny_closed_cgal.stl",
        37706,
        75408,
        1,
        0.1992,
        [0.998, 0.987, 0.773],
    ),
    closed(
        "classic/armadillo_closed_43k.stl",
        43243,
        86482,
        1,
        0.06862,
        [0.839, 1.0, 0.763],
    ),
    closed(
        "classic/dragon_closed_50k.stl",
        50000,
        100000,
        1,
        0.4451,
        [2.0, 0.894, 1.411],
    ),
    closed(
        "small/torus_trimesh.stl",
        4350,
        8700,
        1,
        4.918,
        [3.0, 3.0, 1.0],
    ),
    closed(
        "small/knot1_cgal.stl",
        3200,
        6400,
        1,
        0.09517,
        [0.96, 1.0, 0.46],
    ),
    closed(
        "small/eight_genus2_cgal.stl",
        315,
        634,
        1,
        0.04017,
        [0.49, 0.21, 1.0],
    ),
    closed(
        "small/elephant_cgal.stl",
        2775,
        5558,
        1,
        0.04620,
        [0.72, 1.0, 0.60],
    ),
    closed(
        "small/femur_cgal.stl",
        3897,
        7798,
        1,
        0.02027,
        [0.40, 0.34, 1.0],
    ),
    closed(
        "small/teapot_closed_rainbow.stl",
        528,
        1056,
        1,
        0.1093,
        [1.0, 0.65, 0.51],
    ),
    closed(
        "small/dragon_small_rainbow.stl",
        750,
        1496,
        1,
        0.03323,
        [0.72, 1.0, 0.79],
    ),
    closed("small/cube_cgal.stl", 8, 12, 1, 8.0, [2.0, 2.0, 2.0]),
    open(
        "bad/cube_open_two_faces_missing_cgal.stl",
        8,
        10,
        4,
        1,
        [f64::NAN; 3],
    ),
    open(
        "bad/elephant_with_holes_cgal.stl",
        2733,
        4463,
        1353,
        1,
        [f64::NAN; 3],
    ),
    open(
        "bad/chinese_dragon_10kv_small_hole_cgal.stl",
        10000,
        19994,
        6,
        1,
        [61.6, 112.9, 109.3],
    ),
    Expected {
        file: "bad/tetrahedron_inward_cgal.stl",
        v: 4,
        f: 4,
        watertight: true,
        winding_consistent: None,
        boundary: 0,
        nonmanifold: 0,
        components: 1,
        volume: Some(-1.0 / 6.0),
        extents: [f64::NAN; 3],
    },
    open(
        "bad/triangle_soup_trimesh.stl",
        300,
        100,
        300,
        100,
        [f64::NAN; 3],
    ),
];

#[test]
#[ignore = "real data: run with --ignored"]
fn real_files_match_the_data_readme() {
    let mut failures = Vec::new();
    for e in EXPECTED {
        let path = common::data(e.file);
        let mesh = match load(&path) {
            Ok(m) => m,
            Err(err) => {
                failures.push(format!("{}: {err}", e.file));
                continue;
            }
        };
        let r = mesh.report();
        let mut check = |ok: bool, what: String| {
            if !ok {
                failures.push(format!("{}: {what}", e.file));
            }
        };
        check(r.vertices == e.v, format!("V {} != {}", r.vertices, e.v));
        check(r.triangles == e.f, format!("F {} != {}", r.triangles, e.f));
        check(
            r.components == e.components,
            format!("cc {} != {}", r.components, e.components),
        );
        check(
            r.boundary_edges == e.boundary,
            format!("bnd {} != {}", r.boundary_edges, e.boundary),
        );
        check(
            r.nonmanifold_edges == e.nonmanifold,
            format!("nm {} != {}", r.nonmanifold_edges, e.nonmanifold),
        );
        check(
            r.watertight == e.watertight,
            format!("wt {} != {}", r.watertight, e.watertight),
        );
        if let Some(wc) = e.winding_consistent {
            check(
                r.winding_consistent == wc,
                format!("wc {} != {wc}", r.winding_consistent),
            );
        }
        if e.watertight {
            check(
                r.oriented_closed == r.winding_consistent,
                format!(
                    "oriented_closed {} on a manifold closed mesh",
                    r.oriented_closed
                ),
            );
        }
        if let Some(vol) = e.volume {
            check(
                ((r.volume - vol) / vol).abs() <= 1e-3,
                format!("volume {} != {vol}", r.volume),
            );
        }
        for k in 0..3 {
            let ext = r.bbox_max[k] - r.bbox_min[k];
            let want = e.extents[k];
            check(
                want.is_nan() || (ext - want).abs() <= 0.006 * want.max(1.0),
                format!("extent[{k}] {ext} != {want}"),
            );
        }
    }
    assert!(failures.is_empty(), "mismatches:\n{}", failures.join("\n"));
}

#[test]
#[ignore = "real data: run with --ignored"]
fn jaw_arch_loads_and_reports_quickly() {
    let path = common::data("jaw/ofj_p26_maxilla_teeth.stl.gz");
    let t0 = Instant::now();
    let mesh = load(&path).expect("load");
    let t1 = Instant::now();
    let r = mesh.report();
    let t2 = Instant::now();
    eprintln!(
        "maxilla arch ({} triangles): load {:.0} ms, report {:.0} ms",
        r.triangles,
        (t1 - t0).as_secs_f64() * 1e3,
        (t2 - t1).as_secs_f64() * 1e3
    );
    assert!(r.watertight);
    // Generous: the target is well under 0.5 s in release; debug builds are much slower.
    if !cfg!(debug_assertions) {
        assert!(
            (t2 - t0).as_secs_f64() < 3.0,
            "load + report took {:?}",
            t2 - t0
        );
    }
}

#[test]
#[ignore = "real data: run with --ignored"]
fn truncated_real_files_are_errors_not_panics() {
    for rel in [
        "small/torus_trimesh.stl",
        "small/cube_cgal.stl",
        "bad/tetrahedron_inward_cgal.stl",
    ] {
        let bytes = std::fs::read(common::data(rel)).expect("read");
        let full = load_bytes(&bytes, Format::Stl, Path::new(rel)).expect("full file loads");
        assert!(full.validate().is_ok());
        let step = (bytes.len() / 97).max(1);
        for len in (0..bytes.len()).step_by(step).chain([bytes.len() - 1]) {
            let r = load_bytes(&bytes[..len], Format::Stl, Path::new(rel));
            assert!(r.is_err(), "{rel} cut to {len} bytes loaded");
        }
    }
    // A truncated gzip stream.
    let gz = std::fs::read(common::data("jaw/ofj_p26_maxilla_teeth.stl.gz")).expect("read");
    let path = tmp("maxilla_cut.stl.gz");
    std::fs::write(&path, &gz[..gz.len() / 3]).expect("write");
    assert_parse_error(load(&path), "gzip");
    std::fs::remove_file(path).ok();
}
