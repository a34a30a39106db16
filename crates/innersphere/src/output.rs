//! Writing output files safely: never onto one of the run's inputs, and always through a
//! temporary file in the same folder that is renamed into place once complete.
//!
//! [`ensure_not_input`] refuses an output path that names the same file as an input (the same
//! canonical path, or on Unix the same device and inode, so that symbolic and hard links are
//! caught too; an output that does not exist yet cannot be an input). [`write_atomic`] writes
//! into a temporary file beside the output, flushes it to disk and renames it over the output:
//! readers see the old file or the complete new one, never a part, and a run that fails
//! midway removes its temporary file and leaves the old output as it was.
//!
//! ```
//! # let dir = std::env::temp_dir().join(format!("innersphere-output-doc-{}", std::process::id()));
//! # std::fs::create_dir_all(&dir).unwrap();
//! use innersphere::output::{ensure_not_input, write_atomic};
//! use std::io::Write;
//!
//! let input = dir.join("in.csv");
//! std::fs::write(&input, "a,b\n1,2\n")?;
//! assert!(ensure_not_input(&input, &[&input]).is_err());
//! let out = dir.join("out.csv");
//! ensure_not_input(&out, &[&input])?;
//! write_atomic(&out, |w| w.write_all(b"sum\n3\n"))?;
//! assert_eq!(std::fs::read_to_string(&out)?, "sum\n3\n");
//! # std::fs::remove_dir_all(&dir).unwrap();
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use crate::error::{Error, Result};
use std::io::Write;
use std::path::{Path, PathBuf};

/// True when `a` and `b` name the same existing file: the same device and inode on Unix (a
/// hard link, a symbolic link, `./x` and `x` are all caught), else the same canonical path.
/// False when either does not exist.
pub(crate) fn same_file(a: &Path, b: &Path) -> bool {
    let (Ok(ma), Ok(mb)) = (std::fs::metadata(a), std::fs::metadata(b)) else {
        return false;
    };
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        if ma.dev() == mb.dev() && ma.ino() == mb.ino() {
            return true;
        }
    }
    #[cfg(not(unix))]
    let _ = (ma, mb);
    matches!((a.canonicalize(), b.canonicalize()), (Ok(x), Ok(y)) if x == y)
}

/// An error when `output` is the same file as one of `inputs` (`same_file`): writing it
/// would destroy that input. An output that does not exist yet is never an input.
pub fn ensure_not_input(output: &Path, inputs: &[&Path]) -> Result<()> {
    match inputs.iter().find(|i| same_file(output, i)) {
        None => Ok(()),
        Some(i) if i.as_os_str() == output.as_os_str() => Err(Error::Output(format!(
            "{} is also an input: refusing to overwrite an input; write the output to another file",
            output.display()
        ))),
        Some(i) => Err(Error::Output(format!(
            "{} is the input {} under another name or link: refusing to overwrite an input; write the output to another file",
            output.display(),
            i.display()
        ))),
    }
}

/// `path` as the file system will resolve it, for comparing outputs that may not exist yet:
/// its folder's canonical path (when the folder exists) joined with its name, else the path
/// made absolute lexically (`.` components removed). `out/q.ply`, `./out/q.ply` and
/// `out/../out/q.ply` are one file.
fn resolved(path: &Path) -> PathBuf {
    let parent = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    match (parent.canonicalize(), path.file_name()) {
        (Ok(dir), Some(name)) => dir.join(name),
        _ => std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf()),
    }
}

/// An error when two of `outputs` are the same path or the same file (one would overwrite
/// the other within the run): the same existing file (`same_file`), or two spellings of
/// one path that does not exist yet (`out/q.ply` and `./out/q.ply`).
pub fn ensure_distinct_outputs(outputs: &[&Path]) -> Result<()> {
    for (i, a) in outputs.iter().enumerate() {
        for b in &outputs[i + 1..] {
            if a == b || same_file(a, b) || resolved(a) == resolved(b) {
                return Err(Error::Output(format!(
                    "two outputs are the same file ({} and {}): give each its own file",
                    a.display(),
                    b.display()
                )));
            }
        }
    }
    Ok(())
}

