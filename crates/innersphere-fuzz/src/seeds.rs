//! Generated seed inputs per target: small valid files of every format and variant (and a
//! few near misses), made here from generated shapes so that no data file is needed. The
//! fuzzer starts from them (`examples/write_seeds.rs` writes them into `fuzz/corpus/`), and
//! the corpus test replays them on every run.

use std::fmt::Write as _;
use std::io::Write as _;

use glam::{DQuat, DVec3};
use innersphere::mesh::io::{to_obj_bytes, to_stl_bytes};
use innersphere::shapes;
use innersphere::tree::{file, SphereTree, TreeMeta, NO_PARENT};
use innersphere::{Mesh, Pose};
use innersphere_dental::contact_map::Teeth;
use innersphere_motion::{Frame, Motion};

/// A tetrahedron, outward facing.
pub fn tetrahedron() -> Mesh {
    Mesh {
        vertices: vec![
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
            DVec3::new(0.0, 0.0, 1.0),
        ],
        triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
    }
}

fn meshes() -> Vec<Mesh> {
    vec![
        tetrahedron(),
        shapes::cuboid(DVec3::new(1.0, 0.5, 0.25)),
        shapes::icosphere(0),
    ]
}

fn gzip(bytes: &[u8]) -> Vec<u8> {
    let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::best());
    enc.write_all(bytes).expect("in-memory write");
    enc.finish().expect("in-memory write")
}

fn ascii_stl(m: &Mesh, crlf: bool, upper: bool) -> Vec<u8> {
    let nl = if crlf { "\r\n" } else { "\n" };
    let mut s = format!("solid generated{nl}");
    for t in 0..m.triangles.len() {
        let [a, b, c] = m.triangle(t);
        let n = (b - a).cross(c - a).normalize_or_zero();
        let _ = write!(
            s,
            "  facet normal {} {} {}{nl}    outer loop{nl}",
            n.x, n.y, n.z
        );
        for v in [a, b, c] {
            let _ = write!(s, "      vertex {:e} {} {}{nl}", v.x, v.y, v.z);
        }
        let _ = write!(s, "    endloop{nl}  endfacet{nl}");
    }
    let _ = write!(s, "endsolid generated{nl}");
    if upper {
        s = s.to_uppercase();
    }
    s.into_bytes()
}

fn binary_stl(m: &Mesh) -> Vec<u8> {
    to_stl_bytes(m).expect("generated meshes write as STL")
}

fn obj_variants() -> Vec<Vec<u8>> {
    let mut v: Vec<Vec<u8>> = meshes()
        .iter()
        .map(|m| to_obj_bytes(m).expect("generated meshes write as OBJ"))
        .collect();
    // Quads, negative and slashed references, comments, normals, groups, a `w` coordinate.
    v.push(
        b"# a cube of quads\r\no cube\ng faces\nv -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\n\
          v -1 -1 1 1.0\nv 1 -1 1\nv 1 1 1\nv -1 1 1\nvn 0 0 1\nvt 0.5 0.5\n\
          f 1/1/1 4/1/1 3/1/1 2/1/1\nf 5//1 6//1 7//1 8//1\nf -8 -7 -3 -4\n\
          f 2 3 7 6 # side\nf 3 4 8 7\nf 4 1 5 8\nusemtl none\ns off\nl 1 2\n"
            .to_vec(),
    );
    v.push(b"v 0 0 0\nv 1e-300 0 0\nv 0 1E+3 -0.0\nf 1 2 3\nf 3 2 1\n".to_vec());
    v
}

fn ply_ascii_bodies() -> Vec<Vec<u8>> {
    // Without the `ply` and `format` lines, which the target puts in front.
    let mut v = Vec::new();
    for m in meshes() {
        let mut s = format!(
            "comment generated\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\n\
             element face {}\nproperty list uchar int vertex_indices\nend_header\n",
            m.vertices.len(),
            m.triangles.len()
        );
        for p in &m.vertices {
            let _ = writeln!(s, "{} {} {}", p.x, p.y, p.z);
        }
        for [a, b, c] in &m.triangles {
            let _ = writeln!(s, "3 {a} {b} {c}");
        }
        v.push(s.into_bytes());
    }
    v.push(
        b"obj_info extra elements and properties\nelement vertex 4\nproperty double z\nproperty uchar red\n\
          property double x\nproperty double y\nproperty list uchar float texcoord\n\
          element edge 1\nproperty int vertex1\nproperty int vertex2\n\
          element face 2\nproperty uint flags\nproperty list ushort uint vertex_index\nend_header\r\n\
          0 255 0 0 2 0.5 0.5\n0 0 1 0 0\n0 0 1 1 0\n1 0 0 1 0\n0 1\n7 4 0 1 2 3\n0 3 3 2 1\n"
            .to_vec(),
    );
    v
}

