//! What the penetration query answers: volume, force, torques, the contact patches and the
//! linearised wrench.

use glam::{DMat3, DVec3};

/// A contact patch (world frame): of [`Pair::penetration`](crate::Pair::penetration), a
/// cluster of overlapping leaf pairs; of
/// [`Pair::mesh_penetration_with`](crate::Pair::mesh_penetration_with), a connected piece of
/// the meshes' intersection ([`exact::OverlapPatch`](crate::exact::OverlapPatch)).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Patch {
    /// Spheres: volume-weighted centroid of the pairs' lenses. Meshes: centre of B's
    /// surface inside A in the piece.
    pub point: DVec3,
    /// Unit direction B is pushed (from A into B): volume-weighted over the pairs, or
    /// against the vector area of B's surface in the piece.
    pub normal: DVec3,
    /// Spheres: largest pair overlap `ra + rb − d` in the patch. Meshes: the piece's mean
    /// thickness along `normal`.
    pub depth: f64,
    /// Spheres: sum of the pairs' lens volumes. Meshes: the piece's exact volume.
    pub volume: f64,
    /// Leaf pairs overlapping (spheres) or triangle pairs crossing (meshes).
    pub pairs: u32,
}

/// Result of [`Pair::penetration`](crate::Pair::penetration). The patches themselves stay in
/// the pair until its next query: [`Pair::patches`](crate::Pair::patches).
///
/// Its serde form is the answer every door prints: `contact` (`pairs > 0`), then these
/// fields; the doors add the patches as `patches`.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
#[serde(remote = "Self")]
pub struct Penetration {
    /// Volume of the intersection of the two inner-sphere unions: the sum of the lens
    /// volumes of all overlapping leaf pairs.
    pub volume: f64,
    /// Number of overlapping leaf pairs.
    pub pairs: usize,
    /// Largest leaf-pair overlap `ra + rb − d`.
    pub max_depth: f64,
    /// Contact normal (world): unit `Σ vᵢ·uᵢ`, `uᵢ` the direction from A's sphere centre to
    /// B's of pair `i` and `vᵢ` its lens volume. Zero without penetration.
    pub normal: DVec3,
    /// Force on B (world): `stiffness × volume × normal`. The force on A is its opposite.
    pub force: DVec3,
    /// Torque on A about A's centre of mass (world).
    pub torque_a: DVec3,
    /// Torque on B about B's centre of mass (world).
    pub torque_b: DVec3,
    /// Number of contact patches.
    pub patch_count: usize,
    /// Contact area: the summed areas of the discs where the overlapping leaf spheres'
    /// boundaries meet, which is how fast the volume shrinks per unit of separation
    /// (`−dV/dd` for a motion along every pair's own direction). Zero unless
    /// [`PenetrationOptions::linearize`](super::PenetrationOptions::linearize) is set.
    pub area: f64,
    /// How the force and B's torque change as B moves: what an implicit integrator needs
    /// (see [`ContactStiffness`]). Zero unless [`PenetrationOptions::linearize`](super::PenetrationOptions::linearize) is set.
    pub stiffness: ContactStiffness,
    /// 0 with penetration; otherwise a proved lower bound on the separation.
    pub distance: f64,
    /// Node pairs tested.
    pub visits: u64,
    /// True when the safe-motion bound answered without a traversal.
    pub skipped: bool,
}

impl Patch {
    /// This patch, found in A's frame, in the world frame (A at `pose_a`).
    pub(crate) fn in_world(self, pose_a: &crate::pose::Pose) -> Patch {
        Patch {
            point: pose_a.transform_point(self.point),
            normal: pose_a.transform_vector(self.normal),
            ..self
        }
    }
}

impl Penetration {
    /// This answer, found in A's frame, in the world frame (A at `pose_a`): the vectors
    /// rotated, the stiffness `R K Rᵀ`.
    pub(crate) fn in_world(self, pose_a: &crate::pose::Pose) -> Penetration {
        let rot = |v: DVec3| pose_a.transform_vector(v);
        Penetration {
            normal: rot(self.normal),
            force: rot(self.force),
            torque_a: rot(self.torque_a),
            torque_b: rot(self.torque_b),
            stiffness: self.stiffness.rotated(DMat3::from_quat(pose_a.rotation)),
            ..self
        }
    }
}

impl serde::Serialize for Penetration {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        // The derived fields (`remote = "Self"`) after `contact`.
        #[derive(serde::Serialize)]
        struct Form {
            contact: bool,
            #[serde(flatten, with = "Penetration")]
            answer: Penetration,
        }
        serde::Serialize::serialize(
            &Form {
                contact: self.pairs > 0,
                answer: *self,
            },
            s,
        )
    }
}

/// The linearised penalty wrench: with `δ` a small translation of B and `θ` a small rotation
/// of B about its centre of mass (world frame), B's force and torque change by
/// `−[linear·δ + coupling·θ, couplingᵀ·δ + angular·θ]`. It is the Gauss–Newton part
/// `k Σ aᵢ JᵢJᵢᵀ`, `aᵢ` the area of pair `i`'s lens disc and `Jᵢ = [uᵢ; rᵢ × uᵢ]`: symmetric
/// and positive semi-definite (what an implicit integrator needs to stay stable with stiff
/// contact), leaving out the small terms from the pairs' directions turning.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct ContactStiffness {
    /// Force per translation (force / length).
    pub linear: DMat3,
    /// Force per rotation, and (transposed) torque per translation.
    pub coupling: DMat3,
    /// Torque per rotation (force · length / radian).
    pub angular: DMat3,
}

impl Default for ContactStiffness {
    /// Zero (no contact). By hand: glam's default matrix is the identity.
    fn default() -> ContactStiffness {
        ContactStiffness {
            linear: DMat3::ZERO,
            coupling: DMat3::ZERO,
            angular: DMat3::ZERO,
        }
    }
}

impl ContactStiffness {
    /// The 6×6 matrix `[[linear, coupling], [couplingᵀ, angular]]`, row-major.
    pub fn to_matrix6(&self) -> [[f64; 6]; 6] {
        let mut m = [[0.0; 6]; 6];
        let (l, c, a) = (
            self.linear.to_cols_array_2d(),
            self.coupling.to_cols_array_2d(),
            self.angular.to_cols_array_2d(),
        );
        for i in 0..3 {
            for j in 0..3 {
                // Column-major sources: l[j][i] is row i, column j.
                m[i][j] = l[j][i];
                m[i][j + 3] = c[j][i];
                m[i + 3][j] = c[i][j];
                m[i + 3][j + 3] = a[j][i];
            }
        }
        m
    }

    /// Rotated into another frame: `R K Rᵀ` block by block.
    pub(crate) fn rotated(&self, r: DMat3) -> ContactStiffness {
        let rt = r.transpose();
        ContactStiffness {
            linear: r * self.linear * rt,
            coupling: r * self.coupling * rt,
            angular: r * self.angular * rt,
        }
    }
}
