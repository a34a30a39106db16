//! Mesh file formats: STL (binary and ASCII), OBJ, PLY, OFF, each optionally gzip-compressed.
//!
//! Every loader returns a welded [`Mesh`] that has passed [`Mesh::validate`]: vertices with
//! bit-identical coordinates are merged (the rule of [`Mesh::from_soup`]; `-0.0` and `0.0`
//! are the same point), vertices that no triangle uses are dropped, and polygons are
//! triangulated as fans `(v0, vi, vi+1)`. Non-finite coordinates anywhere in a file are a
//! parse error.
//!
//! The four parsers are written here instead of using `tobj` or `ply-rs-bw`, because a
//! loader for untrusted files must
//! - never size an allocation from a count in a header beyond what the remaining bytes can
//!   hold (a 100-byte file claiming 4 billion triangles is an error, not an out-of-memory
//!   abort),
//! - never panic on any byte input (checked by a proptest in `tests/mesh_io.rs`; with our
//!   own code that property is auditable in this one file),
//! - read coordinates as `f64` (`tobj` reads `f32` unless a feature is switched on),
//! - decide binary vs ASCII STL by the file length, not by the `solid` prefix (binary STL
//!   exporters often write `solid` into the header), and
//! - report errors with a line number or byte offset.
//!
//! The subset read of each format is small: positions and faces only (normals, texture
//! coordinates, colours and materials are ignored).

use std::collections::HashMap;
use std::io::{Read, Write};
use std::path::Path;

use glam::DVec3;

use super::Mesh;
use crate::{Error, Result};

/// The largest decompressed size accepted from a `.gz` file (4 GiB); more is refused as a
/// likely gzip bomb instead of exhausting memory.
pub const MAX_DECOMPRESSED_BYTES: u64 = 4 << 30;

/// A mesh file format.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Format {
    /// STL, binary or ASCII.
    Stl,
    /// Wavefront OBJ (vertex positions and faces).
    Obj,
    /// Stanford PLY: ASCII, binary little endian or binary big endian.
    Ply,
    /// Object File Format, ASCII (`OFF`, `COFF`, `NOFF`, ... headers).
    Off,
}

impl Format {
    /// The format named by a path's extension (case-insensitive), looking through a final
    /// `.gz`: `a.STL` and `a.stl.gz` are both [`Format::Stl`].
    pub fn from_path(path: &Path) -> Result<Format> {
        let unsupported = || Error::UnsupportedFormat(path.to_path_buf());
        let inner = if is_gzip(path) {
            Path::new(path.file_stem().ok_or_else(unsupported)?)
        } else {
            path
        };
        let ext = inner
            .extension()
            .and_then(|e| e.to_str())
            .ok_or_else(unsupported)?;
        match ext.to_ascii_lowercase().as_str() {
            "stl" => Ok(Format::Stl),
            "obj" => Ok(Format::Obj),
            "ply" => Ok(Format::Ply),
            "off" => Ok(Format::Off),
            _ => Err(unsupported()),
        }
    }

    /// The lower-case name of the format (`"stl"`, `"obj"`, `"ply"`, `"off"`).
    pub fn name(self) -> &'static str {
        match self {
            Format::Stl => "stl",
            Format::Obj => "obj",
            Format::Ply => "ply",
            Format::Off => "off",
        }
    }
}

/// Whether a path ends in `.gz` (case-insensitive), i.e. is read and written gzip-compressed.
pub fn is_gzip(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("gz"))
}

/// Loads a mesh file; the format comes from the extension (see [`Format::from_path`]), and a
/// final `.gz` means gzip (at most [`MAX_DECOMPRESSED_BYTES`] decompressed).
pub fn load(path: &Path) -> Result<Mesh> {
    let format = Format::from_path(path)?;
    let mut bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    if is_gzip(path) {
        bytes = gunzip(&bytes, MAX_DECOMPRESSED_BYTES)
            .map_err(|message| parse_error(path, format, message))?;
    }
    load_bytes(&bytes, format, path)
}

/// Parses the (uncompressed) bytes of a mesh file in the given format; `name` is only used
/// in error messages. Returns a welded, validated mesh; never panics.
pub fn load_bytes(bytes: &[u8], format: Format, name: &Path) -> Result<Mesh> {
    let parsed = match format {
        Format::Stl => parse_stl(bytes),
        Format::Obj => parse_obj(bytes),
        Format::Ply => parse_ply(bytes),
        Format::Off => parse_off(bytes),
    };
    let mesh = parsed.map_err(|message| parse_error(name, format, message))?;
    mesh.validate()?;
    Ok(mesh)
}

