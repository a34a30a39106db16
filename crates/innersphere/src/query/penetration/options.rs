//! The options of the penetration query and where its overlapping leaf pairs come from.

/// Options of [`Pair::penetration`](crate::Pair::penetration).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PenetrationOptions {
    /// Force per unit of penetration volume (force = stiffness × volume).
    pub stiffness: f64,
    /// At most this many contact patches (0 = none).
    pub max_patches: usize,
    /// A pair joins the patch whose first point is nearest when within this distance (model
    /// units); 0 = automatic: 1/8 of the smaller root-sphere radius.
    pub patch_radius: f64,
    /// Skip (answer "no penetration") while the last proved separation holds (traversal
    /// only; the front needs no skip).
    pub safe_motion: bool,
    /// Where the overlapping leaf pairs come from (default [`Tracking::Auto`]).
    pub tracking: Tracking,
    /// Also sum [`Penetration::area`](super::Penetration::area) and [`Penetration::stiffness`](super::Penetration::stiffness) (the linearised wrench
    /// an implicit integrator needs; the haptic loop sets it). Off by default: it adds about
    /// a quarter to the slowest frames of deep contact (measured on the jaw pair, see
    /// BENCHMARKS.md).
    pub linearize: bool,
}

/// The stiffest penalty accepted (force per unit volume): far above any material in any
/// units, low enough that stiffness × the largest volume of supported coordinates stays
/// finite.
pub const MAX_STIFFNESS: f64 = 1e30;

impl PenetrationOptions {
    /// Refuses a stiffness that is negative, not finite or above [`MAX_STIFFNESS`] (a force
    /// that would overflow to infinity and NaN).
    pub fn check(&self) -> crate::error::Result<()> {
        if !(self.stiffness.is_finite() && (0.0..=MAX_STIFFNESS).contains(&self.stiffness)) {
            return Err(crate::error::Error::InvalidOption(format!(
                "the stiffness must be from 0 to {} (force per unit volume), not {}",
                crate::error::num(MAX_STIFFNESS),
                crate::error::num(self.stiffness)
            )));
        }
        Ok(())
    }
}

impl Default for PenetrationOptions {
    fn default() -> Self {
        PenetrationOptions {
            stiffness: 1.0,
            max_patches: 8,
            patch_radius: 0.0,
            safe_motion: true,
            tracking: Tracking::Auto,
            linearize: false,
        }
    }
}

/// How [`Pair::penetration`](crate::Pair::penetration) finds the overlapping leaf pairs. Same result either way.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Tracking {
    /// The front for trees of up to [`AUTO_FRONT_NODES`] nodes together, else the traversal.
    #[default]
    Auto,
    /// The kinetic front (ours): re-test only what the motion since the last query could
    /// change. Far fewer node-pair tests, but each is a likely cache miss.
    Front,
    /// A depth-first traversal from the roots every query (larger sphere refined first).
    Traversal,
}

/// [`Tracking::Auto`] uses the front up to this many nodes in both trees together: on the
/// jaw pair the front is 3–6× faster than the traversal with trees of 30k–100k leaves
/// (≈ 80k–300k nodes together) and slower with 570k (1.7M nodes), where its scattered
/// memory accesses dominate.
pub const AUTO_FRONT_NODES: usize = 1_000_000;
