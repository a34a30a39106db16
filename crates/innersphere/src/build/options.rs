//! What the build can be told: [`BuildOptions`] (grid [`Resolution`], packing and hierarchy
//! settings) and [`validate_options`], which checks them before any work starts.

use crate::error::{Error, Result};
use crate::hierarchy::{self, HierarchyOptions};
use crate::packing::PackingOptions;

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
