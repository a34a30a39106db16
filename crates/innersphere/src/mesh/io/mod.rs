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

use std::io::{BufReader, Read, Seek, SeekFrom};
use std::path::Path;

use super::Mesh;
use crate::error::{Error, Result};

/// The most mesh data accepted from one file, after decompression (4 GiB): a larger file, or
/// a gzip file that decompresses to more, is refused (binary STL at this size holds 86
/// million triangles, far beyond what a build can voxelize).
pub const MAX_DECOMPRESSED_BYTES: u64 = 4 << 30;

/// What a gzip file may always decompress to, whatever its compression ratio (64 MiB).
pub const GZIP_FREE_BYTES: u64 = 64 << 20;

/// Beyond [`GZIP_FREE_BYTES`], the decompressed bytes may be at most this many times the
/// compressed bytes read so far. Real meshes compress 1.3× (binary STL) to about 5× (ASCII
/// formats); zeros compress about 230× with `gzip -1` and 1000× with `gzip -9`, so a bomb is
/// stopped after 64 MiB while any real mesh passes with a margin of ten.
pub const MAX_GZIP_RATIO: u64 = 50;

/// Bytes read first, before anything else is allocated, to learn from the format's header
/// how long the data can be (binary STL: exactly `84 + 50 · triangles`; binary PLY: at most
/// what its element counts and property types allow).
const HEAD_BYTES: u64 = 64 << 10;

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
pub(crate) fn is_gzip(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("gz"))
}

/// Loads a mesh file; the format comes from the extension (see [`Format::from_path`]), and a
/// final `.gz` means gzip.
///
/// Memory stays bounded by what a valid file of the same declared size needs: the first
/// 64 KiB are read before anything else, and the data is read only as far as the format's
/// header allows (a binary STL exactly `84 + 50 · triangles` bytes, a binary PLY at most
/// what its counts allow) and never beyond [`MAX_DECOMPRESSED_BYTES`]; gzip is decompressed
/// as a stream from the file, and refused once it expands beyond [`GZIP_FREE_BYTES`] at more
/// than [`MAX_GZIP_RATIO`] times the compressed bytes read. Each limit is a parse error that
/// says which limit was hit.
pub fn load(path: &Path) -> Result<Mesh> {
    let format = Format::from_path(path)?;
    let bytes = read_mesh_file(path, format)?;
    load_bytes(&bytes, format, path)
}

