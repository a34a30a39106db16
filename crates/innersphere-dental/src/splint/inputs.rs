//! What cannot make a wafer, refused before the surface is made, with a sentence a surgeon
//! understands: arches at the wrong scale (another unit), flat arches, arches that do not
//! face each other along the insertion axis (side by side, turned about it), arches too far
//! apart for a wafer to bridge, or passing through each other.
//!
//! The bounds are anatomical, in millimetres, and hold for any human dentition (not
//! calibrated on one patient): a dental arch, crowns only or with roots and bone, is 20 to
//! 150 mm across and at least a crown tall; an intermediate wafer bridges a few millimetres
//! at the molars; scanned bites overlap by tenths of a millimetre.

use glam::DVec3;

use crate::anatomy::AnatomicalFrame;
use crate::columns::ColumnGrid;
use innersphere::error::{Error, Result};
use innersphere::mesh::unit::{unit_warning, DENTAL_SPAN_MM};
use innersphere::mesh::Unit;

/// The least height (mm) of an arch along the insertion axis: a crown alone is 5 mm or more.
pub const MIN_ARCH_HEIGHT: f64 = 1.0;
/// The least area (mm²) over which the arches must face each other, seen along the insertion
/// axis: about one molar's occlusal table.
pub const MIN_FACING_AREA: f64 = 20.0;
/// The widest gap (mm) between the arches' facing surfaces at their closest, along the
/// insertion axis, that a wafer bridges: an intermediate wafer opened 15 mm at the incisors
/// leaves about 10 mm at the molars.
pub const MAX_GAP: f64 = 10.0;
/// The deepest overlap (mm) of the arches along the insertion axis at the given pose: scanned
/// bites overlap by up to a few tenths; beyond this B passes through A.
pub const MAX_OVERLAP: f64 = 2.0;
/// The widest angle (degrees) between the two arches' anterior directions: beyond it one
/// arch is turned against the other.
pub const MAX_ANTERIOR_ANGLE: f64 = 60.0;

/// Refuses an arch at the wrong scale ([`DENTAL_SPAN_MM`]; the message names the unit that
/// fits, [`unit_warning`]) or flat along the insertion axis. `coords` are its
/// vertices in the occlusal frame (z along the insertion axis).
pub fn check_arch(name: &str, coords: impl Iterator<Item = DVec3>) -> Result<()> {
    let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    for c in coords {
        lo = lo.min(c);
        hi = hi.max(c);
    }
    let ext = hi - lo;
    let size = ext.max_element();
    if let Some(w) = unit_warning(size, Unit::Mm) {
        return Err(Error::InvalidMesh(format!("arch {name}: {w}")));
    }
    let (lo, hi) = DENTAL_SPAN_MM;
    if !(lo..=hi).contains(&size) {
        return Err(Error::InvalidMesh(format!(
            "arch {name} is {size:.3} mm across, not the {lo}–{hi} mm of teeth and jaws: not a dental arch (or in a unit smaller than mm)"
        )));
    }
    if ext.z < MIN_ARCH_HEIGHT {
        return Err(Error::InvalidMesh(format!(
            "arch {name} is flat: {:.3} mm tall along the insertion axis, where a crown is 5 mm or more; a wafer needs the scanned crowns",
            ext.z
        )));
    }
    Ok(())
}

/// Refuses arches that turn against each other: A's anterior direction (from its own U shape)
/// more than [`MAX_ANTERIOR_ANGLE`] from B's (`frame.anterior`).
pub fn check_directions(a: &[DVec3], b_world: &[DVec3], frame: &AnatomicalFrame) -> Result<()> {
    let own = AnatomicalFrame::from_points(b_world, a)?;
    let angle = own
        .anterior
        .dot(frame.anterior)
        .clamp(-1.0, 1.0)
        .acos()
        .to_degrees();
    if angle > MAX_ANTERIOR_ANGLE {
        return Err(Error::InvalidMesh(format!(
            "the arches point {angle:.0}° apart (front of A against front of B): B is turned against A at this pose; check the pose (is B in A's frame?)"
        )));
    }
    Ok(())
}

/// Refuses arches that do not face each other along the insertion axis, are too far apart
/// for a wafer, or pass through each other. `a_low` is A's lowest point per column and
/// `b_high` B's highest, both offset by `offset` (infinite where the column misses the arch).
pub fn check_facing(a_low: &[f64], b_high: &[f64], grid: &ColumnGrid, offset: f64) -> Result<()> {
    let (mut both, mut gap, mut overlap) = (0usize, f64::INFINITY, f64::NEG_INFINITY);
    for (a, b) in a_low.iter().zip(b_high) {
        if a.is_finite() && b.is_finite() {
            both += 1;
            // The facing surfaces' vertical distance (negative: overlap).
            let d = (a + offset) - (b - offset);
            gap = gap.min(d);
            overlap = overlap.max(-d);
        }
    }
    let area = both as f64 * grid.h * grid.h;
    if area < MIN_FACING_AREA {
        return Err(Error::InvalidMesh(format!(
            "the arches do not face each other along the insertion axis (they overlap over {area:.1} mm² seen along it, less than one molar's {MIN_FACING_AREA} mm²): check the pose (is B in A's frame, and are the meshes in the same unit?)"
        )));
    }
    if gap > MAX_GAP {
        return Err(Error::InvalidMesh(format!(
            "the arches are {gap:.1} mm apart at their closest along the insertion axis; a wafer bridges at most {MAX_GAP} mm: check the pose and the opening"
        )));
    }
    if overlap > MAX_OVERLAP {
        return Err(Error::InvalidMesh(format!(
            "B passes {overlap:.1} mm into A along the insertion axis at this pose (a scanned bite overlaps by tenths of a millimetre, at most {MAX_OVERLAP} mm here): check the pose and the opening"
        )));
    }
    Ok(())
}
