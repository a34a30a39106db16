//! The plain `#[repr(C)]` structs that cross the boundary, and their conversions.

use crate::error::Fail;
use innersphere::glam::{DQuat, DVec3};
use innersphere::Pose;
use std::ffi::c_int;

/// A rigid pose: p' = R(q) p + t, q = {w, x, y, z} (normalised on use; it must not be zero).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ist_pose {
    /// Translation (model units).
    pub t: [f64; 3],
    /// Rotation quaternion {w, x, y, z}.
    pub q: [f64; 4],
}

impl ist_pose {
    pub(crate) fn to_pose(self) -> Result<Pose, Fail> {
        let [w, x, y, z] = self.q;
        Pose::new(DVec3::from_array(self.t), DQuat::from_xyzw(x, y, z, w))
            .map_err(|e| innersphere::Error::from(e).into())
    }

    pub(crate) fn from_pose(p: &Pose) -> ist_pose {
        let q = p.rotation;
        ist_pose {
            t: p.translation.to_array(),
            q: [q.w, q.x, q.y, q.z],
        }
    }
}

/// Options of ist_tree_build, with the meaning of `ist build`'s flags.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ist_build_options {
    /// Voxel edge length (model units); when > 0 it wins over `resolution`.
    pub voxel_size: f64,
    /// Voxels along the longest side of the mesh's bounding box (used when voxel_size is 0).
    pub resolution: u32,
    /// No inner sphere smaller than this (model units; 0 = down to 1e-4 voxel).
    pub min_radius: f64,
    /// Off-grid refinement steps of each sphere's centre (0 = the paper's packing).
    pub refine_steps: u32,
    /// Stop after this many spheres (0 = no limit).
    pub max_spheres: u64,
    /// The unit of the mesh file's coordinates, converted to mm as it is read:
    /// IST_UNIT_MM (0, the default), IST_UNIT_CM, IST_UNIT_M or IST_UNIT_IN. The tree and
    /// every answer are then in mm.
    pub unit: c_int,
}

/// Mesh files in millimetres.
pub const IST_UNIT_MM: c_int = 0;
/// Mesh files in centimetres.
pub const IST_UNIT_CM: c_int = 1;
/// Mesh files in metres.
pub const IST_UNIT_M: c_int = 2;
/// Mesh files in inches.
pub const IST_UNIT_IN: c_int = 3;

/// Result of ist_distance (world frame).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ist_distance_result {
    /// Distance between the two sphere packings (0 when they overlap), computed from their
    /// single-precision spheres.
    pub distance: f64,
    /// 1 when they overlap, else 0.
    pub contact: c_int,
    /// Closest point on A; when they overlap, a point of an overlapping leaf sphere of A
    /// (which one depends on the pair's history).
    pub point_a: [f64; 3],
    /// Closest point on B; when they overlap, a point of an overlapping leaf sphere of B.
    pub point_b: [f64; 3],
}

/// Options of ist_refined_distance (ist_refine_options_default: the library's defaults).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ist_refine_options {
    /// Radius of the balls searched around the spheres' closest points, as a multiple of the
    /// larger closest leaf's radius (plus `margin`); ≥ 0.
    pub radius_scale: f64,
    /// Added to the radius, in model units; negative: the larger voxel size of the two
    /// trees.
    pub margin: f64,
    /// Skip what cannot beat the best so far by more than this fraction of it; in [0, 1).
    pub rel_tolerance: f64,
    /// Most triangle-BVH node pairs searched (≥ 1); past it `complete` is 0.
    pub max_node_pairs: u64,
}

/// Result of ist_refined_distance (world frame).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ist_refined_distance_result {
    /// Distance between the meshes as refined from the sphere distance: never below the
    /// exact mesh distance, never above `sphere_distance`; 0 when they touch.
    pub distance: f64,
    /// 1 when the bodies touch (two triangles cross, or the sphere packings overlap).
    pub contact: c_int,
    /// 1 when a triangle pair nearer than the spheres was found (the points lie on it).
    pub refined: c_int,
    /// 1 when the local search ended within its budget.
    pub complete: c_int,
    /// Closest point on A.
    pub point_a: [f64; 3],
    /// Closest point on B.
    pub point_b: [f64; 3],
    /// A's triangle of `point_a` (index in A's mesh), UINT32_MAX unless refined.
    pub tri_a: u32,
    /// B's triangle of `point_b`, UINT32_MAX unless refined.
    pub tri_b: u32,
    /// The sphere distance that was refined (as ist_distance's `distance`).
    pub sphere_distance: f64,
}

/// Result of ist_penetration (world frame).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ist_penetration_result {
    /// Volume of the intersection of the two sphere packings (model units³).
    pub volume: f64,
    /// Largest overlap of two leaf spheres (model units).
    pub max_depth: f64,
    /// Unit contact normal: the direction B is pushed (zero without contact).
    pub normal: [f64; 3],
    /// Penalty force on B: stiffness × volume × normal (the force on A is its opposite).
    pub force: [f64; 3],
    /// Torque on A about A's centre of mass (that of the mesh the tree was built from,
    /// stored in the tree file).
    pub torque_a: [f64; 3],
    /// Torque on B about B's centre of mass.
    pub torque_b: [f64; 3],
    /// Number of contact patches, at most 8 (overlaps are grouped with the nearest patch,
    /// within 1/8 of the smaller root sphere's radius; beyond 8 patches, with the nearest
    /// one); read them with ist_penetration_patch.
    pub patch_count: usize,
}

