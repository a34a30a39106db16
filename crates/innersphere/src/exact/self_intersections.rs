//! [`self_intersections`]: the triangle pairs of one mesh that cross or touch away from a
//! shared corner (exact predicates). A printable solid has none: a slicer fills a
//! self-intersecting surface unpredictably.

use super::mesh::ExactMesh;
use super::tri_tri;
use crate::mesh::bvh::TriangleBvh;
use crate::mesh::Mesh;
use glam::DVec3;
use rayon::prelude::*;

/// The pairs of triangles of `mesh` that meet where they should not, as pairs of triangle
/// indices (the smaller first), sorted; at most `limit` of them (the search stops there).
/// Exact predicates decide, as CGAL's `does_self_intersect` does:
/// - sharing no corner: any common point (cross, touch or overlap);
/// - sharing one corner: a common point beyond it (one's far edge meets the other);
/// - sharing an edge: folded onto each other (coplanar, on the same side of the edge);
/// - sharing all three corners: always (a duplicate).
///
/// Each triangle queries the BVH for the triangles whose boxes touch its own, in parallel
/// (rayon); the answer is the same on any number of threads.
pub fn self_intersections(mesh: &ExactMesh, limit: usize) -> Vec<[u32; 2]> {
    pairs(mesh.bvh(), &mesh.mesh().triangles, limit)
}

/// [`self_intersections`] of a plain mesh over its triangle BVH `bvh` (`TriangleBvh::new`
/// of it), not the rest of an [`ExactMesh`]: what a check run many times, as a
/// simplification's, needs, sharing the BVH with its other measurements. Fails on a mesh
/// that [`Mesh::validate`] refuses or a BVH of another triangle count.
pub fn mesh_self_intersections(
    mesh: &Mesh,
    bvh: &TriangleBvh,
    limit: usize,
) -> crate::error::Result<Vec<[u32; 2]>> {
    mesh.validate()?;
    if bvh.len() != mesh.triangles.len() {
        return Err(crate::error::Error::InvalidOption(format!(
            "the triangle tree holds {} triangles, the mesh {}: not its tree",
            bvh.len(),
            mesh.triangles.len()
        )));
    }
    Ok(pairs(bvh, &mesh.triangles, limit))
}

/// The pairs of the triangles `triangles` (vertex ids) in `bvh` (built over them).
fn pairs(bvh: &TriangleBvh, triangles: &[[u32; 3]], limit: usize) -> Vec<[u32; 2]> {
    let ids = |slot: u32| triangles[bvh.order[slot as usize] as usize];
    if limit == 0 || bvh.nodes.is_empty() {
        return vec![];
    }
    let mut out: Vec<[u32; 2]> = (0..bvh.tris.len() as u32)
        .into_par_iter()
        .fold(
            || (Vec::new(), Vec::new()),
            |(mut found, mut stack): (Vec<[u32; 2]>, Vec<u32>), sa| {
                let x = &bvh.tris[sa as usize];
                let (lo, hi) = (x[0].min(x[1]).min(x[2]), x[0].max(x[1]).max(x[2]));
                let u = ids(sa);
                stack.clear();
                stack.push(0);
                while let Some(i) = stack.pop() {
                    let n = &bvh.nodes[i as usize];
                    if (n.lo - hi).max(lo - n.hi).max_element() > 0.0 {
                        continue;
                    }
                    if !n.is_leaf() {
                        stack.push(i + 1);
                        stack.push(n.start);
                        continue;
                    }
                    for sb in n.start.max(sa + 1)..n.start + n.count {
                        let y = &bvh.tris[sb as usize];
                        let (ylo, yhi) = (y[0].min(y[1]).min(y[2]), y[0].max(y[1]).max(y[2]));
                        if (ylo - hi).max(lo - yhi).max_element() > 0.0 {
                            continue;
                        }
                        if improper(&u, x, &ids(sb), y) {
                            let (ta, tb) = (bvh.order[sa as usize], bvh.order[sb as usize]);
                            found.push([ta.min(tb), ta.max(tb)]);
                        }
                    }
                }
                (found, stack)
            },
        )
        .map(|(found, _)| found)
        .reduce(Vec::new, |mut a, b| {
            a.extend(b);
            a
        });
    out.sort_unstable();
    out.truncate(limit);
    out
}

