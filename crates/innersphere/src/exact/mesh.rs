//! [`ExactMesh`]: a mesh prepared for the exact queries (triangle BVH, node shapes,
//! winding-number hierarchy, connected components and vertex adjacency).

use super::bound;
use crate::mesh::bvh::TriangleBvh;
use crate::mesh::union_find::UnionFind;
use crate::mesh::winding::FastWinding;
use crate::mesh::Mesh;
use glam::DVec3;

/// One connected component of a mesh (for the containment test).
#[derive(Debug, Clone, Copy)]
pub(super) struct Component {
    /// A vertex of the component.
    pub(super) rep: u32,
    /// Its extreme vertices along 26 directions: `extremes[start..end]`.
    pub(super) start: u32,
    pub(super) end: u32,
}

/// A mesh prepared for exact queries: its triangle BVH, winding-number hierarchy, connected
/// components and vertex adjacency. Immutable; share it freely between threads.
#[derive(Debug, Clone)]
pub struct ExactMesh {
    pub(super) mesh: Mesh,
    pub(super) winding: FastWinding,
    pub(super) components: Vec<Component>,
    pub(super) extremes: Vec<u32>,
    /// Vertex adjacency (CSR): the neighbours of `v` are `adj[adj_start[v]..adj_start[v + 1]]`.
    pub(super) adj_start: Vec<u32>,
    pub(super) adj: Vec<u32>,
    /// Bounding shapes of the BVH nodes (same indices).
    pub(super) shapes: Vec<bound::Shape>,
    /// Unit normal of the triangle in each BVH slot (zero when degenerate).
    pub(super) normals: Vec<DVec3>,
    /// The triangles (BVH slots) around each vertex (CSR): those of `v` are
    /// `vslots[vslot_start[v]..vslot_start[v + 1]]`.
    pub(super) vslot_start: Vec<u32>,
    pub(super) vslots: Vec<u32>,
    /// Every edge used once in each direction: a closed, consistently wound surface, whose
    /// inside flips at every crossing of it (the flood's regions need no winding number
    /// unless their crossings disagree).
    pub(super) closed: bool,
}

impl ExactMesh {
    /// Prepares `mesh` (which must pass [`Mesh::validate`]: not empty, finite, valid indices).
    pub fn new(mesh: &Mesh) -> crate::error::Result<Self> {
        mesh.validate()?;
        let winding = FastWinding::new(mesh);
        let (shapes, normals) = bound::shapes(winding.bvh());
        let n = mesh.vertices.len();
        // Union-find over vertices.
        let mut sets = UnionFind::new(n);
        let mut degree = vec![0u32; n + 1];
        for t in &mesh.triangles {
            for k in 0..3 {
                let (u, v) = (t[k], t[(k + 1) % 3]);
                sets.union(u, v);
                degree[u as usize] += 1;
                degree[v as usize] += 1;
            }
        }
        // Adjacency (each undirected edge from both of its triangles, deduplicated).
        let mut adj_start = vec![0u32; n + 1];
        for v in 0..n {
            adj_start[v + 1] = adj_start[v] + degree[v];
        }
        let mut fill = adj_start.clone();
        let mut adj = vec![0u32; adj_start[n] as usize];
        for t in &mesh.triangles {
            for k in 0..3 {
                let (u, v) = (t[k], t[(k + 1) % 3]);
                adj[fill[u as usize] as usize] = v;
                fill[u as usize] += 1;
                adj[fill[v as usize] as usize] = u;
                fill[v as usize] += 1;
            }
        }
        let mut compact = Vec::with_capacity(adj.len() / 2);
        let mut new_start = vec![0u32; n + 1];
        for v in 0..n {
            let s = &mut adj[adj_start[v] as usize..adj_start[v + 1] as usize];
            s.sort_unstable();
            let before = compact.len();
            for &w in s.iter() {
                if (compact.len() == before || compact.last() != Some(&w)) && w as usize != v {
                    compact.push(w);
                }
            }
            new_start[v + 1] = compact.len() as u32;
        }
        // Components: representative and 26 extreme vertices each.
        let dirs: Vec<DVec3> = (0..27)
            .filter(|&i| i != 13)
            .map(|i| {
                DVec3::new(
                    (i % 3) as f64 - 1.0,
                    ((i / 3) % 3) as f64 - 1.0,
                    (i / 9) as f64 - 1.0,
                )
            })
            .collect();
        let mut comp_of_root: std::collections::HashMap<u32, usize> = Default::default();
        let mut best: Vec<(u32, Vec<(f64, u32)>)> = Vec::new();
        let mut used = vec![false; n];
        for t in &mesh.triangles {
            for &v in t {
                used[v as usize] = true;
            }
        }
        for v in 0..n as u32 {
            if !used[v as usize] {
                continue;
            }
            let r = sets.find(v);
            let c = *comp_of_root.entry(r).or_insert_with(|| {
                best.push((v, vec![(f64::NEG_INFINITY, v); dirs.len()]));
                best.len() - 1
            });
            let p = mesh.vertices[v as usize];
            for (slot, d) in best[c].1.iter_mut().zip(&dirs) {
                let s = p.dot(*d);
                if s > slot.0 {
                    *slot = (s, v);
                }
            }
        }
        let mut components = Vec::with_capacity(best.len());
        let mut extremes = Vec::new();
        for (rep, ext) in best {
            let start = extremes.len() as u32;
            let mut e: Vec<u32> = ext.iter().map(|x| x.1).collect();
            e.sort_unstable();
            e.dedup();
            extremes.extend(e);
            components.push(Component {
                rep,
                start,
                end: extremes.len() as u32,
            });
        }
        let (vslot_start, vslots) = vertex_slots(n, &winding, mesh);
        Ok(ExactMesh {
            closed: crate::field::inside::EdgeSummary::of(mesh).is_oriented_closed(),
            vslot_start,
            vslots,
            mesh: mesh.clone(),
            winding,
            components,
            extremes,
            adj_start: new_start,
            adj: compact,
            shapes,
            normals,
        })
    }

