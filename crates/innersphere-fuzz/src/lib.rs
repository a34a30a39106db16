//! Fuzz targets for every input innersphere reads from a user: mesh files (STL binary and
//! ASCII, OBJ, PLY ASCII and binary, OFF, gzip-wrapped), tree files, motion CSV, pose text,
//! and the planning commands' teeth-axes JSON, landmarks and option strings ([`teeth`]).
//!
//! Each target is a plain `fn(&[u8])` that feeds the bytes to the library and asserts what
//! must hold for *any* input: no panic, and for an input that is accepted, the properties the
//! documentation promises (a mesh is welded with finite coordinates and valid indices and
//! writes and reads back; a tree passes `validate_structure`, writes back to the same bytes
//! and answers queries; a motion or pose writes as text and reads back). A failed assertion
//! is a panic, which is what a fuzzer reports.
//!
//! Two callers: the cargo-fuzz crate in `fuzz/` (one libFuzzer binary per target, each a
//! one-line call into this crate; `cargo +nightly fuzz run <target>` from this crate's
//! directory), and `tests/corpus.rs`, which replays every generated seed ([`seeds`]), every
//! file of the minimised corpus (`fuzz/corpus/<target>/`) and every crash found
//! (`regressions/<target>/`) on the stable toolchain, so that CI checks them on every run.
//! See `docs/RELIABILITY.md`, "Fuzzing".

use std::cell::Cell;
use std::io::{Read, Write};
use std::path::{Path, PathBuf};

use glam::{DQuat, DVec3};
use innersphere::mesh::io::{to_obj_bytes, to_stl_bytes};
use innersphere::mesh::{load_bytes, Format, Mesh};
use innersphere::tree::file;
use innersphere::{MatrixOrder, MultipointOptions, Pair, Pose, SphereTree};
use innersphere_motion::Motion;

pub mod seeds;
pub mod teeth;

pub use teeth::{landmarks, option_text, teeth_json};

/// A fuzz target: feeds bytes to the library, panics when a property is violated.
pub type Target = fn(&[u8]);

/// Every target by name (the names of the `fuzz/` binaries and of the corpus folders).
pub const TARGETS: &[(&str, Target)] = &[
    ("mesh_stl_binary", mesh_stl_binary),
    ("mesh_stl_ascii", mesh_stl_ascii),
    ("mesh_obj", mesh_obj),
    ("mesh_ply_ascii", mesh_ply_ascii),
    ("mesh_ply_binary", mesh_ply_binary),
    ("mesh_off", mesh_off),
    ("mesh_gzip", mesh_gzip),
    ("tree_file", tree_file),
    ("motion_csv", motion_csv),
    ("pose_text", pose_text),
    ("teeth_json", teeth_json),
    ("landmarks", landmarks),
    ("option_text", option_text),
];

/// The target named `name`.
pub fn target(name: &str) -> Option<Target> {
    TARGETS.iter().find(|(n, _)| *n == name).map(|&(_, f)| f)
}

/// Coordinates within ±this are in range for any sensible limit a loader may impose (loaders
/// refuse coordinates the tree's f32 arrays cannot hold, `mesh::MAX_COORDINATE`). Where an
/// oracle below says "must load", it says so only for files whose coordinates all lie
/// within it.
pub const SAFE_COORDINATE: f64 = 1e6;

// ---------------------------------------------------------------------------------------
// Meshes

fn parse(bytes: &[u8], format: Format) -> innersphere::Result<Mesh> {
    load_bytes(bytes, format, Path::new("fuzz"))
}

