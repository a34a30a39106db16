//! The tree file format (`.ist`), version 1. Little-endian throughout:
//!
//! ```text
//! offset  size        field
//! 0       8           magic  b"ISTREE\r\n" (the CR LF catches text-mode mangling)
//! 8       4           format version (u32) = 1
//! 12      4           meta length M (u32), at most 1 MiB
//! 16      8           node count N (u64)
//! 24      M           meta: JSON of TreeMeta (build parameters, mesh facts)
//! 24+M    16·N        x, y, z, r (f32 each, four arrays)
//!         4·N         first_child (u32)
//!         N           child_count (u8)
//!         4·N         parent (u32)
//!         2·N         depth (u16)
//! end−4   4           CRC-32 of every byte before it
//! ```
//!
//! Reading checks the size implied by the header against the real file size *before*
//! allocating, then the checksum, then the structure ([`SphereTree::validate_structure`]), so a
//! truncated, corrupted or lying file is a clear error and never a panic.

use super::{SphereTree, TreeMeta};
use crate::{Error, Result};
use std::path::Path;

/// The first eight bytes of every tree file.
pub const MAGIC: [u8; 8] = *b"ISTREE\r\n";
/// The format version this library writes and reads.
pub const VERSION: u32 = 1;
const HEADER: usize = 24;
const BYTES_PER_NODE: usize = 16 + 4 + 1 + 4 + 2;
const MAX_META: usize = 1 << 20;

/// Serializes a tree to bytes (deterministic: the same tree gives the same bytes).
pub fn to_bytes(tree: &SphereTree) -> Vec<u8> {
    let meta = serde_json::to_vec(&tree.meta).expect("TreeMeta serializes");
    let n = tree.len();
    let mut out = Vec::with_capacity(HEADER + meta.len() + BYTES_PER_NODE * n + 4);
    out.extend_from_slice(&MAGIC);
    out.extend_from_slice(&VERSION.to_le_bytes());
    out.extend_from_slice(&(meta.len() as u32).to_le_bytes());
    out.extend_from_slice(&(n as u64).to_le_bytes());
    out.extend_from_slice(&meta);
    for arr in [&tree.x, &tree.y, &tree.z, &tree.r] {
        for v in arr.iter() {
            out.extend_from_slice(&v.to_le_bytes());
        }
    }
    for v in &tree.first_child {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out.extend_from_slice(&tree.child_count);
    for v in &tree.parent {
        out.extend_from_slice(&v.to_le_bytes());
    }
    for v in &tree.depth {
        out.extend_from_slice(&v.to_le_bytes());
    }
    let crc = crc32fast::hash(&out);
    out.extend_from_slice(&crc.to_le_bytes());
    out
}

/// Parses a tree from bytes, verifying size, checksum and structure.
pub fn from_bytes(bytes: &[u8]) -> Result<SphereTree> {
    let bad = |m: String| Err(Error::CorruptTree(m));
    if bytes.len() < HEADER + 4 {
        return bad(format!(
            "file too short ({} bytes) to be a tree file",
            bytes.len()
        ));
    }
    if bytes[..8] != MAGIC {
        return bad("not an innersphere tree file (wrong magic number)".into());
    }
    let u32_at = |o: usize| u32::from_le_bytes(bytes[o..o + 4].try_into().expect("4 bytes"));
    let version = u32_at(8);
    if version != VERSION {
        return bad(format!(
            "format version {version} is not supported (this build reads version {VERSION})"
        ));
    }
    let meta_len = u32_at(12) as usize;
    let n = u64::from_le_bytes(bytes[16..24].try_into().expect("8 bytes"));
    if meta_len > MAX_META {
        return bad(format!("meta block of {meta_len} bytes is implausible"));
    }
    let expected = (n as u128) * BYTES_PER_NODE as u128 + (HEADER + meta_len + 4) as u128;
    if expected != bytes.len() as u128 {
        return bad(format!(
            "the header promises {n} nodes ({expected} bytes) but the file has {} bytes (truncated or corrupted)",
            bytes.len()
        ));
    }
    let body = &bytes[..bytes.len() - 4];
    let stored = u32::from_le_bytes(bytes[bytes.len() - 4..].try_into().expect("4 bytes"));
    if crc32fast::hash(body) != stored {
        return bad("checksum mismatch (the file is corrupted)".into());
    }
    let n = n as usize;
    let meta: TreeMeta = match serde_json::from_slice(&bytes[HEADER..HEADER + meta_len]) {
        Ok(m) => m,
        Err(e) => return bad(format!("meta block unreadable: {e}")),
    };
    let mut at = HEADER + meta_len;
    let mut take = |len: usize| {
        let s = &bytes[at..at + len];
        at += len;
        s
    };
    let f32s = |s: &[u8]| -> Vec<f32> {
        s.chunks_exact(4)
            .map(|c| f32::from_le_bytes(c.try_into().expect("4 bytes")))
            .collect()
    };
    let u32s = |s: &[u8]| -> Vec<u32> {
        s.chunks_exact(4)
            .map(|c| u32::from_le_bytes(c.try_into().expect("4 bytes")))
            .collect()
    };
    let x = f32s(take(4 * n));
    let y = f32s(take(4 * n));
    let z = f32s(take(4 * n));
    let r = f32s(take(4 * n));
    let first_child = u32s(take(4 * n));
    let child_count = take(n).to_vec();
    let parent = u32s(take(4 * n));
    let depth = take(2 * n)
        .chunks_exact(2)
        .map(|c| u16::from_le_bytes(c.try_into().expect("2 bytes")))
        .collect();
    let tree = SphereTree {
        x,
        y,
        z,
        r,
        first_child,
        child_count,
        parent,
        depth,
        meta,
    };
    tree.validate_structure()?;
    Ok(tree)
}

/// Writes a tree file.
pub fn save(tree: &SphereTree, path: &Path) -> Result<()> {
    std::fs::write(path, to_bytes(tree)).map_err(|e| Error::io(path, e))
}

/// Reads a tree file.
pub fn load(path: &Path) -> Result<SphereTree> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    from_bytes(&bytes).map_err(|e| match e {
        Error::CorruptTree(m) => Error::CorruptTree(format!("{}: {m}", path.display())),
        other => other,
    })
}

impl SphereTree {
    /// Reads a tree file written by [`SphereTree::save`] (or `ist build`), checking its size,
    /// checksum and structure (see [`load`]). Takes anything path-like (`&str`, `&Path`,
    /// `PathBuf`, ...).
    pub fn load(path: impl AsRef<Path>) -> Result<SphereTree> {
        load(path.as_ref())
    }
    /// Writes the tree file (see [`save`]; the same tree always gives the same bytes).
    pub fn save(&self, path: impl AsRef<Path>) -> Result<()> {
        save(self, path.as_ref())
    }
}
