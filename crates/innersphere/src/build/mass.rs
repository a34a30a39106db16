//! Mass properties stored in the tree's meta at build time.

use crate::mesh::{MassProperties, Mesh};
use crate::packing::Sphere;
use glam::DVec3;
use std::f64::consts::PI;

/// Centre of mass and inertia entries (per unit density, about the centre of mass) of the
/// solid: the mesh's own when it is closed, else those of the inner spheres, which stand for
/// the solid the winding number found.
pub(super) fn mass_of(mesh: &Mesh, closed: bool, spheres: &[Sphere]) -> (DVec3, Option<[f64; 6]>) {
    if closed {
        if let Some(m) = mesh.mass_properties() {
            return (mesh.center_of_mass(), Some(m.inertia_entries()));
        }
    }
    let com = mesh.center_of_mass();
    let vol: f64 = spheres.iter().map(|s| s.radius.powi(3)).sum::<f64>() * (4.0 / 3.0) * PI;
    if vol.is_nan() || vol <= 0.0 {
        return (com, None);
    }
    let c = spheres
        .iter()
        .map(|s| s.center * s.radius.powi(3))
        .sum::<DVec3>()
        * ((4.0 / 3.0) * PI / vol);
    let mut i = glam::DMat3::ZERO;
    for s in spheres {
        let v = (4.0 / 3.0) * PI * s.radius.powi(3);
        let r = s.center - c;
        // A solid ball's own inertia (2/5 v r²) plus the parallel-axis term.
        let own = 0.4 * v * s.radius * s.radius;
        i += glam::DMat3::from_diagonal(DVec3::splat(own + v * r.length_squared()))
            - glam::DMat3::from_cols(r * (v * r.x), r * (v * r.y), r * (v * r.z));
    }
    let m = MassProperties {
        volume: vol,
        center_of_mass: c,
        inertia: i,
    };
    (c, Some(m.inertia_entries()))
}
