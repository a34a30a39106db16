//! Deciding which voxel centres lie inside the mesh.
//!
//! * Oriented-closed meshes (every edge used equally often in both directions) are classified
//!   **exactly**: a ray along +z through every grid column, crossings found with Shewchuk's
//!   exact `orient2d` and symbolic perturbation (so rays through edges and vertices count
//!   once), and the signed crossing count above each cell centre is its winding number.
//! * Other meshes use the generalized winding number ([`FastWinding`]), inside when ≥ 0.5 in
//!   magnitude. It is evaluated only where needed: the same column rays split each column
//!   into runs of cells between surface crossings, along which the winding number is smooth;
//!   its gradient is bounded by the Biot–Savart law over the mesh's open edges, so one
//!   evaluation decides a whole run whenever the bound keeps the run on one side of 0.5
//!   (otherwise the run is bisected).
//! * A triangle soup (most edges used by a single triangle) encloses nothing: no cells.
//!
//! Both use the nonzero rule, so inward-facing meshes and overlapping shells are inside too.

use super::{InsideMethod, VoxelGrid};
use crate::mesh::closest::closest_point_on_segment;
use crate::mesh::winding::{FastWinding, WINDING_ACCURACY};
use crate::mesh::Mesh;
use crate::progress::Progress;
use glam::DVec3;
use rayon::prelude::*;
use robust::{orient2d, Coord};
use std::f64::consts::PI;

/// Grid rows (constant y) handled together by one parallel task.
const BAND: usize = 4;
/// Runs of fewer than `MIN_RUN + 1` cells are evaluated cell by cell (a gradient bound costs
/// about as much as an evaluation).
const MIN_RUN: u32 = 3;

/// Classifies the cell centres of `grid`: returns the linear indices of the inside cells,
/// ascending, and the method used (exact rays for oriented-closed meshes, the generalized
/// winding number otherwise). A mesh that encloses nothing gives an empty list.
pub(crate) fn classify(
    mesh: &Mesh,
    grid: &VoxelGrid,
    progress: &dyn Progress,
) -> crate::error::Result<(Vec<u32>, InsideMethod)> {
    classify_where(mesh, grid, None, progress)
}

/// Which inside cells a classification keeps (`classify_where`): given `(i, j, k)`, the
/// first `k' ≥ k` whose cell `(i, j, k')` it may keep (`k` itself when it keeps that cell;
/// every cell between is dropped).
pub(crate) type Keep<'a> = &'a (dyn Fn(u32, u32, u32) -> u32 + Sync);

/// [`classify`], keeping only the inside cells for which `keep` holds (all without it): the
/// others are dropped row by row, so that the full list is never held.
pub(crate) fn classify_where(
    mesh: &Mesh,
    grid: &VoxelGrid,
    keep: Option<Keep<'_>>,
    progress: &dyn Progress,
) -> crate::error::Result<(Vec<u32>, InsideMethod)> {
    mesh.validate()?;
    if grid.len() > u32::MAX as usize {
        return Err(crate::error::Error::InvalidOption(format!(
            "a grid of {} cells is too large",
            grid.len()
        )));
    }
    let edges = EdgeSummary::of(mesh);
    if edges.is_oriented_closed() {
        Ok((
            rays_inside(mesh, grid, keep, progress),
            InsideMethod::ClosedExact,
        ))
    } else if edges.is_soup() {
        Ok((Vec::new(), InsideMethod::WindingNumber))
    } else {
        let cells = winding_inside(mesh, grid, &edges, keep, progress);
        Ok((cells, InsideMethod::WindingNumber))
    }
}

/// How the edges of a mesh are used.
#[derive(Debug, Clone, Default)]
pub(crate) struct EdgeSummary {
    /// Number of distinct undirected edges (degenerate ones, from repeated indices, ignored).
    pub edges: usize,
    /// Edges used by exactly one triangle.
    pub single_use: usize,
    /// Edges used unequally often in the two directions, as `(u, v, m)`: the net boundary
    /// chain `m · (u → v)` of the surface.
    pub open: Vec<(u32, u32, i32)>,
}

