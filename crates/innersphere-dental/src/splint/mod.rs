//! The occlusal splint (surgical wafer) between two arches at a planned pose: a watertight
//! solid that carries the imprints of both arches, to be printed and wired between them in
//! theatre to transfer the plan.
//!
//! ```text
//! A, B (B placed by the pose in A's frame)
//!   │  anatomy::AnatomicalFrame    occlusal up (the insertion axis), anterior, left
//!   ▼
//! shape::shape                     per column of a 2-D grid across up: the lowest point
//!   │                              within `clearance` of A and the highest of B (exact,
//!   │                              columns — undercuts blocked along the axis),
//!   │                              capped `coverage` beyond each arch's cusp level; the
//!   │                              horseshoe outline `rim` around the teeth; perforations
//!   │                              where the wafer would be thinner than `min_thickness`
//!   ▼
//! extract::extract                 the height field on a 3-D grid → surface nets
//!   │                              (fast-surface-nets) → closed, consistently wound mesh
//!   ▼
//! seat                             every vertex pushed to at least `clearance` from both
//!   │                              arches (exact distances)
//!   ▼
//! simplify::simplify               down to `max_triangles` (meshoptimizer, within half
//!   │                              a cell), folds and thin plates repaired by locking
//!   ▼
//! report::report                   volume, triangles, watertight / manifold, one body,
//!                                  thickness, distances, arch vertices inside, coverage,
//!                                  self-intersections (exact)
//! ```
//!
//! `docs/SPLINT.md` gives the method and the parameters' clinical meaning.

pub mod checks;
pub mod extract;
pub mod inputs;
pub mod raster;
pub mod report;
pub mod shape;
pub mod simplify;
pub mod threemf;
pub mod written;

use std::time::Instant;

use glam::DVec3;
use rayon::prelude::*;

use innersphere::error::{Error, Result};
use innersphere::mesh::bvh::TriangleBvh;
use innersphere::mesh::Mesh;
use innersphere::pose::Pose;

pub use report::SplintReport;

/// What the splint is made to; lengths in model units (millimetres for dental scans).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct SplintOptions {
    /// Gap left between the wafer and each arch, so that it seats without binding
    /// (0.1 mm: a printed resin's fit allowance).
    pub clearance: f64,
    /// How far the wafer climbs each arch's crowns beyond their cusp tips (2 mm: the
    /// occlusal coverage depth found best in a clinical study, BMC Oral Health 2022).
    pub coverage: f64,
    /// Least thickness of the wafer between the two imprints (1 mm: printable and stiff
    /// enough to be wired); thinner places are perforated.
    pub min_thickness: f64,
    /// How far the wafer's buccal and lingual walls stand beyond the teeth (1.5 mm).
    pub rim: f64,
    /// Grid spacing of the height field and the surface (0.1 mm).
    pub voxel: f64,
    /// The most triangles the wafer is written with (300,000: what labs and printer
    /// software take in comfortably); the surface is simplified down to it within a
    /// quarter of `voxel` ([`simplify`]). 0: as extracted (a million or more on a full arch).
    pub max_triangles: usize,
}

/// [`SplintOptions::max_triangles`]' default.
pub const MAX_TRIANGLES: usize = 300_000;
/// The fewest triangles [`SplintOptions::max_triangles`] may ask for (other than 0).
pub const MIN_MAX_TRIANGLES: usize = 1_000;

impl Default for SplintOptions {
    fn default() -> Self {
        SplintOptions {
            clearance: 0.1,
            coverage: 2.0,
            min_thickness: 1.0,
            rim: 1.5,
            voxel: 0.1,
            max_triangles: MAX_TRIANGLES,
        }
    }
}

