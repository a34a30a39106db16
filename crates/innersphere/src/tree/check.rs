//! Independent verification of a tree against its mesh (what `ist check` runs): leaves inside
//! the mesh, leaves disjoint, every node enclosing the leaves below it. It does not trust the
//! tree's hierarchy for any of it: protrusion uses the mesh's triangle BVH and winding number,
//! overlap is a self-join over the hierarchy, sound once enclosure is verified.

use super::SphereTree;
use crate::mesh::bvh::TriangleBvh;
use crate::mesh::winding::FastWinding;
use crate::mesh::Mesh;
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
/// coordinates to f32 or to 6 significant digits moves them by less); the volume and its
/// centroid of `source_shape` about the centre of the tree's box, within 1e-4 (of the
/// volume, of the box's diagonal) plus what moving every vertex by that coordinate tolerance
/// can change them by (first order: the area, and for an open mesh its rim's length times
/// the diagonal). `None` when all agree. A mesh moved, scaled or edited, the same surface
/// with triangles added or removed (a hole closed, widened, or made elsewhere), or another
/// shape is caught; two meshes with the same box, volume and centroid within those
/// tolerances (a nearly symmetric shape and its mirror image) are not told apart (a tree is
/// never compared with a mesh by its spheres here: that is [`check`]'s job).
///
/// Open meshes are checked like closed ones: their enclosed volume is not defined (the
/// tree's [`mesh_volume`](super::TreeMeta::mesh_volume) holds its inside voxels' volume
/// there), but `source_shape`'s is, and the build records it
/// ([`source_volume`](super::TreeMeta::source_volume),
/// [`source_centroid`](super::TreeMeta::source_centroid)). A tree written before they were
/// recorded is compared by its enclosed volume when its mesh was closed, and by its box
/// alone when it was open.
pub fn source_mismatch(tree: &SphereTree, mesh: &Mesh) -> Option<String> {
    let m = &tree.meta;
    let (lo, hi) = mesh.bbox();
    let (tlo, thi) = (DVec3::from_array(m.bbox_min), DVec3::from_array(m.bbox_max));
    let reach = lo
        .abs()
        .max(hi.abs())
        .max(tlo.abs())
        .max(thi.abs())
        .max_element();
    let diag = (hi - lo).length().max((thi - tlo).length());
    let tol = 1e-5 * diag.max(reach);
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
    let ((volume, centroid), recorded) = match m.source_volume {
        Some(v) => (
            source_shape(mesh, (tlo + thi) * 0.5),
            (v, m.source_centroid.map(DVec3::from_array)),
        ),
        None if m.mesh_closed => ((mesh.signed_volume().abs(), None), (m.mesh_volume, None)),
        // An open mesh's tree from before the source's shape was recorded: its mesh_volume
        // is the inside voxels', which no mesh reproduces; the box is all there is.
        None => return (!why.is_empty()).then(|| why.join("; ")),
    };
    let (recorded, recorded_centroid) = recorded;
    let big = volume.max(recorded.abs()).max(f64::MIN_POSITIVE);
    let dv = (volume - recorded).abs();
    let dc = match (centroid, recorded_centroid) {
        (Some(c), Some(r)) => (c - r).length(),
        _ => 0.0,
    };
    let mut vtol = 1e-4 * big + 1e-12 * tol.powi(3);
    let mut ctol = 1e-4 * diag;
    if dv > vtol || dc > ctol {
        // What moving each vertex by up to `tol` can change the volume by (first order):
        // the swept area, plus the cones' sides along edges whose uses do not cancel; the
        // centroid moves by at most twice that, times the diagonal, over the volume.
        // Computed only here: a matching mesh mostly agrees to far less.
        let (area, rim) = area_and_rim(mesh);
        let swept = tol * (area + rim * diag);
        vtol += swept;
        ctol += 2.0 * swept * diag / big;
    }
    if dv.is_nan() || dv > vtol {
        why.push(format!(
            "its volume is {volume:.6e}, the tree's source's was {recorded:.6e} (relative difference {:.1e}, tolerance {:.1e})",
            dv / big,
            vtol / big
        ));
    }
    if let (Some(c), Some(r)) = (centroid, recorded_centroid) {
        if dc.is_nan() || dc > ctol {
            why.push(format!(
                "the centroid of its volume is {:?}, the tree's source's was {:?} (off by {dc:.3e}, tolerance {ctol:.1e})",
                c.to_array(),
                r.to_array()
            ));
        }
    }
    (!why.is_empty()).then(|| why.join("; "))
}

