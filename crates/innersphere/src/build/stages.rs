//! The build's stages, in the order [`build_tree`](super::build_tree) runs them and times them
//! ([`StageSeconds`]): [`prepare`] (check and orient the mesh, choose the grid), [`field`]
//! (triangle tree, thick parts, distance bounds), [`packing`] (the inner spheres),
//! [`hierarchy`] (cluster them), [`tree`] (the [`SphereTree`] with its [`TreeMeta`]) and
//! [`report`] (the [`BuildReport`]). Each takes what the stages before it made and hands on
//! only what the stages after it need.

use super::mass::mass_of;
use super::options::{validate_options, BuildOptions, Resolution};
use super::pipeline::{BuildReport, StageSeconds, MIN_EXTENT};
use super::verdict::MeshVerdict;
use crate::error::{Error, Result};
use crate::field::distance::DistanceBounds;
use crate::field::thick::ThickSet;
use crate::field::{self, InsideMethod, VoxelGrid};
use crate::hierarchy::{self, Hierarchy, HierarchyStats};
use crate::mesh::bvh::TriangleBvh;
use crate::mesh::{Mesh, MeshReport};
use crate::packing::{self, Sphere};
use crate::progress::Progress;
use crate::tree::{BuildStamp, SphereTree, TreeMeta};
use glam::DVec3;
use std::borrow::Cow;
use std::time::Instant;

/// Triangles per leaf of the build's triangle tree: its queries are points far from the
/// surface (the distance bounds, the packing's exact distances, refinement), which larger
/// leaves serve faster (2-core VM, jaw arches, 4 interleaved rounds: build medians 0.96–0.98×
/// those with 4; 12 about as fast as 8, 2 slower). The spheres do not depend on it.
const BUILD_LEAF_SIZE: usize = 8;

/// The prepare stage's output: the mesh checked and oriented, its defect report, the grid
/// the field is sampled on, and the warnings so far.
pub(super) struct Prepared<'m> {
    /// The mesh, flipped when it faced inward.
    pub mesh: Cow<'m, Mesh>,
    /// Defects of the input mesh (before flipping).
    pub report: MeshReport,
    /// The triangle tree built beside the report and its seconds; `None` when the mesh was
    /// flipped (the field stage builds the flipped mesh's own).
    pub bvh: Option<(TriangleBvh, f64)>,
    /// Bounding box of the mesh.
    pub lo: DVec3,
    /// Bounding box of the mesh.
    pub hi: DVec3,
    /// The voxel grid over the bounding box.
    pub grid: VoxelGrid,
    /// Things the user should know (open mesh, flipped faces, ...).
    pub warnings: Vec<String>,
}

/// Prepare: takes the mesh and the options; checks both, makes the mesh's defect report (while
/// the triangle tree is built on the other threads), flips an inward mesh, refuses a soup, a
/// mesh too small or too far from the origin for the tree's `f32` numbers, and chooses the
/// grid. Returns the [`Prepared`] mesh.
pub(super) fn prepare<'m>(
    mesh: &'m Mesh,
    opts: &BuildOptions,
    progress: &dyn Progress,
) -> Result<Prepared<'m>> {
    validate_options(opts)?;
    mesh.validate()?;
    progress.start("triangle tree", 1);
    let (report, bvh) = rayon::join(
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
    let mut mesh = Cow::Borrowed(mesh);
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
    Ok(Prepared {
        mesh,
        report,
        bvh,
        lo,
        hi,
        grid,
        warnings,
    })
}

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

/// The field stage's output (beside the triangle tree, which only the packing still needs).
pub(super) struct Field {
    /// The thick parts' coarse lattice, when the options ask for one and the mesh has any.
    pub thick: Option<ThickSet>,
    /// Upper bounds of the inside voxels' distances.
    pub bounds: DistanceBounds,
}

