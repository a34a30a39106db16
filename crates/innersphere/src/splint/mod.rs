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
//!   │                              field::columns — undercuts blocked along the axis),
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
//! report::report                   volume, triangles, watertight / manifold, one body,
//!                                  thickness, distances, arch vertices inside, coverage
//! ```
//!
//! `docs/SPLINT.md` gives the method and the parameters' clinical meaning.

pub mod extract;
pub mod raster;
pub mod report;
pub mod shape;

use std::time::Instant;

use glam::DVec3;
use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::mesh::bvh::TriangleBvh;
use crate::mesh::Mesh;
use crate::pose::Pose;

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
}

impl Default for SplintOptions {
    fn default() -> Self {
        SplintOptions {
            clearance: 0.1,
            coverage: 2.0,
            min_thickness: 1.0,
            rim: 1.5,
            voxel: 0.1,
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
/// frame; see the [module docs](self). Fails on invalid meshes, a non-finite pose, absurd
/// options or arches that leave no room for a wafer.
pub fn make(a: &Mesh, b: &Mesh, pose: &Pose, opts: &SplintOptions) -> Result<Splint> {
    let start = Instant::now();
    opts.validate()?;
    a.validate()?;
    b.validate()?;
    if !(pose.translation.is_finite() && pose.rotation.is_finite()) {
        return Err(Error::InvalidOption("the pose is not finite".into()));
    }
    let (bvh_a, bvh_b) = rayon::join(|| TriangleBvh::new(a), || TriangleBvh::new(b));
    let t_shape = Instant::now();
    let s = shape::shape(a, b, pose, opts)?;
    let t_surface = Instant::now();
    let (mut mesh, specks) = extract::extract(&s)?;
    let t_seat = Instant::now();
    let moved = seat(&mut mesh, &bvh_a, &bvh_b, pose, opts.clearance);
    let t_report = Instant::now();
    let mut report = report::report(&mesh, a, &bvh_a, b, &bvh_b, pose, opts, &s);
    report.moved_vertices = moved;
    report.dropped_specks = specks;
    report.stage_seconds = [
        t_shape - start,
        t_surface - t_shape,
        t_seat - t_surface,
        t_report - t_seat,
        t_report.elapsed(),
    ]
    .map(|d| d.as_secs_f64());
    report.seconds = start.elapsed().as_secs_f64();
    Ok(Splint { mesh, report })
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