/// Writes a mesh as binary STL (coordinates rounded to `f32`, facet normals from the
/// corners); gzip-compressed when the path ends in `.gz`.
pub fn save_stl(mesh: &Mesh, path: &Path) -> Result<()> {
    write_file(path, &to_stl_bytes(mesh)?)
}

/// Writes a mesh as Wavefront OBJ (`v` and `f` lines, coordinates in full `f64` precision);
/// gzip-compressed when the path ends in `.gz`.
pub fn save_obj(mesh: &Mesh, path: &Path) -> Result<()> {
    write_file(path, &to_obj_bytes(mesh)?)
}

/// The bytes of a binary STL file of the mesh (what [`save_stl`] writes, uncompressed).
/// Fails when a coordinate does not fit in `f32`.
pub fn to_stl_bytes(mesh: &Mesh) -> Result<Vec<u8>> {
    check_writable(mesh)?;
    if let Some(i) = mesh.vertices.iter().position(|v| !v.as_vec3().is_finite()) {
        return Err(Error::InvalidMesh(format!(
            "vertex {i} ({}) does not fit in the f32 coordinates of STL",
            mesh.vertices[i]
        )));
    }
    let count = u32::try_from(mesh.triangles.len()).map_err(|_| {
        Error::InvalidMesh(format!(
            "{} triangles do not fit in a binary STL file",
            mesh.triangles.len()
        ))
    })?;
    let mut out = Vec::with_capacity(84 + 50 * mesh.triangles.len());
    // The header must not start with `solid`, so that no reader mistakes it for ASCII.
    let mut header = [b' '; 80];
    let text = b"binary STL written by innersphere";
    header[..text.len()].copy_from_slice(text);
    out.extend_from_slice(&header);
    out.extend_from_slice(&count.to_le_bytes());
    for t in 0..mesh.triangles.len() {
        let [a, b, c] = mesh.triangle(t);
        let n = (b - a).cross(c - a).normalize_or_zero();
        for v in [n, a, b, c] {
            for x in v.to_array() {
                out.extend_from_slice(&(x as f32).to_le_bytes());
            }
        }
        out.extend_from_slice(&[0, 0]);
    }
    Ok(out)
}

/// The bytes of an OBJ file of the mesh (what [`save_obj`] writes, uncompressed).
pub fn to_obj_bytes(mesh: &Mesh) -> Result<Vec<u8>> {
    check_writable(mesh)?;
    let mut out = Vec::with_capacity(40 * mesh.vertices.len() + 24 * mesh.triangles.len());
    let io_err = |e| Error::io("<memory>", e);
    writeln!(out, "# written by innersphere").map_err(io_err)?;
    for v in &mesh.vertices {
        // `{:?}` prints the shortest representation that reads back to the same f64.
        writeln!(out, "v {:?} {:?} {:?}", v.x, v.y, v.z).map_err(io_err)?;
    }
    for [a, b, c] in &mesh.triangles {
        writeln!(out, "f {} {} {}", a + 1, b + 1, c + 1).map_err(io_err)?;
    }
    Ok(out)
}

// ---------------------------------------------------------------------------------------
// Shared helpers

fn parse_error(path: &Path, format: Format, message: String) -> Error {
    Error::Parse {
        path: path.to_path_buf(),
        format: format.name(),
        message,
    }
}

/// Finite coordinates and valid indices (an empty mesh can be written).
fn check_writable(mesh: &Mesh) -> Result<()> {
    if mesh.triangles.is_empty() {
        return Ok(());
    }
    mesh.validate()
}

fn write_file(path: &Path, bytes: &[u8]) -> Result<()> {
    let file = std::fs::File::create(path).map_err(|e| Error::io(path, e))?;
    let result = if is_gzip(path) {
        let mut enc = flate2::write::GzEncoder::new(file, flate2::Compression::default());
        enc.write_all(bytes).and_then(|()| enc.finish().map(drop))
    } else {
        let mut file = file;
        file.write_all(bytes)
    };
    result.map_err(|e| Error::io(path, e))
}

/// Decompresses gzip data (all members), refusing output longer than `limit` bytes.
fn gunzip(data: &[u8], limit: u64) -> std::result::Result<Vec<u8>, String> {
    let mut out = Vec::new();
    // Size hint from the gzip trailer (size mod 2^32), trusted only up to 64x the input.
    if let Some(tail) = data.len().checked_sub(4).and_then(|s| data.get(s..)) {
        let isize = u32::from_le_bytes([tail[0], tail[1], tail[2], tail[3]]) as u64;
        let hint = isize.min(64 * data.len() as u64).min(limit);
        out.reserve(usize::try_from(hint).unwrap_or(0));
    }
    let mut dec = flate2::bufread::MultiGzDecoder::new(data).take(limit.saturating_add(1));
    dec.read_to_end(&mut out)
        .map_err(|e| format!("gzip decompression failed: {e}"))?;
    if out.len() as u64 > limit {
        return Err(format!(
            "gzip data decompresses to more than {limit} bytes; refusing it (gzip bomb?)"
        ));
    }
    Ok(out)
}

