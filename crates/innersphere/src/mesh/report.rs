//! The defect report of a mesh (what `ist inspect` prints).
//!
//! Edges are counted without hashing: the directed edges of all triangles are bucketed by
//! their smaller vertex (a counting sort), and each small bucket is sorted, so the report
//! of a 450k-triangle mesh takes a few tens of milliseconds.

use serde::Serialize;

use super::union_find::UnionFind;
use super::Mesh;

/// Counts and flags that tell whether a mesh is a usable closed solid.
///
/// Edge rules: an edge is an unordered pair of distinct vertex indices. The three edges of a
/// triangle are counted once each in their direction (`a→b`, `b→c`, `c→a`); an "edge" from
/// a vertex to itself (in a triangle with a repeated index) is not counted.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MeshReport {
    /// Number of vertices.
    pub vertices: usize,
    /// Number of triangles.
    pub triangles: usize,
    /// Number of distinct undirected edges.
    pub edges: usize,
    /// Connected components: triangles connected through shared vertices.
    pub components: usize,
    /// Vertices used by no triangle.
    pub unreferenced_vertices: usize,
    /// Undirected edges used by exactly one triangle.
    pub boundary_edges: usize,
    /// Undirected edges used by more than two triangles.
    pub nonmanifold_edges: usize,
    /// Triangles with a repeated vertex index or whose edge cross product
    /// `(b - a) × (c - a)` is exactly zero in `f64` (collinear or coincident corners).
    pub degenerate_triangles: usize,
    /// Signed enclosed volume ([`Mesh::signed_volume`]): positive when the normals point
    /// outward; only meaningful for closed meshes.
    pub volume: f64,
    /// Total surface area.
    pub area: f64,
    /// Every undirected edge is used by exactly two triangles (false for an empty mesh).
    pub watertight: bool,
    /// Every edge used by exactly two triangles is used once in each direction.
    pub winding_consistent: bool,
    /// Every undirected edge is used equally often in each direction (false for an empty
    /// mesh): the condition under which counting signed ray crossings is an exact inside
    /// test, also for closed non-manifold meshes.
    pub oriented_closed: bool,
    /// Lower corner of the bounding box of the used vertices (zeros for an empty mesh).
    pub bbox_min: [f64; 3],
    /// Upper corner of the bounding box of the used vertices (zeros for an empty mesh).
    pub bbox_max: [f64; 3],
}

impl Mesh {
    /// The defect report of this mesh; see [`MeshReport::of`].
    pub fn report(&self) -> MeshReport {
        MeshReport::of(self)
    }
}

impl MeshReport {
    /// Computes the report.
    ///
    /// # Panics
    /// If a triangle refers to a vertex that does not exist (meshes from
    /// [`super::io::load`] and those that pass [`Mesh::validate`] never do).
    pub fn of(mesh: &Mesh) -> MeshReport {
        let nv = mesh.vertices.len();
        let edges = edge_stats(mesh);

        let mut degenerate = 0;
        let mut area = 0.0;
        for (t, &[a, b, c]) in mesh.triangles.iter().enumerate() {
            let [pa, pb, pc] = mesh.triangle(t);
            let cross = (pb - pa).cross(pc - pa);
            if a == b || b == c || a == c || cross == glam::DVec3::ZERO {
                degenerate += 1;
            }
            area += 0.5 * cross.length();
        }

        let (components, referenced) = components(mesh);
        let nonempty = !mesh.triangles.is_empty();
        let (bbox_min, bbox_max) = if nonempty {
            let (lo, hi) = mesh.bbox();
            (lo.to_array(), hi.to_array())
        } else {
            ([0.0; 3], [0.0; 3])
        };
        MeshReport {
            vertices: nv,
            triangles: mesh.triangles.len(),
            edges: edges.edges,
            components,
            unreferenced_vertices: nv - referenced,
            boundary_edges: edges.boundary,
            nonmanifold_edges: edges.nonmanifold,
            degenerate_triangles: degenerate,
            volume: mesh.signed_volume(),
            area,
            watertight: nonempty && edges.boundary == 0 && edges.nonmanifold == 0,
            winding_consistent: edges.two_face_same_direction == 0,
            oriented_closed: nonempty && edges.unbalanced == 0,
            bbox_min,
            bbox_max,
        }
    }
}

#[derive(Default)]
struct EdgeStats {
    edges: usize,
    boundary: usize,
    nonmanifold: usize,
    /// Edges used by two triangles in the same direction.
    two_face_same_direction: usize,
    /// Edges used a different number of times in the two directions.
    unbalanced: usize,
}