/// What every mesh a loader returns must satisfy: not empty, finite coordinates, indices in
/// range, welded (no two vertices at the same point, `-0.0 == 0.0`), no unused vertex, and
/// it writes as OBJ and reads back identical (OBJ keeps full f64 precision); when it fits
/// STL's f32 (and [`SAFE_COORDINATE`]) it writes as binary STL and reads back with the same
/// triangles.
pub fn check_mesh(m: &Mesh) {
    assert!(!m.triangles.is_empty(), "a loaded mesh has no triangles");
    if let Err(e) = m.validate() {
        panic!("a loaded mesh fails Mesh::validate: {e}");
    }
    let n = m.vertices.len();
    for (i, v) in m.vertices.iter().enumerate() {
        assert!(v.is_finite(), "vertex {i} is not finite: {v}");
    }
    let mut used = vec![false; n];
    for (t, tri) in m.triangles.iter().enumerate() {
        for &i in tri {
            assert!((i as usize) < n, "triangle {t} refers to vertex {i} of {n}");
            used[i as usize] = true;
        }
    }
    if let Some(i) = used.iter().position(|u| !u) {
        panic!("vertex {i} is used by no triangle (loaders drop unused vertices)");
    }
    let mut keys: Vec<[u64; 3]> = m
        .vertices
        .iter()
        .map(|v| {
            [
                (v.x + 0.0).to_bits(),
                (v.y + 0.0).to_bits(),
                (v.z + 0.0).to_bits(),
            ]
        })
        .collect();
    keys.sort_unstable();
    keys.dedup();
    assert_eq!(keys.len(), n, "two vertices at the same point (not welded)");

    let obj = to_obj_bytes(m).expect("a loaded mesh writes as OBJ");
    match parse(&obj, Format::Obj) {
        Ok(back) => assert!(back == *m, "the mesh written as OBJ reads back different"),
        Err(e) => panic!("the mesh written as OBJ does not read back: {e}"),
    }
    let in_range = m
        .vertices
        .iter()
        .all(|v| v.abs().max_element() <= SAFE_COORDINATE);
    if in_range {
        let stl = to_stl_bytes(m).expect("a mesh within ±1e6 writes as STL");
        match parse(&stl, Format::Stl) {
            Ok(back) => assert_eq!(
                back.triangles.len(),
                m.triangles.len(),
                "the mesh written as STL reads back with another triangle count"
            ),
            Err(e) => panic!("the mesh written as STL does not read back: {e}"),
        }
    }
}

fn check_if_loaded(bytes: &[u8], format: Format) -> Option<Mesh> {
    let m = parse(bytes, format).ok()?;
    check_mesh(&m);
    Some(m)
}

fn f32_at(b: &[u8], o: usize) -> f32 {
    f32::from_le_bytes([b[o], b[o + 1], b[o + 2], b[o + 3]])
}

/// Binary STL. The bytes as a file, then the bytes cut to whole 50-byte triangle records
/// behind a header (starting with `solid`, which must not matter) whose count matches: that
/// file must load exactly when it has a triangle and every coordinate is finite (and in
/// [`SAFE_COORDINATE`] range, where a loader may refuse), with one triangle per record at
/// the record's coordinates.
pub fn mesh_stl_binary(data: &[u8]) {
    check_if_loaded(data, Format::Stl);

    let records = &data[..data.len() / 50 * 50];
    let count = records.len() / 50;
    let mut bytes = Vec::with_capacity(84 + records.len());
    let mut header = [b' '; 80];
    header[..15].copy_from_slice(b"solid in binary");
    bytes.extend_from_slice(&header);
    bytes.extend_from_slice(&(count as u32).to_le_bytes());
    bytes.extend_from_slice(records);
    let coords = || {
        records
            .chunks_exact(50)
            .flat_map(|r| (0..9).map(move |i| f32_at(r, 12 + 4 * i)))
    };
    let finite = coords().all(f32::is_finite);
    let in_range = coords().all(|x| f64::from(x).abs() <= SAFE_COORDINATE);
    match parse(&bytes, Format::Stl) {
        Ok(m) => {
            assert!(
                count > 0 && finite,
                "loaded an empty or non-finite binary STL"
            );
            assert_eq!(m.triangles.len(), count, "one triangle per record");
            for (t, r) in records.chunks_exact(50).enumerate() {
                for k in 0..3 {
                    let o = 12 + 12 * (k + 1);
                    let want = DVec3::new(
                        f32_at(r, o - 12).into(),
                        f32_at(r, o - 8).into(),
                        f32_at(r, o - 4).into(),
                    );
                    let got = m.vertices[m.triangles[t][k] as usize];
                    assert!(
                        got == want,
                        "triangle {t} corner {k}: {got} instead of {want}"
                    );
                }
            }
            check_mesh(&m);
        }
        Err(e) => assert!(
            count == 0 || !finite || !in_range,
            "a binary STL of {count} finite triangles within ±{SAFE_COORDINATE} was refused: {e}"
        ),
    }
}