/// Welds vertices with bit-identical coordinates (`-0.0` == `0.0`), in order of first use.
///
/// Hashes with `ahash` (randomly keyed, so crafted files cannot force collisions), which
/// makes welding a jaw arch about twice as fast as the standard SipHash.
struct Welder {
    map: HashMap<[u64; 3], u32, ahash::RandomState>,
    vertices: Vec<DVec3>,
}

impl Welder {
    fn with_capacity(n: usize) -> Self {
        Welder {
            map: HashMap::with_capacity_and_hasher(n, ahash::RandomState::new()),
            vertices: Vec::with_capacity(n),
        }
    }

    fn add(&mut self, v: DVec3) -> std::result::Result<u32, String> {
        let key = [
            (v.x + 0.0).to_bits(),
            (v.y + 0.0).to_bits(),
            (v.z + 0.0).to_bits(),
        ];
        if let Some(&i) = self.map.get(&key) {
            return Ok(i);
        }
        let i = u32::try_from(self.vertices.len())
            .ok()
            .filter(|&i| i < u32::MAX)
            .ok_or("more than 4 billion distinct vertices")?;
        self.vertices.push(v);
        self.map.insert(key, i);
        Ok(i)
    }

    fn finish(self, triangles: Vec<[u32; 3]>) -> Mesh {
        Mesh {
            vertices: self.vertices,
            triangles,
        }
    }
}

/// Welds an indexed mesh whose indices have been checked against `raw`; only vertices
/// used by a triangle are kept.
fn weld_indexed(raw: &[DVec3], tris: &[[usize; 3]]) -> std::result::Result<Mesh, String> {
    let mut remap = vec![u32::MAX; raw.len()];
    let mut welder = Welder::with_capacity(raw.len().min(tris.len() * 3));
    let mut triangles = Vec::with_capacity(tris.len());
    for (f, tri) in tris.iter().enumerate() {
        let mut out = [0u32; 3];
        for (k, &i) in tri.iter().enumerate() {
            let (slot, &v) = remap
                .get_mut(i)
                .zip(raw.get(i))
                .ok_or_else(|| format!("triangle {f} refers to missing vertex {i}"))?;
            if *slot == u32::MAX {
                *slot = welder.add(v)?;
            }
            out[k] = *slot;
        }
        triangles.push(out);
    }
    Ok(welder.finish(triangles))
}

/// Lines of a text file as (1-based line number, line without `\r\n`).
fn lines(b: &[u8]) -> impl Iterator<Item = (usize, &[u8])> {
    b.split(|&c| c == b'\n').enumerate().map(|(i, l)| {
        let l = l.strip_suffix(b"\r").unwrap_or(l);
        (i + 1, l)
    })
}

/// Whitespace-separated tokens of a line.
fn tokens(line: &[u8]) -> impl Iterator<Item = &[u8]> {
    line.split(|c| c.is_ascii_whitespace())
        .filter(|t| !t.is_empty())
}

/// The part of a line before a comment character.
fn strip_comment(line: &[u8], comment: u8) -> &[u8] {
    match line.iter().position(|&c| c == comment) {
        Some(p) => &line[..p],
        None => line,
    }
}

fn show(tok: &[u8]) -> String {
    let s = String::from_utf8_lossy(tok);
    if s.chars().count() > 40 {
        format!("{}...", s.chars().take(40).collect::<String>())
    } else {
        s.into_owned()
    }
}

fn parse_f64(tok: &[u8]) -> Option<f64> {
    std::str::from_utf8(tok).ok()?.parse().ok()
}

fn parse_u64(tok: &[u8]) -> Option<u64> {
    std::str::from_utf8(tok).ok()?.parse().ok()
}

/// Three coordinates from the first three tokens, which must be finite numbers.
fn parse_point<'a>(
    toks: &mut impl Iterator<Item = &'a [u8]>,
    line: usize,
) -> std::result::Result<DVec3, String> {
    let mut p = [0.0; 3];
    for x in &mut p {
        let tok = toks
            .next()
            .ok_or_else(|| format!("line {line}: expected three coordinates"))?;
        *x = parse_f64(tok)
            .ok_or_else(|| format!("line {line}: `{}` is not a number", show(tok)))?;
        if !x.is_finite() {
            return Err(format!(
                "line {line}: non-finite coordinate `{}`",
                show(tok)
            ));
        }
    }
    Ok(DVec3::from_array(p))
}

// ---------------------------------------------------------------------------------------
// STL