impl EdgeSummary {
    /// Counts the directed uses of every edge.
    pub(crate) fn of(mesh: &Mesh) -> Self {
        let mut uses: Vec<(u64, i32)> = Vec::with_capacity(mesh.triangles.len() * 3);
        for t in &mesh.triangles {
            for (u, v) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                if u != v {
                    let (lo, hi, s) = if u < v { (u, v, 1) } else { (v, u, -1) };
                    uses.push(((lo as u64) << 32 | hi as u64, s));
                }
            }
        }
        uses.par_sort_unstable_by_key(|e| e.0);
        let mut summary = EdgeSummary::default();
        for run in uses.chunk_by(|a, b| a.0 == b.0) {
            summary.edges += 1;
            if run.len() == 1 {
                summary.single_use += 1;
            }
            let net: i32 = run.iter().map(|e| e.1).sum();
            if net != 0 {
                summary
                    .open
                    .push(((run[0].0 >> 32) as u32, run[0].0 as u32, net));
            }
        }
        summary
    }

    /// Every edge is used equally often in each direction: exactly then the signed
    /// ray-crossing count is the winding number (manifold or not).
    pub(crate) fn is_oriented_closed(&self) -> bool {
        self.open.is_empty()
    }

    /// Most edges belong to a single triangle: a soup that encloses no volume.
    pub(crate) fn is_soup(&self) -> bool {
        self.single_use * 2 > self.edges
    }
}

#[cfg(test)]
/// True when every undirected edge is used equally often in each direction (see
/// `EdgeSummary::is_oriented_closed`).
pub(crate) fn is_oriented_closed(mesh: &Mesh) -> bool {
    EdgeSummary::of(mesh).is_oriented_closed()
}

#[cfg(test)]
/// Exact inside test by signed ray crossings along +z (the mesh should be oriented-closed;
/// otherwise the result is the signed crossing count of whatever is there). Indices must be
/// valid.
pub(crate) fn inside_by_rays(mesh: &Mesh, grid: &VoxelGrid, progress: &dyn Progress) -> Vec<u32> {
    rays_inside(mesh, grid, None, progress)
}

fn rays_inside(
    mesh: &Mesh,
    grid: &VoxelGrid,
    keep: Option<Keep<'_>>,
    progress: &dyn Progress,
) -> Vec<u32> {
    let nz = grid.dims[2];
    for_each_row(
        mesh,
        grid,
        progress,
        "inside test (exact rays)",
        |j, hits, out| sweep_row(hits, grid, j, nz, keep, out),
    )
}

/// Triangles bucketed by bands of grid rows.
struct RowBuckets {
    /// Per triangle: the rows `[j0, j1]` it may cross (empty when `j0 > j1`).
    rows: Vec<(u32, u32)>,
    /// Band `b` holds `tris[start[b]..start[b + 1]]`.
    start: Vec<u32>,
    tris: Vec<u32>,
}

impl RowBuckets {
    fn new(mesh: &Mesh, grid: &VoxelGrid) -> Self {
        let ny = grid.dims[1];
        let (oy, h) = (grid.origin.y, grid.h);
        // Conservative row ranges (the exact tests decide); none for triangles whose
        // projection has zero area: a perturbed ray never hits them.
        let rows: Vec<(u32, u32)> = (0..mesh.triangles.len())
            .into_par_iter()
            .map(|t| {
                let [a, b, c] = mesh.triangle(t);
                if orient2d(xy(a), xy(b), xy(c)) == 0.0 {
                    return (1, 0);
                }
                let ylo = a.y.min(b.y).min(c.y);
                let yhi = a.y.max(b.y).max(c.y);
                cell_range(ylo, yhi, oy, h, ny).unwrap_or((1, 0))
            })
            .collect();
        // Counting sort into bands (deterministic).
        let nbands = (ny as usize).div_ceil(BAND);
        let mut start = vec![0u32; nbands + 1];
        for &(j0, j1) in &rows {
            if j0 <= j1 {
                for b in j0 as usize / BAND..=j1 as usize / BAND {
                    start[b + 1] += 1;
                }
            }
        }
        for b in 0..nbands {
            start[b + 1] += start[b];
        }
        let mut fill = start.clone();
        let mut tris = vec![0u32; start[nbands] as usize];
        for (t, &(j0, j1)) in rows.iter().enumerate() {
            if j0 <= j1 {
                for b in j0 as usize / BAND..=j1 as usize / BAND {
                    tris[fill[b] as usize] = t as u32;
                    fill[b] += 1;
                }
            }
        }
        RowBuckets { rows, start, tris }
    }
}