/// Field: takes the oriented mesh, its triangle tree when the prepare stage kept one, and the
/// grid; builds the triangle tree if needed, finds the thick parts and bounds every inside
/// voxel's distance (the packing makes exact only those it needs). Returns the triangle tree
/// and the [`Field`]; refuses a mesh with no voxel centre inside.
pub(super) fn field(
    mesh: &Mesh,
    bvh: Option<TriangleBvh>,
    grid: VoxelGrid,
    opts: &BuildOptions,
    progress: &dyn Progress,
) -> Result<(TriangleBvh, Field)> {
    let bvh = bvh.unwrap_or_else(|| {
        progress.start("triangle tree", 1);
        let bvh = TriangleBvh::with_leaf_size(mesh, BUILD_LEAF_SIZE);
        progress.finish();
        bvh
    });
    // Thick parts (bone under teeth) keep a coarse lattice of voxels only.
    let thick = match &opts.thick {
        Some(parts) => field::thick::ThickSet::find(mesh, &bvh, &grid, parts, progress)?,
        None => None,
    };
    let bounds = field::distance::bounds_where(mesh, &bvh, grid, thick.as_ref(), progress)?;
    if bounds.inside.is_empty() {
        return Err(Error::InvalidMesh(format!(
            "the mesh encloses no volume at voxel size {:.6} (no voxel centre lies inside; a triangle soup or a flat sheet?)",
            grid.h
        )));
    }
    Ok((bvh, Field { thick, bounds }))
}

/// Packing: takes the distance bounds, the triangle tree and the mesh's box (for the error);
/// returns the inner spheres, or an error naming the option that left no room for any.
pub(super) fn packing(
    bounds: &DistanceBounds,
    bvh: &TriangleBvh,
    (lo, hi): (DVec3, DVec3),
    opts: &BuildOptions,
    progress: &dyn Progress,
) -> Result<Vec<Sphere>> {
    let spheres = packing::pack_parallel(bounds, bvh, &opts.packing, progress);
    if !spheres.is_empty() {
        return Ok(spheres);
    }
    let grid = &bounds.grid;
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
    Err(Error::InvalidMesh(
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
    ))
}

/// Hierarchy: takes the inner spheres; returns them clustered by BNG and laid out breadth-first
/// ([`hierarchy::cluster`]).
pub(super) fn hierarchy(
    spheres: &[Sphere],
    opts: &BuildOptions,
    progress: &dyn Progress,
) -> Result<Hierarchy> {
    hierarchy::cluster(spheres, &opts.hierarchy, progress)
}

/// The volumes the tree's meta and the report state.
pub(super) struct Volumes {
    /// Total inner-sphere volume.
    pub spheres: f64,
    /// Enclosed volume of the (oriented) mesh.
    pub mesh: f64,
    /// The volume the inside voxels stand for (coarse ones for their whole lattice cell).
    pub inside: f64,
    /// Inside voxels that are coarse lattice nodes of thick parts.
    pub voxels_coarse: usize,
    /// True when the mesh is closed (its inside decided exactly).
    pub closed: bool,
}

impl Volumes {
    /// Measures the volumes of `mesh`, its inside voxels and the inner spheres.
    fn of(mesh: &Mesh, field: &Field, spheres: &[Sphere]) -> Volumes {
        let b = &field.bounds;
        let h = b.grid.h;
        let voxels_coarse = b
            .coarse
            .as_ref()
            .map_or(0, |c| c.flags.iter().filter(|&&f| f).count());
        // In thick parts each coarse voxel stands for the stride³ voxels around it.
        let inside = match &field.thick {
            Some(t) => {
                (b.inside.len() - voxels_coarse) as f64 * h.powi(3)
                    + voxels_coarse as f64 * (f64::from(t.stride()) * h).powi(3)
            }
            None => b.inside.len() as f64 * h.powi(3),
        };
        Volumes {
            spheres: packing::total_volume(spheres),
            mesh: mesh.signed_volume().abs(),
            inside,
            voxels_coarse,
            closed: b.method == InsideMethod::ClosedExact,
        }
    }

    /// What the coverage is relative to (its name in the report) and that volume: the mesh's
    /// when it is closed, the inside voxels' when it is open.
    fn basis(&self) -> (&'static str, f64) {
        if self.closed {
            ("mesh_volume", self.mesh)
        } else {
            ("inside_voxel_volume", self.inside)
        }
    }

    /// Total inner-sphere volume / the basis volume.
    fn coverage(&self) -> f64 {
        self.spheres / self.basis().1.max(f64::MIN_POSITIVE)
    }
}

