//! The whole build, mesh → tree: validate and orient the mesh, voxel distance field, sphere
//! packing, BNG hierarchy, flat layout. [`build_tree`] is what `ist build` runs.

use crate::field::{self, InsideMethod, VoxelGrid};
use crate::hierarchy::{self, HierarchyOptions};
use crate::mesh::bvh::TriangleBvh;
use crate::mesh::MeshReport;
use crate::packing::{self, PackingOptions};
use crate::progress::Progress;
use crate::tree::{BuildStamp, SphereTree, TreeMeta};
use crate::{Error, Mesh, Result};
use std::time::Instant;

/// How fine the voxel grid is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Resolution {
    /// Cell edge length in model units.
    VoxelSize(f64),
    /// Number of cells along the longest side of the mesh's bounding box.
    Cells(u32),
}

/// Everything the build can be told.
#[derive(Debug, Clone, Copy)]
pub struct BuildOptions {
    /// Grid spacing.
    pub resolution: Resolution,
    /// Minimum radius and maximum count of inner spheres.
    pub packing: PackingOptions,
    /// Fan-out and BNG settings.
    pub hierarchy: HierarchyOptions,
}

impl Default for BuildOptions {
    fn default() -> Self {
        BuildOptions {
            resolution: Resolution::Cells(128),
            packing: PackingOptions::default(),
            hierarchy: HierarchyOptions::default(),
        }
    }
}

/// Seconds spent in each stage of the build.
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct StageSeconds {
    /// Mesh validation, defect report and orientation.
    pub prepare: f64,
    /// Inside test and exact distance of every inside voxel.
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
    /// Voxels whose centre is inside the mesh.
    pub voxels_inside: usize,
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

/// Checks options before any work starts.
pub fn validate_options(opts: &BuildOptions) -> Result<()> {
    match opts.resolution {
        Resolution::VoxelSize(h) if !(h.is_finite() && h > 0.0) => {
            return Err(Error::InvalidOption(format!(
                "voxel size must be a positive number, got {h}"
            )))
        }
        Resolution::Cells(n) if !(2..=4096).contains(&n) => {
            return Err(Error::InvalidOption(format!(
                "resolution must be between 2 and 4096 cells, got {n}"
            )))
        }
        _ => {}
    }
    let m = opts.packing.min_radius;
    if !(m.is_finite() && m >= 0.0) {
        return Err(Error::InvalidOption(format!(
            "minimum radius must be a non-negative number, got {m}"
        )));
    }
    if opts.packing.max_spheres == 0 {
        return Err(Error::InvalidOption(
            "maximum sphere count must be at least 1".into(),
        ));
    }
    let f = opts.hierarchy.fanout;
    if !(2..=hierarchy::bng::MAX_PROTOTYPES as u32).contains(&f) {
        return Err(Error::InvalidOption(format!(
            "fanout must be between 2 and {}, got {f}",
            hierarchy::bng::MAX_PROTOTYPES
        )));
    }
    Ok(())
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
    let report = MeshReport::of(mesh);
    let mut warnings = Vec::new();
    let mut mesh = std::borrow::Cow::Borrowed(mesh);
    if report.oriented_closed {
        if report.volume < 0.0 {
            warnings.push(format!(
                "the mesh faces inward (volume {:.6}); its triangles were flipped",
                report.volume
            ));
            mesh.to_mut().flip();
        }
    } else {
        // The winding number fills holes in a surface; it cannot invent a surface. When most
        // edges are open the triangles bound nothing (a soup), and any "inside" would be noise.
        if report.boundary_edges * 2 > report.edges {
            return Err(Error::InvalidMesh(format!(
                "the mesh encloses no volume: {} of its {} edges are open boundary edges and it has {} separate pieces (a triangle soup?)",
                report.boundary_edges, report.edges, report.components
            )));
        }
        warnings.push(format!(
            "the mesh is not closed ({} boundary edges, {} non-manifold edges): inside/outside decided by the generalized winding number",
            report.boundary_edges, report.nonmanifold_edges
        ));
    }
    if report.degenerate_triangles > 0 {
        warnings.push(format!(
            "{} degenerate (zero-area) triangles",
            report.degenerate_triangles
        ));
    }
    let (lo, hi) = mesh.bbox();
    let grid = match opts.resolution {
        Resolution::VoxelSize(h) => VoxelGrid::covering(lo, hi, h)?,
        Resolution::Cells(n) => VoxelGrid::with_resolution(lo, hi, n)?,
    };
    let t_prepare = t0.elapsed().as_secs_f64();

    let t1 = Instant::now();
    let field = field::distance::compute(&mesh, grid, progress)?;
    let t_field = t1.elapsed().as_secs_f64();
    if field.inside.is_empty() {
        return Err(Error::InvalidMesh(format!(
            "the mesh encloses no volume at voxel size {:.6} (no voxel centre lies inside; a triangle soup or a flat sheet?)",
            grid.h
        )));
    }

    let t2 = Instant::now();
    let surface = (opts.packing.refine_steps > 0).then(|| TriangleBvh::new(&mesh));
    let spheres = packing::pack(&field, &opts.packing, surface.as_ref(), progress);
    let t_pack = t2.elapsed().as_secs_f64();
    if spheres.is_empty() {
        return Err(Error::InvalidMesh(format!(
            "no inner sphere of radius ≥ {} fits (minimum radius too large for this mesh?)",
            opts.packing.min_radius
        )));
    }

    let t3 = Instant::now();
    let sphere_volume = packing::total_volume(&spheres);
    let closed = field.method == InsideMethod::ClosedExact;
    let mesh_volume = mesh.signed_volume().abs();
    let inside_volume = field.inside.len() as f64 * grid.h.powi(3);
    let (coverage_basis, basis) = if closed {
        ("mesh_volume", mesh_volume)
    } else {
        ("inside_voxel_volume", inside_volume)
    };
    let coverage = sphere_volume / basis.max(f64::MIN_POSITIVE);
    let com = mesh.center_of_mass();
    let meta = TreeMeta {
        fanout: opts.hierarchy.fanout,
        voxel_size: grid.h,
        min_radius: opts.packing.min_radius,
        mesh_volume: if closed { mesh_volume } else { inside_volume },
        center_of_mass: com.to_array(),
        bbox_min: lo.to_array(),
        bbox_max: hi.to_array(),
        coverage,
        mesh_closed: closed,
        built_by: Some(BuildStamp::current(opts.packing.refine_steps)),
    };
    let (tree, hstats) = hierarchy::build(&spheres, &opts.hierarchy, meta, progress)?;
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
