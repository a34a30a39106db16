//! Brute-force references over all leaf pairs (O(leaves_a × leaves_b)), with the same f32
//! transform and leaf predicates as the queries, for tests and checks on small trees.

use super::kernel::geometry::{overlaps, sphere_distance, Rel32};
use super::penetration::Sums;
use crate::pose::Pose;
use crate::tree::SphereTree;
use glam::DVec3;

/// Leaf indices of A, leaves of B with their centres in A's frame, and the relative pose.
type Leaves = (Vec<u32>, Vec<(u32, [f32; 3])>, Pose);

/// Leaves of A and of B (centres in A's frame).
fn leaves(a: &SphereTree, pose_a: &Pose, b: &SphereTree, pose_b: &Pose) -> Leaves {
    let rel = Pose::relative(pose_a, pose_b);
    let r32 = Rel32::new(&rel);
    let la: Vec<u32> = a.leaves().map(|n| n as u32).collect();
    let lb = b
        .leaves()
        .map(|n| (n as u32, r32.apply(b.x[n], b.y[n], b.z[n])))
        .collect();
    (la, lb, rel)
}

/// Minimum over all leaf pairs of `|cb − ca| − ra − rb` (negative: the deepest overlap) and
/// the pair that attains it.
pub(crate) fn min_distance(
    a: &SphereTree,
    pose_a: &Pose,
    b: &SphereTree,
    pose_b: &Pose,
) -> (f64, u32, u32) {
    let (la, lb, _) = leaves(a, pose_a, b, pose_b);
    let mut best = (f32::INFINITY, 0, 0);
    for &i in &la {
        let n = i as usize;
        for &(j, c) in &lb {
            let d = sphere_distance(a.x[n], a.y[n], a.z[n], a.r[n], c, b.r[j as usize]);
            if d < best.0 {
                best = (d, i, j);
            }
        }
    }
    (best.0 as f64, best.1, best.2)
}

/// All overlapping leaf pairs, ordered by (leaf of A, leaf of B).
pub(crate) fn overlapping_pairs(
    a: &SphereTree,
    pose_a: &Pose,
    b: &SphereTree,
    pose_b: &Pose,
) -> Vec<(u32, u32)> {
    let (la, lb, _) = leaves(a, pose_a, b, pose_b);
    let mut out = Vec::new();
    for &i in &la {
        let n = i as usize;
        for &(j, c) in &lb {
            if overlaps(a.x[n], a.y[n], a.z[n], a.r[n], c, b.r[j as usize]) {
                out.push((i, j));
            }
        }
    }
    out
}

/// True when two leaves overlap at these poses (the leaf predicate of every query).
pub(crate) fn leaves_overlap(
    a: &SphereTree,
    la: u32,
    pose_a: &Pose,
    b: &SphereTree,
    lb: u32,
    pose_b: &Pose,
) -> bool {
    let r32 = Rel32::new(&Pose::relative(pose_a, pose_b));
    let (i, j) = (la as usize, lb as usize);
    let c = r32.apply(b.x[j], b.y[j], b.z[j]);
    overlaps(a.x[i], a.y[i], a.z[i], a.r[i], c, b.r[j])
}

/// Penetration volume, normal, force and torques (world) summed over all leaf pairs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct BrutePenetration {
    /// Sum of lens volumes.
    pub volume: f64,
    /// Overlapping leaf pairs.
    pub pairs: usize,
    /// Largest pair overlap.
    pub max_depth: f64,
    /// Unit volume-weighted direction A → B.
    pub normal: DVec3,
    /// Force on B.
    pub force: DVec3,
    /// Torque on A about its centre of mass.
    pub torque_a: DVec3,
    /// Torque on B about its centre of mass.
    pub torque_b: DVec3,
}

/// [`Pair::penetration`](crate::Pair::penetration) by brute force.
pub(crate) fn penetration(
    a: &SphereTree,
    pose_a: &Pose,
    b: &SphereTree,
    pose_b: &Pose,
    stiffness: f64,
) -> BrutePenetration {
    let (la, lb, rel) = leaves(a, pose_a, b, pose_b);
    let mut sums = Sums::<false>::default();
    for &i in &la {
        let n = i as usize;
        for &(j, c) in &lb {
            if overlaps(a.x[n], a.y[n], a.z[n], a.r[n], c, b.r[j as usize]) {
                sums.add([a.x[n], a.y[n], a.z[n]], a.r[n], c, b.r[j as usize]);
            }
        }
    }
    let com_a = DVec3::from_array(a.meta.center_of_mass);
    let com_b = rel.transform_point(DVec3::from_array(b.meta.center_of_mass));
    let (n, f, ta, tb) = sums.wrench(stiffness, com_a, com_b);
    let rot = |v: DVec3| pose_a.transform_vector(v);
    BrutePenetration {
        volume: sums.volume,
        pairs: sums.pairs,
        max_depth: sums.max_depth,
        normal: rot(n),
        force: rot(f),
        torque_a: rot(ta),
        torque_b: rot(tb),
    }
}
