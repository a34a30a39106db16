//! The pipeline, mesh → tree: [`build_tree`] (also [`SphereTree::build`] /
//! [`SphereTree::build_with_progress`]), its [`BuildReport`] and [`StageSeconds`], and the
//! checks that the mesh's extent and position fit the tree's `f32` numbers.

use super::mass::mass_of;
use super::options::{validate_options, BuildOptions, Resolution};
use super::verdict::MeshVerdict;
use crate::error::{Error, Result};
use crate::field::{self, InsideMethod, VoxelGrid};
use crate::hierarchy;
use crate::mesh::bvh::TriangleBvh;
use crate::mesh::{Mesh, MeshReport};
use crate::packing;
use crate::progress::Progress;
use crate::tree::{BuildStamp, SphereTree, TreeMeta};
use glam::DVec3;
use std::time::Instant;

/// The smallest longest bounding-box side a build accepts (model units). The grid has at most
/// [`MAX_CELLS`](crate::field::grid::MAX_CELLS) cells, so its voxels are at least
/// `extent / 6e8` wide; from 1e-6 up, a voxel's squared size (≥ 2.8e-30) stays a normal
/// `f32` with full precision (below ~1e-31 the queries' squared `f32` distances lose bits,
/// and at 1e-30 across every answer is measured to be 0: no contact between overlapping
/// bodies). Rescale smaller meshes (metres to millimetres, ...).
pub const MIN_EXTENT: f64 = 1e-6;

/// Triangles per leaf of the build's triangle tree: its queries are points far from the
/// surface (the distance bounds, the packing's exact distances, refinement), which larger
/// leaves serve faster (2-core VM, jaw arches, 4 interleaved rounds: build medians 0.96–0.98×
/// those with 4; 12 about as fast as 8, 2 slower). The spheres do not depend on it.
const BUILD_LEAF_SIZE: usize = 8;

/// The spacing of `f32` values at magnitude `x` (one unit in the last place).
fn f32_spacing(x: f64) -> f64 {
    let f = (x.abs() as f32).min(f32::MAX);
    let bits = f.to_bits();
    f64::from(f32::from_bits(bits + 1)) - f64::from(f)
}

/// Refuses a mesh that is so far from the origin (relative to the voxel size `h`) that
/// `f32` values there are spaced wider than a quarter voxel: rounding the two centres of a
/// leaf pair then moves their distance by up to about √3 spacings, which is no longer small
/// against the packing's own voxel-sized error (measured: 5–27 % wrong distances at a
/// spacing of one voxel). Warns when the spacing exceeds 1/32 of a voxel (measured: answers
/// 1–2 % off at 1/8 voxel).
fn check_f32_fit(lo: DVec3, hi: DVec3, h: f64, warnings: &mut Vec<String>) -> Result<()> {
    let far = lo.abs().max(hi.abs()).max_element();
    let spacing = f32_spacing(far);
    if spacing > h / 4.0 {
        return Err(Error::InvalidMesh(format!(
            "the mesh reaches {far:e} model units from the origin, where f32 (the tree's number type) is spaced {spacing:e} apart, more than a quarter of the voxel size {h:e}: the tree cannot hold spheres at this resolution; move the mesh near the origin (subtract its bounding-box centre) or use a voxel size of at least {:e}",
            4.0 * spacing
        )));
    }
    if spacing > h / 32.0 {
        warnings.push(format!(
            "the mesh reaches {far:e} model units from the origin, where f32 (the tree's number type) is spaced {spacing:e} apart, more than 1/32 of the voxel size {h:e}: distances carry rounding errors of about {spacing:e}; the mesh moved near the origin gives a more accurate tree"
        ));
    }
    Ok(())
}

impl SphereTree {
    /// Builds the Inner Sphere Tree of `mesh` (lengths in the mesh's model units).
    ///
    /// The build's warnings (inward faces flipped, open mesh decided by the winding number,
    /// degenerate triangles, ...) are not lost silently by design but are only available
    /// from [`SphereTree::build_with_progress`]'s [`BuildReport`]; call that with
    /// [`Silent`](crate::progress::Silent) to get them without progress output.
    ///
    /// ```
    /// use innersphere::{shapes, BuildOptions, SphereTree};
    /// let mesh = shapes::icosphere(2);
    /// let tree = SphereTree::build(&mesh, &BuildOptions::preset(
    ///     innersphere::build::Preset::Fast, &mesh)?)?;
    /// assert!(tree.leaf_count() > 100);
    /// # Ok::<(), innersphere::Error>(())
    /// ```
    pub fn build(mesh: &Mesh, opts: &BuildOptions) -> Result<SphereTree> {
        build_tree(mesh, opts, &crate::progress::Silent).map(|(tree, _)| tree)
    }