    /// The mesh (local frame).
    pub fn mesh(&self) -> &Mesh {
        &self.mesh
    }

    /// The triangle BVH (shared with the winding-number hierarchy).
    pub fn bvh(&self) -> &TriangleBvh {
        self.winding.bvh()
    }

    /// The winding-number hierarchy.
    pub fn winding(&self) -> &FastWinding {
        &self.winding
    }

    /// Number of connected components (vertex-connected triangle sets).
    #[cfg(test)]
    pub(crate) fn component_count(&self) -> usize {
        self.components.len()
    }

    /// True when the point (local frame) lies inside the solid: winding number ≥ 0.5.
    pub fn contains_point(&self, p: DVec3) -> bool {
        self.winding.winding_number(p).abs() >= 0.5
    }

    /// The neighbours of vertex `v` along mesh edges.
    pub(super) fn neighbours(&self, v: u32) -> &[u32] {
        let s = self.adj_start.get(v as usize).copied().unwrap_or(0) as usize;
        let e = self.adj_start.get(v as usize + 1).copied().unwrap_or(0) as usize;
        self.adj.get(s..e).unwrap_or(&[])
    }

    /// The triangles (BVH slots) around vertex `v`.
    pub(super) fn slots_of(&self, v: u32) -> &[u32] {
        let s = self.vslot_start.get(v as usize).copied().unwrap_or(0) as usize;
        let e = self.vslot_start.get(v as usize + 1).copied().unwrap_or(0) as usize;
        self.vslots.get(s..e).unwrap_or(&[])
    }

    /// Vertex indices of the triangle in BVH slot `slot`.
    pub(super) fn slot_vertices(&self, slot: u32) -> [u32; 3] {
        let t = self.bvh().order[slot as usize];
        self.mesh.triangles[t as usize]
    }
}

/// The BVH slots of the triangles around each vertex of `mesh` (CSR: starts, slots).
fn vertex_slots(n: usize, winding: &FastWinding, mesh: &Mesh) -> (Vec<u32>, Vec<u32>) {
    let order = &winding.bvh().order;
    let mut start = vec![0u32; n + 1];
    for &t in order.iter() {
        for &v in &mesh.triangles[t as usize] {
            start[v as usize + 1] += 1;
        }
    }
    for v in 0..n {
        start[v + 1] += start[v];
    }
    let mut fill = start.clone();
    let mut slots = vec![0u32; start[n] as usize];
    for (slot, &t) in order.iter().enumerate() {
        for &v in &mesh.triangles[t as usize] {
            slots[fill[v as usize] as usize] = slot as u32;
            fill[v as usize] += 1;
        }
    }
    (start, slots)
}