/// Binary when the length is exactly `84 + 50 * count` or the file does not start with
/// `solid`; ASCII otherwise. Many binary exporters write `solid` into the 80-byte header,
/// so the prefix alone decides nothing; the length rule is what real readers use.
fn parse_stl(b: &[u8]) -> std::result::Result<Mesh, String> {
    if b.is_empty() {
        return Err("the file is empty".into());
    }
    let start = b
        .iter()
        .position(|c| !c.is_ascii_whitespace())
        .unwrap_or(b.len());
    let says_solid = b[start..]
        .get(..5)
        .is_some_and(|s| s.eq_ignore_ascii_case(b"solid"));
    let Some(count_bytes) = b.get(80..84) else {
        return if says_solid {
            stl_ascii(b)
        } else {
            Err(format!(
                "{} bytes is too short for a binary STL (84-byte header) and it is not ASCII STL",
                b.len()
            ))
        };
    };
    let count = u32::from_le_bytes([
        count_bytes[0],
        count_bytes[1],
        count_bytes[2],
        count_bytes[3],
    ]);
    let needed = 84 + 50 * u64::from(count);
    if needed == b.len() as u64 {
        return stl_binary(&b[84..], count as usize);
    }
    let lie = format!(
        "as binary STL its header claims {count} triangles ({needed} bytes) but the file has {} bytes (truncated or corrupt)",
        b.len()
    );
    if says_solid {
        stl_ascii(b).map_err(|e| format!("not valid ASCII STL ({e}); {lie}"))
    } else {
        Err(lie)
    }
}

fn stl_binary(records: &[u8], count: usize) -> std::result::Result<Mesh, String> {
    // `count` matches the length of `records`, so these allocations are bounded by it.
    let mut welder = Welder::with_capacity(count / 2 + 16);
    let mut triangles = Vec::with_capacity(count);
    for (t, rec) in records.chunks_exact(50).enumerate() {
        let mut tri = [0u32; 3];
        for (k, slot) in tri.iter_mut().enumerate() {
            let mut p = [0.0f64; 3];
            for (j, x) in p.iter_mut().enumerate() {
                let o = 12 + 12 * k + 4 * j;
                *x = f64::from(f32::from_le_bytes([
                    rec[o],
                    rec[o + 1],
                    rec[o + 2],
                    rec[o + 3],
                ]));
            }
            let v = DVec3::from_array(p);
            if !v.is_finite() {
                return Err(format!("triangle {t} has a non-finite coordinate ({v})"));
            }
            *slot = welder.add(v)?;
        }
        triangles.push(tri);
    }
    Ok(welder.finish(triangles))
}

fn stl_ascii(b: &[u8]) -> std::result::Result<Mesh, String> {
    let mut welder = Welder::with_capacity(1024);
    let mut triangles = Vec::new();
    // Corners of the open facet, if any.
    let mut facet: Option<Vec<u32>> = None;
    let mut last_line = 0;
    for (ln, line) in lines(b) {
        last_line = ln;
        let mut toks = tokens(line);
        let Some(kw) = toks.next() else { continue };
        let kw = kw.to_ascii_lowercase();
        match kw.as_slice() {
            b"solid" | b"endsolid" => {
                if facet.is_some() {
                    return Err(format!("line {ln}: `{}` inside a facet", show(&kw)));
                }
            }
            b"facet" => {
                if facet.is_some() {
                    return Err(format!("line {ln}: `facet` before `endfacet`"));
                }
                facet = Some(Vec::with_capacity(3));
            }
            b"outer" | b"endloop" => {
                if facet.is_none() {
                    return Err(format!("line {ln}: `{}` outside a facet", show(&kw)));
                }
            }
            b"vertex" => {
                let corners = facet
                    .as_mut()
                    .ok_or_else(|| format!("line {ln}: `vertex` outside a facet"))?;
                if corners.len() == 3 {
                    return Err(format!("line {ln}: more than three vertices in a facet"));
                }
                let p = parse_point(&mut toks, ln)?;
                corners.push(welder.add(p)?);
            }
            b"endfacet" => match facet.take() {
                Some(c) if c.len() == 3 => triangles.push([c[0], c[1], c[2]]),
                Some(c) => {
                    return Err(format!(
                        "line {ln}: facet with {} vertices instead of 3",
                        c.len()
                    ))
                }
                None => return Err(format!("line {ln}: `endfacet` without `facet`")),
            },
            _ => return Err(format!("line {ln}: unexpected `{}`", show(&kw))),
        }
    }
    if facet.is_some() {
        return Err(format!("line {last_line}: file ends inside a facet"));
    }
    Ok(welder.finish(triangles))
}

// ---------------------------------------------------------------------------------------
// OBJ