/// Runs `f(j, crossings, out)` for every grid row `j` in parallel, with the crossings of the
/// row's rays sorted by column, then height (then sign); `f` appends inside cells to `out`.
/// Returns all appended cells, sorted.
fn for_each_row<F>(
    mesh: &Mesh,
    grid: &VoxelGrid,
    progress: &dyn Progress,
    stage: &str,
    f: F,
) -> Vec<u32>
where
    F: Fn(u32, &[(u32, f64, i32)], &mut Vec<u32>) + Sync,
{
    let [nx, ny, _] = grid.dims;
    if grid.is_empty() || mesh.triangles.is_empty() {
        return Vec::new();
    }
    let (ox, oy, h) = (grid.origin.x, grid.origin.y, grid.h);
    let buckets = RowBuckets::new(mesh, grid);
    let nbands = buckets.start.len() - 1;
    progress.start(stage, ny as u64);
    let per_band: Vec<(Vec<u32>, Vec<usize>)> = (0..nbands)
        .into_par_iter()
        .map(|b| {
            let tris = &buckets.tris[buckets.start[b] as usize..buckets.start[b + 1] as usize];
            let mut out = Vec::new();
            let mut hits: Vec<(u32, f64, i32)> = Vec::new();
            let rows_here = (b * BAND) as u32..((b + 1) * BAND).min(ny as usize) as u32;
            for j in rows_here.clone() {
                let y = oy + j as f64 * h;
                hits.clear();
                for &t in tris {
                    let (j0, j1) = buckets.rows[t as usize];
                    if j >= j0 && j <= j1 {
                        row_hits(mesh.triangle(t as usize), y, ox, h, nx, &mut hits);
                    }
                }
                hits.sort_unstable_by(|a, b| {
                    a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)).then(a.2.cmp(&b.2))
                });
                f(j, &hits, &mut out);
            }
            progress.advance(rows_here.len() as u64);
            by_layer(out, grid)
        })
        .collect();
    progress.finish();
    merge_layers(&per_band, grid)
}

/// A band's cells, emitted row by row (`j`), column by column (`i`), `k` ascending, regrouped
/// by layer `k` (stable): the cells and where each layer starts (`nz + 1` entries).
fn by_layer(cells: Vec<u32>, grid: &VoxelGrid) -> (Vec<u32>, Vec<usize>) {
    let [nx, ny, nz] = grid.dims;
    let layer = |c: u32| (c / (nx * ny)) as usize;
    let mut start = vec![0usize; nz as usize + 1];
    for &c in &cells {
        start[layer(c) + 1] += 1;
    }
    for k in 0..nz as usize {
        start[k + 1] += start[k];
    }
    let mut at = start.clone();
    let mut out = vec![0u32; cells.len()];
    for c in cells {
        let k = layer(c);
        out[at[k]] = c;
        at[k] += 1;
    }
    (out, start)
}

/// All bands' cells in ascending order: layer by layer, each layer's cells band by band (the
/// bands hold ascending rows), on all threads; a final check falls back to sorting should an
/// emitter ever break the order.
fn merge_layers(bands: &[(Vec<u32>, Vec<usize>)], grid: &VoxelGrid) -> Vec<u32> {
    let nz = grid.dims[2] as usize;
    let size = |k: usize| bands.iter().map(|(_, s)| s[k + 1] - s[k]).sum::<usize>();
    let mut inside = vec![0u32; (0..nz).map(size).sum()];
    let mut layers = Vec::with_capacity(nz);
    let mut rest = &mut inside[..];
    for k in 0..nz {
        let (this, more) = rest.split_at_mut(size(k));
        layers.push(this);
        rest = more;
    }
    layers.into_par_iter().enumerate().for_each(|(k, dst)| {
        let mut at = 0;
        for (cells, start) in bands {
            let src = &cells[start[k]..start[k + 1]];
            dst[at..at + src.len()].copy_from_slice(src);
            at += src.len();
        }
    });
    if !inside.par_windows(2).all(|w| w[0] < w[1]) {
        inside.par_sort_unstable();
    }
    inside
}