/// Parses the (uncompressed) bytes of a mesh file in the given format; `name` is only used
/// in error messages. Returns a welded, validated mesh; never panics. A NUL byte in a text
/// format (OBJ, OFF, an ASCII PLY) is refused: text never holds one.
pub fn load_bytes(bytes: &[u8], format: Format, name: &Path) -> Result<Mesh> {
    if matches!(is_text(format, bytes), Ok(true)) {
        if let Err(ReadFail::Limit(m)) = refuse_nul(format, bytes, 0) {
            return Err(parse_error(name, format, m));
        }
    }
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

/// The names [`save`] writes: binary STL or OBJ, gzip-compressed when the name ends in `.gz`.
pub const SAVED_MESH: crate::output::OutputKind = crate::output::OutputKind {
    what: "a mesh (binary STL or OBJ)",
    extensions: &["stl", "stl.gz", "obj", "obj.gz"],
};

/// Writes a mesh in the format its name says ([`SAVED_MESH`]: [`save_stl`] or [`save_obj`]);
/// any other name is refused, so that a file's bytes always match its extension.
pub fn save(mesh: &Mesh, path: &Path) -> Result<()> {
    SAVED_MESH.check(path)?;
    match Format::from_path(path)? {
        Format::Obj => save_obj(mesh, path),
        _ => save_stl(mesh, path),
    }
}

/// Writes a mesh as binary STL (coordinates rounded to `f32`, facet normals from the
/// corners); gzip-compressed when the path ends in `.gz`.
pub fn save_stl(mesh: &Mesh, path: &Path) -> Result<()> {
    crate::output::write_file(path, &to_stl_bytes(mesh)?)
}

/// Writes a mesh as Wavefront OBJ (`v` and `f` lines, coordinates in full `f64` precision);
/// gzip-compressed when the path ends in `.gz`.
pub fn save_obj(mesh: &Mesh, path: &Path) -> Result<()> {
    crate::output::write_file(path, &to_obj_bytes(mesh)?)
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

/// Why reading stopped: an I/O (or gzip) error, or a limit.
enum ReadFail {
    Io(std::io::Error),
    Limit(String),
}

impl From<std::io::Error> for ReadFail {
    fn from(e: std::io::Error) -> Self {
        ReadFail::Io(e)
    }
}

/// The bytes of a mesh file, decompressed when the path ends in `.gz`, within the limits
/// described at [`load`].
fn read_mesh_file(path: &Path, format: Format) -> Result<Vec<u8>> {
    let mut file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    // The length of a regular file; none for a pipe or a device.
    let known_len = file
        .metadata()
        .ok()
        .filter(|m| m.is_file())
        .map(|m| m.len());
    let limit_error = |m: String| parse_error(path, format, m);
    if !is_gzip(path) {
        if let Some(len) = known_len.filter(|&l| l > MAX_DECOMPRESSED_BYTES) {
            return Err(limit_error(format!(
                "the file has {len} bytes, more than the {MAX_DECOMPRESSED_BYTES} bytes of mesh data accepted"
            )));
        }
        return match read_capped(&mut file, format, known_len.unwrap_or(0)) {
            Ok(bytes) => Ok(bytes),
            Err(ReadFail::Io(e)) => Err(Error::io(path, e)),
            Err(ReadFail::Limit(m)) => Err(limit_error(m)),
        };
    }
    // The gzip trailer's size (mod 2^32) as a hint for the allocation, trusted only up to
    // the bytes that any ratio may produce (one byte more: the read that passes them then
    // fits, and a bomb is stopped before the buffer grows); a larger file grows it as it
    // decompresses.
    let hint = match known_len {
        Some(len) => gzip_size_hint(&mut file, len)
            .map_err(|e| Error::io(path, e))?
            .min(GZIP_FREE_BYTES + 1),
        None => 0,
    };
    let mut guard = RatioGuard {
        decoder: flate2::bufread::MultiGzDecoder::new(BufReader::new(Counted {
            inner: file,
            count: 0,
        })),
        produced: 0,
        tripped: None,
    };
    match read_capped(&mut guard, format, hint) {
        Ok(bytes) => Ok(bytes),
        Err(ReadFail::Limit(m)) => Err(limit_error(m)),
        Err(ReadFail::Io(e)) => Err(limit_error(match guard.tripped {
            Some(m) => m,
            None => format!("gzip decompression failed: {e}"),
        })),
    }
}

/// The ISIZE field of a gzip file's trailer (its last member's size mod 2^32); leaves the
/// file at its start.
fn gzip_size_hint(file: &mut std::fs::File, len: u64) -> std::io::Result<u64> {
    let mut isize = 0;
    if len >= 4 {
        file.seek(SeekFrom::End(-4))?;
        let mut tail = [0u8; 4];
        file.read_exact(&mut tail)?;
        isize = u64::from(u32::from_le_bytes(tail));
    }
    file.rewind()?;
    Ok(isize)
}

/// Reads all of `src` into memory: first [`HEAD_BYTES`], then only as far as the format's
/// header allows ([`declared_limit`]) and never beyond [`MAX_DECOMPRESSED_BYTES`].
/// `size_hint` (the file's length, or the gzip trailer's) sizes the allocation once the
/// header's limit is known, never beyond that limit.
fn read_capped(
    src: &mut dyn Read,
    format: Format,
    size_hint: u64,
) -> std::result::Result<Vec<u8>, ReadFail> {
    let mut out = Vec::new();
    src.take(HEAD_BYTES).read_to_end(&mut out)?;
    let (limit, why) = match declared_limit(format, &out) {
        Some((n, why)) if n <= MAX_DECOMPRESSED_BYTES => (n, why),
        Some((_, why)) => {
            return Err(ReadFail::Limit(format!(
            "{why}: more than the {MAX_DECOMPRESSED_BYTES} bytes of mesh data accepted (corrupt?)"
        )))
        }
        None => (MAX_DECOMPRESSED_BYTES, "the limit on mesh data".to_string()),
    };
    let text = is_text(format, &out)?;
    if text {
        refuse_nul(format, &out, 0)?;
    }
    if out.len() as u64 <= limit {
        let reserve = size_hint.min(limit).saturating_sub(out.len() as u64) as usize;
        if out.try_reserve_exact(reserve).is_err() {
            return Err(ReadFail::Limit(format!(
                "not enough memory for {size_hint} bytes of mesh data"
            )));
        }
        // One byte beyond the limit, to tell "exactly the limit" from "more".
        let mut rest = src.take(limit + 1 - out.len() as u64);
        if text {
            // In chunks, so that binary data behind a text head stops at its first NUL.
            let mut chunk = vec![0u8; HEAD_BYTES as usize];
            loop {
                let n = match rest.read(&mut chunk) {
                    Ok(0) => break,
                    Ok(n) => n,
                    Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                    Err(e) => return Err(e.into()),
                };
                refuse_nul(format, &chunk[..n], out.len())?;
                out.extend_from_slice(&chunk[..n]);
            }
        } else {
            rest.read_to_end(&mut out)?;
        }
    }
    if out.len() as u64 > limit {
        return Err(ReadFail::Limit(format!(
            "the data goes on beyond {limit} bytes ({why}); refusing to read on (corrupt file, or a gzip bomb?)"
        )));
    }
    Ok(out)
}

/// Whether a file of this format with these first bytes is text to its end, where a NUL
/// byte is never valid: OBJ, OFF and an ASCII PLY (after its header). STL is not: a binary
/// STL may start with `solid`, and its length decides. A PLY whose header is not within
/// the first [`HEAD_BYTES`] is refused here, before reading on.
fn is_text(format: Format, head: &[u8]) -> std::result::Result<bool, ReadFail> {
    match format {
        Format::Obj | Format::Off => Ok(true),
        Format::Stl => Ok(false),
        Format::Ply => match ply::is_ascii(head) {
            Ok(ascii) => Ok(ascii),
            Err(_) if (head.len() as u64) < HEAD_BYTES => Ok(false),
            Err(e) => Err(ReadFail::Limit(format!(
                "no PLY header within the first {HEAD_BYTES} bytes ({e}); refusing to read on"
            ))),
        },
    }
}

/// An error at the first NUL byte of `bytes` (which start at byte `at` of the file): text
/// formats never hold one, so a device such as `/dev/zero` or binary data under a text
/// format's extension is refused at its first chunk instead of being read to the 4 GiB
/// limit ([`load_bytes`] refuses the same bytes).
fn refuse_nul(format: Format, bytes: &[u8], at: usize) -> std::result::Result<(), ReadFail> {
    match bytes.iter().position(|&b| b == 0) {
        None => Ok(()),
        Some(i) => Err(ReadFail::Limit(format!(
            "byte {} is a NUL byte, and {} is text: binary data, a device such as /dev/zero, or another format under this extension?",
            at + i,
            match format {
                Format::Obj => "an OBJ file",
                Format::Off => "an OFF file",
                _ => "an ASCII PLY file",
            }
        ))),
    }
}

/// The most bytes a file of this format can have given its first bytes, and why; `None`
/// when the header does not bound the length (text formats).
fn declared_limit(format: Format, head: &[u8]) -> Option<(u64, String)> {
    match format {
        Format::Stl => stl::declared_len(head).map(|(n, count)| {
            (
                n,
                format!("as binary STL its header declares {count} triangles, {n} bytes"),
            )
        }),
        Format::Ply => ply::max_len(head).map(|n| {
            (
                n,
                format!("the most its binary PLY header's counts and types allow is {n} bytes"),
            )
        }),
        Format::Obj | Format::Off => None,
    }
}

/// A reader that counts the bytes read through it.
struct Counted<R> {
    inner: R,
    count: u64,
}

impl<R: Read> Read for Counted<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.count += n as u64;
        Ok(n)
    }
}