fn parse_obj(b: &[u8]) -> std::result::Result<Mesh, String> {
    let mut raw: Vec<DVec3> = Vec::new();
    let mut tris: Vec<[usize; 3]> = Vec::new();
    let mut poly: Vec<usize> = Vec::new();
    for (ln, line) in lines(b) {
        let mut toks = tokens(strip_comment(line, b'#'));
        match toks.next() {
            Some(b"v") => raw.push(parse_point(&mut toks, ln)?),
            Some(b"f") => {
                poly.clear();
                for tok in toks {
                    let idx = tok.split(|&c| c == b'/').next().unwrap_or(tok);
                    let i: i64 = std::str::from_utf8(idx)
                        .ok()
                        .and_then(|s| s.parse().ok())
                        .ok_or_else(|| {
                            format!("line {ln}: bad vertex reference `{}`", show(tok))
                        })?;
                    // 1-based; negative counts back from the last vertex read so far.
                    let n = raw.len() as i64;
                    let zero_based = if i > 0 { i - 1 } else { n + i };
                    if i == 0 || zero_based < 0 || zero_based >= n {
                        return Err(format!(
                            "line {ln}: vertex reference {i} out of range ({n} vertices so far)"
                        ));
                    }
                    poly.push(zero_based as usize);
                }
                if poly.len() < 3 {
                    return Err(format!("line {ln}: face with fewer than 3 vertices"));
                }
                for k in 1..poly.len() - 1 {
                    tris.push([poly[0], poly[k], poly[k + 1]]);
                }
            }
            // Normals, texture coordinates, groups, materials, lines, ...: not needed.
            _ => {}
        }
    }
    weld_indexed(&raw, &tris)
}

// ---------------------------------------------------------------------------------------
// OFF

fn parse_off(b: &[u8]) -> std::result::Result<Mesh, String> {
    if b.is_empty() {
        return Err("the file is empty".into());
    }
    let mut content = lines(b)
        .map(|(ln, l)| (ln, strip_comment(l, b'#')))
        .filter(|(_, l)| tokens(l).next().is_some());
    let (ln, first) = content.next().ok_or("no OFF header")?;
    let mut toks = tokens(first).peekable();
    let head = toks.peek().copied().unwrap_or_default();
    let mut counts: Vec<&[u8]> = Vec::new();
    if head.len() >= 3 && head[head.len() - 3..].eq_ignore_ascii_case(b"OFF") {
        let prefix = &head[..head.len() - 3];
        if !prefix
            .iter()
            .all(|c| matches!(c.to_ascii_uppercase(), b'S' | b'T' | b'C' | b'N'))
        {
            return Err(format!(
                "line {ln}: unsupported OFF variant `{}` (only 3D OFF/COFF/NOFF/STOFF)",
                show(head)
            ));
        }
        toks.next();
        if toks
            .peek()
            .is_some_and(|t| t.eq_ignore_ascii_case(b"BINARY"))
        {
            return Err(format!("line {ln}: binary OFF is not supported"));
        }
        counts.extend(toks);
        if counts.is_empty() {
            let (_, l) = content
                .next()
                .ok_or("no vertex and face counts after the header")?;
            counts.extend(tokens(l));
        }
    } else if parse_u64(head).is_some() {
        // Header keyword omitted: the first line holds the counts.
        counts.extend(toks);
    } else {
        return Err(format!("line {ln}: expected `OFF`, found `{}`", show(head)));
    }
    let count = |k: usize, what: &str| {
        counts
            .get(k)
            .and_then(|t| parse_u64(t))
            .ok_or_else(|| format!("missing or bad {what} count in the OFF header"))
    };
    let nv = count(0, "vertex")?;
    let nf = count(1, "face")?;
    // A vertex line takes at least 6 bytes (`0 0 0\n`), a face line at least 8 (`3 0 1 2\n`).
    if nv.saturating_mul(6).saturating_add(nf.saturating_mul(8)) > b.len() as u64 + 8 {
        return Err(format!(
            "the header claims {nv} vertices and {nf} faces, more than a file of {} bytes can hold",
            b.len()
        ));
    }
    // Both counts are now bounded by the file length.
    let (nv, nf) = (nv as usize, nf as usize);
    let mut raw = Vec::with_capacity(nv);
    for i in 0..nv {
        let (ln, l) = content
            .next()
            .ok_or_else(|| format!("file ends after {i} of {nv} vertices"))?;
        raw.push(parse_point(&mut tokens(l), ln)?);
    }
    let mut tris = Vec::with_capacity(nf);
    for f in 0..nf {
        let (ln, l) = content
            .next()
            .ok_or_else(|| format!("file ends after {f} of {nf} faces"))?;
        let toks: Vec<&[u8]> = tokens(l).collect();
        let n = toks
            .first()
            .and_then(|t| parse_u64(t))
            .ok_or_else(|| format!("line {ln}: bad face vertex count"))?;
        if n < 3 {
            return Err(format!(
                "line {ln}: face with {n} vertices (at least 3 needed)"
            ));
        }
        if n >= toks.len() as u64 {
            return Err(format!(
                "line {ln}: face declares {n} vertices but lists {}",
                toks.len() - 1
            ));
        }
        let n = n as usize;
        let idx = |k: usize| -> std::result::Result<usize, String> {
            let tok = toks[k + 1];
            match parse_u64(tok) {
                Some(i) if i < nv as u64 => Ok(i as usize),
                _ => Err(format!(
                    "line {ln}: bad vertex index `{}` ({nv} vertices)",
                    show(tok)
                )),
            }
        };
        let v0 = idx(0)?;
        let mut prev = idx(1)?;
        for k in 2..n {
            let next = idx(k)?;
            tris.push([v0, prev, next]);
            prev = next;
        }
    }
    weld_indexed(&raw, &tris)
}

