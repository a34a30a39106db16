//! The local contact model (Adachi's intermediate representation; Otaduy & Lin's linearised
//! contact): the penalty wrench a penetration query found at one tool pose, with its
//! linearisation, so that the servo tick can evaluate the contact at the tool's *current*
//! pose without a query. What the collision thread publishes and the servo reads.

use crate::body::rotation_between;
use crate::mat6::{self, Mat6};
use crate::step::Wrench;
use glam::DVec3;
use innersphere::pose::Pose;
use innersphere::query::{MeshPenetration, Penetration};
use std::time::Instant;

/// Where the contact comes from: the inner-sphere packings' penetration volume (the paper's,
/// tens of microseconds a query) or the meshes' own exact intersection volume (the scanned
/// surfaces, milliseconds in deep contact: the collision thread's).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ContactSource {
    /// [`Pair::penetration`](innersphere::Pair::penetration).
    #[default]
    Spheres,
    /// [`Pair::mesh_penetration_with`](innersphere::Pair::mesh_penetration_with); needs both
    /// trees' meshes.
    Mesh,
}

impl std::str::FromStr for ContactSource {
    type Err = innersphere::Error;
    fn from_str(s: &str) -> innersphere::Result<Self> {
        match s {
            "spheres" => Ok(ContactSource::Spheres),
            "mesh" => Ok(ContactSource::Mesh),
            _ => Err(innersphere::Error::InvalidOption(format!(
                "the contact is `spheres` or `mesh`, not `{s}`"
            ))),
        }
    }
}

/// Fraction of the model's own push below which the linearised wrench fades out: a
/// linearised penalty would pull once the tool has backed out past the contact, and a
/// contact only pushes.
const FADE: f64 = 0.25;

/// The contact at one tool pose, linearised about it. Plain values (`Copy`): it crosses
/// threads through a lock-free buffer without allocating.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactModel {
    /// The tool's pose the query answered at.
    pub pose: Pose,
    /// Penalty force on the tool there (N, world).
    pub force: DVec3,
    /// Penalty torque on the tool there, about its centre of mass (N·mm, world).
    pub torque: DVec3,
    /// `−∂(force, torque)/∂(translation, rotation)` (6×6, row-major, world frame, about the
    /// centre of mass): the linearised contact ([`innersphere::ContactStiffness::to_matrix6`]).
    pub stiffness: [[f64; 6]; 6],
    /// Penetration volume there (mm³).
    pub volume: f64,
    /// Deepest leaf-pair overlap there (mm).
    pub max_depth: f64,
    /// Volume-weighted contact normal (unit, world; zero without contact).
    pub normal: DVec3,
    /// Contact patches of the query (0 when it was the time-critical one).
    pub patches: usize,
    /// Largest penalty force the contact can have (N): `contact stiffness × the time-critical
    /// query's upper bound on the volume` when only that query answered since the model was
    /// made; infinite otherwise. The model's force is capped to it.
    pub force_cap: f64,
    /// When the tool pose it answered for was taken: the model's age is counted from here.
    pub sampled: Instant,
    /// Seconds the query took.
    pub query_seconds: f64,
    /// Number of the query that made it (counts from 1; 0: no query yet).
    pub seq: u64,
}

impl ContactModel {
    /// No contact, as known at `pose` (the model before any query).
    pub fn none(pose: Pose) -> ContactModel {
        ContactModel {
            pose,
            force: DVec3::ZERO,
            torque: DVec3::ZERO,
            stiffness: [[0.0; 6]; 6],
            volume: 0.0,
            max_depth: 0.0,
            normal: DVec3::ZERO,
            patches: 0,
            force_cap: f64::INFINITY,
            sampled: Instant::now(),
            query_seconds: 0.0,
            seq: 0,
        }
    }

    /// The model of an exact (linearised) penetration query of the tool at `pose`.
    pub fn from_penetration(pose: Pose, p: &Penetration, sampled: Instant) -> ContactModel {
        ContactModel {
            pose,
            force: p.force,
            torque: p.torque_b,
            stiffness: p.stiffness.to_matrix6(),
            volume: p.volume,
            max_depth: p.max_depth,
            normal: p.normal,
            patches: p.patch_count,
            force_cap: f64::INFINITY,
            sampled,
            query_seconds: 0.0,
            seq: 0,
        }
    }

    /// The model of the meshes' own penetration ([`MeshPenetration`]) of the tool at `pose`.
    pub fn from_mesh_penetration(
        pose: Pose,
        m: &MeshPenetration,
        sampled: Instant,
    ) -> ContactModel {
        ContactModel {
            pose,
            force: m.force,
            torque: m.torque_b,
            stiffness: m.stiffness.to_matrix6(),
            volume: m.volume,
            max_depth: m.max_depth,
            normal: m.normal,
            patches: m.patch_count,
            force_cap: f64::INFINITY,
            sampled,
            query_seconds: 0.0,
            seq: 0,
        }
    }

