//! The files a subcommand reads and writes: trees and meshes loaded with an error that names
//! a file of the other kind (and the fix), outputs checked against the inputs before any
//! work, and the warning for a tree not built by the current builder.

use innersphere::output::OutputKind;

/// A tree file (`ist build -o`).
pub const TREE_FILE: OutputKind = OutputKind {
    what: "a tree file",
    extensions: &["ist"],
};
/// A CSV written through [`innersphere::output::write_file`] (compressed when named `.gz`).
pub const CSV_FILE: OutputKind = OutputKind {
    what: "a CSV table",
    extensions: &["csv", "csv.gz"],
};
/// A CSV written as it is (`ist replay --csv`, `ist export --format csv`).
pub const PLAIN_CSV: OutputKind = OutputKind {
    what: "a CSV table",
    extensions: &["csv"],
};
/// A chart.
pub const PNG_FILE: OutputKind = OutputKind {
    what: "a PNG picture",
    extensions: &["png"],
};
/// The spheres of a tree as PLY (`ist export --format ply`).
pub const SPHERES_PLY: OutputKind = OutputKind {
    what: "the spheres as PLY",
    extensions: &["ply"],
};

/// Refuses, before any work, outputs whose names promise another format than the one
/// written ([`OutputKind::check`]), outputs that are one of the inputs or the same file
/// twice (the library's [`innersphere::output`] checks: canonical paths, and device and inode
/// on Unix, so links are caught), and outputs whose folder is missing or not writable. Every
/// output is then written through [`innersphere::output::write_atomic`].
pub fn check_outputs(
    outputs: &[(&std::path::Path, OutputKind)],
    inputs: &[&std::path::Path],
) -> anyhow::Result<()> {
    let paths: Vec<&std::path::Path> = outputs.iter().map(|o| o.0).collect();
    for o in &paths {
        innersphere::output::ensure_not_input(o, inputs)?;
    }
    innersphere::output::ensure_distinct_outputs(&paths)?;
    for (path, kind) in outputs {
        kind.check(path)?;
        innersphere::output::ensure_folder_writable(path)?;
    }
    Ok(())
}

/// Loads a tree file; a mesh given instead (by its extension) is named as such, with the fix.
/// Every error names the file once (the library's errors already carry the path).
pub fn load_tree(path: &std::path::Path) -> anyhow::Result<innersphere::SphereTree> {
    match innersphere::SphereTree::load(path) {
        Ok(tree) => Ok(tree),
        Err(innersphere::Error::CorruptTree(_))
            if innersphere::mesh::Format::from_path(path).is_ok() =>
        {
            anyhow::bail!(
                "{} is a mesh, not a tree file: run `ist build` on it first (`ist build MESH -o TREE.ist`) and give the tree",
                path.display()
            )
        }
        Err(e) => Err(e.into()),
    }
}

/// The unit of the mesh files a command reads (`--unit`).
#[derive(clap::Args, Debug, Clone, Copy)]
pub struct UnitArg {
    /// The unit of the mesh files' coordinates: mm, cm, m or in. They are converted to mm as
    /// they are read; everything else (poses, lengths, answers, written files) is in mm.
    #[arg(long, default_value = "mm", value_parser = parse_unit)]
    pub unit: innersphere::mesh::Unit,
}

/// `--unit`'s parser: the library's names, its message.
pub fn parse_unit(s: &str) -> Result<innersphere::mesh::Unit, String> {
    s.parse().map_err(|e: innersphere::Error| e.to_string())
}

/// Prints a warning when `mesh` (read in `unit`, now in mm) has a size that suggests another
/// unit for a dental body ([`innersphere::mesh::unit::unit_warning`]); the command goes on.
pub fn warn_unit(path: &std::path::Path, mesh: &innersphere::Mesh, unit: innersphere::mesh::Unit) {
    let (lo, hi) = mesh.bbox();
    if let Some(w) = innersphere::mesh::unit::unit_warning((hi - lo).max_element(), unit) {
        eprintln!("warning: {}: {w}", path.display());
    }
}

/// Loads a mesh file whose coordinates are in `unit`, converted to mm
/// ([`innersphere::Mesh::load_in`]); a tree file given instead (by its magic number) is named
/// as such, with the fix. Every error names the file once.
pub fn load_mesh(
    path: &std::path::Path,
    unit: innersphere::mesh::Unit,
) -> anyhow::Result<innersphere::Mesh> {
    match innersphere::Mesh::load_in(path, unit) {
        Ok(mesh) => Ok(mesh),
        Err(e @ (innersphere::Error::UnsupportedFormat(_) | innersphere::Error::Parse { .. })) => {
            if is_tree_file(path) {
                anyhow::bail!(
                    "{} is an Inner Sphere Tree file, not a mesh: give a mesh file here (.stl, .obj, .ply or .off, optionally .gz; for `ist check --mesh`, the mesh the tree was built from)",
                    path.display()
                )
            }
            Err(e.into())
        }
        Err(e) => Err(e.into()),
    }
}

/// True when the file starts with the tree file's magic number.
pub fn is_tree_file(path: &std::path::Path) -> bool {
    use std::io::Read;
    let mut magic = [0u8; 8];
    std::fs::File::open(path)
        .and_then(|mut f| f.read_exact(&mut magic))
        .is_ok()
        && magic == innersphere::tree::file::MAGIC
}

/// Prints the library's warning about a tree not built by the current builder
/// ([`innersphere::SphereTree::staleness`]) to stderr; the command goes on.
pub fn warn_if_stale(path: &std::path::Path, tree: &innersphere::SphereTree) {
    if let Some(w) = tree.staleness() {
        eprintln!("warning: {}: {w}", path.display());
    }
}