/// ASCII STL: the bytes behind `solid ` (one byte longer when that length would make it a
/// binary file), and the bytes as they are.
pub fn mesh_stl_ascii(data: &[u8]) {
    let mut bytes = Vec::with_capacity(data.len() + 7);
    bytes.extend_from_slice(b"solid ");
    bytes.extend_from_slice(data);
    if let Some(c) = bytes.get(80..84) {
        let count = u32::from_le_bytes([c[0], c[1], c[2], c[3]]);
        if 84 + 50 * u64::from(count) == bytes.len() as u64 {
            bytes.push(b'\n');
        }
    }
    check_if_loaded(&bytes, Format::Stl);
    check_if_loaded(data, Format::Stl);
}

/// Wavefront OBJ, the bytes as they are.
pub fn mesh_obj(data: &[u8]) {
    check_if_loaded(data, Format::Obj);
}

/// Object File Format, the bytes as they are.
pub fn mesh_off(data: &[u8]) {
    check_if_loaded(data, Format::Off);
}

/// ASCII PLY: the bytes behind `ply` / `format ascii 1.0` (so that mutations explore the
/// elements and the body), and the bytes as they are.
pub fn mesh_ply_ascii(data: &[u8]) {
    let mut bytes = b"ply\nformat ascii 1.0\n".to_vec();
    bytes.extend_from_slice(data);
    check_if_loaded(&bytes, Format::Ply);
    check_if_loaded(data, Format::Ply);
}

/// Binary PLY: the first byte picks the byte order (even: little endian, odd: big endian),
/// the rest follows `ply` / `format binary_..._endian 1.0`.
pub fn mesh_ply_binary(data: &[u8]) {
    let Some((&order, rest)) = data.split_first() else {
        return;
    };
    let mut bytes = if order % 2 == 0 {
        b"ply\nformat binary_little_endian 1.0\n".to_vec()
    } else {
        b"ply\nformat binary_big_endian 1.0\n".to_vec()
    };
    bytes.extend_from_slice(rest);
    check_if_loaded(&bytes, Format::Ply);
}

const FORMATS: [Format; 4] = [Format::Stl, Format::Obj, Format::Ply, Format::Off];

thread_local! {
    static FILE_NO: Cell<u64> = const { Cell::new(0) };
}

/// Loads `bytes` as the file `fuzz.<ext>.gz` through [`Mesh::load`] (the only public way to
/// the library's gzip reader), from a file of this process and thread in the temp folder.
fn load_gz_file(bytes: &[u8], format: Format) -> innersphere::Result<Mesh> {
    let n = FILE_NO.with(|c| {
        c.set(c.get() + 1);
        c.get()
    });
    let thread = format!("{:?}", std::thread::current().id())
        .chars()
        .filter(char::is_ascii_digit)
        .collect::<String>();
    let path: PathBuf = std::env::temp_dir().join(format!(
        "innersphere-fuzz-{}-{thread}-{n}.{}.gz",
        std::process::id(),
        format.name()
    ));
    std::fs::write(&path, bytes).expect("write to the temp folder");
    let result = Mesh::load(&path);
    let _ = std::fs::remove_file(&path);
    result
}

/// Decompresses like a gzip reader should (every member), independently of the library's
/// code path; `None` when the stream is not valid gzip.
fn reference_gunzip(bytes: &[u8]) -> Option<Vec<u8>> {
    let mut out = Vec::new();
    flate2::read::MultiGzDecoder::new(bytes)
        .take(1 << 26)
        .read_to_end(&mut out)
        .ok()?;
    Some(out)
}

