//! The penetration of the meshes themselves (ours, beyond the paper): the exact volume of the
//! intersection of the two solids the trees were built from, and the penalty wrench that
//! follows from its exact gradient ([`exact::intersection_volume`](crate::exact::intersection_volume)).

use super::penetration::{ContactStiffness, Patch};
use crate::exact::{intersection_volume, ExactMesh, ExactScratch, MeshOverlap};
use crate::pose::Pose;
use glam::DVec3;

/// Result of [`Pair::mesh_penetration_with`](crate::Pair::mesh_penetration_with) (world frame).
///
/// The same force law as [`Penetration`](crate::Penetration), on the meshes' exact volume
/// `V`: the force on B is `stiffness × V` along `normal`, the direction in which moving B
/// loses overlap fastest (`−∇V / |∇V|`, `∇V` the gradient with respect to B's
/// translation); the torque on B is the same scale times `−∇_θV / |∇V|` (`∇_θV` the gradient
/// with respect to a rotation of B about its centre of mass), i.e. the moment of that force
/// about the point where the overlap's surface is centred. The patches (the intersection's
/// connected pieces) stay in the pair until its next query:
/// [`Pair::patches`](crate::Pair::patches). Its serde form is the answer every door prints;
/// the doors add the patches as `patches`.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct MeshPenetration {
    /// True when the solids overlap (`volume > 0`).
    pub contact: bool,
    /// Volume of the intersection of the two solids (model units³).
    pub volume: f64,
    /// Unit direction B is pushed (from A into B); zero without contact.
    pub normal: DVec3,
    /// Force on B: `stiffness × volume × normal`. The force on A is its opposite.
    pub force: DVec3,
    /// Torque on A about A's centre of mass.
    pub torque_a: DVec3,
    /// Torque on B about B's centre of mass.
    pub torque_b: DVec3,
    /// `∇V`: the gradient of the volume with respect to B's translation (the vector area of
    /// B's surface inside A).
    pub gradient: DVec3,
    /// `∇_θV`: the gradient with respect to a rotation of B about its centre of mass.
    pub rotation_gradient: DVec3,
    /// Area of B's surface inside A.
    pub area: f64,
    /// The largest mean thickness of a patch along the direction it pushes B (its volume
    /// over its area projected across that direction): a flat contact's depth exactly, about
    /// half the peak of a lens-shaped one. (The largest distance of a vertex inside the other
    /// body to its surface, [`exact::penetration`](crate::exact::penetration), costs
    /// milliseconds in deep contact.)
    pub max_depth: f64,
    /// Connected pieces of the intersection (the pair keeps the largest
    /// [`PenetrationOptions::max_patches`](crate::PenetrationOptions::max_patches)).
    pub patch_count: usize,
    /// How the force and B's torque change as B moves: `stiffness × Σ a·JJᵀ` over the
    /// parts of B's surface inside A (`a` a part's area, `J = [n; r × n]`, `n` its normal,
    /// `r` its centroid from B's centre of mass), the Gauss–Newton form of the spheres'
    /// [`Penetration::stiffness`](crate::Penetration::stiffness): exact for a flat contact,
    /// symmetric and positive semi-definite.
    pub stiffness: ContactStiffness,
    /// Triangle pairs that cross.
    pub crossing_pairs: usize,
}

/// The meshes' penetration at world poses; `com_a`, `com_b` the bodies' centres of mass in
/// their own frames.
#[allow(clippy::too_many_arguments)]
pub(crate) fn mesh_penetration(
    a: &ExactMesh,
    pose_a: &Pose,
    b: &ExactMesh,
    pose_b: &Pose,
    com_a: DVec3,
    com_b: DVec3,
    stiffness: f64,
    max_patches: usize,
    scratch: &mut ExactScratch,
    patches: &mut Vec<Patch>,
) -> MeshPenetration {
    let v: MeshOverlap = intersection_volume(a, pose_a, b, pose_b, com_b, scratch);
    patches.clear();
    patches.extend(scratch.patches().iter().take(max_patches).map(|p| Patch {
        point: pose_a.transform_point(p.point),
        normal: pose_a.transform_vector(p.normal),
        depth: p.depth,
        volume: p.volume,
        pairs: p.pairs,
    }));
    let g = v.gradient.length();
    if !(v.volume > 0.0 && g > 0.0) {
        return MeshPenetration {
            crossing_pairs: v.crossing_pairs,
            gradient: v.gradient,
            rotation_gradient: v.rotation_gradient,
            area: v.area_b,
            // Wholly inside (no surface crossing): overlap without a direction to push.
            contact: v.volume > 0.0,
            volume: v.volume,
            max_depth: v.max_depth,
            patch_count: v.patch_count,
            ..Default::default()
        };
    }
    let scale = stiffness * v.volume / g;
    let force = -v.gradient * scale;
    let torque_b = -v.rotation_gradient * scale;
    // Newton's third law about both centres: the torques sum with the forces' moments to 0.
    let (ca, cb) = (pose_a.transform_point(com_a), pose_b.transform_point(com_b));
    let torque_a = -torque_b - (cb - ca).cross(force);
    MeshPenetration {
        contact: true,
        volume: v.volume,
        normal: -v.gradient / g,
        force,
        torque_a,
        torque_b,
        gradient: v.gradient,
        rotation_gradient: v.rotation_gradient,
        area: v.area_b,
        max_depth: v.max_depth,
        patch_count: v.patch_count,
        stiffness: ContactStiffness {
            linear: v.moments.linear * stiffness,
            coupling: v.moments.coupling * stiffness,
            angular: v.moments.angular * stiffness,
        },
        crossing_pairs: v.crossing_pairs,
    }
}
