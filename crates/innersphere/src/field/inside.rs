//! Deciding which voxel centres lie inside the mesh.
//!
//! * Oriented-closed meshes (every edge used equally often in both directions) are classified
//!   **exactly**: a ray along +z through every grid column, crossings found with Shewchuk's
//!   exact `orient2d` and symbolic perturbation (so rays through edges and vertices count
//!   once), and the signed crossing count above each cell centre is its winding number.
//! * Other meshes use the generalized winding number ([`FastWinding`]), inside when ≥ 0.5 in
//!   magnitude.
//!
//! Both use the nonzero rule, so inward-facing meshes and overlapping shells are inside too.

use super::{InsideMethod, VoxelGrid};
use crate::mesh::winding::FastWinding;
use crate::progress::Progress;
use crate::Mesh;
use glam::DVec3;
use rayon::prelude::*;
use robust::{orient2d, Coord};

/// Grid rows (constant y) handled together by one parallel task of the ray test.
const BAND: usize = 4;

/// Classifies the cell centres of `grid`: returns the linear indices of the inside cells,
/// ascending, and the method used (exact rays for oriented-closed meshes, the generalized
/// winding number otherwise). A mesh that encloses nothing gives an empty list.
pub fn classify(
    mesh: &Mesh,
    grid: &VoxelGrid,
    progress: &dyn Progress,
) -> crate::Result<(Vec<u32>, InsideMethod)> {
    mesh.validate()?;
    if grid.len() > u32::MAX as usize {
        return Err(crate::Error::InvalidOption(format!(
            "a grid of {} cells is too large",
            grid.len()
        )));
    }
    if is_oriented_closed(mesh) {
        Ok((inside_by_rays(mesh, grid, progress), InsideMethod::ClosedExact))
    } else {
        Ok((
            inside_by_winding(mesh, grid, progress),
            InsideMethod::WindingNumber,
        ))
    }
}

/// True when every undirected edge is used equally often in each direction (degenerate edges
/// from repeated indices are ignored). Exactly then the signed ray-crossing count is the
/// winding number, for manifold and non-manifold meshes alike.
pub fn is_oriented_closed(mesh: &Mesh) -> bool {
    let mut edges: Vec<(u64, i32)> = Vec::with_capacity(mesh.triangles.len() * 3);
    for t in &mesh.triangles {
        for (u, v) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            if u != v {
                let (lo, hi, s) = if u < v { (u, v, 1) } else { (v, u, -1) };
                edges.push(((lo as u64) << 32 | hi as u64, s));
            }
        }
    }
    edges.par_sort_unstable_by_key(|e| e.0);
    edges
        .chunk_by(|a, b| a.0 == b.0)
        .all(|run| run.iter().map(|e| e.1).sum::<i32>() == 0)
}

/// Exact inside test by signed ray crossings along +z (the mesh should be oriented-closed;
/// otherwise the result is the crossing parity of whatever is there). Indices must be valid.
pub fn inside_by_rays(mesh: &Mesh, grid: &VoxelGrid, progress: &dyn Progress) -> Vec<u32> {
    let [nx, ny, nz] = grid.dims;
    if grid.is_empty() || mesh.triangles.is_empty() {
        return Vec::new();
    }
    let (ox, oy, h) = (grid.origin.x, grid.origin.y, grid.h);
    // Rows each triangle may cross (conservative: the exact tests decide), or none for
    // triangles whose projection has zero area.
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
    // Bucket triangles by band of rows (counting sort, deterministic).
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
    let mut band_tris = vec![0u32; start[nbands] as usize];
    for (t, &(j0, j1)) in rows.iter().enumerate() {
        if j0 <= j1 {
            for b in j0 as usize / BAND..=j1 as usize / BAND {
                band_tris[fill[b] as usize] = t as u32;
                fill[b] += 1;
            }
        }
    }
    progress.start("inside test (exact rays)", ny as u64);
    let per_band: Vec<Vec<u32>> = (0..nbands)
        .into_par_iter()
        .map(|b| {
            let tris = &band_tris[start[b] as usize..start[b + 1] as usize];
            let mut out = Vec::new();
            let mut hits: Vec<(u32, f64, i32)> = Vec::new();
            let rows_here = (b * BAND) as u32..((b + 1) * BAND).min(ny as usize) as u32;
            for j in rows_here.clone() {
                let y = oy + j as f64 * h;
                hits.clear();
                for &t in tris {
                    let (j0, j1) = rows[t as usize];
                    if j < j0 || j > j1 {
                        continue;
                    }
                    row_hits(mesh.triangle(t as usize), y, ox, h, nx, &mut hits);
                }
                sweep_row(&mut hits, grid, j, nz, &mut out);
            }
            progress.advance(rows_here.len() as u64);
            out
        })
        .collect();
    progress.finish();
    let mut inside: Vec<u32> = per_band.concat();
    inside.par_sort_unstable();
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
    if !(a <= b) || b < 0.0 || a > (n - 1) as f64 {
        return None;
    }
    Some((a.max(0.0) as u32, b.min((n - 1) as f64) as u32))
}