impl SplintOptions {
    /// Refuses absurd values with a message that names the option.
    pub fn validate(&self) -> Result<()> {
        let check = |name: &str, v: f64, lo: f64, hi: f64| -> Result<()> {
            if v.is_finite() && v >= lo && v <= hi {
                Ok(())
            } else {
                Err(Error::InvalidOption(format!(
                    "{name} must be a number in {lo} ..= {hi}, got {v}"
                )))
            }
        };
        check("clearance", self.clearance, 0.0, 5.0)?;
        check("coverage", self.coverage, 0.0, 20.0)?;
        check("min thickness", self.min_thickness, 0.05, 20.0)?;
        check("rim", self.rim, 0.1, 20.0)?;
        check("voxel size", self.voxel, 0.01, 2.0)?;
        if self.max_triangles != 0 && self.max_triangles < MIN_MAX_TRIANGLES {
            return Err(Error::InvalidOption(format!(
                "max triangles must be 0 (as extracted) or at least {MIN_MAX_TRIANGLES}, got {}",
                self.max_triangles
            )));
        }
        Ok(())
    }
}

/// A splint and what was measured on it.
#[derive(Debug, Clone)]
pub struct Splint {
    /// The closed, outward-facing surface, in A's frame.
    pub mesh: Mesh,
    /// The measurements.
    pub report: SplintReport,
}

/// Makes the splint between arch `a` (upper) and arch `b` (lower) with B at `pose` in A's
/// frame; see the [module docs](self). Fails on invalid meshes, a pose that is not finite or
/// places B beyond the supported coordinates, absurd options, and arches that cannot make a
/// wafer ([`inputs`]: another unit, flat, not facing each other, too far apart, passing
/// through each other). The report is measured on the mesh as written and read back
/// ([`written`]); [`SplintReport::fit`] says whether it keeps every guarantee
/// ([`checks::judge`]), and a door must not hand out an unfit wafer as fit.
pub fn make(a: &Mesh, b: &Mesh, pose: &Pose, opts: &SplintOptions) -> Result<Splint> {
    let start = Instant::now();
    opts.validate()?;
    a.validate()?;
    b.validate()?;
    b.ensure_placed_within_range(pose, "B")?;
    let (bvh_a, bvh_b) = rayon::join(|| TriangleBvh::new(a), || TriangleBvh::new(b));
    let t_shape = Instant::now();
    let s = shape::shape(a, b, pose, opts)?;
    let t_surface = Instant::now();
    let (mut mesh, specks) = extract::extract(&s)?;
    let t_seat = Instant::now();
    let moved = seat(&mut mesh, &bvh_a, &bvh_b, pose, opts.clearance);
    let extracted = mesh.triangles.len();
    let mut simplify_error = 0.0;
    if opts.max_triangles > 0 && extracted > opts.max_triangles {
        // Within half a cell: the surface nets' own approximation.
        // The kept vertices are seated ones, unmoved (an edge collapse keeps one of its
        // ends): seating again would push single vertices of large triangles and fold them.
        // Beyond the surface's own defects, a plate thinner than the thickness check allows
        // (a rim collapsed onto the sheet across) is one.
        let up = s.frame.axes[2];
        let thin = opts.min_thickness - checks::THICKNESS_TOLERANCE_CELLS * opts.voxel;
        // On the extracted surface (the first call) the plates within a few cells of that
        // limit are locked from the start: simplification folds thin plates first.
        let first = std::cell::Cell::new(true);
        let defects = |m: &Mesh| -> Result<Vec<[DVec3; 3]>> {
            // Measured as written, as the report measures it; one tree for both checks.
            let written = simplify::rounded_to_f32(m);
            let bvh = TriangleBvh::new(&written);
            // The extracted surface has no folds (its report checks it once more).
            let (thin, mut bad) = if first.replace(false) {
                (thin + THIN_LOCK_CELLS * opts.voxel, vec![])
            } else {
                (thin, simplify::surface_defects(&written, &bvh)?)
            };
            bad.extend(
                report::vertex_thickness(&written, &bvh, up)
                    .into_iter()
                    .filter(|&(_, t)| t < thin)
                    .map(|(v, t)| {
                        let p = written.vertices[v as usize];
                        [p, p + up * t, p - up * t]
                    }),
            );
            Ok(bad)
        };
        let (simpler, err, _) = simplify::simplify(
            &mesh,
            opts.max_triangles,
            opts.voxel / 2.0,
            4.0 * opts.voxel,
            &defects,
        )?;
        mesh = simpler;
        simplify_error = err;
    }
    let (mesh, separated) = written::as_written(mesh)?;
    let self_crossing = innersphere::exact::self_intersections(
        &innersphere::exact::ExactMesh::new(&mesh)?,
        SELF_INTERSECTIONS_COUNTED,
    )
    .len();
    let t_report = Instant::now();
    let mut report = report::report(&mesh, a, &bvh_a, b, &bvh_b, pose, opts, &s);
    report.moved_vertices = moved;
    report.extracted_triangles = extracted;
    report.simplify_error = simplify_error;
    report.self_intersections = self_crossing;
    report.separated_vertices = separated;
    report.dropped_specks = specks;
    report.checks = checks::judge(&report, opts);
    report.fit = report.checks.iter().all(|c| c.ok);
    report.stage_seconds = [
        t_shape - start,
        t_surface - t_shape,
        t_seat - t_surface,
        t_report - t_seat,
        t_report.elapsed(),
    ]
    .map(|d| d.as_secs_f64());
    report.pose = pose.to_array();
    report.seconds = start.elapsed().as_secs_f64();
    Ok(Splint { mesh, report })
}

