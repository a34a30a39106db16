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
//! truncated, corrupted or lying file is a clear error and never a panic. [`load`] reads the
//! 24-byte header first and then exactly the size it declares: a file that is not a tree
//! (wrong magic, `/dev/zero`), that declares more than [`MAX_NODES`] nodes, or whose length
//! differs from the declared size is refused before the rest is read; a source of unknown
//! length (a pipe) is read only as far as the declared size, so memory follows the bytes that
//! really arrive.
//!
//! Writing ([`save`], [`to_checked_bytes`]) refuses what reading would refuse (a non-finite
//! sphere or meta value, a broken structure, too many nodes), so a written tree always reads
//! back.

use super::{SphereTree, TreeMeta};
use crate::error::{Error, Result};
use std::io::Read;
use std::path::Path;

/// The first eight bytes of every tree file.
pub const MAGIC: [u8; 8] = *b"ISTREE\r\n";
/// The format version this library writes and reads.
pub const VERSION: u32 = 1;
const HEADER: usize = 24;
const BYTES_PER_NODE: usize = 16 + 4 + 1 + 4 + 2;
const MAX_META: usize = 1 << 20;
/// The most nodes a tree file may declare (2^31, a 58 GB file). No build comes near it: the
/// voxel grid has at most `MAX_CELLS` = 6·10^8 cells, every
/// inner sphere takes its own inside cell, and a hierarchy of fan-out ≥ 2 has fewer inner
/// nodes than leaves, so a build makes fewer than 1.2·10^9 nodes. A header beyond it is
/// refused before anything is read or allocated.
pub const MAX_NODES: u64 = 1 << 31;
/// Bytes reserved up front when the length of the source is unknown (a pipe); beyond it the
/// buffer grows with the bytes that really arrive.
const UNKNOWN_LENGTH_RESERVE: u64 = 64 << 20;

/// Checks that a tree can be written so that [`from_bytes`] reads it back: at most
/// [`MAX_NODES`] nodes, the structure of [`SphereTree::validate_structure`] (finite spheres,
/// consistent links), and finite meta values (JSON has no NaN or infinity: a non-finite volume
/// would be written as `null`, which no reader accepts).
pub(crate) fn check_writable(tree: &SphereTree) -> Result<()> {
    if tree.len() as u64 > MAX_NODES {
        return Err(Error::CorruptTree(format!(
            "{} nodes are more than a tree file holds ({MAX_NODES})",
            tree.len()
        )));
    }
    tree.validate_structure()?;
    let m = &tree.meta;
    let scalars = [
        ("voxel_size", m.voxel_size),
        ("min_radius", m.min_radius),
        ("mesh_volume", m.mesh_volume),
        ("source_volume", m.source_volume.unwrap_or_default()),
        ("coverage", m.coverage),
    ];
    let points = [
        ("center_of_mass", m.center_of_mass),
        ("bbox_min", m.bbox_min),
        ("bbox_max", m.bbox_max),
    ];
    let inertia = m.inertia.unwrap_or_default().map(|x| ("inertia", x));
    let centroid = m
        .source_centroid
        .unwrap_or_default()
        .map(|x| ("source_centroid", x));
    let values = scalars
        .into_iter()
        .chain(
            points
                .into_iter()
                .flat_map(|(name, p)| p.into_iter().map(move |x| (name, x))),
        )
        .chain(inertia)
        .chain(centroid);
    for (name, x) in values {
        if !x.is_finite() {
            return Err(Error::CorruptTree(format!(
                "the tree's {name} is {x}, which a tree file cannot hold (a mesh beyond the supported coordinate range?)"
            )));
        }
    }
    Ok(())
}

/// [`to_bytes`] after `check_writable` (the tree's limits): the bytes of a tree that reads back.
pub fn to_checked_bytes(tree: &SphereTree) -> Result<Vec<u8>> {
    check_writable(tree)?;
    let bytes = to_bytes(tree);
    let meta_len = u32::from_le_bytes(bytes[12..16].try_into().expect("4 bytes")) as usize;
    if meta_len > MAX_META {
        return Err(Error::CorruptTree(format!(
            "meta block of {meta_len} bytes is more than a tree file holds ({MAX_META})"
        )));
    }
    Ok(bytes)
}