#[inline]
fn xy(v: DVec3) -> Coord<f64> {
    Coord { x: v.x, y: v.y }
}

/// Cells `[c0, c1]` whose centres `o + c·h` may lie in `[lo, hi]`, widened by one cell on each
/// side against rounding; `None` when outside the grid or not finite.
#[inline]
fn cell_range(lo: f64, hi: f64, o: f64, h: f64, n: u32) -> Option<(u32, u32)> {
    let a = ((lo - o) / h).floor() - 1.0;
    let b = ((hi - o) / h).ceil() + 1.0;
    if a.is_nan() || b.is_nan() || a > b || b < 0.0 || a > (n - 1) as f64 {
        return None;
    }
    Some((a.max(0.0) as u32, b.min((n - 1) as f64) as u32))
}

/// Whether the point `p`, symbolically perturbed to `(x + ε, y + ε²)`, lies strictly left of
/// the directed line `a → b` (`a ≠ b`). Never undecided.
#[inline]
fn left_of(a: Coord<f64>, b: Coord<f64>, p: Coord<f64>) -> bool {
    let o = orient2d(a, b, p);
    // orient2d(a, b, p') = orient2d(a, b, p) − (b.y − a.y)·ε + (b.x − a.x)·ε².
    if o != 0.0 {
        o > 0.0
    } else if b.y != a.y {
        b.y < a.y
    } else {
        b.x > a.x
    }
}

/// Appends the crossings of triangle `[a, b, c]` with the rays of row `y`: `(column, z, ±1)`,
/// +1 where the triangle is counter-clockwise seen from +z.
fn row_hits(tri: [DVec3; 3], y: f64, ox: f64, h: f64, nx: u32, hits: &mut Vec<(u32, f64, i32)>) {
    let [a, b, c] = tri;
    // x-extent of the triangle along the line y (conservative; the exact tests decide).
    let mut xlo = f64::INFINITY;
    let mut xhi = f64::NEG_INFINITY;
    for (u, v) in [(a, b), (b, c), (c, a)] {
        let (ylo, yhi) = (u.y.min(v.y), u.y.max(v.y));
        if y < ylo || y > yhi {
            continue;
        }
        if u.y == v.y {
            xlo = xlo.min(u.x.min(v.x));
            xhi = xhi.max(u.x.max(v.x));
        } else {
            let t = ((y - u.y) / (v.y - u.y)).clamp(0.0, 1.0);
            let x = u.x + t * (v.x - u.x);
            xlo = xlo.min(x);
            xhi = xhi.max(x);
        }
    }
    if xlo > xhi {
        return; // the row passes beside the triangle (also under the perturbation)
    }
    let Some((i0, i1)) = cell_range(xlo, xhi, ox, h, nx) else {
        return;
    };
    let (pa, pb, pc) = (xy(a), xy(b), xy(c));
    let mut canon = [a, b, c];
    canon.sort_unstable_by(|u, v| {
        u.x.total_cmp(&v.x)
            .then(u.y.total_cmp(&v.y))
            .then(u.z.total_cmp(&v.z))
    });
    for i in i0..=i1 {
        let p = Coord {
            x: ox + i as f64 * h,
            y,
        };
        let s_ab = left_of(pa, pb, p);
        if left_of(pb, pc, p) != s_ab || left_of(pc, pa, p) != s_ab {
            continue;
        }
        // Barycentric z from the sub-areas of the corners in a canonical order, so that the
        // same triangle in either orientation (or rotation) crosses at the same height.
        let z = crossing_height(canon, p);
        hits.push((i, z, if s_ab { 1 } else { -1 }));
    }
}

