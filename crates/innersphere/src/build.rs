//! The whole build, mesh → tree: validate and orient the mesh, voxel distance field, sphere
//! packing, BNG hierarchy, flat layout.
//!
//! [`SphereTree::build`] is the short way (tree only); [`SphereTree::build_with_progress`]
//! also reports progress and returns the [`BuildReport`] (warnings included);
//! [`build_tree`] is the same function under its older name (what `ist build` runs).
//!
//! Lengths are in **model units**: the library never assumes a unit. [`BuildOptions`] says
//! how fine the packing is, either as numbers or from a named [`Preset`]
//! ([`BuildOptions::preset`], [`BuildOptions::recommended_for`]), which are functions of the
//! mesh because a fixed voxel size only makes sense for a known unit and scale.

use crate::field::{self, InsideMethod, VoxelGrid};
use crate::hierarchy::{self, HierarchyOptions};
use crate::mesh::bvh::TriangleBvh;
use crate::mesh::MeshReport;
use crate::packing::{self, PackingOptions, Sphere};
use crate::progress::Progress;
use crate::tree::{BuildStamp, SphereTree, TreeMeta};
use crate::{Error, Mesh, Result};
use glam::DVec3;
use std::f64::consts::PI;
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

/// Named build settings, each a function of the mesh ([`BuildOptions::preset`]).
///
/// Why a function of the mesh: the build cost and the accuracy of a tree follow the voxel
/// size *relative to the model* (cells along it) while an accuracy requirement is usually an
/// *absolute* length. The unit-free presets (`Fast`, `Default`, `Fine`) therefore scale the
/// voxel with the mesh's bounding box; the jaw presets fix it in millimetres, because that is
/// what their accuracy was calibrated for, and refuse a mesh whose size says it is not a
/// dental scan in millimetres (a jaw in metres would get a one-cell grid, one in micrometres
/// a grid too large to build).
///
/// Numbers below come from `docs/RESULTS.md` ("Calibration") and `BENCHMARKS.md`, measured
/// on the project's 2-core VM; "error" is the distance error of the sphere sets against the
/// exact mesh distance along a chewing motion.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Preset {
    /// A quick look: 64 cells along the longest side of the bounding box, plain greedy
    /// packing (no minimum radius, no refinement). 8× fewer voxels than `Default`: the bunny
    /// (`../shared/data/classic`) in 0.2 s, 16k spheres.
    Fast,
    /// [`BuildOptions::default`]: 128 cells along the longest side, plain greedy packing (the
    /// paper's). The bunny in 1.7 s, 92k spheres (`BENCHMARKS.md`).
    Default,
    /// The calibrated packing scaled to the mesh: voxel = longest side / 384 (the main trees
    /// of the paper's evaluation, `ist bench paper`), minimum radius half a voxel and 8
    /// off-grid refinement steps (the ratio and steps chosen in `docs/RESULTS.md`, where they
    /// gave a distance error p95 of about a quarter voxel with 4× fewer spheres than the
    /// plain packing at the same error). 27× the voxels of `Default`, and the refinement
    /// runs on one thread: the bunny in 40 s and 0.7 GiB, 131k spheres. What
    /// [`BuildOptions::recommended_for`] returns.
    Fine,
    /// Jaw scans in **millimetres**, the accuracy-calibrated setting of `docs/RESULTS.md`:
    /// 0.1 mm voxels, 0.05 mm minimum radius, 8 refinement steps. On the real arches:
    /// distance error p95 0.027 mm (the bar is 0.03 mm), no missed contact deeper than
    /// 0.1 mm, about 150k spheres, 32–40 s and 0.9–1.1 GiB per arch; a molar in 1.3 s
    /// (14k spheres, p95 0.023 mm).
    Jaw,
    /// Jaw scans in **millimetres**, the query benchmark's trees (`BENCHMARKS.md`): 0.15 mm
    /// voxels, 0.05 mm minimum radius, 8 refinement steps. About 110k spheres and 9 s per
    /// arch (4× faster to build than `Jaw`), but distance error p95 0.046 mm on the molars,
    /// above the 0.03 mm bar: for iterating and timing, not for the final trees.
    JawFast,
}