/// The volume and its centroid that a tree records of its source
/// ([`TreeMeta::source_volume`](super::TreeMeta::source_volume),
/// [`source_centroid`](super::TreeMeta::source_centroid)) and [`source_mismatch`] compares:
/// of the signed cones from `apex` (the centre of the source's bounding box) to the
/// triangles, `|Σ (a−o)·((b−o)×(c−o))| / 6` and the centroid of that signed volume. For a
/// closed mesh these are its enclosed volume and centre of mass, wherever the apex lies; for
/// an open mesh, whose enclosed volume is not defined, they are numbers its triangles fix
/// (removing, adding or moving one changes them), unlike the inside that a build decides by
/// the winding number. Orientation does not matter (the build flips an inward mesh). The
/// centroid is `None` when the volume is zero.
pub(crate) fn source_shape(mesh: &Mesh, apex: DVec3) -> (f64, Option<DVec3>) {
    let (mut vol, mut moment) = (0.0, DVec3::ZERO);
    for t in 0..mesh.triangles.len() {
        let [a, b, c] = mesh.triangle(t);
        let (a, b, c) = (a - apex, b - apex, c - apex);
        let v = a.dot(b.cross(c));
        vol += v;
        // The centroid of the tetrahedron (apex, a, b, c), relative to the apex.
        moment += v * (a + b + c) / 4.0;
    }
    let centroid = (vol != 0.0).then(|| apex + moment / vol);
    ((vol / 6.0).abs(), centroid.filter(|c| c.is_finite()))
}

/// The area of `mesh`, and the length of its edges whose uses do not cancel (each counted
/// `|uses a→b − uses b→a|` times: none on a closed, consistently oriented mesh, the boundary
/// of an open one): what bounds how much `source_shape` moves when the vertices do.
fn area_and_rim(mesh: &Mesh) -> (f64, f64) {
    let mut area = 0.0;
    let mut edges: Vec<(u32, u32, i32)> = Vec::with_capacity(3 * mesh.triangles.len());
    for (t, tri) in mesh.triangles.iter().enumerate() {
        let [a, b, c] = mesh.triangle(t);
        area += 0.5 * (b - a).cross(c - a).length();
        for k in 0..3 {
            let (u, v) = (tri[k], tri[(k + 1) % 3]);
            edges.push(if u < v { (u, v, 1) } else { (v, u, -1) });
        }
    }
    edges.sort_unstable_by_key(|e| (e.0, e.1));
    let rim = edges
        .chunk_by(|x, y| (x.0, x.1) == (y.0, y.1))
        .map(|g| {
            let net = g.iter().map(|e| e.2).sum::<i32>().unsigned_abs() as f64;
            net * (mesh.vertices[g[0].1 as usize] - mesh.vertices[g[0].0 as usize]).length()
        })
        .sum();
    (area, rim)
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
    // On an open mesh the solid is where |w| ≥ ½, and across a hole w passes ½ smoothly (on
    // a planar cut, exactly at ½ in its plane: the build's f64 voxel centre is inside, the
    // tree's f32 copy may not be). A centre counts as outside there only beyond the winding
    // number's accuracy; a closed mesh's w jumps at the surface and keeps the plain ½.
    let threshold = if area_and_rim(mesh).1 == 0.0 {
        0.5
    } else {
        0.5 - crate::mesh::winding::WINDING_ACCURACY
    };
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
            let inside = winding.winding_number(c).abs() >= threshold;
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

#[cfg(test)]
/// Largest overlap r_a + r_b − |c_a − c_b| between two distinct leaves, by a self-join over
/// the tree's own hierarchy. This is sound only when every node encloses the leaves below it,
/// which [`check`] verifies independently (and reports as not ok otherwise): then every
/// overlapping leaf pair lies under a chain of overlapping node pairs and is found. ([`check`]
/// itself searches with twice its tolerance as slack, since it accepts nodes that miss their
/// leaves by up to the tolerance.)
pub(crate) fn max_leaf_overlap(tree: &SphereTree) -> f64 {
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