/// Height at which the vertical line through `p` meets the plane of the triangle `t` (whose
/// projection contains `p`), clamped to the triangle's z-range.
fn crossing_height(t: [DVec3; 3], p: Coord<f64>) -> f64 {
    let [a, b, c] = t;
    let wa = orient2d(xy(b), xy(c), p);
    let wb = orient2d(xy(c), xy(a), p);
    let wc = orient2d(xy(a), xy(b), p);
    let den = wa + wb + wc;
    let z = if den != 0.0 {
        (wa * a.z + wb * b.z + wc * c.z) / den
    } else {
        a.z
    };
    let zlo = a.z.min(b.z).min(c.z);
    let zhi = a.z.max(b.z).max(c.z);
    if z.is_nan() {
        a.z
    } else {
        z.clamp(zlo, zhi)
    }
}

/// Turns the crossings of one row into inside cells: the winding number of a cell centre is
/// the signed count of crossings above it; nonzero means inside.
fn sweep_row(
    hits: &[(u32, f64, i32)],
    grid: &VoxelGrid,
    j: u32,
    nz: u32,
    keep: Option<Keep<'_>>,
    out: &mut Vec<u32>,
) {
    let (oz, h) = (grid.origin.z, grid.h);
    for col in hits.chunk_by(|a, b| a.0 == b.0) {
        let i = col[0].0;
        let total: i32 = col.iter().map(|c| c.2).sum();
        // Below the lowest crossing the winding number is `total` (0 for a closed mesh).
        let kf = ((col[0].1 - oz) / h).floor() - 1.0;
        let k0 = if total != 0 || kf.is_nan() || kf <= 0.0 {
            0
        } else if kf >= nz as f64 {
            nz
        } else {
            kf as u32
        };
        let mut w = total;
        let mut next = 0;
        let mut k = k0;
        while k < nz {
            let z = oz + k as f64 * h;
            while next < col.len() && col[next].1 <= z {
                w -= col[next].2;
                next += 1;
            }
            if next == col.len() {
                break; // above every crossing: winding number 0
            }
            if w != 0 {
                match keep.map(|keep| keep(i, j, k)) {
                    Some(skip) if skip > k => {
                        // Dropped up to `skip` (crossings in between are taken there).
                        k = skip;
                        continue;
                    }
                    _ => out.push(grid.index(i, j, k) as u32),
                }
            }
            k += 1;
        }
    }
}

#[cfg(test)]
/// Inside test by the generalized winding number: cells with |w| ≥ 0.5. Works on any mesh;
/// a soup that encloses nothing gives (almost) no cells.
pub(crate) fn inside_by_winding(
    mesh: &Mesh,
    grid: &VoxelGrid,
    progress: &dyn Progress,
) -> Vec<u32> {
    winding_inside(mesh, grid, &EdgeSummary::of(mesh), None, progress)
}

fn winding_inside(
    mesh: &Mesh,
    grid: &VoxelGrid,
    edges: &EdgeSummary,
    keep: Option<Keep<'_>>,
    progress: &dyn Progress,
) -> Vec<u32> {
    if grid.is_empty() || mesh.triangles.is_empty() {
        return Vec::new();
    }
    progress.start("winding number tree", 1);
    let fw = FastWinding::new(mesh);
    let bound = GradientBound::new(mesh, &edges.open);
    progress.finish();
    let runs = WindingRuns {
        fw: &fw,
        bound: &bound,
        grid,
    };
    for_each_row(
        mesh,
        grid,
        progress,
        "inside test (winding number)",
        |j, hits, out| {
            let first = out.len();
            runs.row(j, hits, out);
            if let Some(keep) = keep {
                let [nx, ny, _] = grid.dims;
                let mut kept = first;
                for n in first..out.len() {
                    let c = out[n];
                    let k = c / (nx * ny);
                    if keep(c % nx, j, k) == k {
                        out[kept] = c;
                        kept += 1;
                    }
                }
                out.truncate(kept);
            }
        },
    )
}

/// Classifies the runs of cells between surface crossings along the columns of a row.
struct WindingRuns<'a> {
    fw: &'a FastWinding,
    bound: &'a GradientBound,
    grid: &'a VoxelGrid,
}