/// What an output file is and the names it may have: a command writes one format per output,
/// and a name whose extension promises another (`map.stl` for a PLY, `map.ply.gz` written
/// uncompressed) is refused before any work rather than written with the wrong bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct OutputKind {
    /// What the file holds, for messages ("the contact map (PLY)").
    pub what: &'static str,
    /// The accepted extensions, lower case, without the leading dot; a `.gz` ending is listed
    /// where the writer compresses (`"ply.gz"`).
    pub extensions: &'static [&'static str],
}

impl OutputKind {
    /// An error naming the accepted extensions when `path`'s does not match one (case
    /// does not matter).
    pub fn check(&self, path: &Path) -> Result<()> {
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().to_ascii_lowercase())
            .unwrap_or_default();
        if self
            .extensions
            .iter()
            .any(|e| name.len() > e.len() + 1 && name.ends_with(&format!(".{e}")))
        {
            return Ok(());
        }
        let list: Vec<String> = self.extensions.iter().map(|e| format!(".{e}")).collect();
        Err(Error::Output(format!(
            "{}: {} is written with the extension {}; the name promises another format",
            path.display(),
            self.what,
            list.join(", ")
        )))
    }
}

/// An error when the folder that is to hold `path` does not exist, is not a folder, or
/// refuses a new file: found before the work, not after it. Probed by creating and removing
/// a temporary file there (the only test that sees permissions, read-only mounts and full
/// quotas alike).
pub fn ensure_folder_writable(path: &Path) -> Result<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let why = match std::fs::metadata(dir) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            Some("the folder does not exist; create it first".to_string())
        }
        Err(e) => Some(e.to_string()),
        Ok(m) if !m.is_dir() => Some(format!("{} is not a folder", dir.display())),
        Ok(_) => match tempfile::Builder::new()
            .prefix(".innersphere-probe.")
            .tempfile_in(dir)
        {
            Ok(_) => None,
            Err(e) => Some(temp_error(dir, e).to_string()),
        },
    };
    match why {
        None => Ok(()),
        Some(why) => Err(Error::Output(format!(
            "{} cannot be written: {why}",
            path.display()
        ))),
    }
}

/// Writes the file `path` with `write`, through a temporary file in the same folder renamed
/// into place once `write` succeeded and the data reached the disk. On any error the
/// temporary file is removed and an existing `path` is left untouched.
///
/// A symbolic link at `path` is followed (its target is replaced, the link kept). An existing
/// file keeps its permissions; a new one gets the usual `0o666` less the umask (Unix). An
/// existing `path` that is not a regular file (`/dev/null`, a named pipe) is written directly,
/// as it cannot be replaced by a rename.
pub fn write_atomic(
    path: &Path,
    write: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> Result<()> {
    let err = |e: std::io::Error| Error::io(path, e);
    let existing = std::fs::metadata(path).ok();
    if let Some(m) = &existing {
        if m.is_dir() {
            return Err(err(std::io::Error::other("is a folder, not a file")));
        }
        if m.permissions().readonly() {
            // What File::create would say: a read-only file is not replaced behind its back.
            return Err(err(std::io::Error::from(
                std::io::ErrorKind::PermissionDenied,
            )));
        }
        if !m.is_file() {
            let mut f = std::fs::OpenOptions::new()
                .write(true)
                .open(path)
                .map_err(err)?;
            return write(&mut f).and_then(|()| f.flush()).map_err(err);
        }
    }
    // Replace the target of a link, not the link.
    let target: PathBuf = match std::fs::symlink_metadata(path) {
        Ok(m) if m.file_type().is_symlink() => path.canonicalize().map_err(err)?,
        _ => path.to_path_buf(),
    };
    let dir = match target.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let name = target
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let mut builder = tempfile::Builder::new();
    let prefix = format!(".{name}.");
    builder.prefix(&prefix).suffix(".tmp");
    // tempfile makes its files private (0o600); an output gets what File::create gives it.
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        builder.permissions(std::fs::Permissions::from_mode(0o666));
    }
    let mut tmp = builder
        .tempfile_in(dir)
        .map_err(|e| err(temp_error(dir, e)))?;
    if let Some(m) = &existing {
        tmp.as_file()
            .set_permissions(m.permissions())
            .map_err(err)?;
    }
    {
        let mut w = std::io::BufWriter::new(tmp.as_file_mut());
        write(&mut w).and_then(|()| w.flush()).map_err(err)?;
    }
    tmp.as_file().sync_all().map_err(err)?;
    tmp.persist(&target).map_err(|e| err(e.error))?;
    Ok(())
}

