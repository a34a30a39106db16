//! A folder of built trees keyed by what they were built from, so that opening the same scan
//! again costs a file read instead of a build ([`BuildCache::get_or_build`]).
//!
//! - **Key**: a BLAKE3 hash of the mesh as loaded (vertex coordinates' bits and triangle
//!   indices, after the loaders' welding), the build options, the tree file format's version,
//!   the builder's revision ([`BUILD_REVISION`](crate::tree::BUILD_REVISION)) and the
//!   library's version. An entry is `<key>.ist`: other options, another builder or another
//!   format give another key, so an entry is never used for what it was not built from.
//! - **Trust**: an entry is read with the tree file's own checks (header, sizes, CRC,
//!   structure); one that fails them (truncated, corrupt) is removed and rebuilt.
//! - **Writes** go through a temporary file renamed into place
//!   ([`write_atomic`](crate::output::write_atomic)): two processes building the same mesh at
//!   once both succeed and leave one entry.
//! - **Bound**: after each write the oldest entries (by last use: a hit touches its entry)
//!   are removed until the folder's entries fit `max_bytes` (the entry just written is kept
//!   even when it alone is larger).

use super::{build_tree, BuildOptions, BuildReport};
use crate::error::{Error, Result};
use crate::mesh::Mesh;
use crate::progress::Progress;
use crate::tree::SphereTree;
use std::path::{Path, PathBuf};

/// Default bound of a cache folder: 2 GiB (about 300 jaw-arch trees).
pub const DEFAULT_MAX_BYTES: u64 = 2 << 30;

/// A folder of built trees (see the module docs).
#[derive(Debug, Clone)]
pub struct BuildCache {
    dir: PathBuf,
    max_bytes: u64,
}

/// Where a tree of [`BuildCache::get_or_build`] came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum CacheOutcome {
    /// Read from the cache.
    Hit,
    /// Built and stored (no entry).
    Built,
    /// Built and stored again: the entry failed the tree file's checks.
    Rebuilt,
}

impl BuildCache {
    /// A cache in `dir` (created when first written) bounded to `max_bytes`.
    pub fn new(dir: impl Into<PathBuf>, max_bytes: u64) -> BuildCache {
        BuildCache {
            dir: dir.into(),
            max_bytes,
        }
    }

    /// The platform's cache folder for this library (`$XDG_CACHE_HOME/innersphere` or
    /// `~/.cache/innersphere` on Linux, `~/Library/Caches/innersphere` on macOS,
    /// `%LOCALAPPDATA%\innersphere` on Windows); `None` where the platform has none.
    pub fn default_dir() -> Option<PathBuf> {
        dirs::cache_dir().map(|d| d.join("innersphere"))
    }

    /// The folder.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The key of `mesh` built with `opts` (64 hex digits; see the module docs).
    pub fn key(mesh: &Mesh, opts: &BuildOptions) -> String {
        let mut h = blake3::Hasher::new();
        h.update(b"innersphere tree cache\0");
        h.update(env!("CARGO_PKG_VERSION").as_bytes());
        h.update(&crate::tree::BUILD_REVISION.to_le_bytes());
        h.update(&crate::tree::file::VERSION.to_le_bytes());
        h.update(format!("{opts:?}").as_bytes());
        h.update(mesh.content_hash().as_bytes());
        h.finalize().to_hex().to_string()
    }

    /// The entry of `key`.
    pub fn entry(&self, key: &str) -> PathBuf {
        self.dir.join(format!("{key}.ist"))
    }

    /// The tree of `mesh` built with `opts`: read from the cache when a valid entry is there,
    /// else built (reporting to `progress`) and stored, with the build's report (its
    /// warnings). Fails when the build fails or the entry cannot be written (the folder is not
    /// writable, the disk is full).
    pub fn get_or_build(
        &self,
        mesh: &Mesh,
        opts: &BuildOptions,
        progress: &dyn Progress,
    ) -> Result<(SphereTree, CacheOutcome, Option<BuildReport>)> {
        let path = self.entry(&Self::key(mesh, opts));
        let outcome = match crate::tree::file::load(&path) {
            Ok(tree) => {
                touch(&path);
                return Ok((tree, CacheOutcome::Hit, None));
            }
            Err(Error::Io { source, .. }) if source.kind() == std::io::ErrorKind::NotFound => {
                CacheOutcome::Built
            }
            // Truncated, corrupt, unreadable: never trusted.
            Err(_) => {
                let _ = std::fs::remove_file(&path);
                CacheOutcome::Rebuilt
            }
        };
        let (tree, report) = build_tree(mesh, opts, progress)?;
        std::fs::create_dir_all(&self.dir).map_err(|e| Error::io(&self.dir, e))?;
        crate::tree::file::save(&tree, &path)?;
        self.evict(&path);
        Ok((tree, outcome, Some(report)))
    }

    /// Removes the least recently used entries until the entries fit the bound, keeping
    /// `keep`. Entries another process removes at the same time are skipped.
    pub fn evict(&self, keep: &Path) {
        let Ok(list) = std::fs::read_dir(&self.dir) else {
            return;
        };
        let mut entries: Vec<(std::time::SystemTime, u64, PathBuf)> = list
            .filter_map(|e| e.ok())
            .filter(|e| e.path().extension().is_some_and(|x| x == "ist"))
            .filter_map(|e| {
                let m = e.metadata().ok()?;
                Some((m.modified().ok()?, m.len(), e.path()))
            })
            .collect();
        let mut total: u64 = entries.iter().map(|e| e.1).sum();
        entries.sort();
        for (_, len, path) in entries {
            if total <= self.max_bytes {
                break;
            }
            if path == keep {
                continue;
            }
            if std::fs::remove_file(&path).is_ok() {
                total -= len;
            }
        }
    }
}

/// Marks an entry as just used (its modification time), for the eviction order.
fn touch(path: &Path) {
    if let Ok(f) = std::fs::OpenOptions::new().append(true).open(path) {
        let _ = f.set_modified(std::time::SystemTime::now());
    }
}

impl SphereTree {
    /// [`SphereTree::build_with_progress`] through `cache` ([`BuildCache::get_or_build`]).
    pub fn build_cached(
        mesh: &Mesh,
        opts: &BuildOptions,
        cache: &BuildCache,
        progress: &dyn Progress,
    ) -> Result<(SphereTree, CacheOutcome, Option<BuildReport>)> {
        cache.get_or_build(mesh, opts, progress)
    }
}
