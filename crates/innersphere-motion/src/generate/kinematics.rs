//! The jaw's kinematics around the bite: the pose of B for an incisal opening (a rotation
//! about the hinge), a lateral shift with a slight turn about the vertical, and a
//! protrusion.

use glam::{DQuat, DVec3};
use innersphere::Pose;

/// The jaw's kinematics around the bite.
pub(super) struct Kin {
    pub(super) bite: Pose,
    pub(super) hinge: DVec3,
    pub(super) left: DVec3,
    pub(super) up: DVec3,
    pub(super) anterior: DVec3,
    /// Distance from the hinge to the incisal point.
    pub(super) r_inc: f64,
    /// How far any point of the pair moves per unit of incisal opening (at most).
    pub(super) lip: f64,
}

/// Turn about the vertical per lateral shift, as a fraction of the shift seen at the incisal
/// point.
const BENNETT: f64 = 0.3;

impl Kin {
    /// The pose for an incisal opening `o`, a lateral shift `lat` (to the left) and a
    /// protrusion `pro`.
    pub(super) fn pose(&self, o: f64, lat: f64, pro: f64) -> Pose {
        let theta = o / self.r_inc;
        let psi = BENNETT * lat / self.r_inc;
        let r = (DQuat::from_axis_angle(self.left, theta) * DQuat::from_axis_angle(self.up, psi))
            .normalize();
        let m = Pose {
            rotation: r,
            translation: self.hinge - r * self.hinge + self.left * lat + self.anterior * pro,
        };
        m.then(&self.bite)
    }
}
