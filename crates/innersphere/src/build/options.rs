//! What the build can be told: [`BuildOptions`] (grid [`Resolution`], packing and hierarchy
//! settings) and [`validate_options`], which checks them before any work starts.

use crate::error::{Error, Result};
use crate::field::thick::ThickParts;
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
    /// Parts thicker than this rule's balls packed from a coarse lattice with a larger
    /// minimum radius (the build's thick-part stage); `None`: every part alike. The jaw presets set
    /// it (bone is thicker than any tooth); the unit-free presets do not.
    pub thick: Option<ThickParts>,
}

impl Default for BuildOptions {
    fn default() -> Self {
        BuildOptions {
            resolution: Resolution::Cells(128),
            packing: PackingOptions::default(),
            hierarchy: HierarchyOptions::default(),
            thick: None,
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
    if let Some(t) = &opts.thick {
        if !(t.radius.is_finite() && t.radius > 0.0) {
            return Err(Error::InvalidOption(format!(
                "the thick-part radius must be a positive number, got {}",
                t.radius
            )));
        }
        if !(t.margin.is_finite() && t.margin >= 0.0) {
            return Err(Error::InvalidOption(format!(
                "the thick-part margin must be a non-negative number, got {}",
                t.margin
            )));
        }
        if !(2..=64).contains(&t.stride) {
            return Err(Error::InvalidOption(format!(
                "the thick-part stride must be between 2 and 64 voxels, got {}",
                t.stride
            )));
        }
        if !(t.min_radius.is_finite() && t.min_radius >= 0.0) {
            return Err(Error::InvalidOption(format!(
                "the thick-part minimum radius must be a non-negative number, got {}",
                t.min_radius
            )));
        }
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