/// Whether triangles `x` (vertex ids `u`) and `y` (`v`) meet where they should not (see
/// [`self_intersections`]).
fn improper(u: &[u32; 3], x: &[DVec3; 3], v: &[u32; 3], y: &[DVec3; 3]) -> bool {
    let shared: Vec<(usize, usize)> = (0..3)
        .flat_map(|i| (0..3).map(move |j| (i, j)))
        .filter(|&(i, j)| u[i] == v[j])
        .collect();
    match shared.as_slice() {
        [] => tri_tri::intersection_point(x, y).is_some(),
        // The far edge of either meets the other: a common point that is not the corner.
        [(i, j)] => {
            let far = |t: &[DVec3; 3], k: usize| (t[(k + 1) % 3], t[(k + 2) % 3]);
            let ((p, q), (r, s)) = (far(x, *i), far(y, *j));
            tri_tri::segment_triangle_intersect(p, q, y[0], y[1], y[2])
                || tri_tri::segment_triangle_intersect(r, s, x[0], x[1], x[2])
        }
        [(i0, _), (i1, _)] => {
            let (a, b) = (x[*i0], x[*i1]);
            let c = x[3 - i0 - i1];
            let (j0, j1) = (shared[0].1, shared[1].1);
            let d = y[3 - j0 - j1];
            tri_tri::same_side_coplanar(a, b, c, d)
        }
        _ => true,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes;
    use glam::DVec3;

    /// A closed sphere has none; two spheres in one mesh that overlap have them, and exactly
    /// the pairs an all-pairs test finds.
    #[test]
    fn overlapping_shells_cross_and_a_sphere_does_not() {
        let s = shapes::icosphere(2);
        let m = ExactMesh::new(&s).unwrap();
        assert!(self_intersections(&m, usize::MAX).is_empty());
        let mut two = s.clone();
        let n = s.vertices.len() as u32;
        two.vertices
            .extend(s.vertices.iter().map(|v| *v + DVec3::new(0.7, 0.1, 0.05)));
        two.triangles
            .extend(s.triangles.iter().map(|t| t.map(|i| i + n)));
        let got = self_intersections(&ExactMesh::new(&two).unwrap(), usize::MAX);
        let mut want = vec![];
        let tri = |m: &Mesh, t: usize| m.triangles[t].map(|i| m.vertices[i as usize]);
        for i in 0..two.triangles.len() {
            for j in i + 1..two.triangles.len() {
                let (a, b) = (two.triangles[i], two.triangles[j]);
                if a.iter().any(|k| b.contains(k)) {
                    continue;
                }
                if tri_tri::triangles_intersect(&tri(&two, i), &tri(&two, j)) {
                    want.push([i as u32, j as u32]);
                }
            }
        }
        assert!(!want.is_empty());
        assert_eq!(got, want);
        assert_eq!(
            mesh_self_intersections(&two, &TriangleBvh::new(&two), usize::MAX).unwrap(),
            want
        );
        assert!(mesh_self_intersections(&two, &TriangleBvh::new(&s), 1).is_err());
        assert_eq!(
            self_intersections(&ExactMesh::new(&two).unwrap(), 3).len(),
            3
        );
    }

    /// Neighbours that fold: a vertex of a sphere pushed through the far side of the fan
    /// around it (its triangles cross their neighbours beyond the shared corners), and a
    /// flap folded flat onto the triangle across its edge. A sphere pushed a little keeps
    /// none.
    #[test]
    fn folded_neighbours_are_found() {
        let s = shapes::icosphere(2);
        let mut pushed = s.clone();
        pushed.vertices[0] *= 0.98;
        assert!(self_intersections(&ExactMesh::new(&pushed).unwrap(), usize::MAX).is_empty());
        // Through the far side: its fan crosses triangles it shares nothing with.
        pushed.vertices[0] = -s.vertices[0] * 1.5;
        assert!(!self_intersections(&ExactMesh::new(&pushed).unwrap(), usize::MAX).is_empty());
        // Sharing one corner: through the other beyond it, or apart.
        let o = DVec3::ZERO;
        let t1 = [o, DVec3::X, DVec3::Y];
        let through = [o, DVec3::new(0.5, 0.5, -0.5), DVec3::new(0.2, 0.2, 0.5)];
        let apart = [o, DVec3::new(-1.0, 0.0, 1.0), DVec3::new(0.0, -1.0, 1.0)];
        assert!(improper(&[0, 1, 2], &t1, &[0, 3, 4], &through));
        assert!(!improper(&[0, 1, 2], &t1, &[0, 3, 4], &apart));
        assert!(improper(
            &[0, 1, 2],
            &t1,
            &[2, 0, 1],
            &[t1[2], t1[0], t1[1]]
        ));
        // Two triangles on one edge, the second folded onto the first (a closed mesh is not
        // needed to ask).
        let flap = Mesh {
            vertices: vec![
                DVec3::new(0.0, 0.0, 0.0),
                DVec3::new(1.0, 0.0, 0.0),
                DVec3::new(0.3, 1.0, 0.0),
                DVec3::new(0.6, 0.5, 0.0),
            ],
            triangles: vec![[0, 1, 2], [1, 0, 3]],
        };
        assert_eq!(
            self_intersections(&ExactMesh::new(&flap).unwrap(), usize::MAX),
            vec![[0, 1]]
        );
        let mut open = flap.clone();
        open.vertices[3] = DVec3::new(0.6, -0.5, 0.0);
        assert!(self_intersections(&ExactMesh::new(&open).unwrap(), usize::MAX).is_empty());
    }
}