/// Plates within this many grid cells of the least thickness the checks allow are kept as
/// extracted when the wafer is simplified (measured on generated arches: 3 cells took the
/// rounds to a clean wafer where none left one defect in six rounds).
pub const THIN_LOCK_CELLS: f64 = 3.0;

/// How many self-intersecting triangle pairs a wafer's report counts before it stops
/// looking (one is already a failed guarantee).
pub const SELF_INTERSECTIONS_COUNTED: usize = 100;

/// The widest incisal opening (mm) a wafer is made at: an intermediate wafer opens a few
/// millimetres, and beyond this B swings so far about the hinge that its crowns no longer
/// face A's along one axis.
pub const MAX_OPENING: f64 = 20.0;
/// The most B may be closed beyond the given pose (a negative opening, mm): enough to press
/// a slightly open scan together, not to swing B through A.
pub const MAX_CLOSING: f64 = 2.0;

/// How far B is opened about the hinge before the splint is made ([`make_opened`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Opening {
    /// This far at the incisors (model units; 0: at the pose as given), within
    /// −[`MAX_CLOSING`] ..= [`MAX_OPENING`].
    By(f64),
    /// The least that leaves room for the wafer ([`least_opening`]).
    Auto,
}

/// [`make`] at `pose` opened about the hinge as asked ([`opened`], [`least_opening`]): the
/// intermediate splint (`By(o)`) or the final one (`Auto`). The report says how far it
/// opened and the pose it was made at.
pub fn make_opened(
    a: &Mesh,
    b: &Mesh,
    pose: &Pose,
    opening: Opening,
    opts: &SplintOptions,
) -> Result<Splint> {
    let o = match opening {
        Opening::By(o) if (-MAX_CLOSING..=MAX_OPENING).contains(&o) => o,
        Opening::By(o) => {
            return Err(Error::InvalidOption(format!(
                "the opening must be within -{MAX_CLOSING} ..= {MAX_OPENING} mm at the incisors, got {o}: a wafer is made between facing arches"
            )))
        }
        Opening::Auto => least_opening(a, b, pose, opts)?,
    };
    let at = if o != 0.0 {
        opened(a, b, pose, o)?
    } else {
        *pose
    };
    let mut s = make(a, b, &at, opts)?;
    s.report.opened = o;
    Ok(s)
}

