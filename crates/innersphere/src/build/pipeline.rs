//! The pipeline, mesh → tree: [`build_tree`] (also [`SphereTree::build`] /
//! [`SphereTree::build_with_progress`]), which runs the build's stages (`stages.rs`) in order and times them,
//! its [`BuildReport`] and [`StageSeconds`], and the smallest mesh it accepts
//! ([`MIN_EXTENT`]).

use super::options::BuildOptions;
use super::stages;
use crate::error::Result;
use crate::field::{DistanceField, InsideMethod, VoxelGrid};
use crate::hierarchy::{self, HierarchyOptions, HierarchyStats};
use crate::mesh::{Mesh, MeshReport};
use crate::packing::{self, PackingOptions, Sphere};
use crate::progress::Progress;
use crate::tree::{SphereTree, TreeMeta};
use glam::DVec3;
use std::time::Instant;

/// The smallest longest bounding-box side a build accepts (model units). The grid has at most
/// `MAX_CELLS` (6·10^8) cells, so its voxels are at least
/// `extent / 6e8` wide; from 1e-6 up, a voxel's squared size (≥ 2.8e-30) stays a normal
/// `f32` with full precision (below ~1e-31 the queries' squared `f32` distances lose bits,
/// and at 1e-30 across every answer is measured to be 0: no contact between overlapping
/// bodies). Rescale smaller meshes (metres to millimetres, ...).
pub const MIN_EXTENT: f64 = 1e-6;

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
    /// The tree's meta (volumes, mass properties, source shape) and the check that its file
    /// can hold it.
    pub tree: f64,
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

/// Builds the Inner Sphere Tree of `mesh`: runs the build's stages in order (prepare, field,
/// packing, hierarchy, tree, report) and times each ([`StageSeconds`]).
pub fn build_tree(
    mesh: &Mesh,
    opts: &BuildOptions,
    progress: &dyn Progress,
) -> Result<(SphereTree, BuildReport)> {
    let t0 = Instant::now();
    let mut prep = stages::prepare(mesh, opts, progress)?;
    // The triangle tree built beside the mesh's report counts to the field stage that uses
    // it; a flipped mesh's, built again there, leaves the discarded one in prepare's time.
    let (bvh, bvh_seconds) = prep.bvh.take().unzip();
    let bvh_seconds = bvh_seconds.unwrap_or(0.0);
    let prepare = (t0.elapsed().as_secs_f64() - bvh_seconds).max(0.0);

    let t = Instant::now();
    let (bvh, field) = stages::field(&prep.mesh, bvh, prep.grid, opts, progress)?;
    let distance_field = bvh_seconds + t.elapsed().as_secs_f64();

    let t = Instant::now();
    let spheres = stages::packing(&field.bounds, &bvh, (prep.lo, prep.hi), opts, progress);
    drop(bvh);
    let spheres = spheres?;
    let packing = t.elapsed().as_secs_f64();

    let t = Instant::now();
    let clustered = stages::hierarchy(&spheres, opts, progress)?;
    let hierarchy = t.elapsed().as_secs_f64();

    let t = Instant::now();
    let built = stages::tree(&prep, &field, &spheres, clustered, opts)?;
    let tree = t.elapsed().as_secs_f64();

    let stage_seconds = StageSeconds {
        prepare,
        distance_field,
        packing,
        hierarchy,
        tree,
    };
    let seconds = t0.elapsed().as_secs_f64();
    let report = stages::report(prep, &field, &spheres, &built, opts, seconds, stage_seconds);
    Ok((built.tree, report))
}

/// The inner spheres of an analytic solid, given by its signed distance function `sdf`
/// (positive inside and there the exact distance to the surface; implicit surfaces, CSG, the
/// evaluation's solids): the build's packing over the voxel centres of size `voxel` in the
/// box `[lo, hi]`, no mesh needed. [`tree_of_spheres`] makes their tree.
pub fn pack_signed_distance(
    lo: DVec3,
    hi: DVec3,
    voxel: f64,
    sdf: impl Fn(DVec3) -> f64,
    opts: &PackingOptions,
) -> Result<Vec<Sphere>> {
    let grid = VoxelGrid::covering(lo, hi, voxel)?;
    let field = DistanceField::from_signed_distance(grid, sdf);
    Ok(packing::pack(&field, opts, None, &crate::progress::Silent))
}

/// The tree over a sphere set that was not packed from a mesh (hand-made or analytic): the
/// build's hierarchy and tree stages without a mesh, the spheres clustered with `opts` and
/// laid out as a [`SphereTree`] carrying `meta` (e.g. [`TreeMeta::unmeasured`]). Returns the
/// hierarchy's facts beside it; refuses an empty sphere set and a fan-out outside `2..=32`.
pub fn tree_of_spheres(
    spheres: &[Sphere],
    opts: &HierarchyOptions,
    meta: TreeMeta,
    progress: &dyn Progress,
) -> Result<(SphereTree, HierarchyStats)> {
    let clustered = hierarchy::cluster(spheres, opts, progress)?;
    Ok(stages::assemble(clustered, meta))
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