// ---------------------------------------------------------------------------------------
// PLY

#[derive(Debug, Clone, Copy)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(name: &str) -> Option<Scalar> {
        Some(match name {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }
}

struct PlyProperty {
    name: String,
    /// The count type when the property is a list.
    list: Option<Scalar>,
    ty: Scalar,
}

struct PlyElement {
    name: String,
    count: u64,
    props: Vec<PlyProperty>,
}

#[derive(Clone, Copy, PartialEq)]
enum PlyEncoding {
    Ascii,
    Binary { big_endian: bool },
}

struct PlyHeader {
    encoding: PlyEncoding,
    elements: Vec<PlyElement>,
    /// Byte offset of the body.
    body: usize,
    /// Number of header lines.
    lines: usize,
}

fn ply_header(b: &[u8]) -> std::result::Result<PlyHeader, String> {
    let mut pos = 0;
    let mut ln = 0;
    let mut encoding = None;
    let mut elements: Vec<PlyElement> = Vec::new();
    loop {
        let rest = &b[pos..];
        let nl = rest
            .iter()
            .position(|&c| c == b'\n')
            .ok_or("the header has no `end_header` line")?;
        let raw = &rest[..nl];
        let raw = raw.strip_suffix(b"\r").unwrap_or(raw);
        pos += nl + 1;
        ln += 1;
        let line = std::str::from_utf8(raw).map_err(|_| format!("header line {ln} is not text"))?;
        let toks: Vec<&str> = line.split_ascii_whitespace().collect();
        if ln == 1 {
            if toks != ["ply"] {
                return Err("the file does not start with `ply`".into());
            }
            continue;
        }
        match toks.first().copied() {
            None | Some("comment") | Some("obj_info") => {}
            Some("format") => {
                encoding = Some(match toks.get(1).copied() {
                    Some("ascii") => PlyEncoding::Ascii,
                    Some("binary_little_endian") => PlyEncoding::Binary { big_endian: false },
                    Some("binary_big_endian") => PlyEncoding::Binary { big_endian: true },
                    _ => return Err(format!("header line {ln}: unknown format `{line}`")),
                });
            }
            Some("element") => {
                let (Some(name), Some(count)) =
                    (toks.get(1), toks.get(2).and_then(|c| c.parse().ok()))
                else {
                    return Err(format!("header line {ln}: bad element line `{line}`"));
                };
                elements.push(PlyElement {
                    name: name.to_string(),
                    count,
                    props: Vec::new(),
                });
            }
            Some("property") => {
                let el = elements
                    .last_mut()
                    .ok_or_else(|| format!("header line {ln}: property before any element"))?;
                let bad = || format!("header line {ln}: bad property line `{line}`");
                let prop = if toks.get(1) == Some(&"list") {
                    match toks[..] {
                        [_, _, count, item, name] => PlyProperty {
                            name: name.to_string(),
                            list: Some(Scalar::parse(count).ok_or_else(bad)?),
                            ty: Scalar::parse(item).ok_or_else(bad)?,
                        },
                        _ => return Err(bad()),
                    }
                } else {
                    match toks[..] {
                        [_, ty, name] => PlyProperty {
                            name: name.to_string(),
                            list: None,
                            ty: Scalar::parse(ty).ok_or_else(bad)?,
                        },
                        _ => return Err(bad()),
                    }
                };
                el.props.push(prop);
            }
            Some("end_header") => break,
            Some(other) => return Err(format!("header line {ln}: unknown keyword `{other}`")),
        }
    }
    Ok(PlyHeader {
        encoding: encoding.ok_or("the header has no `format` line")?,
        elements,
        body: pos,
        lines: ln,
    })
}

