//! A body given as a tree file or as a mesh: a mesh is built into a tree with a preset and
//! kept in the build cache ([`innersphere::build::BuildCache`]), so that the subcommands that
//! take two bodies open scans directly and a second run starts at once.

use crate::build::PresetArg;
use crate::progress::Bars;
use anyhow::Context;
use innersphere::build::{BuildCache, BuildOptions, CacheOutcome, Preset};
use innersphere::SphereTree;
use std::path::{Path, PathBuf};

/// How a mesh given for a body becomes its tree.
#[derive(clap::Args, Debug, Clone)]
pub struct BodyArgs {
    /// For a mesh given instead of a tree: its build preset (default: the library's
    /// recommendation for a mesh of unknown unit, `fine`; `jaw` for dental scans in mm).
    #[arg(long, value_enum)]
    pub preset: Option<PresetArg>,
    /// Folder of the build cache: the trees built from meshes, keyed by the mesh's content,
    /// the options and the library's version, and checked against the mesh when read. They
    /// are kept in its own subfolder innersphere-trees-v1 (tagged with a CACHEDIR.TAG), which
    /// is bounded to 2 GiB, least recently used first out; nothing else in the folder is
    /// touched (default: $IST_CACHE, else the platform's cache folder, e.g.
    /// ~/.cache/innersphere).
    #[arg(long, env = "IST_CACHE")]
    pub cache: Option<PathBuf>,
    /// Build meshes without reading or writing the cache.
    #[arg(long)]
    pub no_cache: bool,
    /// The unit of the bodies' mesh files (and of --meshes).
    #[command(flatten)]
    pub unit: crate::files::UnitArg,
}

/// Whether `path` names a mesh (by its extension) rather than a tree file.
pub fn is_mesh(path: &Path) -> bool {
    !crate::files::is_tree_file(path) && innersphere::mesh::Format::from_path(path).is_ok()
}

/// The tree of a body: a tree file as it is, a mesh built (or read from the cache) with
/// `args`, saying on stderr which preset it chose and where the tree came from.
pub fn load(path: &Path, args: &BodyArgs) -> anyhow::Result<SphereTree> {
    load_body(path, args).map(|(tree, _)| tree)
}

/// [`load`], and the mesh when the body was given as one (for drawing it).
pub fn load_body(
    path: &Path,
    args: &BodyArgs,
) -> anyhow::Result<(SphereTree, Option<innersphere::Mesh>)> {
    if !is_mesh(path) {
        let tree = crate::files::load_tree(path)?;
        crate::files::warn_if_stale(path, &tree);
        return Ok((tree, None));
    }
    let mesh = crate::files::load_mesh(path, args.unit.unit)?;
    if args.preset.is_some_and(|p| Preset::from(p).is_dental()) {
        crate::files::warn_unit(path, &mesh, args.unit.unit);
    }
    let (opts, why) = match args.preset {
        Some(p) => (
            BuildOptions::preset(p.into(), &mesh)?,
            format!("preset {}", Preset::from(p).name()),
        ),
        None => (
            BuildOptions::recommended_for(&mesh)?,
            "preset fine, the recommendation for a mesh of unknown unit (voxel = longest side / 384; --preset jaw for dental scans in mm)".to_string(),
        ),
    };
    let bars = Bars::new(false);
    let t0 = std::time::Instant::now();
    let Some(cache) = build_cache(args.cache.as_ref(), args.no_cache) else {
        eprintln!(
            "{}: a mesh; building its tree with {why}, not cached",
            path.display()
        );
        let (tree, report) = SphereTree::build_with_progress(&mesh, &opts, &bars)?;
        for w in &report.warnings {
            eprintln!("warning: {}: {w}", path.display());
        }
        return Ok((tree, Some(mesh)));
    };
    eprintln!("{}: a mesh; its tree with {why}", path.display());
    let (tree, outcome, report) = cache.get_or_build(&mesh, &opts, &bars)?;
    for w in report.iter().flat_map(|r| &r.warnings) {
        eprintln!("warning: {}: {w}", path.display());
    }
    let secs = t0.elapsed().as_secs_f64();
    match outcome {
        CacheOutcome::Hit => eprintln!(
            "{}: tree read from the cache {} in {secs:.2} s",
            path.display(),
            cache.entries_dir().display()
        ),
        CacheOutcome::Built | CacheOutcome::Rebuilt => eprintln!(
            "{}: tree built in {secs:.1} s{} and cached in {}",
            path.display(),
            if outcome == CacheOutcome::Rebuilt {
                " (the cached entry was not used: see the warning)"
            } else {
                ""
            },
            cache.entries_dir().display()
        ),
    }
    Ok((tree, Some(mesh)))
}

/// The build cache of `--cache` / `IST_CACHE` (default the platform's folder), `None` with
/// `--no-cache`. A cache that cannot be used (a file in its way, no permission) costs the
/// cache, not the command: a warning, and `None`.
pub fn build_cache(dir: Option<&PathBuf>, no_cache: bool) -> Option<BuildCache> {
    let dir = match (dir, no_cache) {
        (_, true) => None,
        (Some(d), false) => Some(d.clone()),
        (None, false) => BuildCache::default_dir(),
    };
    dir.map(|d| BuildCache::new(d, innersphere::build::cache::DEFAULT_MAX_BYTES))
        .filter(|c| match c.prepare() {
            Ok(()) => true,
            Err(e) => {
                eprintln!(
                    "warning: the build cache cannot be used: {e}; building without it (--cache DIR or IST_CACHE name another folder, --no-cache turns the cache off)"
                );
                false
            }
        })
}

/// `tree` with its mesh for the meshes' queries (refined distance, mesh penetration): `given` (--meshes, in `unit`), else the
/// body's own mesh, else the mesh the tree names as its source (in the unit it recorded); an
/// error that says which to give.
pub fn with_mesh(
    tree: innersphere::SharedTree,
    given: Option<&PathBuf>,
    own: Option<innersphere::Mesh>,
    body: &str,
    unit: innersphere::mesh::Unit,
) -> anyhow::Result<innersphere::SharedTree> {
    let mesh = match (given, own) {
        (Some(p), _) => crate::files::load_mesh(p, unit)?,
        (None, Some(m)) => m,
        (None, None) => match &tree.meta.source {
            Some(src) => src.load().with_context(|| {
                format!("body {body}'s tree names its mesh, but it cannot be used: give --meshes MESH_A MESH_B")
            })?,
            None => anyhow::bail!(
                "the meshes' queries need the meshes: body {body}'s tree does not name the mesh it was built from; give --meshes MESH_A MESH_B"
            ),
        },
    };
    tree.with_mesh(&mesh)
        .with_context(|| format!("body {body}'s mesh"))
}