fn ply_binary_bodies() -> Vec<Vec<u8>> {
    // The first byte picks the order (0: little, 1: big endian); the header from `element`.
    let mut v = Vec::new();
    for (k, m) in meshes().into_iter().enumerate() {
        for big in [false, true] {
            let double = k == 1;
            let mut out = vec![u8::from(big)];
            let ty = if double { "double" } else { "float" };
            let _ = write!(
                out,
                "element vertex {}\nproperty {ty} x\nproperty {ty} y\nproperty {ty} z\n\
                 element face {}\nproperty list uchar uint vertex_indices\nend_header\n",
                m.vertices.len(),
                m.triangles.len()
            );
            for p in &m.vertices {
                for x in p.to_array() {
                    match (double, big) {
                        (true, true) => out.extend_from_slice(&x.to_be_bytes()),
                        (true, false) => out.extend_from_slice(&x.to_le_bytes()),
                        (false, true) => out.extend_from_slice(&(x as f32).to_be_bytes()),
                        (false, false) => out.extend_from_slice(&(x as f32).to_le_bytes()),
                    }
                }
            }
            for t in &m.triangles {
                out.push(3);
                for &i in t {
                    if big {
                        out.extend_from_slice(&i.to_be_bytes());
                    } else {
                        out.extend_from_slice(&i.to_le_bytes());
                    }
                }
            }
            v.push(out);
        }
    }
    // Every scalar type once: char/short/int vertices, a ushort list count.
    let mut out = vec![0u8];
    out.extend_from_slice(
        b"element vertex 3\nproperty char x\nproperty short y\nproperty int z\nproperty uint8 s\n\
          element face 1\nproperty list ushort int16 vertex_indices\nend_header\n",
    );
    for (x, y, z) in [(0i8, 0i16, 0i32), (1, 0, 0), (0, 1, 5)] {
        out.push(x as u8);
        out.extend_from_slice(&y.to_le_bytes());
        out.extend_from_slice(&z.to_le_bytes());
        out.push(9);
    }
    out.extend_from_slice(&3u16.to_le_bytes());
    for i in [0i16, 1, 2] {
        out.extend_from_slice(&i.to_le_bytes());
    }
    v.push(out);
    v
}

fn off_variants() -> Vec<Vec<u8>> {
    let mut v = Vec::new();
    for m in meshes() {
        let mut s = format!(
            "OFF\n# generated\n{} {} 0\n",
            m.vertices.len(),
            m.triangles.len()
        );
        for p in &m.vertices {
            let _ = writeln!(s, "{} {} {}", p.x, p.y, p.z);
        }
        for [a, b, c] in &m.triangles {
            let _ = writeln!(s, "3 {a} {b} {c}");
        }
        v.push(s.into_bytes());
    }
    v.push(
        b"COFF 8 6 12\n-1 -1 -1 255 0 0 255\n1 -1 -1 0 0 0 0\n1 1 -1 0 0 0 0\n-1 1 -1 0 0 0 0\n\
          -1 -1 1 0 0 0 0\n1 -1 1 0 0 0 0\n1 1 1 0 0 0 0\n-1 1 1 0 0 0 0\n\
          4 0 3 2 1 255 0 0\n4 4 5 6 7\n4 0 1 5 4\n4 2 3 7 6 # back\n4 1 2 6 5\n4 3 0 4 7\n"
            .to_vec(),
    );
    v.push(b"4 2 0\r\n0 0 0\r\n1 0 0\r\n0 1 0\r\n0 0 1\r\n3 0 1 2\r\n3 0 3 1\r\n".to_vec());
    v.push(b"NOFF\n3 1 0\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n3 0 1 2\n".to_vec());
    v
}