fn gzip(parts: &[&[u8]]) -> Vec<u8> {
    let mut out = Vec::new();
    for part in parts {
        let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
        enc.write_all(part).expect("in-memory write");
        out.extend(enc.finish().expect("in-memory write"));
    }
    out
}

/// Gzip-wrapped mesh files, read through a `.gz` path. The first byte picks the format (bits
/// 0-1: STL, OBJ, PLY, OFF) and the mode (bit 2):
/// - clear: the rest is the `.gz` file. It must load exactly when it is valid gzip (per an
///   independent decoder) of a file that loads uncompressed, and give the same mesh. A
///   loader may refuse, as a likely gzip bomb, data that inflates to more than 16 times its
///   compressed size, with an error that says gzip.
/// - set: the second byte is a split point, the rest the plain file, compressed here as two
///   gzip members split there. It must load exactly as the plain file does.
pub fn mesh_gzip(data: &[u8]) {
    let Some((&mode, rest)) = data.split_first() else {
        return;
    };
    let format = FORMATS[(mode & 3) as usize];
    if mode & 4 == 0 {
        let loaded = load_gz_file(rest, format);
        let plain = reference_gunzip(rest);
        match (loaded, plain) {
            (Ok(m), Some(plain)) => {
                check_mesh(&m);
                match parse(&plain, format) {
                    Ok(direct) => assert!(direct == m, "gzip gave another mesh than plain"),
                    Err(e) => panic!("loaded from gzip, but the plain file fails: {e}"),
                }
            }
            (Ok(_), None) => panic!("loaded a .gz file that is not valid gzip"),
            (Err(e), Some(plain)) => {
                if let Ok(_direct) = parse(&plain, format) {
                    let bomb = plain.len() > 16 * rest.len();
                    let says_gzip = e.to_string().contains("gzip");
                    assert!(
                        bomb && says_gzip,
                        "valid gzip of a loadable {} file was refused: {e}",
                        format.name()
                    );
                }
            }
            (Err(_), None) => {}
        }
    } else {
        let Some((&split, plain)) = rest.split_first() else {
            return;
        };
        let split = usize::from(split).min(plain.len());
        let gz = gzip(&[&plain[..split], &plain[split..]]);
        let loaded = load_gz_file(&gz, format);
        let direct = parse(plain, format);
        match (loaded, direct) {
            (Ok(m), Ok(d)) => {
                check_mesh(&m);
                assert!(m == d, "gzip gave another mesh than plain");
            }
            (Err(e), Ok(_)) => panic!("the gzip of a loadable file was refused: {e}"),
            (Ok(_), Err(e)) => panic!("loaded from gzip, but the plain file fails: {e}"),
            (Err(_), Err(_)) => {}
        }
    }
}

// ---------------------------------------------------------------------------------------
// Tree files

const TREE_HEADER: usize = 24;
const TREE_BYTES_PER_NODE: usize = 27;

/// The bytes made into a file that passes the size and checksum checks (magic and version
/// set, the meta length clamped, the node count from the length, the tail cut to whole
/// nodes, the CRC recomputed), so that mutations reach the meta block and the structure
/// checks; `None` when too short.
pub fn repair_tree_bytes(data: &[u8]) -> Option<Vec<u8>> {
    if data.len() < TREE_HEADER + 4 {
        return None;
    }
    let mut b = data.to_vec();
    b[..8].copy_from_slice(&file::MAGIC);
    b[8..12].copy_from_slice(&file::VERSION.to_le_bytes());
    let room = b.len() - TREE_HEADER - 4;
    let meta_len = (u32::from_le_bytes([b[12], b[13], b[14], b[15]]) as usize).min(room);
    let n = (room - meta_len) / TREE_BYTES_PER_NODE;
    b[12..16].copy_from_slice(&(meta_len as u32).to_le_bytes());
    b[16..24].copy_from_slice(&(n as u64).to_le_bytes());
    b.truncate(TREE_HEADER + meta_len + TREE_BYTES_PER_NODE * n);
    let crc = crc32fast::hash(&b);
    b.extend_from_slice(&crc.to_le_bytes());
    Some(b)
}

