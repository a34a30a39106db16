//! The regions of an arch without a teeth file: five stretches along the arch, from the
//! pair's anatomical frame (the midline through the incisal point, the left axis), and the
//! balance of the contacts between the left and right sides: what a planner reads first when
//! nobody has numbered the teeth.

use super::summary::{region_stats, RegionSummary};
use crate::anatomy::AnatomicalFrame;
use glam::DVec3;
use innersphere::mesh::Mesh;
use serde::Serialize;

/// The regions, right to left (the patient's), and where each ends along the left axis from
/// the midline (mm at the frame's scale 1). Calibrated on a typical adult arch, not on any
/// scan here: the central and lateral incisors span about ±9 mm of the midline, the canine
/// and premolars reach about 21 mm; beyond are the molars. A teeth file gives the true
/// boundaries.
pub const ARCH_REGIONS: [(&str, f64); 5] = [
    ("right molars", -21.0),
    ("right canine and premolars", -9.0),
    ("incisors", 9.0),
    ("left canine and premolars", 21.0),
    ("left molars", f64::INFINITY),
];

/// What one region of an arch shows (as [`RegionSummary`] does per tooth).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ArchRegion {
    /// Its name ([`ARCH_REGIONS`]).
    pub region: &'static str,
    /// Its summary (its `tooth` is 0).
    #[serde(flatten)]
    pub summary: RegionSummary,
}

/// The region of each of `vertices` (in the frame's coordinates), as an index into
/// [`ARCH_REGIONS`].
pub fn arch_region_of(frame: &AnatomicalFrame, vertices: &[DVec3]) -> Vec<u32> {
    let scale = frame.scale.max(f64::MIN_POSITIVE);
    vertices
        .iter()
        .map(|v| {
            let x = (*v - frame.incisal).dot(frame.left) / scale;
            ARCH_REGIONS
                .iter()
                .position(|&(_, end)| x < end)
                .unwrap_or(ARCH_REGIONS.len() - 1) as u32
        })
        .collect()
}

/// The summary per region of `mesh` (its vertices in the frame's coordinates) with
/// per-vertex `gaps`.
pub fn arch_regions(frame: &AnatomicalFrame, mesh: &Mesh, gaps: &[f64]) -> Vec<ArchRegion> {
    let region = arch_region_of(frame, &mesh.vertices);
    region_stats(mesh, gaps, &region, ARCH_REGIONS.len())
        .into_iter()
        .zip(ARCH_REGIONS)
        .map(|(summary, (region, _))| ArchRegion { region, summary })
        .collect()
}

/// The contact area (mm², gap ≤ 0.1 mm) on each side of the midline, and the left side's
/// share of it: a balanced bite is near 0.5.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Balance {
    /// Contact area left of the midline.
    pub left: f64,
    /// Contact area right of it.
    pub right: f64,
    /// `left / (left + right)`; `null` in JSON (NaN) without contact.
    pub left_share: f64,
}

impl Balance {
    /// The balance of `mesh` (vertices in the frame's coordinates) with per-vertex `gaps`.
    pub fn of(frame: &AnatomicalFrame, mesh: &Mesh, gaps: &[f64]) -> Balance {
        let side: Vec<u32> = mesh
            .vertices
            .iter()
            .map(|v| u32::from((*v - frame.incisal).dot(frame.left) < 0.0))
            .collect();
        let s = region_stats(mesh, gaps, &side, 2);
        let (left, right) = (s[0].area_within_0_1, s[1].area_within_0_1);
        Balance {
            left,
            right,
            left_share: left / (left + right),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A flat strip along the left axis, every vertex in contact: each region's area is its
    /// stretch of the strip, and the balance splits it at the midline.
    #[test]
    fn regions_and_balance_of_a_strip_in_contact() {
        let frame = AnatomicalFrame {
            up: DVec3::Z,
            left: DVec3::X,
            anterior: DVec3::Y,
            incisal: DVec3::ZERO,
            hinge: DVec3::new(0.0, -50.0, 0.0),
            scale: 1.0,
        };
        // x from -30 to 30 in 1 mm steps, 1 mm wide.
        let mut vertices = vec![];
        let mut triangles = vec![];
        for i in 0..=60 {
            let x = i as f64 - 30.0;
            vertices.push(DVec3::new(x, 0.0, 0.0));
            vertices.push(DVec3::new(x, 1.0, 0.0));
            if i > 0 {
                let k = 2 * i as u32;
                triangles.push([k - 2, k, k - 1]);
                triangles.push([k - 1, k, k + 1]);
            }
        }
        let mesh = Mesh {
            vertices,
            triangles,
        };
        let gaps = vec![0.0; mesh.vertices.len()];
        let r = arch_regions(&frame, &mesh, &gaps);
        let area: Vec<f64> = r.iter().map(|r| r.summary.area_within_0_1).collect();
        // Right molars: x in [-30, -21) → 9 mm of strip (vertex areas: ends carry halves).
        assert!((area[0] - 8.5).abs() < 0.01, "{area:?}");
        assert!((area[2] - 18.0).abs() < 0.01, "{area:?}");
        assert!((area.iter().sum::<f64>() - 60.0).abs() < 1e-9);
        assert!(r.iter().all(|r| r.summary.spots == 1));
        let b = Balance::of(&frame, &mesh, &gaps);
        assert!((b.left + b.right - 60.0).abs() < 1e-9);
        assert!((b.left_share - 0.5).abs() < 0.02, "{b:?}");
    }
}