fn gzip_variants() -> Vec<Vec<u8>> {
    // First byte: format (0 STL, 1 OBJ, 2 PLY, 3 OFF) + 4 when the rest is the plain file.
    let ply = |body: &[u8]| {
        let mut b = b"ply\nformat ascii 1.0\n".to_vec();
        b.extend_from_slice(body);
        b
    };
    let tet = tetrahedron();
    let files: Vec<(u8, Vec<u8>)> = vec![
        (0, binary_stl(&tet)),
        (0, ascii_stl(&tet, false, false)),
        (1, to_obj_bytes(&tet).expect("writes")),
        (2, ply(&ply_ascii_bodies()[0])),
        (3, off_variants()[0].clone()),
    ];
    let mut v = Vec::new();
    for (format, plain) in files {
        let mut raw = vec![format];
        raw.extend(gzip(&plain));
        v.push(raw);
        let mut wrap = vec![format | 4, (plain.len() / 3) as u8];
        wrap.extend_from_slice(&plain);
        v.push(wrap);
    }
    // Two gzip members.
    let obj = to_obj_bytes(&tet).expect("writes");
    let (a, b) = obj.split_at(obj.len() / 2);
    let mut two = vec![1u8];
    two.extend(gzip(a));
    two.extend(gzip(b));
    v.push(two);
    v
}

/// A hand-made tree of a root and two leaves (meta as a build writes it).
pub fn small_tree() -> SphereTree {
    SphereTree {
        x: vec![0.0, -0.5, 0.5],
        y: vec![0.0; 3],
        z: vec![0.0; 3],
        r: vec![1.0, 0.5, 0.5],
        first_child: vec![1, 0, 0],
        child_count: vec![2, 0, 0],
        parent: vec![NO_PARENT, 0, 0],
        depth: vec![0, 1, 1],
        meta: TreeMeta {
            coverage: 0.5,
            built_by: Some(innersphere::tree::BuildStamp::current(0)),
            ..TreeMeta::unmeasured(2, 0.25, [-1.0; 3], [1.0; 3])
        },
    }
}

fn tree_variants() -> Vec<Vec<u8>> {
    let mut one = small_tree();
    for a in [&mut one.x, &mut one.y, &mut one.z, &mut one.r] {
        a.truncate(1);
    }
    one.first_child = vec![0];
    one.child_count = vec![0];
    one.parent.truncate(1);
    one.depth.truncate(1);
    one.meta.built_by = None;
    let mut v = vec![file::to_bytes(&small_tree()), file::to_bytes(&one)];
    // A built tree: a coarse grid over a tetrahedron.
    let opts = innersphere::BuildOptions {
        resolution: innersphere::Resolution::Cells(6),
        ..Default::default()
    };
    if let Ok(t) = SphereTree::build(&tetrahedron(), &opts) {
        v.push(file::to_bytes(&t));
    }
    v
}

fn motion_variants() -> Vec<Vec<u8>> {
    let frames = (0..12)
        .map(|i| {
            let s = f64::from(i) * 0.001;
            Frame {
                t: s,
                pose: Pose::new(
                    DVec3::new(0.1 * s, -2.0 + s, 3.0 * s * s),
                    DQuat::from_rotation_y(s) * DQuat::from_rotation_z(-2.0 * s),
                )
                .expect("a valid pose"),
            }
        })
        .collect();
    let m = Motion { frames };
    vec![
        m.to_csv().into_bytes(),
        "\u{feff}t,tx,ty,tz,qw,qx,qy,qz\r\n\r\n0, 1, 2, 3, 1, 0, 0, 0\r\n  1e-3,1,2,3.5,0.9999,0,0.0141,0\r\n\
         \r\n2e-3,-1e3,+2,3,0.7071,0.7071,0,0\r\n"
            .into(),
        b"t,tx,ty,tz,qw,qx,qy,qz\n5,0,0,0,0,0,0,1\n".to_vec(),
    ]
}

fn pose_variants() -> Vec<Vec<u8>> {
    let p = Pose::new(
        DVec3::new(1.5, -2.25, 1e-3),
        DQuat::from_rotation_x(0.4) * DQuat::from_rotation_z(1.2),
    )
    .expect("a valid pose");
    vec![
        b"0 0 0 1 0 0 0".to_vec(),
        p.to_string().into_bytes(),
        format!("{p:.3}").into_bytes(),
        b"1,2,3, 0.7071,0.7071,0,0".to_vec(),
        b"  1e300\t-1e-300 0 2 0 0 0 \n".to_vec(),
        b"-0 +0.5 5e-324 1e-6 0 0 1".to_vec(),
    ]
}