/// Result of ist_mesh_penetration (world frame): the penetration of the meshes themselves.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ist_mesh_penetration_result {
    /// 1 when the solids overlap, else 0.
    pub contact: c_int,
    /// Volume of the intersection of the two solids (model units³), exact.
    pub volume: f64,
    /// Unit direction B is pushed: the one that loses overlap fastest (zero without contact).
    pub normal: [f64; 3],
    /// Penalty force on B: stiffness × volume × normal (the force on A is its opposite).
    pub force: [f64; 3],
    /// Torque on A about A's centre of mass.
    pub torque_a: [f64; 3],
    /// Torque on B about B's centre of mass.
    pub torque_b: [f64; 3],
    /// Area of B's surface inside A.
    pub area: f64,
    /// The largest thickness of a patch along the direction it pushes B.
    pub max_depth: f64,
    /// Connected pieces of the intersection; read them with ist_penetration_patch (the 8
    /// largest).
    pub patch_count: usize,
}

impl From<&innersphere::MeshPenetration> for ist_mesh_penetration_result {
    fn from(m: &innersphere::MeshPenetration) -> Self {
        ist_mesh_penetration_result {
            contact: m.contact as c_int,
            volume: m.volume,
            normal: m.normal.to_array(),
            force: m.force.to_array(),
            torque_a: m.torque_a.to_array(),
            torque_b: m.torque_b.to_array(),
            area: m.area,
            max_depth: m.max_depth,
            patch_count: m.patch_count,
        }
    }
}

/// Result of ist_penetration_within (world frame): what a time-critical penetration query
/// found within its node-pair budget.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ist_budgeted_result {
    /// Volume of the overlapping leaf pairs found (model units³; at most the exact volume).
    pub volume: f64,
    /// Proved upper bound on the exact volume (= volume when complete).
    pub upper_bound: f64,
    /// 1 when every overlapping pair was refined: volume is exact.
    pub complete: c_int,
    /// Largest leaf overlap found (model units).
    pub max_depth: f64,
    /// Unit normal of the pairs found and, when the budget ran out, of the unrefined node
    /// pairs counted as their bounds.
    pub normal: [f64; 3],
    /// Penalty force on B of the same (stiffness × volume found and bounds).
    pub force: [f64; 3],
    /// Torque on B about its centre of mass, of the same.
    pub torque_b: [f64; 3],
    /// Node pairs tested.
    pub visits: u64,
}

/// One contact patch of the last ist_penetration (world frame).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ist_patch {
    /// Volume-weighted centroid of the overlaps.
    pub point: [f64; 3],
    /// Unit direction from A into B.
    pub normal: [f64; 3],
    /// Largest overlap in the patch.
    pub depth: f64,
    /// Volume of the patch.
    pub volume: f64,
    /// Overlapping leaf pairs in the patch.
    pub pairs: u32,
}

/// One contact of ist_multipoint (world frame).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ist_contact_point {
    /// Point in the middle of the overlap.
    pub point: [f64; 3],
    /// Unit direction from A's sphere centre to B's.
    pub normal: [f64; 3],
    /// Overlap of the two spheres (> 0).
    pub depth: f64,
    /// Leaf (node index) of tree A.
    pub leaf_a: u32,
    /// Leaf (node index) of tree B.
    pub leaf_b: u32,
}

impl From<&innersphere::Penetration> for ist_penetration_result {
    fn from(p: &innersphere::Penetration) -> Self {
        ist_penetration_result {
            volume: p.volume,
            max_depth: p.max_depth,
            normal: p.normal.to_array(),
            force: p.force.to_array(),
            torque_a: p.torque_a.to_array(),
            torque_b: p.torque_b.to_array(),
            patch_count: p.patch_count,
        }
    }
}

impl ist_refine_options {
    /// The options `opts` points to, or the library's defaults for NULL.
    ///
    /// # Safety
    /// `opts` is NULL or points to options.
    pub(crate) unsafe fn read(opts: *const ist_refine_options) -> innersphere::RefineOptions {
        match unsafe { opts.as_ref() } {
            None => innersphere::RefineOptions::default(),
            Some(o) => innersphere::RefineOptions {
                radius_scale: o.radius_scale,
                margin: o.margin,
                rel_tolerance: o.rel_tolerance,
                max_node_pairs: o.max_node_pairs,
            },
        }
    }
}

impl From<&innersphere::RefinedDistance> for ist_refined_distance_result {
    fn from(r: &innersphere::RefinedDistance) -> Self {
        ist_refined_distance_result {
            distance: r.distance,
            contact: r.intersecting as c_int,
            refined: r.refined as c_int,
            complete: r.complete as c_int,
            point_a: r.point_a.to_array(),
            point_b: r.point_b.to_array(),
            tri_a: r.tri_a,
            tri_b: r.tri_b,
            sphere_distance: r.spheres.distance,
        }
    }
}