impl Preset {
    /// Every preset, in the order of [`Preset::name`]'s documentation.
    pub const ALL: [Preset; 5] = [
        Preset::Fast,
        Preset::Default,
        Preset::Fine,
        Preset::Jaw,
        Preset::JawFast,
    ];

    /// The name used on the command line (`ist build --preset NAME`): `fast`, `default`,
    /// `fine`, `jaw`, `jaw-fast`.
    pub fn name(self) -> &'static str {
        match self {
            Preset::Fast => "fast",
            Preset::Default => "default",
            Preset::Fine => "fine",
            Preset::Jaw => "jaw",
            Preset::JawFast => "jaw-fast",
        }
    }
}

impl std::fmt::Display for Preset {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Preset {
    type Err = Error;
    fn from_str(s: &str) -> Result<Preset> {
        Preset::ALL
            .into_iter()
            .find(|p| p.name() == s)
            .ok_or_else(|| {
                let names: Vec<_> = Preset::ALL.iter().map(|p| p.name()).collect();
                Error::InvalidOption(format!(
                    "unknown preset \"{s}\" (expected one of {})",
                    names.join(", ")
                ))
            })
    }
}

/// Cells along the longest side of the bounding box for [`Preset::Fast`].
pub const FAST_CELLS: u32 = 64;
/// Voxel size of [`Preset::Fine`] = longest side of the bounding box / this.
pub const FINE_CELLS: u32 = 384;
/// Minimum radius of the calibrated packing as a fraction of the voxel size (0.05 mm at
/// 0.1 mm voxels in `docs/RESULTS.md`).
pub const CALIBRATED_MIN_RADIUS_PER_VOXEL: f64 = 0.5;
/// Off-grid refinement steps of the calibrated packing (`docs/RESULTS.md`: 16 steps gain
/// little over 8 for twice the packing time).
pub const CALIBRATED_REFINE_STEPS: u32 = 8;
/// Longest bounding-box sides (mm) the jaw presets accept: a single tooth crown to a skull.
/// Outside it the mesh is almost certainly not in millimetres.
pub const JAW_PRESET_SIZE_MM: std::ops::RangeInclusive<f64> = 1.0..=500.0;

/// The smallest longest bounding-box side a build accepts (model units). The grid has at most
/// [`MAX_CELLS`](crate::field::grid::MAX_CELLS) cells, so its voxels are at least
/// `extent / 6e8` wide; from 1e-6 up, a voxel's squared size (≥ 2.8e-30) stays a normal
/// `f32` with full precision (below ~1e-31 the queries' squared `f32` distances lose bits,
/// and at 1e-30 across every answer is measured to be 0: no contact between overlapping
/// bodies). Rescale smaller meshes (metres to millimetres, ...).
pub const MIN_EXTENT: f64 = 1e-6;

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

/// Longest side of the mesh's bounding box, or an error for a mesh without extent.
fn longest_side(mesh: &Mesh) -> Result<f64> {
    let (lo, hi) = mesh.bbox();
    let longest = (hi - lo).max_element();
    if longest.is_finite() && longest > 0.0 {
        Ok(longest)
    } else {
        Err(Error::InvalidMesh(
            "the mesh has no extent (empty, a point, or non-finite coordinates)".into(),
        ))
    }
}

impl BuildOptions {
    /// The options of a named [`Preset`] for this mesh. Lengths are model units; the jaw
    /// presets require the mesh to be in millimetres and fail with
    /// [`Error::InvalidOption`] when its longest side lies outside
    /// [`JAW_PRESET_SIZE_MM`]. Fails with [`Error::InvalidMesh`] for a mesh without extent
    /// (the relative presets need its size). Change any field afterwards to override it
    /// (`ist build --preset` does that with the explicitly given flags).
    pub fn preset(preset: Preset, mesh: &Mesh) -> Result<BuildOptions> {
        let longest = longest_side(mesh)?;
        let calibrated = |voxel: f64, min_radius: f64| BuildOptions {
            resolution: Resolution::VoxelSize(voxel),
            packing: PackingOptions {
                min_radius,
                refine_steps: CALIBRATED_REFINE_STEPS,
                ..PackingOptions::default()
            },
            hierarchy: HierarchyOptions::default(),
        };
        let jaw = |voxel_mm: f64, min_radius_mm: f64| {
            if JAW_PRESET_SIZE_MM.contains(&longest) {
                Ok(calibrated(voxel_mm, min_radius_mm))
            } else {
                Err(Error::InvalidOption(format!(
                    "preset {preset} is in millimetres, for dental scans {}–{} mm across; this mesh is {longest:.4} model units across (not millimetres? scale it, or use the unit-free presets fast, default or fine)",
                    JAW_PRESET_SIZE_MM.start(),
                    JAW_PRESET_SIZE_MM.end()
                )))
            }
        };
        match preset {
            Preset::Fast => Ok(BuildOptions {
                resolution: Resolution::Cells(FAST_CELLS),
                ..BuildOptions::default()
            }),
            Preset::Default => Ok(BuildOptions::default()),
            Preset::Fine => {
                let voxel = longest / FINE_CELLS as f64;
                Ok(calibrated(voxel, voxel * CALIBRATED_MIN_RADIUS_PER_VOXEL))
            }
            Preset::Jaw => jaw(0.1, 0.05),
            Preset::JawFast => jaw(0.15, 0.05),
        }
    }

