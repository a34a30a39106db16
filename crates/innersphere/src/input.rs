//! Reading the small text inputs a user names (teeth-axes JSON, landmarks, motion files):
//! never more than a stated number of bytes, whatever the path names — a regular file, a
//! pipe, a FIFO or a device such as `/dev/zero` or `/dev/urandom`.
//!
//! [`read_text`] is the one reader of such files; each kind of file states its limit
//! ([`TextInput`]). A regular file longer than the limit is refused before it is read; a
//! stream is read in 64 KiB chunks and refused at the first chunk that passes the limit, holds
//! a NUL byte (text never does: zeros from a device, binary data) or is not UTF-8, so that
//! `/dev/zero` and `/dev/urandom` are refused after one chunk. Every refusal names the file,
//! what it was read as and the limit. A final `.gz` in the path means gzip, as for meshes and
//! motions; the limit then holds for the decompressed text, so a gzip bomb costs at most the
//! limit. Mesh and tree files have readers of their own, bounded by their headers
//! (`mesh::io`, `tree::file`).
//!
//! ```
//! use innersphere::input::{read_text, TextInput};
//! let small = TextInput { what: "note", max_bytes: 16 };
//! let e = read_text("/dev/zero".as_ref(), small).unwrap_err().to_string();
//! assert!(e.contains("the 16-byte limit for a note"), "{e}");
//! ```

use crate::error::{Error, Result};
use std::io::Read;
use std::path::Path;

/// A kind of text input: its name in messages and the most bytes it may hold.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TextInput {
    /// What the file is read as, for messages ("teeth-axes JSON file").
    pub what: &'static str,
    /// The most bytes accepted (decompressed, for a `.gz` path).
    pub max_bytes: u64,
}

/// A teeth-axes JSON file (`contact_map::Teeth`; also `ist occlude --landmarks`): at most
/// 1 MiB. A real one is 7 KB for 15 teeth (four points of 17-digit numbers per tooth); 32
/// teeth with every number at full precision and a few extra keys stay under 40 KB, so
/// 1 MiB leaves a margin of 25 while parsing it takes about a millisecond.
pub const TEETH_FILE: TextInput = TextInput {
    what: "teeth-axes JSON file",
    max_bytes: 1 << 20,
};

/// Bytes read at a time from a stream: a refusal (too long, NUL, not UTF-8) comes after at
/// most this much beyond what was accepted so far.
const CHUNK: usize = 64 << 10;

/// The bytes as a message writes a size: `1 MiB`, `64 KiB`, `1 GiB`, or bytes.
fn human(bytes: u64) -> String {
    for (unit, name) in [(1u64 << 30, "GiB"), (1 << 20, "MiB"), (1 << 10, "KiB")] {
        if bytes >= unit && bytes.is_multiple_of(unit) {
            return format!("{} {name}", bytes / unit);
        }
    }
    format!("{bytes} bytes")
}

/// "the 1048576-byte (1 MiB) limit for a teeth-axes JSON file".
fn limit(kind: TextInput) -> String {
    match human(kind.max_bytes) {
        h if h.ends_with("bytes") => {
            format!("the {}-byte limit for a {}", kind.max_bytes, kind.what)
        }
        h => format!(
            "the {}-byte ({h}) limit for a {}",
            kind.max_bytes, kind.what
        ),
    }
}

/// "1048576 bytes (1 MiB)", or "100000 bytes".
fn size(bytes: u64) -> String {
    match human(bytes) {
        h if h.ends_with("bytes") => h,
        h => format!("{bytes} bytes ({h})"),
    }
}

fn refused(path: &Path, message: String) -> Error {
    Error::Input {
        path: path.to_path_buf(),
        message,
    }
}

/// The text of the file at `path` (gzip-decompressed when the path ends in `.gz`), at most
/// `kind.max_bytes` bytes of UTF-8 without NUL bytes; see the [module docs](self).
pub fn read_text(path: &Path, kind: TextInput) -> Result<String> {
    let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    let gzip = crate::mesh::io::is_gzip(path);
    // The length of a regular file; none for a pipe or a device.
    let known = file
        .metadata()
        .ok()
        .filter(|m| m.is_file())
        .map(|m| m.len());
    if let Some(len) = known.filter(|&l| !gzip && l > kind.max_bytes) {
        return Err(refused(
            path,
            format!(
                "the file has {len} bytes, more than {}; refused unread",
                limit(kind)
            ),
        ));
    }
    let hint = if gzip { 0 } else { known.unwrap_or(0) };
    if gzip {
        let mut src = flate2::read::MultiGzDecoder::new(std::io::BufReader::new(file));
        read_text_from(&mut src, path, kind, hint)
    } else {
        let mut src = file;
        read_text_from(&mut src, path, kind, hint)
    }
}