/// A gzip decoder that fails once its output passes [`GZIP_FREE_BYTES`] at more than
/// [`MAX_GZIP_RATIO`] times the compressed bytes read so far (the message is kept in
/// `tripped`).
struct RatioGuard<R: Read> {
    decoder: flate2::bufread::MultiGzDecoder<BufReader<Counted<R>>>,
    produced: u64,
    tripped: Option<String>,
}

impl<R: Read> Read for RatioGuard<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.decoder.read(buf)?;
        self.produced += n as u64;
        let consumed = self.decoder.get_ref().get_ref().count;
        if self.produced > GZIP_FREE_BYTES
            && self.produced > MAX_GZIP_RATIO.saturating_mul(consumed)
        {
            let m = format!(
                "gzip data expands to more than {GZIP_FREE_BYTES} bytes at over {MAX_GZIP_RATIO} times its compressed size ({} bytes from {consumed} compressed bytes; real meshes compress 1.3 to 5 times): refused as a likely gzip bomb",
                self.produced
            );
            self.tripped = Some(m.clone());
            return Err(std::io::Error::new(std::io::ErrorKind::InvalidData, m));
        }
        Ok(n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    fn gzip(data: &[u8], level: u32) -> Vec<u8> {
        let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::new(level));
        enc.write_all(data).expect("in-memory write");
        enc.finish().expect("in-memory write")
    }

    fn guard(gz: &[u8]) -> RatioGuard<&[u8]> {
        RatioGuard {
            decoder: flate2::bufread::MultiGzDecoder::new(BufReader::new(Counted {
                inner: gz,
                count: 0,
            })),
            produced: 0,
            tripped: None,
        }
    }

    fn limit_message(r: std::result::Result<Vec<u8>, ReadFail>) -> String {
        match r {
            Err(ReadFail::Limit(m)) => m,
            Err(ReadFail::Io(e)) => format!("io: {e}"),
            Ok(b) => panic!("{} bytes read, expected a limit", b.len()),
        }
    }

    #[test]
    fn gzip_of_spaces_stops_at_the_ratio_limit() {
        // Spaces: text, so only the ratio stops them (zeros stop at their first NUL).
        let gz = gzip(&vec![b' '; (GZIP_FREE_BYTES + (8 << 20)) as usize], 1);
        let mut g = guard(&gz);
        let message = limit_message(read_capped(&mut g, Format::Obj, 0));
        let tripped = g.tripped.expect("the ratio guard tripped");
        assert!(
            message.contains("gzip bomb") && tripped.contains("gzip bomb"),
            "{message}"
        );
        assert!(g.produced < GZIP_FREE_BYTES + (1 << 20), "{}", g.produced);
    }

    #[test]
    fn text_formats_stop_at_their_first_nul() {
        let mut bytes = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n".to_vec();
        bytes.resize(3 << 20, 0);
        for format in [Format::Obj, Format::Off] {
            let mut src: &[u8] = &bytes;
            let message = limit_message(read_capped(&mut src, format, 0));
            assert!(message.contains("byte 32 is a NUL byte"), "{message}");
            // Refused at the head: nothing read beyond it.
            assert_eq!(src.len(), bytes.len() - HEAD_BYTES as usize);
        }
        // The same bytes parsed directly are refused alike.
        let e = load_bytes(&bytes, Format::Obj, Path::new("x.obj")).unwrap_err();
        assert!(e.to_string().contains("byte 32 is a NUL byte"), "{e}");
        // A text head, then NULs after the first chunk: refused there.
        let mut late = b"v 0 0 0\n".repeat(20_000);
        let n = late.len();
        late.resize(n + 4096, 0);
        let mut src: &[u8] = &late;
        let message = limit_message(read_capped(&mut src, Format::Obj, 0));
        assert!(
            message.contains(&format!("byte {n} is a NUL byte")),
            "{message}"
        );
        // "solid" with a NUL in the head: binary STL, bounded by its declared count.
        let mut solid = b"solid binary header".to_vec();
        solid.resize(80, 0);
        solid.extend_from_slice(&0u32.to_le_bytes());
        solid.resize(1 << 20, b' ');
        let mut src: &[u8] = &solid;
        let message = limit_message(read_capped(&mut src, Format::Stl, 0));
        assert!(message.contains("declares 0 triangles"), "{message}");
    }

    #[test]
    fn binary_stl_is_read_only_as_far_as_its_header_declares() {
        // 84 zero bytes are a binary STL of 0 triangles; what follows is refused unread.
        let mut src: &[u8] = &[0u8; 1 << 20];
        let message = limit_message(read_capped(&mut src, Format::Stl, 0));
        assert!(
            message.contains("declares 0 triangles, 84 bytes"),
            "{message}"
        );
        assert!(src.len() > (1 << 20) - HEAD_BYTES as usize - 1);
        // Exactly the declared length is read.
        let mut exact = vec![7u8; 84 + 50];
        exact[80..84].copy_from_slice(&1u32.to_le_bytes());
        let mut src: &[u8] = &exact;
        assert!(matches!(read_capped(&mut src, Format::Stl, 0), Ok(b) if b == exact));
        // A header declaring more than the limit is refused before reading on.
        exact[80..84].copy_from_slice(&u32::MAX.to_le_bytes());
        let mut src: &[u8] = &exact;
        let message = limit_message(read_capped(&mut src, Format::Stl, 0));
        assert!(message.contains("more than the"), "{message}");
    }

    #[test]
    fn binary_ply_is_read_only_as_far_as_its_counts_allow() {
        let header = "ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty float x\n\
                      property float y\nproperty float z\nelement face 1\n\
                      property list uchar int vertex_indices\nend_header\n";
        let most = header.len() as u64 + 2 * 12 + (1 + 255 * 4);
        let mut data = header.as_bytes().to_vec();
        data.resize(most as usize + 1, 0);
        assert_eq!(ply::max_len(&data), Some(most));
        let mut src: &[u8] = &data;
        let message = limit_message(read_capped(&mut src, Format::Ply, 0));
        assert!(
            message.contains(&format!("allow is {most} bytes")),
            "{message}"
        );
        let ascii = header.replace("binary_little_endian", "ascii");
        assert_eq!(ply::max_len(ascii.as_bytes()), None);
        let wide = header.replace("list uchar", "list uint");
        assert_eq!(ply::max_len(wide.as_bytes()), None);
    }

    #[test]
    fn real_gzip_passes_the_guard() {
        let text: Vec<u8> = (0..200_000)
            .flat_map(|i: u32| format!("v {} {} {}\n", i, i * 7 % 13, i % 101).into_bytes())
            .collect();
        let gz = gzip(&text, 9);
        let mut g = guard(&gz);
        assert!(matches!(read_capped(&mut g, Format::Obj, 0), Ok(b) if b == text));
    }

    #[test]
    fn corrupt_gzip_is_an_io_error() {
        let mut g = guard(b"not gzip at all");
        assert!(matches!(
            read_capped(&mut g, Format::Obj, 0),
            Err(ReadFail::Io(_))
        ));
        assert!(g.tripped.is_none());
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