/// The largest share of the outline that [`least_opening`] leaves perforated.
pub const AUTO_PERFORATION: f64 = 0.005;
/// The widest incisal opening [`least_opening`] tries, in model units (mm).
pub const MAX_AUTO_OPENING: f64 = 10.0;

/// B's `pose` followed by an opening of `opening` at the incisors about the pair's hinge
/// axis (the [`AnatomicalFrame`](crate::anatomy::AnatomicalFrame) of A and B at `pose`):
/// the intermediate splint's vertical opening, or the room a final splint needs for its
/// material.
pub fn opened(a: &Mesh, b: &Mesh, pose: &Pose, opening: f64) -> Result<Pose> {
    if !opening.is_finite() {
        return Err(Error::InvalidOption(format!(
            "the opening must be a finite number, got {opening}"
        )));
    }
    let b_world: Vec<DVec3> = b
        .vertices
        .iter()
        .map(|v| pose.transform_point(*v))
        .collect();
    Ok(
        crate::anatomy::AnatomicalFrame::from_points(&a.vertices, &b_world)?
            .opening(opening)
            .then(pose),
    )
}

/// The least opening about the hinge (to 0.05 model units) at which a wafer between the
/// arches is perforated over at most [`AUTO_PERFORATION`] of its outline: where the arches
/// touch (the final occlusion) a wafer needs room for `min_thickness` of material, and
/// opening about the hinge, as an articulator's raised pin does, keeps the bite's relation.
/// Searched by bisection on the height field at a grid of at least 0.2.
pub fn least_opening(a: &Mesh, b: &Mesh, pose: &Pose, opts: &SplintOptions) -> Result<f64> {
    opts.validate()?;
    let coarse = SplintOptions {
        voxel: opts.voxel.max(0.2),
        ..*opts
    };
    let share = |o: f64| -> Result<f64> {
        let s = shape::shape(a, b, &opened(a, b, pose, o)?, &coarse)?;
        Ok(s.perforated_area / s.outline_area.max(f64::MIN_POSITIVE))
    };
    if share(0.0)? <= AUTO_PERFORATION {
        return Ok(0.0);
    }
    if share(MAX_AUTO_OPENING)? > AUTO_PERFORATION {
        return Err(Error::InvalidMesh(format!(
            "even opened {MAX_AUTO_OPENING} at the incisors the arches leave too little room for a wafer {} thick",
            opts.min_thickness
        )));
    }
    let (mut lo, mut hi) = (0.0, MAX_AUTO_OPENING);
    while hi - lo > 0.05 {
        let mid = 0.5 * (lo + hi);
        if share(mid)? <= AUTO_PERFORATION {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    Ok(hi)
}

/// Pushes every vertex closer than `clearance` to an arch out along the line from its
/// nearest arch point, to `clearance` (plus a hair); returns how many moved.
fn seat(mesh: &mut Mesh, a: &TriangleBvh, b: &TriangleBvh, pose: &Pose, c: f64) -> usize {
    let inv = pose.inverse();
    let target = c + 1e-4;
    let moved: usize = mesh
        .vertices
        .par_iter_mut()
        .map(|v| {
            let mut hit = false;
            for _ in 0..3 {
                let mut again = false;
                if let Some(cl) = a.closest_point(*v, c * c) {
                    *v = push(*v, cl.point, target);
                    again = true;
                }
                let local = inv.transform_point(*v);
                if let Some(cl) = b.closest_point(local, c * c) {
                    *v = pose.transform_point(push(local, cl.point, target));
                    again = true;
                }
                hit |= again;
                if !again {
                    break;
                }
            }
            usize::from(hit)
        })
        .sum();
    moved
}

/// `v` moved along the ray from `p` through it to distance `d` from `p`.
fn push(v: DVec3, p: DVec3, d: f64) -> DVec3 {
    let dir = v - p;
    let l = dir.length();
    if l > 0.0 {
        p + dir * (d / l)
    } else {
        v
    }
}