/// The tree stage's output: the tree, its hierarchy's facts, and the volumes it was measured
/// with.
pub(super) struct Built {
    /// The finished tree.
    pub tree: SphereTree,
    /// Facts about its hierarchy.
    pub stats: HierarchyStats,
    /// Volumes of the mesh, the inside voxels and the spheres.
    pub volumes: Volumes,
}

/// Tree: takes the prepared mesh, the field, the inner spheres and their hierarchy; measures
/// the volumes, mass properties and source shape, makes the [`TreeMeta`] and the
/// [`SphereTree`], and refuses a tree that its file could not hold. Returns the [`Built`] tree.
pub(super) fn tree(
    prep: &Prepared,
    field: &Field,
    spheres: &[Sphere],
    h: Hierarchy,
    opts: &BuildOptions,
) -> Result<Built> {
    let mesh: &Mesh = &prep.mesh;
    let volumes = Volumes::of(mesh, field, spheres);
    let (com, inertia) = mass_of(mesh, volumes.closed, spheres);
    let source = crate::tree::check::source_shape(mesh, (prep.lo + prep.hi) * 0.5);
    let meta = TreeMeta {
        fanout: opts.hierarchy.fanout,
        voxel_size: field.bounds.grid.h,
        min_radius: opts.packing.min_radius,
        mesh_volume: volumes.basis().1,
        source_volume: Some(source.0),
        source_centroid: source.1.map(|c| c.to_array()),
        center_of_mass: com.to_array(),
        bbox_min: prep.lo.to_array(),
        bbox_max: prep.hi.to_array(),
        coverage: volumes.coverage(),
        mesh_closed: volumes.closed,
        built_by: Some(BuildStamp::current(opts.packing.refine_steps)),
        inertia,
        source: None,
    };
    let (tree, stats) = assemble(h, meta);
    // The tree must read back from its file: never hand out one that `save` would refuse.
    crate::tree::file::check_writable(&tree)?;
    Ok(Built {
        tree,
        stats,
        volumes,
    })
}

/// The [`SphereTree`] of the hierarchy `h` with `meta`, and the hierarchy's facts.
pub(super) fn assemble(h: Hierarchy, meta: TreeMeta) -> (SphereTree, HierarchyStats) {
    let tree = SphereTree {
        x: h.x,
        y: h.y,
        z: h.z,
        r: h.r,
        first_child: h.first_child,
        child_count: h.child_count,
        parent: h.parent,
        depth: h.depth,
        meta,
    };
    (tree, h.stats)
}

/// Report: takes what the stages made and their seconds; returns the [`BuildReport`], with a
/// warning added when BNG could not separate some spheres.
pub(super) fn report(
    prep: Prepared,
    field: &Field,
    spheres: &[Sphere],
    built: &Built,
    opts: &BuildOptions,
    seconds: f64,
    stage_seconds: StageSeconds,
) -> BuildReport {
    let mut warnings = prep.warnings;
    if built.stats.fallback_splits > 0 {
        warnings.push(format!(
            "{} nodes were split by position because BNG could not separate their spheres",
            built.stats.fallback_splits
        ));
    }
    let (min_r, max_r) = spheres.iter().fold((f64::MAX, 0.0f64), |(a, b), s| {
        (a.min(s.radius), b.max(s.radius))
    });
    let b = &field.bounds;
    let v = &built.volumes;
    BuildReport {
        spheres: spheres.len(),
        nodes: built.tree.len(),
        depth: built.tree.max_depth(),
        voxels_inside: b.inside.len(),
        voxels_coarse: v.voxels_coarse,
        thick_volume: field
            .thick
            .as_ref()
            .map_or(0.0, |t| t.voxels() * b.grid.h.powi(3)),
        grid_dims: b.grid.dims,
        voxel_size: b.grid.h,
        coverage: v.coverage(),
        coverage_basis: v.basis().0,
        sphere_volume: v.spheres,
        mesh_volume: v.mesh,
        min_sphere_radius: min_r,
        max_sphere_radius: max_r,
        fanout: opts.hierarchy.fanout,
        enclosing_ratio_mean: built.stats.enclosing_ratio_mean,
        enclosing_ratio_max: built.stats.enclosing_ratio_max,
        inside_method: b.method,
        mesh: prep.report,
        warnings,
        seconds,
        stage_seconds,
    }
}