/// Serializes a tree to bytes (deterministic: the same tree gives the same bytes). Checks
/// nothing, so that tests can write broken trees; [`save`] and [`to_checked_bytes`] refuse a
/// tree that [`from_bytes`] would refuse.
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

/// The meta length and node count of a header, and the total file size they declare;
/// refuses a wrong magic number, another version, or implausible sizes.
fn parse_header(h: &[u8]) -> Result<(usize, u64, u64)> {
    let bad = |m: String| Err(Error::CorruptTree(m));
    if h.len() < HEADER {
        return bad(format!(
            "file too short ({} bytes) to be a tree file",
            h.len()
        ));
    }
    if h[..8] != MAGIC {
        return bad("not an innersphere tree file (wrong magic number)".into());
    }
    let u32_at = |o: usize| u32::from_le_bytes(h[o..o + 4].try_into().expect("4 bytes"));
    let version = u32_at(8);
    if version != VERSION {
        return bad(format!(
            "format version {version} is not supported (this build reads version {VERSION})"
        ));
    }
    let meta_len = u32_at(12) as usize;
    let n = u64::from_le_bytes(h[16..24].try_into().expect("8 bytes"));
    if meta_len > MAX_META {
        return bad(format!("meta block of {meta_len} bytes is implausible"));
    }
    if n > MAX_NODES {
        return bad(format!(
            "the header declares {n} nodes, more than a tree file may hold ({MAX_NODES})"
        ));
    }
    // At most 2^31 · 27 + 1 MiB + 28: no overflow.
    let total = n * BYTES_PER_NODE as u64 + (HEADER + meta_len + 4) as u64;
    Ok((meta_len, n, total))
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
    let (meta_len, n, expected) = parse_header(&bytes[..HEADER])?;
    if expected != bytes.len() as u64 {
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

/// Writes a tree file; refuses a tree that would not read back (see `check_writable` (the tree's limits)).
pub fn save(tree: &SphereTree, path: &Path) -> Result<()> {
    let bytes = to_checked_bytes(tree)?;
    crate::output::write_atomic(path, |w| w.write_all(&bytes))
}

/// Reads a tree file: the header first, then exactly the size it declares (see the module
/// documentation), so that a file that is no tree, or lies about its size, is refused before
/// its bytes are read.
pub fn load(path: &Path) -> Result<SphereTree> {
    let named = |e: Error| match e {
        Error::CorruptTree(m) => Error::CorruptTree(format!("{}: {m}", path.display())),
        other => other,
    };
    let io = |e: std::io::Error| Error::io(path, e);
    let file = std::fs::File::open(path).map_err(io)?;
    // The length of a regular file; none for a pipe or a device such as /dev/zero.
    let known_len = file
        .metadata()
        .ok()
        .filter(|m| m.is_file())
        .map(|m| m.len());
    let mut bytes = Vec::with_capacity(HEADER);
    let mut file = file;
    (&mut file)
        .take(HEADER as u64)
        .read_to_end(&mut bytes)
        .map_err(io)?;
    let (_, n, expected) = parse_header(&bytes).map_err(named)?;
    if let Some(len) = known_len.filter(|&len| len != expected) {
        return Err(named(Error::CorruptTree(format!(
            "the header promises {n} nodes ({expected} bytes) but the file has {len} bytes (truncated or corrupted)"
        ))));
    }
    let reserve = match known_len {
        Some(_) => expected,
        None => expected.min(UNKNOWN_LENGTH_RESERVE),
    };
    let reserve = usize::try_from(reserve).unwrap_or(usize::MAX) - HEADER;
    bytes.try_reserve_exact(reserve).map_err(|_| {
        named(Error::CorruptTree(format!(
            "not enough memory to read a tree of {n} nodes ({expected} bytes)"
        )))
    })?;
    // One byte more than declared, so that a longer source is noticed by `from_bytes`.
    file.take(expected + 1 - HEADER as u64)
        .read_to_end(&mut bytes)
        .map_err(io)?;
    from_bytes(&bytes).map_err(named)
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
