//! Independent verification of a tree against its mesh (what `ist check` runs): leaves inside
//! the mesh, leaves disjoint, every node enclosing the leaves below it. It does not trust the
//! tree's hierarchy for any of it: protrusion uses the mesh's triangle BVH and winding number,
//! overlap is a self-join over the hierarchy, sound once enclosure is verified.

use super::SphereTree;
use crate::mesh::bvh::TriangleBvh;
use crate::mesh::winding::FastWinding;
use crate::mesh::Mesh;
use rayon::prelude::*;

/// Result of [`check`]; `ok` is the verdict.
#[derive(Debug, Clone, serde::Serialize)]
pub struct CheckReport {
    /// True when every invariant holds within `tolerance`.
    pub ok: bool,
    /// Leaf spheres (inner spheres).
    pub spheres: usize,
    /// Nodes in the tree.
    pub nodes: usize,
    /// Largest distance by which a leaf sphere pokes out of the mesh (0 when all are inside).
    pub max_protrusion: f64,
    /// Leaf spheres whose centre lies outside the mesh.
    pub centers_outside: usize,
    /// Largest overlap r_a + r_b − |c_a − c_b| of two leaf spheres (0 when all are disjoint).
    pub max_overlap: f64,
    /// Inner nodes whose sphere does not contain every leaf sphere below it (beyond
    /// `tolerance`). (Nodes need not contain their children's spheres: the hierarchy uses the
    /// smaller sphere around the leaves.)
    pub enclosure_violations: usize,
    /// Tolerance used for all three (model units): 1e-6 of the mesh's bounding-box diagonal.
    pub tolerance: f64,
}

/// Why `mesh` is not the mesh `tree` was built from, from the facts the tree keeps about its
/// source ([`TreeMeta`](super::TreeMeta)): the bounding box, each coordinate within 1e-5 of
/// the larger of the box's diagonal and its farthest coordinate from the origin (rounding the
/// coordinates to f32 or to 6 significant digits moves them by less), and the enclosed volume,
/// within 1e-4 of itself. `None` when both agree. A tree of the same shape moved, scaled or
/// edited, or of another shape with another box or volume, is caught; a tree is never
/// compared with a mesh by its spheres here (that is [`check`]'s job).
pub fn source_mismatch(tree: &SphereTree, mesh: &Mesh) -> Option<String> {
    let m = &tree.meta;
    let (lo, hi) = mesh.bbox();
    let (tlo, thi) = (
        glam::DVec3::from_array(m.bbox_min),
        glam::DVec3::from_array(m.bbox_max),
    );
    let reach = lo
        .abs()
        .max(hi.abs())
        .max(tlo.abs())
        .max(thi.abs())
        .max_element();
    let tol = 1e-5 * (hi - lo).length().max((thi - tlo).length()).max(reach);
    let mut why = Vec::new();
    let off = (lo - tlo).abs().max((hi - thi).abs()).max_element();
    // NaN (a mesh or a tree with non-finite facts) counts as a mismatch.
    if off.is_nan() || off > tol {
        why.push(format!(
            "its bounding box is {:?} to {:?}, the tree's source's was {:?} to {:?} (off by {off:.3e}, tolerance {tol:.1e})",
            lo.to_array(),
            hi.to_array(),
            m.bbox_min,
            m.bbox_max
        ));
    }
    let volume = mesh.signed_volume().abs();
    let vtol = 1e-4 * volume.max(m.mesh_volume.abs()) + 1e-12 * tol.powi(3);
    let dv = (volume - m.mesh_volume).abs();
    if dv.is_nan() || dv > vtol {
        why.push(format!(
            "its volume is {volume:.6e}, the tree's source's was {:.6e} (relative difference {:.1e}, tolerance 1e-4)",
            m.mesh_volume,
            dv / volume.max(m.mesh_volume.abs()).max(f64::MIN_POSITIVE)
        ));
    }
    (!why.is_empty()).then(|| why.join("; "))
}

/// [`check`] of `tree` against the mesh it was built from: an error when `mesh` is not that
/// mesh ([`source_mismatch`]), since the spheres of a tree checked against another mesh say
/// nothing about either (a smaller tree fits inside a larger mesh and would pass).
pub fn check_built_from(tree: &SphereTree, mesh: &Mesh) -> crate::error::Result<CheckReport> {
    mesh.validate()?;
    if let Some(why) = source_mismatch(tree, mesh) {
        return Err(crate::error::Error::InvalidMesh(format!(
            "not the mesh the tree was built from: {why}"
        )));
    }
    check(tree, mesh)
}

