//! The haptic tool as a rigid body: mass and inertia from its tree's meta, and its state.

use glam::{DMat3, DQuat, DVec3};
use innersphere::error::{num, vec3};
use innersphere::error::{Error, Result};
use innersphere::pose::Pose;
use innersphere::tree::SphereTree;

/// Density of teeth (enamel about 2.9 g/cm³, dentin about 2.1 g/cm³), kg/mm³: the default
/// of [`HapticOptions::density`](crate::HapticOptions::density).
pub const TOOTH_DENSITY: f64 = 2.1e-6;

/// Mass properties of a rigid body (kilograms, millimetres).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RigidBody {
    /// Mass (kg).
    pub mass: f64,
    /// Centre of mass in the body's model frame (mm).
    pub center_of_mass: DVec3,
    /// Inertia tensor about the centre of mass, model axes (kg·mm²).
    pub inertia: DMat3,
}

impl RigidBody {
    /// The body a tree was built from, at `density` (kg per model unit³). Trees written
    /// before the inertia was stored are refused with a message that says to rebuild them.
    pub fn from_tree(tree: &SphereTree, density: f64) -> Result<RigidBody> {
        if !(density.is_finite() && density > 0.0) {
            return Err(Error::InvalidOption(format!(
                "the density must be positive and finite, not {}",
                num(density)
            )));
        }
        let Some(entries) = tree.meta.inertia else {
            return Err(Error::InvalidOption(
                "the tree holds no inertia tensor (it was written by an older innersphere): \
                 rebuild it with `ist build` to use it as a haptic tool"
                    .into(),
            ));
        };
        let volume = tree.meta.mesh_volume;
        let inertia = innersphere::mesh::MassProperties::inertia_from_entries(entries) * density;
        let body = RigidBody {
            mass: volume * density,
            center_of_mass: DVec3::from_array(tree.meta.center_of_mass),
            inertia,
        };
        body.check()?;
        Ok(body)
    }

    /// Refuses a body that no integrator can move: non-positive or non-finite mass, or an
    /// inertia tensor that is not positive definite.
    pub fn check(&self) -> Result<()> {
        let i = &self.inertia;
        let (a, b, c) = (
            i.x_axis.x,
            i.x_axis.x * i.y_axis.y - i.y_axis.x * i.x_axis.y,
            i.determinant(),
        );
        let finite =
            i.to_cols_array().iter().all(|x| x.is_finite()) && self.center_of_mass.is_finite();
        if !(self.mass.is_finite() && self.mass > 0.0 && finite && a > 0.0 && b > 0.0 && c > 0.0) {
            return Err(Error::InvalidOption(format!(
                "the tool's mass ({} kg) must be positive and finite and its inertia tensor \
                 positive definite and finite (its diagonal: {} kg·mm²); check the density \
                 and the mesh",
                num(self.mass),
                vec3(glam::DVec3::new(i.x_axis.x, i.y_axis.y, i.z_axis.z))
            )));
        }
        Ok(())
    }
}

/// Where a rigid body is and how it moves (world frame; velocities of its centre of mass).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyState {
    /// The body's pose (its model frame in the world).
    pub pose: Pose,
    /// Linear velocity of the centre of mass (mm/s).
    pub velocity: DVec3,
    /// Angular velocity (rad/s).
    pub angular_velocity: DVec3,
}

impl BodyState {
    /// At rest at `pose`.
    pub fn at_rest(pose: Pose) -> BodyState {
        BodyState {
            pose,
            velocity: DVec3::ZERO,
            angular_velocity: DVec3::ZERO,
        }
    }
}

/// The rotation vector (axis × angle, the shorter way round) that turns `from` into `to`:
/// `to = exp(v) · from`.
pub fn rotation_between(from: DQuat, to: DQuat) -> DVec3 {
    let mut d = to * from.conjugate();
    if d.w < 0.0 {
        d = -d;
    }
    d.to_scaled_axis()
}

/// `exp(v)`: the rotation by `|v|` about `v`.
pub fn exp(v: DVec3) -> DQuat {
    let a = v.length();
    if a < 1e-300 {
        DQuat::IDENTITY
    } else {
        DQuat::from_axis_angle(v / a, a)
    }
}