/// What every tree the reader accepts must satisfy: it passes `validate_structure`, writes
/// back to bytes that read back to the same tree (and those bytes are a fixed point), and
/// every query kind answers on it without a panic; answers are never NaN when every sphere
/// lies within ±1e18 (where f32 squares cannot overflow).
pub fn check_tree(tree: SphereTree) {
    if let Err(e) = tree.validate_structure() {
        panic!("a loaded tree fails validate_structure: {e}");
    }
    let bytes = file::to_bytes(&tree);
    match file::from_bytes(&bytes) {
        Ok(back) => {
            assert!(back == tree, "the tree written back reads back different");
            assert!(
                file::to_bytes(&back) == bytes,
                "to_bytes is not a fixed point"
            );
        }
        Err(e) => panic!("the tree written back does not read back: {e}"),
    }
    let _ = tree.staleness();
    let mut sink = Vec::new();
    innersphere::tree::export::write_ply(&tree, innersphere::tree::export::Which::All, &mut sink)
        .expect("in-memory write");

    let small = (0..tree.len()).all(|i| {
        let (c, r) = tree.sphere(i);
        c.abs().max_element() <= 1e18 && r <= 1e18
    });
    let mut pair = Pair::new(tree.clone(), tree);
    let apart =
        Pose::new(DVec3::new(0.25, -0.5, 1.0), DQuat::from_rotation_y(0.3)).expect("a valid pose");
    for pb in [Pose::IDENTITY, apart] {
        let pa = Pose::IDENTITY;
        let d = pair.distance(&pa, &pb);
        let c = pair.contact(&pa, &pb);
        let m = pair.multipoint(&pa, &pb, &MultipointOptions::default());
        let contacts = pair.contacts().len();
        let p = pair.penetration(&pa, &pb);
        let patches = pair.patches().len();
        let w = pair.penetration_within(&pa, &pb, 1000);
        let _ = (contacts, patches);
        if small {
            for (what, x) in [
                ("distance", d.distance),
                ("contact distance", c.distance),
                ("multipoint distance", m.distance),
                ("penetration volume", p.volume),
                ("budgeted volume", w.volume),
            ] {
                assert!(!x.is_nan(), "{what} is NaN on a tree within ±1e18");
            }
        }
    }
}

/// Tree files: the bytes as they are, then repaired to pass the size and checksum checks
/// ([`repair_tree_bytes`]); every tree read must pass [`check_tree`].
pub fn tree_file(data: &[u8]) {
    if let Ok(t) = file::from_bytes(data) {
        check_tree(t);
    }
    if let Some(fixed) = repair_tree_bytes(data) {
        if let Ok(t) = file::from_bytes(&fixed) {
            check_tree(t);
        }
    }
}

// ---------------------------------------------------------------------------------------
// Motions and poses

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol
}

/// The same rotation (q and −q are), componentwise within `tol`.
fn same_rotation(a: DQuat, b: DQuat, tol: f64) -> bool {
    let d = |b: DQuat| {
        (a.x - b.x)
            .abs()
            .max((a.y - b.y).abs())
            .max((a.z - b.z).abs())
            .max((a.w - b.w).abs())
    };
    d(b).min(d(-b)) <= tol
}