    /// What this library recommends for a mesh of unknown unit: [`Preset::Fine`] (the
    /// calibrated packing at longest side / 384). For jaw scans in millimetres prefer
    /// [`Preset::Jaw`], whose absolute voxel size is what the 0.03 mm accuracy bar was met
    /// with; for a quick look [`Preset::Fast`]. Fails only for a mesh without extent.
    pub fn recommended_for(mesh: &Mesh) -> Result<BuildOptions> {
        BuildOptions::preset(Preset::Fine, mesh)
    }
}

/// What the build does with a mesh, decided from its defect report alone; `ist inspect`
/// prints it as its verdict, and [`build_tree`] acts on the same value, so the two cannot
/// disagree.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum MeshVerdict {
    /// Every edge is used equally often in each direction
    /// ([`MeshReport::oriented_closed`]; non-manifold edges allowed) and the volume is
    /// positive: the exact inside test (signed ray crossings with exact predicates).
    Closed,
    /// Closed as above, but the signed volume is negative (normals point inward): the build
    /// flips every triangle, warns, then uses the exact inside test.
    ClosedInward,
    /// Holes, open boundaries or inconsistent orientation, with at most half the edges
    /// open: inside/outside decided by the generalized winding number (≥ 0.5, which closes
    /// small holes); the build warns, and the coverage is relative to the inside-voxel volume
    /// instead of the mesh volume.
    Open,
    /// More than half the edges are open boundary edges: a triangle soup that bounds
    /// nothing; the build refuses it ([`Error::InvalidMesh`]).
    Soup,
}

