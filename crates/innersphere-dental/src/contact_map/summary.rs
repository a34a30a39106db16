//! Per-region summaries of a contact map: the minimum gap, the contact areas within 0.1 and
//! 0.2 mm, and the contact spots.

use super::teeth::Teeth;
use innersphere::mesh::union_find::UnionFind;
use innersphere::mesh::Mesh;

/// The gap (mm) within which a vertex is in contact for [`RegionSummary::spots`].
pub const SPOT_GAP: f64 = 0.1;

/// What one tooth's crown shows on a contact map.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct RegionSummary {
    /// Tooth number (Universal Numbering System).
    pub tooth: u32,
    /// Vertices assigned to the tooth.
    pub vertices: usize,
    /// Smallest signed gap of its vertices (negative: inside the other arch); `null` in JSON
    /// (infinite) when it has none.
    pub min_gap: f64,
    /// Surface area (mm²) whose gap is at most 0.1 mm: each vertex carries a third of the
    /// area of its triangles.
    pub area_within_0_1: f64,
    /// The same within 0.2 mm.
    pub area_within_0_2: f64,
    /// Contact spots: connected patches (along mesh edges) of the tooth's vertices with a
    /// gap of at most [`SPOT_GAP`].
    pub spots: usize,
}

/// The summary of every tooth of `teeth` on `mesh` with per-vertex `gaps` and `region`s
/// ([`Teeth::regions`]), in tooth order.
pub fn summarise(mesh: &Mesh, gaps: &[f64], teeth: &Teeth, region: &[u32]) -> Vec<RegionSummary> {
    region_stats(mesh, gaps, region, teeth.teeth.len())
        .into_iter()
        .zip(&teeth.teeth)
        .map(|(s, t)| RegionSummary {
            tooth: t.number,
            ..s
        })
        .collect()
}

/// The summary of each of `count` regions (`region[v]`: vertex `v`'s, `u32::MAX` or beyond
/// `count` for none), `tooth` left 0: what [`summarise`] gives per tooth and
/// [`arch_regions`](super::arch_regions) per region of the arch.
pub(crate) fn region_stats(
    mesh: &Mesh,
    gaps: &[f64],
    region: &[u32],
    count: usize,
) -> Vec<RegionSummary> {
    let n = mesh.vertices.len().min(gaps.len()).min(region.len());
    let mut area = vec![0.0f64; n];
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| i as usize);
        if a >= n || b >= n || c >= n {
            continue;
        }
        let (pa, pb, pc) = (mesh.vertices[a], mesh.vertices[b], mesh.vertices[c]);
        let third = (pb - pa).cross(pc - pa).length() / 6.0;
        for v in [a, b, c] {
            area[v] += third;
        }
    }
    // Spots: union-find over the edges whose ends are both in contact and in one region.
    let mut sets = UnionFind::new(n);
    let contact = |v: usize| gaps[v] <= SPOT_GAP;
    for t in &mesh.triangles {
        for k in 0..3 {
            let (u, v) = (t[k] as usize, t[(k + 1) % 3] as usize);
            if u < n && v < n && contact(u) && contact(v) && region[u] == region[v] {
                sets.union(u as u32, v as u32);
            }
        }
    }
    let mut out = vec![
        RegionSummary {
            tooth: 0,
            vertices: 0,
            min_gap: f64::INFINITY,
            area_within_0_1: 0.0,
            area_within_0_2: 0.0,
            spots: 0,
        };
        count
    ];
    for v in 0..n {
        let Some(s) = out.get_mut(region[v] as usize) else {
            continue;
        };
        let g = gaps[v];
        s.vertices += 1;
        s.min_gap = s.min_gap.min(g);
        if g <= 0.1 {
            s.area_within_0_1 += area[v];
        }
        if g <= 0.2 {
            s.area_within_0_2 += area[v];
        }
        if contact(v) && sets.find(v as u32) == v as u32 {
            s.spots += 1;
        }
    }
    out
}
