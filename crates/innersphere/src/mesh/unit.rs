//! The unit of a mesh file. The library works in millimetres (the presets, the planning
//! tools' anatomical bounds, the contact map's colour bands, the haptic stiffnesses all
//! assume them), so a mesh in another unit is converted to millimetres as it is loaded
//! ([`Mesh::load_in`](super::Mesh::load_in)); everything after that, poses and answers
//! included, is in millimetres.

use std::fmt;
use std::str::FromStr;

use crate::error::{Error, Result};

/// The unit of a mesh file's coordinates.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Default, Hash, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "lowercase")]
pub enum Unit {
    /// Millimetres: dental scanners and CBCT segmentations (the default).
    #[default]
    Mm,
    /// Centimetres.
    Cm,
    /// Metres: some research datasets and CAD exports.
    M,
    /// Inches.
    In,
}

impl Unit {
    /// Every unit, in the order the doors list them.
    pub const ALL: [Unit; 4] = [Unit::Mm, Unit::Cm, Unit::M, Unit::In];

    /// Millimetres per unit.
    pub fn to_mm(self) -> f64 {
        match self {
            Unit::Mm => 1.0,
            Unit::Cm => 10.0,
            Unit::M => 1000.0,
            Unit::In => 25.4,
        }
    }

    /// The name the doors take (`mm`, `cm`, `m`, `in`).
    pub fn name(self) -> &'static str {
        match self {
            Unit::Mm => "mm",
            Unit::Cm => "cm",
            Unit::M => "m",
            Unit::In => "in",
        }
    }

    /// True for millimetres (kept out of the tree file's meta, so that trees of millimetre
    /// meshes keep their bytes).
    pub(crate) fn is_mm(&self) -> bool {
        *self == Unit::Mm
    }
}

impl fmt::Display for Unit {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Unit {
    type Err = Error;

    fn from_str(s: &str) -> Result<Unit> {
        Unit::ALL
            .into_iter()
            .find(|u| u.name().eq_ignore_ascii_case(s.trim()))
            .ok_or_else(|| {
                Error::InvalidOption(format!(
                    "unknown unit \"{s}\": give mm, cm, m or in (the unit of the mesh files)"
                ))
            })
    }
}

/// The span (mm, longest side of the bounding box) of the bodies the planning tools and the
/// dental presets are made for: a single tooth is about 8 mm, a skull about 200 mm.
pub const DENTAL_SPAN_MM: (f64, f64) = (5.0, 300.0);

/// A warning when a body `size` mm across (its longest side, as loaded in `assumed`) is out
/// of the dental span while another unit would put it in (e.g. an arch of 0.06 "mm" is
/// 60 mm in metres); `None` when the size fits the assumed unit or no unit explains it.
pub fn unit_warning(size_mm: f64, assumed: Unit) -> Option<String> {
    let (lo, hi) = DENTAL_SPAN_MM;
    if !size_mm.is_finite() || (lo..=hi).contains(&size_mm) {
        return None;
    }
    let raw = size_mm / assumed.to_mm();
    let fits = Unit::ALL
        .into_iter()
        .filter(|u| *u != assumed && (lo..=hi).contains(&(raw * u.to_mm())))
        .map(|u| format!("--unit {u} ({:.0} mm)", raw * u.to_mm()))
        .collect::<Vec<_>>();
    (!fits.is_empty()).then(|| {
        format!(
            "it is {size_mm:.3} mm across in {assumed}, outside the {lo}–{hi} mm of teeth and jaws; if its file is in another unit, say so: {}",
            fits.join(" or ")
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_factors_and_the_warning() {
        for u in Unit::ALL {
            assert_eq!(u.name().parse::<Unit>().unwrap(), u);
        }
        assert_eq!("M".parse::<Unit>().unwrap(), Unit::M);
        assert!("metre".parse::<Unit>().is_err());
        assert_eq!(Unit::In.to_mm(), 25.4);
        // An arch in metres read as mm.
        let w = unit_warning(0.06, Unit::Mm).unwrap();
        assert!(w.contains("--unit m (60 mm)"), "{w}");
        assert!(unit_warning(60.0, Unit::Mm).is_none());
        assert!(unit_warning(60.0, Unit::M).is_none());
        // A bunny of 1 "unit": cm or in would make it dental-sized, so they are named.
        assert!(unit_warning(1.0, Unit::Mm).is_some());
        assert!(unit_warning(1e9, Unit::Mm).is_none());
    }
}
