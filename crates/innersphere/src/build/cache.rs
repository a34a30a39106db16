//! A folder of built trees keyed by what they were built from, so that opening the same scan
//! again costs a file read instead of a build ([`BuildCache::get_or_build`]).
//!
//! - **Ownership**: the cache keeps its trees in a subfolder of its own, [`SUBFOLDER`], of the
//!   folder it is given, made with a `CACHEDIR.TAG` file (the Cache Directory Tagging
//!   standard, which backup tools honour) that marks it as the cache's. There it reads,
//!   writes and removes only names of its own: entries `<key>.ist` (64 lowercase hex digits)
//!   and the temporary files `.<key>.ist.*.tmp` of writes under way. Nothing else, in the
//!   given folder or in its subfolder, is ever listed, read, touched or removed, so pointing
//!   the cache at a folder of one's own (`.`, the home folder, a patient's folder full of
//!   `.ist` files) costs nothing but the subfolder. A subfolder of that name that the cache did
//!   not make (no tag) is not used ([`BuildCache::prepare`] says so).
//! - **Key**: a BLAKE3 hash of the mesh as loaded (vertex coordinates' bits and triangle
//!   indices, after the loaders' welding), the build options, the tree file format's version,
//!   the builder's revision ([`BUILD_REVISION`](crate::tree::BUILD_REVISION)) and the
//!   library's version. An entry is `<key>.ist`: other options, another builder or another
//!   format give another key.
//! - **Trust**: an entry is read with the tree file's own checks (header, sizes, CRC,
//!   structure), then verified against the mesh and options it is asked for: the source the
//!   tree records (its box, volume and centroid, [`source_mismatch`]) and its fan-out, minimum radius
//!   and refinement steps. The key alone is not trusted: a valid tree copied or planted under
//!   another mesh's key is caught. An entry that fails either is removed and rebuilt, and the
//!   build's report carries a warning that says why ([`CacheOutcome::Rebuilt`]).
//! - **Writes** go through a temporary file renamed into place
//!   ([`write_atomic`](crate::output::write_atomic)): two processes building the same mesh at
//!   once both succeed and leave one entry.
//! - **Bound**: after each write the oldest entries (by last use: a hit touches its entry)
//!   are removed until the entries fit `max_bytes` (the entry just written is kept even when
//!   it alone is larger). Temporary files of the cache's own that are more than an hour old
//!   (a process killed while writing) are removed at the same time.

use super::{build_tree, BuildOptions, BuildReport};
use crate::error::{Error, Result};
use crate::mesh::Mesh;
use crate::progress::Progress;
use crate::tree::check::source_mismatch;
use crate::tree::SphereTree;
use std::path::{Path, PathBuf};

/// Default bound of a cache folder: 2 GiB (about 300 jaw-arch trees).
pub const DEFAULT_MAX_BYTES: u64 = 2 << 30;

/// The cache's own subfolder of the folder it is given: where all its files are. The `v1`
/// names this layout (entry names, tag), not the tree file format (which is in the key).
pub const SUBFOLDER: &str = "innersphere-trees-v1";

/// The tag file that marks [`SUBFOLDER`] as the cache's (<https://bford.info/cachedir/>).
const TAG: &str = "CACHEDIR.TAG";
const TAG_TEXT: &str = "Signature: 8a477f597d28d172789f06886806bc55\n\
# This folder is a cache of trees built by innersphere (its build cache).\n\
# It may be deleted at any time; the trees are built again when needed.\n\
# For information about cache directory tags see https://bford.info/cachedir/\n";

/// A temporary file of the cache older than this is left over from a write that was
/// interrupted (a write takes seconds: the tree is built before its file is opened).
const STALE_TEMPORARY: std::time::Duration = std::time::Duration::from_secs(3600);

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
    /// Built and stored again: the entry failed the tree file's checks or was not the tree of
    /// the mesh and options asked for (the report's warnings say which).
    Rebuilt,
}

impl BuildCache {
    /// A cache in `dir` (its subfolder [`SUBFOLDER`] made when first used) bounded to
    /// `max_bytes`.
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

    /// The folder given.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The cache's own subfolder of [`dir`](Self::dir), which holds its entries.
    pub fn entries_dir(&self) -> PathBuf {
        self.dir.join(SUBFOLDER)
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
        self.entries_dir().join(format!("{key}.ist"))
    }