impl WindingRuns<'_> {
    fn row(&self, j: u32, hits: &[(u32, f64, i32)], out: &mut Vec<u32>) {
        let [nx, _, nz] = self.grid.dims;
        let (oz, h) = (self.grid.origin.z, self.grid.h);
        let mut next = 0;
        for i in 0..nx {
            let first = next;
            while next < hits.len() && hits[next].0 == i {
                next += 1;
            }
            let col = &hits[first..next];
            // Split the column between cells k and k + 1 wherever a crossing lies in
            // [z_k, z_{k+1}] (a crossing exactly at a centre isolates that cell).
            let mut c = 0;
            let mut k0 = 0;
            for k in 0..nz {
                let zk = oz + k as f64 * h;
                while c < col.len() && col[c].1 < zk {
                    c += 1;
                }
                let split = k + 1 == nz || (c < col.len() && col[c].1 <= oz + (k + 1) as f64 * h);
                if split {
                    self.run(i, j, k0, k, out);
                    k0 = k + 1;
                }
            }
        }
    }

    /// Cells `k0..=k1` of column `(i, j)`, joined by a segment that crosses no triangle.
    fn run(&self, i: u32, j: u32, k0: u32, k1: u32, out: &mut Vec<u32>) {
        let g = self.grid;
        let m = k0 + (k1 - k0) / 2;
        let w = self.fw.winding_number(g.center(i, j, m)).abs();
        let inside = w >= 0.5;
        if k1 - k0 >= MIN_RUN {
            // Along the run the winding number changes by at most |∇w| times the distance.
            let margin = (w - 0.5).abs() - WINDING_ACCURACY;
            let reach = (m - k0).max(k1 - m) as f64 * g.h;
            if margin > 0.0 {
                let mid = (g.center(i, j, k0) + g.center(i, j, k1)) * 0.5;
                let half = (k1 - k0) as f64 * 0.5 * g.h;
                let cap = margin / reach;
                if self.bound.max_gradient(mid, half, cap) < cap {
                    if inside {
                        out.extend((k0..=k1).map(|k| g.index(i, j, k) as u32));
                    }
                    return;
                }
            }
            if m > k0 {
                self.run(i, j, k0, m - 1, out);
            }
            if m < k1 {
                self.run(i, j, m + 1, k1, out);
            }
        } else {
            // Short runs: every cell on its own.
            for k in (k0..=k1).filter(|&k| k != m) {
                if self.fw.winding_number(g.center(i, j, k)).abs() >= 0.5 {
                    out.push(g.index(i, j, k) as u32);
                }
            }
        }
        if inside {
            out.push(g.index(i, j, m) as u32);
        }
    }
}

/// An upper bound of |∇w| near a point, from the Biot–Savart law: the gradient of the
/// winding number of a surface with boundary chain Γ is `(1/4π) ∮_Γ (x − p) × dl / |x − p|³`,
/// so `|∇w(p)| ≤ (1/4π) Σ_e |m_e| · |e| / dist(p, e)²` over the open edges `e` (multiplicity
/// `m_e`). Edges are clustered in a small sphere tree for speed.
struct GradientBound {
    /// Open edges `(a, b, |m| · |b − a|)`, in tree order.
    edges: Vec<(DVec3, DVec3, f64)>,
    /// The same edges as `m · (b − a)`.
    vectors: Vec<DVec3>,
    nodes: Vec<EdgeNode>,
}

#[derive(Clone, Copy)]
struct EdgeNode {
    centre: DVec3,
    radius: f64,
    /// Σ |m| · length below the node.
    weight: f64,
    /// |Σ m · (b − a)|: the net edge vector (zero for complete boundary loops).
    net: f64,
    /// Leaf: edges `start..start + count`; inner node (count 0): second child at `start`,
    /// first child next.
    start: u32,
    count: u32,
}

const EDGE_LEAF: usize = 8;

impl GradientBound {
    fn new(mesh: &Mesh, open: &[(u32, u32, i32)]) -> Self {
        // Oriented so that the multiplicity is positive: (a, b, |m| · |b − a|).
        let mut edges: Vec<(DVec3, DVec3, f64)> = open
            .iter()
            .map(|&(u, v, m)| {
                let (a, b) = (mesh.vertices[u as usize], mesh.vertices[v as usize]);
                let (a, b) = if m > 0 { (a, b) } else { (b, a) };
                (a, b, m.unsigned_abs() as f64 * (b - a).length())
            })
            .collect();
        let mut nodes = Vec::new();
        if !edges.is_empty() {
            Self::build(&mut edges, 0, &mut nodes);
        }
        // Multiplicities: weight / length (1 for simple boundaries).
        let vectors: Vec<DVec3> = edges
            .iter()
            .map(|&(a, b, w)| {
                let len = (b - a).length();
                if len > 0.0 {
                    (b - a) * (w / len)
                } else {
                    DVec3::ZERO
                }
            })
            .collect();
        let mut gb = GradientBound {
            edges,
            vectors,
            nodes,
        };
        if !gb.nodes.is_empty() {
            gb.fill_net(0);
        }
        gb
    }