/// The body of a PLY file, read one scalar at a time.
trait PlySource {
    /// Reads one value of type `ty`.
    fn read(&mut self, ty: Scalar) -> std::result::Result<f64, String>;
    /// Where the reader is, for error messages.
    fn location(&self) -> String;
}

struct PlyBinary<'a> {
    b: &'a [u8],
    pos: usize,
    big_endian: bool,
}

impl PlySource for PlyBinary<'_> {
    fn read(&mut self, ty: Scalar) -> std::result::Result<f64, String> {
        let n = ty.size();
        let bytes = self
            .b
            .get(self.pos..self.pos.saturating_add(n))
            .ok_or_else(|| format!("unexpected end of data at byte {}", self.pos))?;
        self.pos += n;
        let mut a = [0u8; 8];
        a[..n].copy_from_slice(bytes);
        if self.big_endian {
            a[..n].reverse();
        }
        // `a` is now little endian.
        Ok(match ty {
            Scalar::I8 => f64::from(a[0] as i8),
            Scalar::U8 => f64::from(a[0]),
            Scalar::I16 => f64::from(i16::from_le_bytes([a[0], a[1]])),
            Scalar::U16 => f64::from(u16::from_le_bytes([a[0], a[1]])),
            Scalar::I32 => f64::from(i32::from_le_bytes([a[0], a[1], a[2], a[3]])),
            Scalar::U32 => f64::from(u32::from_le_bytes([a[0], a[1], a[2], a[3]])),
            Scalar::F32 => f64::from(f32::from_le_bytes([a[0], a[1], a[2], a[3]])),
            Scalar::F64 => f64::from_le_bytes(a),
        })
    }

    fn location(&self) -> String {
        format!("byte {}", self.pos)
    }
}

struct PlyAscii<'a> {
    b: &'a [u8],
    pos: usize,
    line: usize,
}

impl PlySource for PlyAscii<'_> {
    fn read(&mut self, _ty: Scalar) -> std::result::Result<f64, String> {
        while let Some(&c) = self.b.get(self.pos) {
            if !c.is_ascii_whitespace() {
                break;
            }
            if c == b'\n' {
                self.line += 1;
            }
            self.pos += 1;
        }
        let start = self.pos;
        while self
            .b
            .get(self.pos)
            .is_some_and(|c| !c.is_ascii_whitespace())
        {
            self.pos += 1;
        }
        let tok = &self.b[start..self.pos];
        if tok.is_empty() {
            return Err(format!("line {}: unexpected end of data", self.line));
        }
        parse_f64(tok).ok_or_else(|| format!("line {}: `{}` is not a number", self.line, show(tok)))
    }

    fn location(&self) -> String {
        format!("line {}", self.line)
    }
}

fn parse_ply(b: &[u8]) -> std::result::Result<Mesh, String> {
    let header = ply_header(b)?;
    let body = &b[header.body..];
    match header.encoding {
        PlyEncoding::Ascii => ply_body(
            &header.elements,
            body.len(),
            &mut PlyAscii {
                b: body,
                pos: 0,
                line: header.lines + 1,
            },
        ),
        PlyEncoding::Binary { big_endian } => ply_body(
            &header.elements,
            body.len(),
            &mut PlyBinary {
                b: body,
                pos: 0,
                big_endian,
            },
        ),
    }
}

/// A list length or vertex index: a non-negative integer.
fn ply_index(v: f64, src: &impl PlySource) -> std::result::Result<usize, String> {
    if v >= 0.0 && v.fract() == 0.0 && v < 9.0e15 {
        Ok(v as usize)
    } else {
        Err(format!(
            "{}: `{v}` is not a valid count or index",
            src.location()
        ))
    }
}

