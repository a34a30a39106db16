//! Independent verification of a tree against its mesh (what `ist check` runs): leaves inside
//! the mesh, leaves disjoint, parents enclosing children. It does not trust the tree's
//! hierarchy for any of it: protrusion uses the mesh's triangle BVH and winding number,
//! overlap uses a uniform grid over the leaves.

use super::SphereTree;
use crate::mesh::bvh::TriangleBvh;
use crate::mesh::winding::FastWinding;
use crate::Mesh;
use glam::DVec3;
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
    /// Inner nodes whose sphere does not contain every child sphere (beyond `tolerance`).
    pub enclosure_violations: usize,
    /// Tolerance used for all three (model units): 1e-6 of the mesh's bounding-box diagonal.
    pub tolerance: f64,
}

/// Verifies `tree` against `mesh`.
pub fn check(tree: &SphereTree, mesh: &Mesh) -> crate::Result<CheckReport> {
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

    let max_overlap = max_leaf_overlap(&leaves.iter().map(|&n| sphere(n)).collect::<Vec<_>>());

    let enclosure_violations = (0..tree.len())
        .into_par_iter()
        .filter(|&n| {
            let (cp, rp) = sphere(n);
            tree.children(n).any(|ch| {
                let (cc, rc) = sphere(ch);
                (cc - cp).length() + rc - rp > tolerance
            })
        })
        .count();

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

/// Largest pairwise overlap among `balls`, found with a uniform grid (cell = twice the median
/// radius; every ball is entered in each cell its bounding box touches).
pub fn max_leaf_overlap(balls: &[(DVec3, f64)]) -> f64 {
    if balls.len() < 2 {
        return 0.0;
    }
    let mut radii: Vec<f64> = balls.iter().map(|b| b.1).collect();
    radii.sort_by(f64::total_cmp);
    let cell = (2.0 * radii[radii.len() / 2]).max(1e-12);
    let lo = balls
        .iter()
        .fold(DVec3::splat(f64::MAX), |l, b| l.min(b.0 - b.1));
    let key = |p: DVec3| {
        let q = ((p - lo) / cell).floor();
        (q.x as i64, q.y as i64, q.z as i64)
    };
    let mut cells: std::collections::HashMap<(i64, i64, i64), Vec<u32>> =
        std::collections::HashMap::new();
    for (i, b) in balls.iter().enumerate() {
        let a = key(b.0 - b.1);
        let z = key(b.0 + b.1);
        for x in a.0..=z.0 {
            for y in a.1..=z.1 {
                for w in a.2..=z.2 {
                    cells.entry((x, y, w)).or_default().push(i as u32);
                }
            }
        }
    }
    cells
        .par_iter()
        .map(|(_, ids)| {
            let mut worst = 0.0f64;
            for (a, &i) in ids.iter().enumerate() {
                for &j in &ids[a + 1..] {
                    let (ci, ri) = balls[i as usize];
                    let (cj, rj) = balls[j as usize];
                    worst = worst.max(ri + rj - (ci - cj).length());
                }
            }
            worst
        })
        .reduce(|| 0.0, f64::max)
}