    /// Sets the net edge vector length of node `i` and below; returns its net vector.
    fn fill_net(&mut self, i: usize) -> DVec3 {
        let n = self.nodes[i];
        let v = if n.count > 0 {
            let r = n.start as usize..(n.start + n.count) as usize;
            self.vectors[r].iter().copied().sum()
        } else {
            self.fill_net(i + 1) + self.fill_net(n.start as usize)
        };
        self.nodes[i].net = v.length();
        v
    }

    fn build(edges: &mut [(DVec3, DVec3, f64)], first: u32, nodes: &mut Vec<EdgeNode>) {
        let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        for e in edges.iter() {
            lo = lo.min(e.0).min(e.1);
            hi = hi.max(e.0).max(e.1);
        }
        let centre = (lo + hi) * 0.5;
        let radius = edges
            .iter()
            .map(|e| (e.0 - centre).length().max((e.1 - centre).length()))
            .fold(0.0, f64::max);
        let weight = edges.iter().map(|e| e.2).sum();
        let me = nodes.len();
        nodes.push(EdgeNode {
            centre,
            radius,
            weight,
            net: 0.0,
            start: first,
            count: edges.len() as u32,
        });
        if edges.len() <= EDGE_LEAF {
            return;
        }
        let ext = hi - lo;
        let axis = if ext.x >= ext.y && ext.x >= ext.z {
            0
        } else if ext.y >= ext.z {
            1
        } else {
            2
        };
        let mid = edges.len() / 2;
        edges.select_nth_unstable_by(mid, |a, b| (a.0 + a.1)[axis].total_cmp(&(b.0 + b.1)[axis]));
        let (l, r) = edges.split_at_mut(mid);
        nodes[me].count = 0;
        Self::build(l, first, nodes);
        nodes[me].start = nodes.len() as u32;
        Self::build(r, first + mid as u32, nodes);
    }

    /// An upper bound of |∇w| over the ball `B(p, r)`, or a value ≥ `cap` as soon as the
    /// bound cannot stay below `cap`.
    ///
    /// A cluster of edges (centre c, radius ρ, net vector L, total weighted length W) seen
    /// from q with |q − c| ≥ D > ρ contributes at most `|L|/D² + 2ρW/(D − ρ)³` (the kernel
    /// `y/|y|³` varies by at most `2|s|/|y|³` per offset `s`), which is small for complete
    /// loops (L = 0); single edges contribute at most `|m|·|e|/dist²`.
    fn max_gradient(&self, p: DVec3, r: f64, cap: f64) -> f64 {
        if self.nodes.is_empty() {
            return 0.0;
        }
        let cap = cap * 4.0 * PI;
        let mut sum = 0.0;
        let mut stack = vec![0usize];
        while let Some(i) = stack.pop() {
            let n = &self.nodes[i];
            let dist = (p - n.centre).length() - r; // from any point of the ball
            let gap = dist - n.radius;
            if gap > n.radius + r {
                let dipole = n.net / (dist * dist) + 2.0 * n.radius * n.weight / (gap * gap * gap);
                sum += dipole.min(n.weight / (gap * gap));
            } else if n.count > 0 {
                for &(a, b, w) in &self.edges[n.start as usize..(n.start + n.count) as usize] {
                    let d = (p - closest_point_on_segment(p, a, b)).length() - r;
                    if d.is_nan() || d <= 0.0 {
                        return f64::INFINITY;
                    }
                    sum += w / (d * d);
                }
            } else {
                stack.push(n.start as usize);
                stack.push(i + 1);
            }
            if sum.is_nan() || sum >= cap {
                return f64::INFINITY;
            }
        }
        sum / (4.0 * PI)
    }
}