fn ply_body(
    elements: &[PlyElement],
    body_len: usize,
    src: &mut impl PlySource,
) -> std::result::Result<Mesh, String> {
    let mut raw: Option<Vec<DVec3>> = None;
    let mut tris: Vec<[usize; 3]> = Vec::new();
    let mut poly: Vec<usize> = Vec::new();
    for el in elements {
        if el.props.is_empty() {
            continue; // nothing to read
        }
        // Every property takes at least one byte, so a count beyond this is a lie.
        if el.count.saturating_mul(el.props.len() as u64) > body_len as u64 {
            return Err(format!(
                "the header claims {} `{}` elements, more than {body_len} bytes of data can hold",
                el.count, el.name
            ));
        }
        let count = el.count as usize; // bounded by body_len
        let find = |name: &str| {
            el.props
                .iter()
                .position(|p| p.name == name && p.list.is_none())
        };
        match el.name.as_str() {
            "vertex" => {
                if raw.is_some() {
                    return Err("more than one `vertex` element".into());
                }
                let (Some(xi), Some(yi), Some(zi)) = (find("x"), find("y"), find("z")) else {
                    return Err("the `vertex` element lacks an x, y or z property".into());
                };
                let mut verts = Vec::with_capacity(count);
                for i in 0..count {
                    let mut p = [0.0; 3];
                    for (k, prop) in el.props.iter().enumerate() {
                        let v = ply_read_property(prop, src, None)?;
                        let slot = if k == xi {
                            0
                        } else if k == yi {
                            1
                        } else if k == zi {
                            2
                        } else {
                            continue;
                        };
                        if !v.is_finite() {
                            return Err(format!("vertex {i} has a non-finite coordinate"));
                        }
                        p[slot] = v;
                    }
                    verts.push(DVec3::from_array(p));
                }
                raw = Some(verts);
            }
            "face" => {
                let lists: Vec<usize> = (0..el.props.len())
                    .filter(|&k| el.props[k].list.is_some())
                    .collect();
                let li = el
                    .props
                    .iter()
                    .position(|p| {
                        p.list.is_some() && (p.name == "vertex_indices" || p.name == "vertex_index")
                    })
                    .or(if lists.len() == 1 {
                        Some(lists[0])
                    } else {
                        None
                    })
                    .ok_or("the `face` element has no `vertex_indices` list")?;
                for f in 0..count {
                    for (k, prop) in el.props.iter().enumerate() {
                        if k == li {
                            poly.clear();
                            ply_read_property(prop, src, Some(&mut poly))?;
                        } else {
                            ply_read_property(prop, src, None)?;
                        }
                    }
                    if poly.len() < 3 {
                        return Err(format!(
                            "face {f} has {} vertices (at least 3 needed)",
                            poly.len()
                        ));
                    }
                    for k in 1..poly.len() - 1 {
                        tris.push([poly[0], poly[k], poly[k + 1]]);
                    }
                }
            }
            _ => {
                for _ in 0..count {
                    for prop in &el.props {
                        ply_read_property(prop, src, None)?;
                    }
                }
            }
        }
    }
    let raw = raw.ok_or("no `vertex` element")?;
    if let Some((f, &i)) = tris
        .iter()
        .enumerate()
        .find_map(|(f, t)| t.iter().find(|&&i| i >= raw.len()).map(|i| (f, i)))
    {
        return Err(format!(
            "triangle {f} refers to vertex {i} but there are only {} vertices",
            raw.len()
        ));
    }
    weld_indexed(&raw, &tris)
}

/// Reads one property; a list's items go to `items` when given (as indices), else are
/// skipped. Returns the value of a scalar property (0 for a list).
fn ply_read_property(
    prop: &PlyProperty,
    src: &mut impl PlySource,
    items: Option<&mut Vec<usize>>,
) -> std::result::Result<f64, String> {
    let Some(count_ty) = prop.list else {
        return src.read(prop.ty);
    };
    let n = ply_index(src.read(count_ty)?, src)?;
    match items {
        // Each item read consumes input, so a lying count fails at the end of the data.
        Some(items) => {
            for _ in 0..n {
                let v = src.read(prop.ty)?;
                items.push(ply_index(v, src)?);
            }
        }
        None => {
            for _ in 0..n {
                src.read(prop.ty)?;
            }
        }
    }
    Ok(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gunzip_refuses_more_than_the_limit() {
        let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::best());
        enc.write_all(&vec![0u8; 1 << 20]).expect("in-memory write");
        let gz = enc.finish().expect("in-memory write");
        let err = gunzip(&gz, 1000).expect_err("over the limit");
        assert!(err.contains("gzip bomb"), "{err}");
        assert_eq!(
            gunzip(&gz, 1 << 20).expect("exactly the limit").len(),
            1 << 20
        );
    }

    #[test]
    fn gunzip_rejects_garbage() {
        assert!(gunzip(b"not gzip at all", 1000).is_err());
    }

    #[test]
    fn format_from_path() {
        let f = |p: &str| Format::from_path(Path::new(p)).ok();
        assert_eq!(f("a.STL"), Some(Format::Stl));
        assert_eq!(f("dir.x/a.stl.GZ"), Some(Format::Stl));
        assert_eq!(f("a.obj"), Some(Format::Obj));
        assert_eq!(f("a.Ply.gz"), Some(Format::Ply));
        assert_eq!(f("a.off"), Some(Format::Off));
        assert_eq!(f("a.gz"), None);
        assert_eq!(f("a.txt"), None);
        assert_eq!(f("stl"), None);
        assert!(is_gzip(Path::new("a.off.Gz")));
        assert!(!is_gzip(Path::new("a.off")));
    }
}