/// Motion CSV (the bytes as UTF-8 text). An accepted motion has frames, passes
/// `Motion::validate`, has finite strictly increasing times and unit quaternions, and its
/// `to_csv` text reads back to the same frames (times and translations exactly, rotations to
/// 1e-15). A refusal names a line of the text (or the one after the last).
pub fn motion_csv(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    match Motion::parse(text, "fuzz.csv") {
        Ok(m) => {
            assert!(!m.is_empty(), "a motion without frames was accepted");
            if let Err(e) = m.validate("fuzz.csv") {
                panic!("an accepted motion fails validate: {e}");
            }
            for (i, f) in m.frames.iter().enumerate() {
                assert!(f.t.is_finite(), "frame {i}: time not finite");
                assert!(f.pose.translation.is_finite(), "frame {i}: not finite");
                assert!(
                    close(f.pose.rotation.length(), 1.0, 1e-12),
                    "frame {i}: the rotation is not normalised"
                );
                if i > 0 {
                    assert!(f.t > m.frames[i - 1].t, "frame {i}: time does not increase");
                }
            }
            let back = match Motion::parse(&m.to_csv(), "back.csv") {
                Ok(b) => b,
                Err(e) => panic!("to_csv of an accepted motion does not read back: {e}"),
            };
            assert_eq!(back.len(), m.len(), "to_csv reads back another frame count");
            for (i, (a, b)) in m.frames.iter().zip(&back.frames).enumerate() {
                assert!(
                    a.t == b.t,
                    "frame {i}: time changed writing and reading back"
                );
                assert!(
                    a.pose.translation == b.pose.translation,
                    "frame {i}: translation changed writing and reading back"
                );
                assert!(
                    same_rotation(a.pose.rotation, b.pose.rotation, 1e-15),
                    "frame {i}: rotation changed writing and reading back"
                );
            }
        }
        Err(innersphere::Error::Motion { line, .. }) => {
            let lines = text.lines().count();
            assert!(
                line >= 1 && line <= lines + 1,
                "the error names line {line} of a text of {lines} lines"
            );
        }
        Err(e) => panic!("a motion parse error that is not Error::Motion: {e}"),
    }
}

/// Pose text (`tx ty tz qw qx qy qz`, the bytes as UTF-8). An accepted pose is finite with a
/// unit quaternion, and reads back from its `Display` text with the same translation and the
/// rotation to 1e-15 (with `{:.17}`, the translation to 1e-16 relative); it goes through `to_array` / `from_array`, a 4×4
/// matrix in both orders and a 3×3 rotation matrix and back (rotation to 1e-12,
/// translation exactly).
pub fn pose_text(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(p) = text.parse::<Pose>() else {
        return;
    };
    assert!(p.translation.is_finite(), "an accepted pose is not finite");
    assert!(
        close(p.rotation.length(), 1.0, 1e-12),
        "an accepted pose's rotation is not normalised: {}",
        p.rotation.length()
    );
    match p.to_string().parse::<Pose>() {
        Ok(back) => {
            assert!(
                back.translation == p.translation,
                "the translation changed through {p}"
            );
            assert!(
                same_rotation(back.rotation, p.rotation, 1e-15),
                "the rotation changed through {p}"
            );
        }
        Err(e) => panic!("the pose's text {p} does not read back: {e}"),
    }
    // With a precision: every number to 17 decimals.
    let shown = format!("{p:.17}");
    match shown.parse::<Pose>() {
        Ok(back) => {
            let tol = 1e-16 * p.translation.abs().max_element().max(1.0);
            assert!(
                (back.translation - p.translation).abs().max_element() <= tol,
                "the translation changed through {shown:?}"
            );
            assert!(
                same_rotation(back.rotation, p.rotation, 1e-15),
                "the rotation changed through {shown:?}"
            );
        }
        Err(e) => panic!("the pose's text {shown:?} does not read back: {e}"),
    }
    let back = Pose::from_array(p.to_array()).expect("to_array reads back");
    assert!(back.translation == p.translation);
    assert!(same_rotation(back.rotation, p.rotation, 1e-15));
    for order in [MatrixOrder::RowMajor, MatrixOrder::ColumnMajor] {
        match Pose::from_matrix4(&p.to_matrix4(order), order) {
            Ok(back) => {
                assert!(
                    back.translation == p.translation,
                    "the translation changed through a 4×4 matrix ({order:?})"
                );
                assert!(
                    same_rotation(back.rotation, p.rotation, 1e-12),
                    "the rotation changed through a 4×4 matrix ({order:?})"
                );
            }
            Err(e) => panic!("the pose's 4×4 matrix ({order:?}) is refused: {e}"),
        }
    }
    match Pose::from_rotation_matrix(p.to_rotation_matrix(), p.translation) {
        Ok(back) => assert!(
            same_rotation(back.rotation, p.rotation, 1e-12),
            "the rotation changed through a 3×3 matrix"
        ),
        Err(e) => panic!("the pose's rotation matrix is refused: {e}"),
    }
}