/// [`write_atomic`] of `bytes`, gzip-compressed when `path` ends in `.gz` (any case).
pub fn write_file(path: &Path, bytes: &[u8]) -> Result<()> {
    write_stream(path, |w| w.write_all(bytes))
}

/// [`write_atomic`], gzip-compressed when `path` ends in `.gz` (any case): `write` sees the
/// uncompressed stream.
pub fn write_stream(
    path: &Path,
    write: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> Result<()> {
    let gz = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("gz"));
    write_atomic(path, |w| {
        if gz {
            let mut enc = flate2::write::GzEncoder::new(w, flate2::Compression::default());
            write(&mut enc)?;
            enc.finish().map(drop)
        } else {
            write(w)
        }
    })
}

/// Renders a file that a library writes by path (e.g. a chart) into a temporary file in the
/// same folder with the same extension, then renames it into place as [`write_atomic`] does:
/// `render` receives the temporary path.
pub fn render_atomic(path: &Path, render: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
    let err = |e: std::io::Error| Error::io(path, e);
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let suffix = path
        .extension()
        .map(|e| format!(".{}", e.to_string_lossy()))
        .unwrap_or_default();
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let prefix = format!(".{name}.");
    let tmp = tempfile::Builder::new()
        .prefix(&prefix)
        .suffix(&suffix)
        .tempfile_in(dir)
        .map_err(|e| err(temp_error(dir, e)))?;
    render(tmp.path())?;
    tmp.as_file().sync_all().map_err(err)?;
    tmp.persist(path).map_err(|e| err(e.error))?;
    Ok(())
}

