//! Mesh file formats: STL (binary and ASCII), OBJ, PLY, OFF, each optionally gzip-compressed.
//!
//! Every loader returns a welded [`Mesh`] that has passed [`Mesh::validate`]: vertices with
//! bit-identical coordinates are merged (the rule of [`Mesh::from_soup`]; `-0.0` and `0.0`
//! are the same point), vertices that no triangle uses are dropped, and polygons are
//! triangulated as fans `(v0, vi, vi+1)`. A coordinate anywhere in a file that is
//! non-finite or beyond ±[`MAX_COORDINATE`](super::MAX_COORDINATE) is a parse error naming
//! its line (text formats), triangle (binary STL) or vertex (PLY).
//!
//! The four parsers are written here instead of using `tobj` or `ply-rs-bw`, because a
//! loader for untrusted files must
//! - never size an allocation from a count in a header beyond what the remaining bytes can
//!   hold (a 100-byte file claiming 4 billion triangles is an error, not an out-of-memory
//!   abort),
//! - never panic on any byte input (checked by a proptest in `tests/mesh_io.rs`; with our
//!   own code that property is auditable in this module),
//! - read coordinates as `f64` (`tobj` reads `f32` unless a feature is switched on),
//! - decide binary vs ASCII STL by the file length, not by the `solid` prefix (binary STL
//!   exporters often write `solid` into the header), and
//! - report errors with a line number or byte offset.
//!
//! The subset read of each format is small: positions and faces only (normals, texture
//! coordinates, colours and materials are ignored).
//!
//! This file holds format detection, gzip, [`load`] / [`load_bytes`] and the save functions;
//! each format's reader (and writer, for STL and OBJ) has its own file, and the welding and
//! text-tokenizing helpers they share live in `weld` and `text`.

mod obj;
mod off;
mod ply;
mod stl;
mod text;
mod weld;

pub use obj::to_obj_bytes;
pub use stl::to_stl_bytes;

use std::io::{Read, Write};
use std::path::Path;

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
        Format::Stl => stl::parse_stl(bytes),
        Format::Obj => obj::parse_obj(bytes),
        Format::Ply => ply::parse_ply(bytes),
        Format::Off => off::parse_off(bytes),
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

// ---------------------------------------------------------------------------------------
// Errors, writing and gzip

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