fn edge_stats(mesh: &Mesh) -> EdgeStats {
    let nv = mesh.vertices.len();
    let directed = || {
        mesh.triangles
            .iter()
            .flat_map(|&[a, b, c]| [(a, b), (b, c), (c, a)])
            .filter(|(u, v)| u != v)
    };
    // Bucket every edge by its smaller vertex (counting sort).
    let mut start = vec![0usize; nv + 1];
    for (u, v) in directed() {
        start[u.min(v) as usize + 1] += 1;
    }
    for i in 0..nv {
        start[i + 1] += start[i];
    }
    let mut fill = start.clone();
    // Entry: larger vertex << 1 | (1 when the edge runs from the smaller to the larger).
    let mut slots = vec![0u64; start[nv]];
    for (u, v) in directed() {
        let lo = u.min(v) as usize;
        slots[fill[lo]] = (u64::from(u.max(v)) << 1) | u64::from(u < v);
        fill[lo] += 1;
    }
    let mut stats = EdgeStats::default();
    for lo in 0..nv {
        let bucket = &mut slots[start[lo]..start[lo + 1]];
        bucket.sort_unstable();
        for run in bucket.chunk_by(|x, y| x >> 1 == y >> 1) {
            let uses = run.len();
            let forward = run.iter().filter(|&&x| x & 1 == 1).count();
            stats.edges += 1;
            match uses {
                1 => stats.boundary += 1,
                2 => {}
                _ => stats.nonmanifold += 1,
            }
            if uses == 2 && forward != 1 {
                stats.two_face_same_direction += 1;
            }
            if 2 * forward != uses {
                stats.unbalanced += 1;
            }
        }
    }
    stats
}

/// Connected components of the triangles (through shared vertices) and the number of
/// vertices used by some triangle.
fn components(mesh: &Mesh) -> (usize, usize) {
    let nv = mesh.vertices.len();
    let mut sets = UnionFind::new(nv);
    let mut used = vec![false; nv];
    for &[a, b, c] in &mesh.triangles {
        used[a as usize] = true;
        used[b as usize] = true;
        used[c as usize] = true;
        for v in [b, c] {
            sets.union(a, v);
        }
    }
    let mut count = 0;
    let mut referenced = 0;
    for (v, _) in used.iter().enumerate().filter(|(_, &u)| u) {
        referenced += 1;
        if sets.find(v as u32) == v as u32 {
            count += 1;
        }
    }
    (count, referenced)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    fn tetra() -> Mesh {
        Mesh {
            vertices: vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z],
            triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        }
    }

    #[test]
    fn closed_tetrahedron() {
        let r = tetra().report();
        assert_eq!(
            (r.vertices, r.triangles, r.edges, r.components),
            (4, 4, 6, 1)
        );
        assert_eq!(
            (
                r.boundary_edges,
                r.nonmanifold_edges,
                r.degenerate_triangles
            ),
            (0, 0, 0)
        );
        assert!(r.watertight && r.winding_consistent && r.oriented_closed);
        assert!((r.volume - 1.0 / 6.0).abs() < 1e-15);
        assert_eq!(r.bbox_min, [0.0; 3]);
        assert_eq!(r.bbox_max, [1.0; 3]);
    }

    #[test]
    fn one_flipped_face() {
        let mut m = tetra();
        m.triangles[3].swap(1, 2);
        let r = m.report();
        assert!(r.watertight);
        assert!(!r.winding_consistent);
        assert!(!r.oriented_closed);
    }

    #[test]
    fn two_tetrahedra_sharing_an_edge_are_oriented_closed_but_not_manifold() {
        let mut m = tetra();
        m.vertices
            .extend([DVec3::new(-1.0, 0.0, 0.0), DVec3::new(0.0, -1.0, -1.0)]);
        // A second tetrahedron (0, 4, 5, 2) sharing edge 0-2 with the first.
        let (o, p, q, r) = (0u32, 4u32, 5u32, 2u32);
        let mut second = Mesh {
            vertices: m.vertices.clone(),
            triangles: vec![[o, q, p], [o, p, r], [o, r, q], [p, q, r]],
        };
        if second.signed_volume() < 0.0 {
            second.flip();
        }
        m.triangles.extend(second.triangles);
        let r = m.report();
        assert_eq!(r.components, 1);
        assert_eq!(r.nonmanifold_edges, 1);
        assert!(!r.watertight);
        assert!(r.oriented_closed);
        assert!(r.winding_consistent);
    }

    #[test]
    fn components_merge_through_one_triangle() {
        let m = Mesh {
            vertices: (0..10)
                .map(|i| DVec3::new(i as f64, (i * i) as f64, 1.0))
                .collect(),
            triangles: vec![[0, 1, 2], [3, 4, 5], [6, 7, 8], [6, 3, 0]],
        };
        let r = m.report();
        assert_eq!(r.components, 1);
        assert_eq!(r.unreferenced_vertices, 1);
        let m = Mesh {
            triangles: m.triangles[..3].to_vec(),
            ..m
        };
        assert_eq!(m.report().components, 3);
    }

    #[test]
    fn degenerate_and_unreferenced() {
        let m = Mesh {
            vertices: vec![DVec3::ZERO, DVec3::X, 2.0 * DVec3::X, DVec3::Y],
            triangles: vec![[0, 1, 2], [0, 0, 3]],
        };
        let r = m.report();
        assert_eq!(r.degenerate_triangles, 2);
        assert_eq!(r.unreferenced_vertices, 0);
        assert_eq!(r.components, 1);
        let empty = Mesh::default().report();
        assert!(!empty.watertight && !empty.oriented_closed);
        assert_eq!(empty.components, 0);
    }
}