/// The error of creating the temporary file in `dir`, without the temporary file's random
/// name that tempfile appends (" at path ..."): the user knows the output's name only.
fn temp_error(dir: &Path, e: std::io::Error) -> std::io::Error {
    let text = e.to_string();
    let text = text.split(" at path ").next().unwrap_or(&text);
    std::io::Error::new(
        e.kind(),
        format!("cannot create a file in {}: {text}", dir.display()),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dir(name: &str) -> PathBuf {
        let d =
            std::env::temp_dir().join(format!("innersphere-output-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    fn leftovers(d: &Path) -> Vec<String> {
        std::fs::read_dir(d)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.ends_with(".tmp"))
            .collect()
    }

    #[test]
    fn the_same_file_under_other_names_is_an_input() {
        let d = dir("same");
        let a = d.join("a.stl");
        std::fs::write(&a, "x").unwrap();
        assert!(ensure_not_input(&a, &[&a]).is_err());
        // Another spelling of the same path.
        let dotted = d.join(".").join("a.stl");
        assert!(ensure_not_input(&dotted, &[&a]).is_err());
        // A file that does not exist yet, and another existing file, are fine.
        let b = d.join("b.stl");
        assert!(ensure_not_input(&b, &[&a]).is_ok());
        std::fs::write(&b, "x").unwrap();
        assert!(ensure_not_input(&b, &[&a]).is_ok());
        #[cfg(unix)]
        {
            let hard = d.join("hard.stl");
            std::fs::hard_link(&a, &hard).unwrap();
            let e = ensure_not_input(&hard, &[&a]).unwrap_err().to_string();
            assert!(e.contains("another name or link"), "{e}");
            let soft = d.join("soft.stl");
            std::os::unix::fs::symlink(&a, &soft).unwrap();
            assert!(ensure_not_input(&soft, &[&b, &a]).is_err());
        }
        assert!(ensure_distinct_outputs(&[&b, &d.join("c")]).is_ok());
        assert!(ensure_distinct_outputs(&[&b, &d.join("c"), &b]).is_err());
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn a_failed_write_leaves_the_old_file_and_no_temporary() {
        let d = dir("atomic");
        let p = d.join("out.ist");
        write_atomic(&p, |w| w.write_all(b"old")).unwrap();
        let e = write_atomic(&p, |w| {
            w.write_all(b"half of the new")?;
            Err(std::io::Error::other("disk on fire"))
        })
        .unwrap_err();
        assert!(e.to_string().contains("disk on fire"), "{e}");
        assert_eq!(std::fs::read(&p).unwrap(), b"old");
        assert!(leftovers(&d).is_empty(), "{:?}", leftovers(&d));
        // A new file that fails is not created at all.
        let q = d.join("new.csv");
        assert!(write_atomic(&q, |_| Err(std::io::Error::other("no"))).is_err());
        assert!(!q.exists());
        assert!(leftovers(&d).is_empty());
        // Success replaces the content.
        write_atomic(&p, |w| w.write_all(b"new")).unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"new");
        // A folder is not a file.
        assert!(write_atomic(&d, |w| w.write_all(b"x")).is_err());
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[cfg(unix)]
    #[test]
    fn permissions_links_and_devices() {
        use std::os::unix::fs::PermissionsExt;
        let d = dir("perm");
        let p = d.join("kept.csv");
        std::fs::write(&p, "x").unwrap();
        std::fs::set_permissions(&p, std::fs::Permissions::from_mode(0o640)).unwrap();
        write_atomic(&p, |w| w.write_all(b"y")).unwrap();
        let mode = std::fs::metadata(&p).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode, 0o640);
        // A new file is readable by others as File::create makes it (under the usual umask).
        let n = d.join("new.csv");
        write_atomic(&n, |w| w.write_all(b"y")).unwrap();
        let mode = std::fs::metadata(&n).unwrap().permissions().mode() & 0o777;
        assert_ne!(mode & 0o600, 0o000);
        assert_eq!(
            mode,
            std::fs::File::create(d.join("plain"))
                .map(|f| f.metadata().unwrap().permissions().mode() & 0o777)
                .unwrap()
        );
        // A link is kept and its target replaced.
        let link = d.join("link.csv");
        std::os::unix::fs::symlink(&p, &link).unwrap();
        write_atomic(&link, |w| w.write_all(b"through the link")).unwrap();
        assert!(std::fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink());
        assert_eq!(std::fs::read(&p).unwrap(), b"through the link");
        // A device is written directly.
        write_atomic(Path::new("/dev/null"), |w| w.write_all(b"gone")).unwrap();
        // Gzip by extension.
        let g = d.join("m.csv.gz");
        write_file(&g, b"hello").unwrap();
        let bytes = std::fs::read(&g).unwrap();
        assert_eq!(&bytes[..2], &[0x1f, 0x8b]);
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn render_atomic_renames_into_place_and_cleans_up() {
        let d = dir("render");
        let p = d.join("chart.png");
        render_atomic(&p, |tmp| {
            assert_eq!(tmp.extension().unwrap(), "png");
            std::fs::write(tmp, b"png").map_err(|e| Error::io(tmp, e))
        })
        .unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"png");
        assert!(render_atomic(&p, |_| Err(Error::Output("no".into()))).is_err());
        assert_eq!(std::fs::read(&p).unwrap(), b"png");
        let left: Vec<_> = std::fs::read_dir(&d).unwrap().collect();
        assert_eq!(left.len(), 1);
        std::fs::remove_dir_all(&d).unwrap();
    }
}