impl MeshVerdict {
    /// The verdict for a mesh with this defect report.
    pub fn of(report: &MeshReport) -> MeshVerdict {
        if report.oriented_closed {
            if report.volume < 0.0 {
                MeshVerdict::ClosedInward
            } else {
                MeshVerdict::Closed
            }
        } else if report.boundary_edges * 2 > report.edges {
            // The winding number fills holes in a surface; it cannot invent a surface. When
            // most edges are open the triangles bound nothing, and any "inside" would be noise.
            MeshVerdict::Soup
        } else {
            MeshVerdict::Open
        }
    }
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
    match MeshVerdict::of(&report) {
        MeshVerdict::Closed => {}
        MeshVerdict::ClosedInward => {
            warnings.push(format!(
                "the mesh faces inward (volume {:.6}); its triangles were flipped",
                report.volume
            ));
            mesh.to_mut().flip();
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
    let (com, inertia) = mass_of(&mesh, closed, &spheres);
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
        inertia,
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

/// Centre of mass and inertia entries (per unit density, about the centre of mass) of the
/// solid: the mesh's own when it is closed, else those of the inner spheres, which stand for
/// the solid the winding number found.
fn mass_of(mesh: &Mesh, closed: bool, spheres: &[Sphere]) -> (DVec3, Option<[f64; 6]>) {
    if closed {
        if let Some(m) = mesh.mass_properties() {
            return (mesh.center_of_mass(), Some(m.inertia_entries()));
        }
    }
    let com = mesh.center_of_mass();
    let vol: f64 = spheres.iter().map(|s| s.radius.powi(3)).sum::<f64>() * (4.0 / 3.0) * PI;
    if vol.is_nan() || vol <= 0.0 {
        return (com, None);
    }
    let c = spheres
        .iter()
        .map(|s| s.center * s.radius.powi(3))
        .sum::<DVec3>()
        * ((4.0 / 3.0) * PI / vol);
    let mut i = glam::DMat3::ZERO;
    for s in spheres {
        let v = (4.0 / 3.0) * PI * s.radius.powi(3);
        let r = s.center - c;
        // A solid ball's own inertia (2/5 v r²) plus the parallel-axis term.
        let own = 0.4 * v * s.radius * s.radius;
        i += glam::DMat3::from_diagonal(DVec3::splat(own + v * r.length_squared()))
            - glam::DMat3::from_cols(r * (v * r.x), r * (v * r.y), r * (v * r.z));
    }
    let m = crate::mesh::MassProperties {
        volume: vol,
        center_of_mass: c,
        inertia: i,
    };
    (c, Some(m.inertia_entries()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes;
    use glam::DVec3;

    /// `mesh` scaled by `s` about the origin.
    fn scaled(mesh: &Mesh, s: f64) -> Mesh {
        let mut m = mesh.clone();
        for v in &mut m.vertices {
            *v *= s;
        }
        m
    }

    fn voxel(o: &BuildOptions) -> f64 {
        match o.resolution {
            Resolution::VoxelSize(h) => h,
            Resolution::Cells(n) => panic!("expected a voxel size, got {n} cells"),
        }
    }

    #[test]
    fn presets_have_names_that_parse_back() {
        for p in Preset::ALL {
            assert_eq!(p.name().parse::<Preset>().unwrap(), p);
            assert_eq!(p.to_string(), p.name());
        }
        let err = "coarse".parse::<Preset>().unwrap_err().to_string();
        assert!(err.contains("unknown preset \"coarse\""), "{err}");
        assert!(err.contains("fast, default, fine, jaw, jaw-fast"), "{err}");
    }

    #[test]
    fn every_preset_gives_valid_options() {
        // A 17 mm molar: in range for the jaw presets too.
        let molar = shapes::molar(3, 0.0);
        for p in Preset::ALL {
            let o = BuildOptions::preset(p, &molar).unwrap();
            validate_options(&o).unwrap_or_else(|e| panic!("{p}: {e}"));
            assert_eq!(o.hierarchy.fanout, 4, "{p}");
            assert_eq!(o.packing.max_spheres, usize::MAX, "{p}");
        }
    }

    #[test]
    fn unit_free_presets_scale_with_the_mesh() {
        let ball = shapes::icosphere(2); // longest side 2
        let fast = BuildOptions::preset(Preset::Fast, &ball).unwrap();
        assert_eq!(fast.resolution, Resolution::Cells(FAST_CELLS));
        assert_eq!(fast.packing, PackingOptions::default());
        let default = BuildOptions::preset(Preset::Default, &ball).unwrap();
        assert_eq!(default.resolution, BuildOptions::default().resolution);
        assert_eq!(default.packing, BuildOptions::default().packing);

        let fine = BuildOptions::preset(Preset::Fine, &ball).unwrap();
        let (lo, hi) = ball.bbox();
        let h = (hi - lo).max_element() / 384.0;
        assert_eq!(voxel(&fine), h);
        assert_eq!(fine.packing.min_radius, h / 2.0);
        assert_eq!(fine.packing.refine_steps, 8);
        // The same shape in other units: every length scales, nothing else changes.
        for s in [1e-3, 1e3] {
            let big = BuildOptions::preset(Preset::Fine, &scaled(&ball, s)).unwrap();
            assert!((voxel(&big) / (h * s) - 1.0).abs() < 1e-12);
            assert!((big.packing.min_radius / (h * s / 2.0) - 1.0).abs() < 1e-12);
            assert_eq!(big.packing.refine_steps, 8);
        }
        let rec = BuildOptions::recommended_for(&ball).unwrap();
        assert_eq!(rec.resolution, fine.resolution);
        assert_eq!(rec.packing, fine.packing);
    }

    #[test]
    fn jaw_presets_are_absolute_millimetres_and_refuse_other_units() {
        let molar = shapes::molar(3, 0.0); // about 10 x 10 x 17 mm
        let jaw = BuildOptions::preset(Preset::Jaw, &molar).unwrap();
        assert_eq!(jaw.resolution, Resolution::VoxelSize(0.1));
        assert_eq!(jaw.packing.min_radius, 0.05);
        assert_eq!(jaw.packing.refine_steps, 8);
        let fast = BuildOptions::preset(Preset::JawFast, &molar).unwrap();
        assert_eq!(fast.resolution, Resolution::VoxelSize(0.15));
        assert_eq!(fast.packing.min_radius, 0.05);
        assert_eq!(fast.packing.refine_steps, 8);
        // The same numbers for a whole arch (a larger mesh): absolute, not relative.
        let arch = BuildOptions::preset(Preset::Jaw, &scaled(&molar, 4.0)).unwrap();
        assert_eq!(arch.resolution, Resolution::VoxelSize(0.1));
        // In metres or micrometres: refused, with the reason.
        for s in [1e-3, 1e3] {
            for p in [Preset::Jaw, Preset::JawFast] {
                let err = BuildOptions::preset(p, &scaled(&molar, s))
                    .unwrap_err()
                    .to_string();
                assert!(err.contains("millimetres"), "{err}");
                assert!(err.contains(&format!("preset {p}")), "{err}");
            }
        }
    }

    #[test]
    fn presets_need_a_mesh_with_extent() {
        let point = Mesh {
            vertices: vec![DVec3::ONE],
            triangles: vec![[0, 0, 0]],
        };
        for p in Preset::ALL {
            assert!(matches!(
                BuildOptions::preset(p, &point),
                Err(Error::InvalidMesh(_))
            ));
        }
        assert!(BuildOptions::recommended_for(&Mesh::default()).is_err());
    }

    #[test]
    fn the_verdict_is_what_the_build_does() {
        let ball = shapes::icosphere(2);
        assert_eq!(MeshVerdict::of(&ball.report()), MeshVerdict::Closed);
        let mut inward = ball.clone();
        inward.flip();
        assert_eq!(MeshVerdict::of(&inward.report()), MeshVerdict::ClosedInward);
        let mut holed = ball.clone();
        holed.triangles.pop();
        assert_eq!(MeshVerdict::of(&holed.report()), MeshVerdict::Open);
        let soup = Mesh::from_soup(
            &(0..20)
                .map(|i| {
                    let o = DVec3::splat(i as f64 * 3.0);
                    [o, o + DVec3::X, o + DVec3::Y]
                })
                .collect::<Vec<_>>(),
        );
        assert_eq!(MeshVerdict::of(&soup.report()), MeshVerdict::Soup);

        let opts = BuildOptions::preset(Preset::Fast, &ball).unwrap();
        let (_, r) =
            SphereTree::build_with_progress(&inward, &opts, &crate::progress::Silent).unwrap();
        assert!(r.warnings.iter().any(|w| w.contains("flipped")), "{r:?}");
        assert_eq!(r.inside_method, InsideMethod::ClosedExact);
        let (_, r) =
            SphereTree::build_with_progress(&holed, &opts, &crate::progress::Silent).unwrap();
        assert_eq!(r.inside_method, InsideMethod::WindingNumber);
        assert!(matches!(
            SphereTree::build(&soup, &opts),
            Err(Error::InvalidMesh(_))
        ));
    }

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