/// Verifies `tree` against `mesh` (any mesh: [`check_built_from`] first makes sure it is
/// the tree's own).
pub fn check(tree: &SphereTree, mesh: &Mesh) -> crate::error::Result<CheckReport> {
    mesh.validate()?;
    tree.validate_structure()?;
    let (lo, hi) = mesh.bbox();
    let tolerance = 1e-6 * (hi - lo).length();
    let bvh = TriangleBvh::new(mesh);
    let winding = FastWinding::new(mesh);
    let leaves: Vec<usize> = tree.leaves().collect();
    let sphere = |n: usize| {
        let (c, r) = tree.sphere(n);
        (c.as_dvec3(), r as f64)
    };

    // Protrusion: r − signed distance of the centre (positive inside).
    let (max_protrusion, centers_outside) = leaves
        .par_iter()
        .map(|&n| {
            let (c, r) = sphere(n);
            let d = bvh
                .closest_point(c, f64::INFINITY)
                .map(|h| h.dist_sq.sqrt())
                .unwrap_or(0.0);
            let inside = winding.winding_number(c).abs() >= 0.5;
            let signed = if inside { d } else { -d };
            ((r - signed).max(0.0), usize::from(!inside))
        })
        .reduce(|| (0.0, 0), |a, b| (a.0.max(b.0), a.1 + b.1));

    // Nodes may miss their leaves by up to `tolerance` (as verified below), so two leaves
    // may overlap by up to 2·tolerance more than their ancestors do.
    let max_overlap = leaf_overlap_search(tree, 2.0 * tolerance);

    // Every leaf against every ancestor (depth · leaves tests).
    let mut violators: Vec<usize> = leaves
        .par_iter()
        .flat_map_iter(|&leaf| {
            let (cl, rl) = sphere(leaf);
            let mut out = Vec::new();
            let mut n = tree.parent[leaf];
            while n != super::NO_PARENT && (n as usize) < tree.len() {
                let (cp, rp) = sphere(n as usize);
                if (cl - cp).length() + rl - rp > tolerance {
                    out.push(n as usize);
                }
                n = tree.parent[n as usize];
            }
            out
        })
        .collect();
    violators.sort_unstable();
    violators.dedup();
    let enclosure_violations = violators.len();

    Ok(CheckReport {
        ok: max_protrusion <= tolerance
            && centers_outside == 0
            && max_overlap <= tolerance
            && enclosure_violations == 0,
        spheres: leaves.len(),
        nodes: tree.len(),
        max_protrusion,
        centers_outside,
        max_overlap,
        enclosure_violations,
        tolerance,
    })
}

/// Largest overlap r_a + r_b − |c_a − c_b| between two distinct leaves, by a self-join over
/// the tree's own hierarchy. This is sound only when every node encloses the leaves below it,
/// which [`check`] verifies independently (and reports as not ok otherwise): then every
/// overlapping leaf pair lies under a chain of overlapping node pairs and is found. ([`check`]
/// itself searches with twice its tolerance as slack, since it accepts nodes that miss their
/// leaves by up to the tolerance.)
pub fn max_leaf_overlap(tree: &SphereTree) -> f64 {
    leaf_overlap_search(tree, 0.0)
}

/// [`max_leaf_overlap`] for a tree whose nodes may miss the leaves below them by up to
/// `slack / 2`: only node pairs that are more than `slack` apart are skipped.
fn leaf_overlap_search(tree: &SphereTree, slack: f64) -> f64 {
    let sphere = |n: usize| {
        let (c, r) = tree.sphere(n);
        (c.as_dvec3(), r as f64)
    };
    let overlap = |a: usize, b: usize| {
        let (ca, ra) = sphere(a);
        let (cb, rb) = sphere(b);
        ra + rb - (ca - cb).length()
    };
    // Seed with the root's children pairs so that the work splits across threads.
    let mut seeds = Vec::new();
    if tree.is_leaf(0) {
        return 0.0;
    }
    let top: Vec<usize> = tree.children(0).collect();
    for (i, &a) in top.iter().enumerate() {
        for &b in &top[i..] {
            seeds.push((a, b));
        }
    }
    seeds
        .into_par_iter()
        .map(|seed| {
            let mut worst = 0.0f64;
            let mut stack = vec![seed];
            while let Some((a, b)) = stack.pop() {
                if a == b {
                    let ch: Vec<usize> = tree.children(a).collect();
                    for (i, &x) in ch.iter().enumerate() {
                        for &y in &ch[i..] {
                            stack.push((x, y));
                        }
                    }
                    continue;
                }
                if overlap(a, b) <= -slack {
                    continue;
                }
                match (tree.is_leaf(a), tree.is_leaf(b)) {
                    (true, true) => worst = worst.max(overlap(a, b)),
                    (la, lb) => {
                        // Descend the larger inner node.
                        let split_a = !la && (lb || tree.r[a] >= tree.r[b]);
                        if split_a {
                            stack.extend(tree.children(a).map(|c| (c, b)));
                        } else {
                            stack.extend(tree.children(b).map(|c| (a, c)));
                        }
                    }
                }
            }
            worst
        })
        .reduce(|| 0.0, f64::max)
}
