//! Mass properties of the solid a closed mesh encloses: volume, centre of mass and inertia
//! tensor, per unit density. The haptic tool (`innersphere-haptic`) is a rigid body with these.

use super::Mesh;
use glam::{DMat3, DVec3};

/// Volume, centre of mass and inertia tensor of a uniform solid, per unit density.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MassProperties {
    /// Enclosed volume (model units³), positive.
    pub volume: f64,
    /// Centre of mass (model frame).
    pub center_of_mass: DVec3,
    /// Inertia tensor about the centre of mass, model axes, per unit density:
    /// `∫ (|r|² I − r rᵀ) dV` with `r` from the centre of mass (model units⁵). Multiply by a
    /// density (mass per unit volume) for the physical tensor.
    pub inertia: DMat3,
}

impl MassProperties {
    /// The six independent entries of [`inertia`](Self::inertia): `[xx, yy, zz, xy, xz, yz]`
    /// (the form stored in a tree's meta).
    pub fn inertia_entries(&self) -> [f64; 6] {
        let m = &self.inertia;
        [
            m.x_axis.x, m.y_axis.y, m.z_axis.z, m.y_axis.x, m.z_axis.x, m.z_axis.y,
        ]
    }

    /// The symmetric tensor from `[xx, yy, zz, xy, xz, yz]`.
    pub fn inertia_from_entries(e: [f64; 6]) -> DMat3 {
        let [xx, yy, zz, xy, xz, yz] = e;
        DMat3::from_cols(
            DVec3::new(xx, xy, xz),
            DVec3::new(xy, yy, yz),
            DVec3::new(xz, yz, zz),
        )
    }
}

impl Mesh {
    /// Mass properties of the enclosed solid (divergence theorem over the tetrahedra from the
    /// origin to each triangle, Tonon 2004), whatever the mesh's orientation: an inward-facing
    /// mesh gives the same answer as its outward-facing flip. `None` when the enclosed volume
    /// is (nearly) zero. Meaningful only for closed meshes.
    pub fn mass_properties(&self) -> Option<MassProperties> {
        // Work relative to a vertex near the middle: the integrals then stay well conditioned
        // for a mesh far from the origin.
        let (lo, hi) = self.bbox();
        let o = if lo.is_finite() && hi.is_finite() {
            0.5 * (lo + hi)
        } else {
            DVec3::ZERO
        };
        let mut vol = 0.0;
        let mut first = DVec3::ZERO;
        // Σ over tetrahedra of ∫ r rᵀ dV (the covariance, not yet about the centre).
        let mut cov = DMat3::ZERO;
        for t in 0..self.triangles.len() {
            let [a, b, c] = self.triangle(t);
            let (a, b, c) = (a - o, b - o, c - o);
            let det = a.dot(b.cross(c));
            vol += det;
            first += det * (a + b + c);
            // ∫ r rᵀ over the tetrahedron (0, a, b, c) = det/120 · (Σ vᵢvᵢᵀ + (Σvᵢ)(Σvᵢ)ᵀ).
            let s = a + b + c;
            let outer = |v: DVec3| DMat3::from_cols(v * v.x, v * v.y, v * v.z);
            cov += (outer(a) + outer(b) + outer(c) + outer(s)) * det;
        }
        let volume = vol / 6.0;
        if volume.is_nan() || volume.abs() <= 1e-300 || !volume.is_finite() {
            return None;
        }
        let com = first / (24.0 * volume);
        let cov = cov * (1.0 / 120.0);
        // Sign: an inward-facing mesh has every det negated, so volume and the covariance
        // flip sign together; normalise to the positive solid.
        let (volume, cov) = if volume < 0.0 {
            (-volume, cov * -1.0)
        } else {
            (volume, cov)
        };
        // About the centre of mass (parallel axis): C_com = C − V·c cᵀ.
        let c = com;
        let cov_com = cov - DMat3::from_cols(c * c.x, c * c.y, c * c.z) * volume;
        let trace = cov_com.x_axis.x + cov_com.y_axis.y + cov_com.z_axis.z;
        let inertia = DMat3::from_diagonal(DVec3::splat(trace)) - cov_com;
        Some(MassProperties {
            volume,
            center_of_mass: com + o,
            inertia,
        })
    }
}