/// [`read_text`] from any reader (`path` names it in messages; `size_hint`, the expected
/// length, sizes the buffer up to the limit).
pub fn read_text_from(
    src: &mut dyn Read,
    path: &Path,
    kind: TextInput,
    size_hint: u64,
) -> Result<String> {
    // The whole expected length is reserved once the first chunk has shown text: a sparse
    // file of zeros costs one chunk, not its length.
    let mut reserve = size_hint.min(kind.max_bytes) as usize;
    let mut out: Vec<u8> = Vec::new();
    let mut chunk = vec![0u8; CHUNK];
    // Bytes known to be whole UTF-8 characters (a character may straddle two chunks).
    let mut valid = 0usize;
    loop {
        let n = match src.read(&mut chunk) {
            Ok(0) => break,
            Ok(n) => n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(Error::io(path, e)),
        };
        if out.len() as u64 + n as u64 > kind.max_bytes {
            return Err(refused(
                path,
                format!(
                    "larger than {}; stopped reading there (a device, or not a {}?)",
                    limit(kind),
                    kind.what
                ),
            ));
        }
        if let Some(i) = chunk[..n].iter().position(|&b| b == 0) {
            return Err(refused(
                path,
                format!(
                    "not a {}: byte {} is a NUL byte, and a {} is UTF-8 text of at most {}: binary data, or a device such as /dev/zero?",
                    kind.what,
                    out.len() + i,
                    kind.what,
                    size(kind.max_bytes)
                ),
            ));
        }
        if reserve > 0 && !out.is_empty() {
            out.reserve_exact(reserve.saturating_sub(out.len()));
            reserve = 0;
        }
        out.extend_from_slice(&chunk[..n]);
        match std::str::from_utf8(&out[valid..]) {
            Ok(_) => valid = out.len(),
            // An incomplete character at the end: the next chunk completes it.
            Err(e) if e.error_len().is_none() => valid += e.valid_up_to(),
            Err(e) => return Err(not_utf8(path, kind, &out, valid + e.valid_up_to())),
        }
    }
    if valid != out.len() {
        return Err(not_utf8(path, kind, &out, valid));
    }
    String::from_utf8(out).map_err(|e| {
        let at = e.utf8_error().valid_up_to();
        not_utf8(path, kind, e.as_bytes(), at)
    })
}

fn not_utf8(path: &Path, kind: TextInput, bytes: &[u8], at: usize) -> Error {
    let line = 1 + bytes[..at].iter().filter(|&&b| b == b'\n').count();
    refused(
        path,
        format!(
            "not a {}: line {line} (byte {at}) is not UTF-8 text (binary data, or another encoding?)",
            kind.what
        ),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    const NOTE: TextInput = TextInput {
        what: "note",
        max_bytes: 100_000,
    };

    fn from(bytes: &[u8], kind: TextInput) -> Result<String> {
        read_text_from(&mut &bytes[..], Path::new("n.txt"), kind, 0)
    }

    #[test]
    fn reads_text_up_to_the_limit_and_refuses_beyond() {
        let text = "é".repeat(50_000); // 100,000 bytes, characters across chunk borders
        assert_eq!(from(text.as_bytes(), NOTE).unwrap(), text);
        let more = format!("{text}x");
        let e = from(more.as_bytes(), NOTE).unwrap_err().to_string();
        assert!(
            e.starts_with("n.txt: larger than the 100000-byte limit for a note"),
            "{e}"
        );
        assert_eq!(from(b"", NOTE).unwrap(), "");
    }

    #[test]
    fn refuses_nul_and_bad_utf8_with_where() {
        let mut b = vec![b'a'; 70_000];
        b[69_999] = 0;
        let e = from(&b, NOTE).unwrap_err().to_string();
        assert!(e.contains("byte 69999 is a NUL byte"), "{e}");
        assert!(e.contains("at most 100000 bytes"), "{e}");
        let e = from(b"ab\ncd\xff", NOTE).unwrap_err().to_string();
        assert!(e.contains("line 2 (byte 5)"), "{e}");
        // Cut inside a character.
        let e = from("aé".as_bytes().split_last().unwrap().1, NOTE)
            .unwrap_err()
            .to_string();
        assert!(e.contains("byte 1"), "{e}");
    }

    #[test]
    fn files_devices_and_gzip() {
        let dir = std::env::temp_dir().join(format!("innersphere-input-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let big = dir.join("big.json");
        std::fs::File::create(&big)
            .unwrap()
            .set_len(TEETH_FILE.max_bytes + 1)
            .unwrap();
        let e = read_text(&big, TEETH_FILE).unwrap_err().to_string();
        assert!(
            e.contains("1048577 bytes, more than the 1048576-byte (1 MiB) limit for a teeth-axes JSON file; refused unread"),
            "{e}"
        );
        let gz = dir.join("t.json.gz");
        crate::output::write_file(&gz, b"{\"1\": {}}").unwrap();
        assert_eq!(read_text(&gz, TEETH_FILE).unwrap(), "{\"1\": {}}");
        std::fs::remove_dir_all(&dir).ok();
        for dev in ["/dev/zero", "/dev/urandom"] {
            if Path::new(dev).exists() {
                let e = read_text(Path::new(dev), TEETH_FILE).unwrap_err();
                assert!(matches!(e, Error::Input { .. }), "{e}");
                assert!(e.to_string().contains("1 MiB"), "{e}");
            }
        }
    }
}
