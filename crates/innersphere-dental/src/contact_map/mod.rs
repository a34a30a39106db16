//! Contact maps: each of two meshes coloured by its signed gap to the other (what a dentist
//! reads from articulating paper, and 3Shape, Exocad or T-Scan show), with per-region
//! summaries (per tooth, from the teeth's crown centres).
//!
//! The gaps are exact: every vertex's f64 distance to the other mesh's nearest triangle,
//! negative inside it ([`vertex_gaps`]). The files: `teeth` (regions from a teeth-axes
//! JSON, its one parser), `check` (whether a teeth file fits the arch it labels), `summary`
//! (per-region minimum gap, contact areas, spots), `arch_regions` (regions of the arch
//! without a teeth file, and the left/right balance), `colour` (the colour scale), `ply` (the
//! coloured mesh as a PLY file).

mod arch_regions;
mod check;
mod colour;
mod ply;
mod summary;
mod teeth;

pub use arch_regions::{arch_region_of, arch_regions, ArchRegion, Balance, ARCH_REGIONS};
pub use check::{check_pair, ArchContext, TeethFit, TEETH_BOX_MARGIN};
pub use colour::{gap_colour, LEGEND};
pub use ply::{save_ply, write_ply, MAP_FILE};
pub use summary::{summarise, RegionSummary, SPOT_GAP};
pub use teeth::{Jaw, Teeth, Tooth, MAX_TOOTH_REACH};

use innersphere::error::{Error, Result};
use innersphere::exact::{vertex_gaps, ExactMesh};
use innersphere::pose::Pose;

/// The signed gaps of both meshes: A's vertices to B's surface and B's to A's, mm where the
/// meshes are in mm.
#[derive(Debug, Clone, PartialEq)]
pub struct ContactMap {
    /// Per vertex of A, its signed gap to B (negative inside B).
    pub gaps_a: Vec<f64>,
    /// Per vertex of B, its signed gap to A (negative inside A).
    pub gaps_b: Vec<f64>,
}

impl ContactMap {
    /// The gaps of `a` at `pose_a` and `b` at `pose_b` (world poses), capped at `cap` (see
    /// [`vertex_gaps`]; `f64::INFINITY` for none). Errors on a pose that is not finite or
    /// places its mesh beyond the supported coordinates
    /// ([`Mesh::ensure_placed_within_range`](innersphere::mesh::Mesh::ensure_placed_within_range)), or a NaN or negative cap.
    pub fn new(
        a: &ExactMesh,
        pose_a: &Pose,
        b: &ExactMesh,
        pose_b: &Pose,
        cap: f64,
    ) -> Result<ContactMap> {
        for (p, m, what) in [(pose_a, a, "A"), (pose_b, b, "B")] {
            m.mesh().ensure_placed_within_range(p, what)?;
        }
        if cap.is_nan() || cap < 0.0 {
            return Err(Error::InvalidOption(format!(
                "the gap cap must be ≥ 0, got {cap}"
            )));
        }
        Ok(ContactMap {
            gaps_a: vertex_gaps(a, pose_a, b, pose_b, cap),
            gaps_b: vertex_gaps(b, pose_b, a, pose_a, cap),
        })
    }
}