/// Teeth-axes files: the generated arches' own (crown centres only, and with the axes'
/// end points as the real files give them), and near misses (a key twice, both arches, in
/// metres, keys that are no tooth numbers, a tooth twice under two spellings).
// Over 120 lines: a table of cases, one short block each.
fn teeth_variants() -> Vec<Vec<u8>> {
    let (upper, lower) = Teeth::of_arch_pair(6);
    let full: String = {
        let entries: Vec<String> = lower
            .teeth
            .iter()
            .map(|t| {
                let c = t.centre;
                format!(
                    "\"{}\": {{\"c\": [{}, {}, {}], \"x\": [{}, {}, {}], \"y\": [{}, {}, {}], \"z\": [{}, {}, {}]}}",
                    t.number,
                    c.x, c.y, c.z,
                    c.x + 1.0, c.y, c.z,
                    c.x, c.y + 1.0, c.z,
                    c.x, c.y, c.z + 1.0
                )
            })
            .collect();
        format!("{{\n    {}\n}}\n", entries.join(",\n    "))
    };
    let lower_json = lower.to_json();
    vec![
        upper.to_json().into_bytes(),
        lower_json.clone().into_bytes(),
        full.into_bytes(),
        lower_json
            .replacen('{', r#"{"22": {"c": [0, 0, 0]}, "#, 1)
            .into_bytes(),
        format!(
            "{},{}",
            &upper.to_json()[..upper.to_json().len() - 1],
            &lower_json[1..]
        )
        .into_bytes(),
        lower
            .scaled(0.001)
            .expect("a positive factor")
            .to_json()
            .into_bytes(),
        br#"{"18": {"c": [1, 2, 3]}, " 018 ": {"c": [1, 2, 3]}}"#.to_vec(),
        br#"{"incisal": {"c": [0, 40, 1]}, "UL6": {"c": [1, 2, 3]}}"#.to_vec(),
        br#"{"3": {"c": [1, 2, 3], "c": [4, 5, 6]}}"#.to_vec(),
        br#"{"3": {"c": [1e308, 2, -1e-300]}, "4": {"c": [0, 0]}}"#.to_vec(),
    ]
}

/// Landmarks: a read step, then a teeth file; and files the bounded reader must refuse (a
/// NUL, a character cut by the end, more than the target's 2048-byte limit).
fn landmark_variants() -> Vec<Vec<u8>> {
    let mut v: Vec<Vec<u8>> = teeth_variants()
        .into_iter()
        .enumerate()
        .map(|(i, t)| {
            let mut b = vec![i as u8];
            b.extend(t);
            b
        })
        .collect();
    v.push(b"\x03{\"18\": {\"c\": [1, 2, 3]}}\x00".to_vec());
    v.push("\x01{\"18\": {\"c\": [1, 2, 3], \"n\": \"é\"}}".as_bytes()[..31].to_vec());
    let mut long = b"\x07".to_vec();
    long.extend(std::iter::repeat_n(b' ', 2049));
    v.push(long);
    v
}

/// Option strings: `p` + a pose, `r` + a preset, `s` + a scenario, `d` + a device class.
fn option_variants() -> Vec<Vec<u8>> {
    [
        "p0 0 -3 1 0 0 0",
        "p1e17 0 0 1 0 0 0",
        "p0,0,0, 0.7071,0,0.7071,0",
        "rjaw",
        "rfast",
        "rfine",
        "schew",
        "sopen_close",
        " sRANDOM-CONTACT",
        "dtouch",
        "d Omega ",
        "x",
    ]
    .iter()
    .map(|s| s.as_bytes().to_vec())
    .collect()
}

/// The seeds of a target (empty for an unknown name).
pub fn seeds(target: &str) -> Vec<Vec<u8>> {
    match target {
        "mesh_stl_binary" => {
            let mut v: Vec<Vec<u8>> = meshes().iter().map(binary_stl).collect();
            // A header that claims more triangles than the file has.
            let mut lie = binary_stl(&tetrahedron());
            lie[80] = 5;
            v.push(lie);
            v
        }
        "mesh_stl_ascii" => {
            let m = meshes();
            vec![
                ascii_stl(&m[0], false, false),
                ascii_stl(&m[1], true, false),
                ascii_stl(&m[0], false, true),
                ascii_stl(&m[2], false, false),
            ]
        }
        "mesh_obj" => obj_variants(),
        "mesh_ply_ascii" => ply_ascii_bodies(),
        "mesh_ply_binary" => ply_binary_bodies(),
        "mesh_off" => off_variants(),
        "mesh_gzip" => gzip_variants(),
        "tree_file" => tree_variants(),
        "motion_csv" => motion_variants(),
        "pose_text" => pose_variants(),
        "teeth_json" => teeth_variants(),
        "landmarks" => landmark_variants(),
        "option_text" => option_variants(),
        _ => Vec::new(),
    }
}