    /// Seconds since the pose it answered for was taken.
    pub fn age(&self, now: Instant) -> f64 {
        now.saturating_duration_since(self.sampled).as_secs_f64()
    }

    /// True when it holds a contact.
    pub fn touching(&self) -> bool {
        self.force.length_squared() > 0.0
    }

    /// The contact wrench on the tool at `pose` (`com`: the tool's centre of mass in its
    /// model frame) and the stiffness to integrate it with: `w₀ − K·Δ`, `Δ` the motion of
    /// the centre of mass and the rotation since the model's pose. Unilateral: as the
    /// linearised push along the model's force direction drops below a quarter of the
    /// model's own, the wrench and stiffness fade linearly to zero (a contact never pulls);
    /// capped at [`force_cap`](Self::force_cap).
    pub fn wrench_at(&self, pose: &Pose, com: DVec3) -> (Wrench, Mat6) {
        let f0 = self.force.length();
        if f0 <= 0.0 || !f0.is_finite() {
            return (Wrench::default(), [[0.0; 6]; 6]);
        }
        let dx = pose.transform_point(com) - self.pose.transform_point(com);
        let dth = rotation_between(self.pose.rotation, pose.rotation);
        let kd = mat6::mul(&self.stiffness, [dx.x, dx.y, dx.z, dth.x, dth.y, dth.z]);
        let mut force = self.force - DVec3::new(kd[0], kd[1], kd[2]);
        let mut torque = self.torque - DVec3::new(kd[3], kd[4], kd[5]);
        let push = force.dot(self.force / f0);
        let mut fade = (push / (FADE * f0)).clamp(0.0, 1.0);
        if !fade.is_finite() {
            fade = 0.0;
        }
        let l = force.length() * fade;
        if l > self.force_cap {
            fade *= self.force_cap / l;
        }
        force *= fade;
        torque *= fade;
        let mut k = self.stiffness;
        if fade < 1.0 {
            for row in &mut k {
                for v in row {
                    *v *= fade;
                }
            }
        }
        (Wrench { force, torque }, k)
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use std::time::Duration;

    /// A contact pushing up with `f` N at the identity pose, stiffness 100 N/mm along z.
    pub(crate) fn pushing(f: f64) -> ContactModel {
        let mut k = [[0.0; 6]; 6];
        k[2][2] = 100.0;
        ContactModel {
            force: DVec3::new(0.0, 0.0, f),
            volume: f / 10.0,
            stiffness: k,
            ..ContactModel::none(Pose::IDENTITY)
        }
    }

    #[test]
    fn a_models_age_counts_from_its_sample_and_never_goes_negative() {
        let m = pushing(1.0);
        assert_eq!(m.age(m.sampled + Duration::from_millis(3)), 0.003);
        assert_eq!(m.age(m.sampled), 0.0);
        let earlier = ContactModel {
            sampled: m.sampled + Duration::from_millis(5),
            ..m
        };
        assert_eq!(earlier.age(m.sampled), 0.0);
    }

    #[test]
    fn only_a_model_with_a_force_is_touching() {
        assert!(!ContactModel::none(Pose::IDENTITY).touching());
        assert!(pushing(0.5).touching());
        assert!(ContactModel {
            force: DVec3::new(0.0, -1e-3, 0.0),
            ..ContactModel::none(Pose::IDENTITY)
        }
        .touching());
    }

    #[test]
    fn a_model_of_non_finite_force_pushes_nothing() {
        let m = ContactModel {
            force: DVec3::new(f64::INFINITY, 0.0, 1.0),
            ..pushing(1.0)
        };
        let (w, k) = m.wrench_at(&Pose::IDENTITY, DVec3::ZERO);
        assert_eq!((w.force, w.torque), (DVec3::ZERO, DVec3::ZERO));
        assert_eq!(k, [[0.0; 6]; 6]);
    }

    #[test]
    fn the_fade_and_the_cap_scale_with_the_models_own_force() {
        // 2 N, the tool 0.017 mm up: 0.3 N of linearised push, under a quarter of 2 N, so
        // faded by 0.3 / 0.5 to 0.18 N, the stiffness with it.
        let m = pushing(2.0);
        let up = Pose::from_translation(DVec3::new(0.0, 0.0, 0.017));
        let (w, k) = m.wrench_at(&up, DVec3::ZERO);
        assert!((w.force.z - 0.3 * 0.6).abs() < 1e-12, "{}", w.force.z);
        assert!((k[2][2] - 100.0 * 0.6).abs() < 1e-9, "{}", k[2][2]);
        // A cap under the faded force: the force is the cap exactly.
        let capped = ContactModel {
            force_cap: 0.1,
            ..m
        };
        let (w, _) = capped.wrench_at(&up, DVec3::ZERO);
        assert!((w.force.z - 0.1).abs() < 1e-12, "{}", w.force.z);
    }
}