    /// Makes the folder and the cache's tagged subfolder when they do not exist yet (the
    /// subfolder appears whole, tag included, even with other processes at it). An error,
    /// in a sentence that names the path, when the folder is a file (or a file is in the way
    /// of making it), when the subfolder's name is taken by a file or by a folder the cache
    /// did not make (no tag), or when they cannot be made (no permission, a read-only disk).
    /// [`get_or_build`](Self::get_or_build) calls it; a caller that would rather go on
    /// without the cache, or say how to name another folder, calls it first.
    pub fn prepare(&self) -> Result<()> {
        let sub = self.entries_dir();
        if is_tagged(&sub) {
            return Ok(());
        }
        match std::fs::metadata(&self.dir) {
            Ok(m) if !m.is_dir() => return Err(a_file(&self.dir, None)),
            Ok(_) => {}
            Err(_) => std::fs::create_dir_all(&self.dir).map_err(|e| {
                // A file on the way down: say which.
                match self
                    .dir
                    .ancestors()
                    .skip(1)
                    .find(|a| std::fs::metadata(a).is_ok_and(|m| !m.is_dir()))
                {
                    Some(file) => a_file(file, Some(&self.dir)),
                    None => Error::io(&self.dir, e),
                }
            })?,
        }
        if let Ok(m) = std::fs::symlink_metadata(&sub) {
            // Another builder may have renamed its tagged subfolder into place since the
            // first look.
            if is_tagged(&sub) {
                return Ok(());
            }
            return Err(not_ours(&sub, m.is_dir()));
        }
        // Made beside it with its tag, then renamed into place: no process ever sees the
        // subfolder without its tag.
        let prefix = format!(".{SUBFOLDER}.");
        let mut builder = tempfile::Builder::new();
        builder.prefix(&prefix);
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            builder.permissions(std::fs::Permissions::from_mode(0o777));
        }
        let tmp = builder
            .tempdir_in(&self.dir)
            .map_err(|e| Error::io(&self.dir, e))?;
        std::fs::write(tmp.path().join(TAG), TAG_TEXT).map_err(|e| Error::io(&self.dir, e))?;
        let made = tmp.keep();
        match std::fs::rename(&made, &sub) {
            Ok(()) => Ok(()),
            Err(e) => {
                let _ = std::fs::remove_file(made.join(TAG));
                let _ = std::fs::remove_dir(&made);
                // Another process made it first.
                if is_tagged(&sub) {
                    Ok(())
                } else if let Ok(m) = std::fs::symlink_metadata(&sub) {
                    Err(not_ours(&sub, m.is_dir()))
                } else {
                    Err(Error::io(&sub, e))
                }
            }
        }
    }

    /// The tree of `mesh` built with `opts`: read from the cache when a valid entry of that
    /// mesh is there, else built (reporting to `progress`) and stored, with the build's
    /// report (its warnings, and why an entry was not used). Fails when the build fails, or
    /// the cache cannot be used ([`prepare`](Self::prepare)) or written (the folder is not
    /// writable, the disk is full).
    pub fn get_or_build(
        &self,
        mesh: &Mesh,
        opts: &BuildOptions,
        progress: &dyn Progress,
    ) -> Result<(SphereTree, CacheOutcome, Option<BuildReport>)> {
        self.prepare()?;
        let path = self.entry(&Self::key(mesh, opts));
        let refused = match crate::tree::file::load(&path) {
            Ok(tree) => match entry_mismatch(&tree, mesh, opts) {
                None => {
                    touch(&path);
                    return Ok((tree, CacheOutcome::Hit, None));
                }
                Some(why) => Some(format!("it is not the tree of this mesh ({why})")),
            },
            Err(Error::Io { source, .. }) if source.kind() == std::io::ErrorKind::NotFound => None,
            // Truncated, corrupt, unreadable: never trusted.
            Err(e) => Some(format!("it failed the tree file's checks ({e})")),
        };
        if refused.is_some() {
            let _ = std::fs::remove_file(&path);
        }
        let (tree, mut report) = build_tree(mesh, opts, progress)?;
        crate::tree::file::save(&tree, &path)?;
        self.evict(&path);
        let outcome = match refused {
            None => CacheOutcome::Built,
            Some(why) => {
                report.warnings.push(format!(
                    "the build cache's entry {} was not used: {why}; built again",
                    path.display()
                ));
                CacheOutcome::Rebuilt
            }
        };
        Ok((tree, outcome, Some(report)))
    }

    /// Removes the least recently used entries until the entries fit the bound, keeping
    /// `keep`, and the cache's own temporary files left by interrupted writes. Only the
    /// cache's own names in its own subfolder are considered; entries another process
    /// removes at the same time are skipped.
    pub(crate) fn evict(&self, keep: &Path) {
        let Ok(list) = std::fs::read_dir(self.entries_dir()) else {
            return;
        };
        let now = std::time::SystemTime::now();
        let mut entries: Vec<(std::time::SystemTime, u64, PathBuf)> = Vec::new();
        for e in list.filter_map(|e| e.ok()) {
            if !e.file_type().is_ok_and(|t| t.is_file()) {
                continue;
            }
            let name = e.file_name();
            let Some(name) = name.to_str() else {
                continue;
            };
            let Ok(m) = e.metadata() else {
                continue;
            };
            let Ok(modified) = m.modified() else {
                continue;
            };
            if is_entry_name(name) {
                entries.push((modified, m.len(), e.path()));
            } else if is_temporary_name(name)
                && now
                    .duration_since(modified)
                    .is_ok_and(|age| age > STALE_TEMPORARY)
            {
                let _ = std::fs::remove_file(e.path());
            }
        }
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

/// Why `tree`, read from the entry of `mesh` and `opts`, is not the tree they build: another
/// source ([`source_mismatch`]), or other options where the tree records them.
fn entry_mismatch(tree: &SphereTree, mesh: &Mesh, opts: &BuildOptions) -> Option<String> {
    if let Some(why) = source_mismatch(tree, mesh) {
        return Some(why);
    }
    let m = &tree.meta;
    let steps = m.built_by.as_ref().map(|b| b.refine_steps);
    if m.fanout != opts.hierarchy.fanout
        || m.min_radius.to_bits() != opts.packing.min_radius.to_bits()
        || steps != Some(opts.packing.refine_steps)
    {
        return Some(format!(
            "built with fan-out {}, minimum radius {}, {} refinement steps; asked for {}, {}, {}",
            m.fanout,
            m.min_radius,
            steps.map_or("unknown".into(), |s| s.to_string()),
            opts.hierarchy.fanout,
            opts.packing.min_radius,
            opts.packing.refine_steps
        ));
    }
    None
}

/// The error of a file given as the cache's folder, or in the way of making it (`inside`).
/// What to do instead is the door's to say (`--cache`, `cache=`).
fn a_file(file: &Path, inside: Option<&Path>) -> Error {
    let so = match inside {
        None => "so it cannot hold the build cache".to_string(),
        Some(dir) => format!("so the build cache folder {} cannot be made", dir.display()),
    };
    Error::io(
        file,
        std::io::Error::new(
            std::io::ErrorKind::NotADirectory,
            format!("is a file, not a folder, {so}"),
        ),
    )
}

/// The error of a [`SUBFOLDER`] that the cache did not make.
fn not_ours(sub: &Path, is_dir: bool) -> Error {
    let what = if is_dir {
        "this folder was not made by innersphere's build cache (it has no CACHEDIR.TAG), so the cache does not use it"
    } else {
        "a file has the name of the build cache's folder"
    };
    Error::io(
        sub,
        std::io::Error::new(
            std::io::ErrorKind::AlreadyExists,
            format!("{what}: rename or remove it, or name another folder for the cache"),
        ),
    )
}

/// Whether `sub` holds the cache's tag (it is the cache's own folder).
fn is_tagged(sub: &Path) -> bool {
    std::fs::metadata(sub.join(TAG)).is_ok_and(|m| m.is_file())
}

/// `<64 lowercase hex digits>.ist`: an entry's name.
fn is_entry_name(name: &str) -> bool {
    name.strip_suffix(".ist").is_some_and(|key| {
        key.len() == 64 && key.bytes().all(|b| matches!(b, b'0'..=b'9' | b'a'..=b'f'))
    })
}

/// `.<entry name>.<anything>.tmp`: the temporary file of an entry's write
/// ([`write_atomic`](crate::output::write_atomic)'s names).
fn is_temporary_name(name: &str) -> bool {
    name.strip_prefix('.')
        .and_then(|n| n.strip_suffix(".tmp"))
        .is_some_and(|n| n.len() > 68 && n.as_bytes()[68] == b'.' && is_entry_name(&n[..68]))
}

/// Marks an entry as just used (its modification time), for the eviction order.
fn touch(path: &Path) {
    if let Ok(f) = std::fs::OpenOptions::new().append(true).open(path) {
        let _ = f.set_modified(std::time::SystemTime::now());
    }
}

impl SphereTree {}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_the_caches_own_names_are_its_own() {
        let key = "0123456789abcdef".repeat(4);
        assert!(is_entry_name(&format!("{key}.ist")));
        for other in [
            "my_maxilla.ist".to_string(),
            format!("{}.ist", key.to_uppercase()),
            format!("{}.ist", &key[1..]),
            format!("{key}0.ist"),
            format!("{key}.ist.bak"),
            format!("{key}.stl"),
            key.clone(),
        ] {
            assert!(!is_entry_name(&other), "{other}");
            assert!(!is_temporary_name(&other), "{other}");
        }
        assert!(is_temporary_name(&format!(".{key}.ist.Ab3xYz.tmp")));
        assert!(!is_temporary_name(&format!(".{key}.ist.tmp")));
        assert!(!is_temporary_name(".my_maxilla.ist.Ab3xYz.tmp"));
        assert!(!is_temporary_name(&format!("{key}.ist.Ab3xYz.tmp")));
    }
}