/// Whether the point `p`, symbolically perturbed to `(x + ε, y + ε²)`, lies strictly left of
/// the directed line `a → b` (`a ≠ b`). Never undecided.
#[inline]
fn left_of(a: Coord<f64>, b: Coord<f64>, p: Coord<f64>) -> (bool, f64) {
    let o = orient2d(a, b, p);
    // orient2d(a, b, p') = orient2d(a, b, p) − (b.y − a.y)·ε + (b.x − a.x)·ε².
    let left = if o != 0.0 {
        o > 0.0
    } else if b.y != a.y {
        b.y < a.y
    } else {
        b.x > a.x
    };
    (left, o)
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
    for i in i0..=i1 {
        let p = Coord {
            x: ox + i as f64 * h,
            y,
        };
        let (s_ab, w_c) = left_of(pa, pb, p);
        let (s_bc, w_a) = left_of(pb, pc, p);
        if s_ab != s_bc {
            continue;
        }
        let (s_ca, w_b) = left_of(pc, pa, p);
        if s_ca != s_ab {
            continue;
        }
        // Barycentric z from the (same-signed) sub-areas.
        let den = w_a + w_b + w_c;
        let mut z = if den != 0.0 {
            (w_a * a.z + w_b * b.z + w_c * c.z) / den
        } else {
            a.z
        };
        let zlo = a.z.min(b.z).min(c.z);
        let zhi = a.z.max(b.z).max(c.z);
        z = z.clamp(zlo, zhi);
        hits.push((i, z, if s_ab { 1 } else { -1 }));
    }
}

/// Turns the crossings of one row into inside cells: the winding number of a cell centre is
/// the signed count of crossings above it; nonzero means inside.
fn sweep_row(hits: &mut [(u32, f64, i32)], grid: &VoxelGrid, j: u32, nz: u32, out: &mut Vec<u32>) {
    hits.sort_unstable_by(|a, b| a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)).then(a.2.cmp(&b.2)));
    let (oz, h) = (grid.origin.z, grid.h);
    for col in hits.chunk_by(|a, b| a.0 == b.0) {
        let i = col[0].0;
        let total: i32 = col.iter().map(|c| c.2).sum();
        // Below the lowest crossing the winding number is `total` (0 for a closed mesh).
        let kf = ((col[0].1 - oz) / h).floor() - 1.0;
        let k0 = if total != 0 || !(kf > 0.0) {
            0
        } else if kf >= nz as f64 {
            nz
        } else {
            kf as u32
        };
        let mut w = total;
        let mut next = 0;
        for k in k0..nz {
            let z = oz + k as f64 * h;
            while next < col.len() && col[next].1 <= z {
                w -= col[next].2;
                next += 1;
            }
            if next == col.len() {
                break; // above every crossing: winding number 0
            }
            if w != 0 {
                out.push(grid.index(i, j, k) as u32);
            }
        }
    }
}

/// Inside test by the generalized winding number: cells with |w| ≥ 0.5. Works on any mesh;
/// a soup that encloses nothing gives (almost) no cells.
pub fn inside_by_winding(mesh: &Mesh, grid: &VoxelGrid, progress: &dyn Progress) -> Vec<u32> {
    let [nx, ny, nz] = grid.dims;
    if grid.is_empty() || mesh.triangles.is_empty() {
        return Vec::new();
    }
    progress.start("winding number tree", 1);
    let fw = FastWinding::new(mesh);
    progress.finish();
    let rows = ny as usize * nz as usize;
    progress.start("inside test (winding number)", rows as u64);
    let per_row: Vec<Vec<u32>> = (0..rows)
        .into_par_iter()
        .map(|r| {
            let (j, k) = ((r % ny as usize) as u32, (r / ny as usize) as u32);
            let mut out = Vec::new();
            for i in 0..nx {
                let w = fw.winding_number(grid.center(i, j, k));
                if w.abs() >= 0.5 {
                    out.push(grid.index(i, j, k) as u32);
                }
            }
            progress.advance(1);
            out
        })
        .collect();
    progress.finish();
    per_row.concat()
}