    /// Builds the tree like [`SphereTree::build`], reporting each long stage to `progress`,
    /// and returns the [`BuildReport`] beside it (sphere count, coverage, stage times,
    /// warnings). A trait object, not a generic: it is called a few thousand times per
    /// build, so dynamic dispatch costs nothing measurable and keeps one compiled builder.
    pub fn build_with_progress(
        mesh: &Mesh,
        opts: &BuildOptions,
        progress: &dyn Progress,
    ) -> Result<(SphereTree, BuildReport)> {
        build_tree(mesh, opts, progress)
    }
}

/// Seconds spent in each stage of the build.
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct StageSeconds {
    /// Mesh validation, defect report and orientation.
    pub prepare: f64,
    /// Inside test, the triangle tree and an upper bound of every inside voxel's distance
    /// (the exact distances the packing needs are timed in `packing`).
    pub distance_field: f64,
    /// Greedy sphere packing.
    pub packing: f64,
    /// BNG clustering, enclosing spheres and layout.
    pub hierarchy: f64,
}

/// What the build did and what came out (printed by `ist build --json`).
#[derive(Debug, Clone, serde::Serialize)]
pub struct BuildReport {
    /// Inner spheres (= leaves).
    pub spheres: usize,
    /// Tree nodes, leaves included.
    pub nodes: usize,
    /// Largest leaf depth (root = 0).
    pub depth: u16,
    /// Voxels whose centre is inside the mesh and that the packing used (in thick parts only
    /// the coarse lattice's).
    pub voxels_inside: usize,
    /// Of those, the coarse ones: lattice nodes of thick parts (0 without thick parts).
    pub voxels_coarse: usize,
    /// The volume the thick parts cover (0 without them).
    pub thick_volume: f64,
    /// Grid cells along x, y, z.
    pub grid_dims: [u32; 3],
    /// Voxel edge length (model units).
    pub voxel_size: f64,
    /// Total inner-sphere volume / mesh volume (or / inside-voxel volume for open meshes).
    pub coverage: f64,
    /// What `coverage` is relative to: "mesh_volume" or "inside_voxel_volume".
    pub coverage_basis: &'static str,
    /// Total inner-sphere volume.
    pub sphere_volume: f64,
    /// Enclosed volume of the mesh (after orientation).
    pub mesh_volume: f64,
    /// Smallest inner-sphere radius.
    pub min_sphere_radius: f64,
    /// Largest inner-sphere radius.
    pub max_sphere_radius: f64,
    /// Fan-out used.
    pub fanout: u32,
    /// Mean of node radius / exact minimal enclosing radius of its children (1 = optimal).
    pub enclosing_ratio_mean: f64,
    /// Largest such ratio.
    pub enclosing_ratio_max: f64,
    /// How inside/outside was decided.
    pub inside_method: InsideMethod,
    /// Defects of the input mesh.
    pub mesh: MeshReport,
    /// Things the user should know (open mesh, inward faces, degenerate triangles, ...).
    pub warnings: Vec<String>,
    /// Total seconds of the build (not counting file loading).
    pub seconds: f64,
    /// Seconds per stage.
    pub stage_seconds: StageSeconds,
}
/// Builds the Inner Sphere Tree of `mesh`.
pub fn build_tree(
    mesh: &Mesh,
    opts: &BuildOptions,
    progress: &dyn Progress,
) -> Result<(SphereTree, BuildReport)> {
    let t0 = Instant::now();
    validate_options(opts)?;
    mesh.validate()?;
    // The mesh's report (serial: edges, components) is made while the triangle tree is
    // built on the other threads; a mesh that must be flipped gets a tree of its own below.
    // Its time counts to the distance field's stage, as when it is built there.
    progress.start("triangle tree", 1);
    let (report, (bvh, t_bvh)) = rayon::join(
        || MeshReport::of(mesh),
        || {
            let t = Instant::now();
            let bvh = TriangleBvh::with_leaf_size(mesh, BUILD_LEAF_SIZE);
            (bvh, t.elapsed().as_secs_f64())
        },
    );
    progress.finish();
    let mut bvh = Some(bvh);
    let mut warnings = Vec::new();
    let mut mesh = std::borrow::Cow::Borrowed(mesh);
    match MeshVerdict::of(&report) {
        MeshVerdict::Closed => {}
        MeshVerdict::ClosedInward => {
            warnings.push(format!(
                "the mesh faces inward (volume {:.6}); its triangles were flipped",
                report.volume
            ));
            mesh.to_mut().flip();
            bvh = None;
        }
        MeshVerdict::Soup => {
            return Err(Error::InvalidMesh(format!(
                "the mesh encloses no volume: {} of its {} edges are open boundary edges and it has {} separate pieces (a triangle soup?)",
                report.boundary_edges, report.edges, report.components
            )));
        }
        MeshVerdict::Open => warnings.push(format!(
            "the mesh is not closed ({} boundary edges, {} non-manifold edges): inside/outside decided by the generalized winding number",
            report.boundary_edges, report.nonmanifold_edges
        )),
    }
    if report.degenerate_triangles > 0 {
        warnings.push(format!(
            "{} degenerate (zero-area) triangles",
            report.degenerate_triangles
        ));
    }
    let (lo, hi) = mesh.bbox();
    let longest = (hi - lo).max_element();
    if longest < MIN_EXTENT {
        return Err(Error::InvalidMesh(format!(
            "the mesh is {longest:e} model units across, less than the supported {MIN_EXTENT:e}: the tree's f32 squared distances would underflow; scale the mesh up (metres to millimetres, ...)"
        )));
    }
    let grid = match opts.resolution {
        Resolution::VoxelSize(h) => VoxelGrid::covering(lo, hi, h)?,
        Resolution::Cells(n) => VoxelGrid::with_resolution(lo, hi, n)?,
    };
    check_f32_fit(lo, hi, grid.h, &mut warnings)?;
    let t_prepare = (t0.elapsed().as_secs_f64() - t_bvh).max(0.0);

    let t1 = Instant::now();
    // A flipped mesh's tree is built here, inside the field stage's own time.
    let (bvh, t_bvh) = match bvh {
        Some(bvh) => (bvh, t_bvh),
        None => {
            progress.start("triangle tree", 1);
            let bvh = TriangleBvh::with_leaf_size(&mesh, BUILD_LEAF_SIZE);
            progress.finish();
            (bvh, 0.0)
        }
    };
    // Thick parts (bone under teeth) keep a coarse lattice of voxels only.
    let thick = match &opts.thick {
        Some(parts) => field::thick::ThickSet::find(&mesh, &bvh, &grid, parts, progress)?,
        None => None,
    };
    // Upper bounds of the voxels' distances; the packing makes exact only those it needs.
    let field = field::distance::bounds_where(&mesh, &bvh, grid, thick.as_ref(), progress)?;
    let t_field = t_bvh + t1.elapsed().as_secs_f64();
    if field.inside.is_empty() {
        return Err(Error::InvalidMesh(format!(
            "the mesh encloses no volume at voxel size {:.6} (no voxel centre lies inside; a triangle soup or a flat sheet?)",
            grid.h
        )));
    }

    let t2 = Instant::now();
    let spheres = packing::pack_parallel(&field, &bvh, &opts.packing, progress);
    drop(bvh);
    let t_pack = t2.elapsed().as_secs_f64();
    if spheres.is_empty() {
        // The packing's floor is the larger of the minimum radius and 1e-4 voxel: blame the
        // one that set it.
        let short = |x: f64| {
            if x != 0.0 && !(1e-4..1e6).contains(&x.abs()) {
                format!("{x:e}")
            } else {
                let t = format!("{x:.6}");
                t.trim_end_matches('0').trim_end_matches('.').to_string()
            }
        };
        let longest = (hi - lo).max_element();
        return Err(Error::InvalidMesh(
            if opts.packing.min_radius > 1e-4 * grid.h {
                format!(
                    "no inner sphere of radius ≥ {} fits: the minimum radius is too large for this mesh, whose longest side is {}",
                    short(opts.packing.min_radius),
                    short(longest)
                )
            } else {
                format!(
                    "no inner sphere fits at voxel size {}: the voxel size is too large for this mesh, whose longest side is {} (a {} × {} × {} grid); give a smaller voxel size, e.g. {} (the longest side / 128), or a resolution in cells",
                    short(grid.h),
                    short(longest),
                    grid.dims[0],
                    grid.dims[1],
                    grid.dims[2],
                    short(longest / 128.0)
                )
            },
        ));
    }

    let voxels_coarse = field
        .coarse
        .as_ref()
        .map_or(0, |c| c.flags.iter().filter(|&&f| f).count());
    let t3 = Instant::now();
    let sphere_volume = packing::total_volume(&spheres);
    let closed = field.method == InsideMethod::ClosedExact;
    let mesh_volume = mesh.signed_volume().abs();
    // In thick parts each coarse voxel stands for the stride³ voxels around it.
    let inside_volume = match &thick {
        Some(t) => {
            (field.inside.len() - voxels_coarse) as f64 * grid.h.powi(3)
                + voxels_coarse as f64 * (f64::from(t.stride()) * grid.h).powi(3)
        }
        None => field.inside.len() as f64 * grid.h.powi(3),
    };
    let (coverage_basis, basis) = if closed {
        ("mesh_volume", mesh_volume)
    } else {
        ("inside_voxel_volume", inside_volume)
    };
    let coverage = sphere_volume / basis.max(f64::MIN_POSITIVE);
    let (com, inertia) = mass_of(&mesh, closed, &spheres);
    let source = crate::tree::check::source_shape(&mesh, (lo + hi) * 0.5);
    let meta = TreeMeta {
        fanout: opts.hierarchy.fanout,
        voxel_size: grid.h,
        min_radius: opts.packing.min_radius,
        mesh_volume: if closed { mesh_volume } else { inside_volume },
        source_volume: Some(source.0),
        source_centroid: source.1.map(|c| c.to_array()),
        center_of_mass: com.to_array(),
        bbox_min: lo.to_array(),
        bbox_max: hi.to_array(),
        coverage,
        mesh_closed: closed,
        built_by: Some(BuildStamp::current(opts.packing.refine_steps)),
        inertia,
        source: None,
    };
    let (tree, hstats) = hierarchy::build(&spheres, &opts.hierarchy, meta, progress)?;
    // The tree must read back from its file: never hand out one that `save` would refuse.
    crate::tree::file::check_writable(&tree)?;
    let t_hier = t3.elapsed().as_secs_f64();
    if hstats.fallback_splits > 0 {
        warnings.push(format!(
            "{} nodes were split by position because BNG could not separate their spheres",
            hstats.fallback_splits
        ));
    }
    let (min_r, max_r) = spheres.iter().fold((f64::MAX, 0.0f64), |(a, b), s| {
        (a.min(s.radius), b.max(s.radius))
    });
    let report = BuildReport {
        spheres: spheres.len(),
        nodes: tree.len(),
        depth: tree.max_depth(),
        voxels_inside: field.inside.len(),
        voxels_coarse,
        thick_volume: thick.as_ref().map_or(0.0, |t| t.voxels() * grid.h.powi(3)),
        grid_dims: grid.dims,
        voxel_size: grid.h,
        coverage,
        coverage_basis,
        sphere_volume,
        mesh_volume,
        min_sphere_radius: min_r,
        max_sphere_radius: max_r,
        fanout: opts.hierarchy.fanout,
        enclosing_ratio_mean: hstats.enclosing_ratio_mean,
        enclosing_ratio_max: hstats.enclosing_ratio_max,
        inside_method: field.method,
        mesh: report,
        warnings,
        seconds: t0.elapsed().as_secs_f64(),
        stage_seconds: StageSeconds {
            prepare: t_prepare,
            distance_field: t_field,
            packing: t_pack,
            hierarchy: t_hier,
        },
    };
    Ok((tree, report))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::build::Preset;
    use crate::shapes;

    #[test]
    fn build_gives_the_tree_of_build_tree() {
        let ball = shapes::icosphere(2);
        let opts = BuildOptions::preset(Preset::Fast, &ball).unwrap();
        let tree = SphereTree::build(&ball, &opts).unwrap();
        let (same, report) = build_tree(&ball, &opts, &crate::progress::Silent).unwrap();
        assert_eq!(tree, same);
        assert_eq!(report.spheres, tree.leaf_count());
    }

    #[test]
    fn load_and_save_take_any_path_like() {
        let dir = std::env::temp_dir().join(format!("innersphere-api-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let ball = shapes::icosphere(2);
        let stl = dir.join("ball.stl");
        crate::mesh::save_stl(&ball, &stl).unwrap();
        // &Path, &str and PathBuf all work.
        let mesh = Mesh::load(stl.as_path()).unwrap();
        assert_eq!(Mesh::load(stl.to_str().unwrap()).unwrap(), mesh);
        assert_eq!(Mesh::load(stl.clone()).unwrap(), mesh);
        let tree =
            SphereTree::build(&mesh, &BuildOptions::preset(Preset::Fast, &mesh).unwrap()).unwrap();
        let file = dir.join("ball.ist");
        tree.save(file.to_str().unwrap()).unwrap();
        assert_eq!(SphereTree::load(&file).unwrap(), tree);
        tree.save(file.clone()).unwrap();
        assert_eq!(SphereTree::load(file.as_path()).unwrap(), tree);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
