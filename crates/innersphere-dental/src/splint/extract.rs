//! The splint's surface: the height field sampled on a 3-D grid and extracted with naive
//! surface nets (the `fast-surface-nets` crate: shared vertices, so the surface of a closed
//! level set comes out closed; quads split into consistently wound triangles).
//!
//! The sampled field is `min(z − lower, upper − z, side)` per column (positive inside), so a
//! grid edge along `z` crosses the imprint exactly where the column's height is, and the
//! walls sit where the outline's margin crosses zero. The grid is sheared along z to follow
//! the wafer's mid-surface, so it is only as tall as the wafer is thick.
//!
//! Surface nets gives an edge four triangles where a grid face has its inside corners on
//! one diagonal only (a "checkerboard" face); such corners are moved outside first (which
//! only removes material, never moves the wafer towards an arch), so the surface is a
//! 2-manifold.

use fast_surface_nets::ndshape::{RuntimeShape, Shape as _};
use fast_surface_nets::{surface_nets, SurfaceNetsBuffer};
use glam::DVec3;
use rayon::prelude::*;

use super::shape::Shape;
use innersphere::error::{Error, Result};
use innersphere::mesh::union_find::UnionFind;
use innersphere::mesh::untangle::untangle;
use innersphere::mesh::Mesh;

/// Field values are clamped to ± this many cells: only values near zero place vertices.
const CLAMP_CELLS: f32 = 4.0;
/// The most memory (bytes) the wafer's surface may take: its grid and the surface made from
/// it. A bound on bytes, not on cells, so that a finer voxel is refused with a message
/// before the allocation fails (the grid grows with the inverse cube of the voxel size).
pub const MAX_SPLINT_BYTES: u64 = 3 << 30;
/// Bytes per cell of the extraction grid: the field (`f32`) and surface nets' index (`u32`).
const GRID_BYTES_PER_CELL: u64 = 8;
/// Bytes of surface per kept column: about four vertices (surface nets' position, normal and
/// cell, then the mesh's `f64` point) and eight triangles (surface nets' and the mesh's
/// indices) for the top, the bottom and the walls.
const SURFACE_BYTES_PER_COLUMN: u64 = 4 * 56 + 8 * 24;

/// The refusal of a voxel size `h` whose splint would take `bytes` (`at_least`: a lower
/// bound, estimated before the wafer's height is known), naming the smallest voxel size that
/// fits (memory grows with the inverse cube of the voxel size).
pub fn too_fine(h: f64, bytes: u64, at_least: bool) -> Error {
    let fits = (h * (bytes as f64 / MAX_SPLINT_BYTES as f64).cbrt() * 1000.0).ceil() / 1000.0;
    Error::InvalidOption(format!(
        "a voxel size of {h} would take {} {:.1} GB for these arches, more than the {:.0} GB a splint may use; {}",
        if at_least { "at least" } else { "about" },
        bytes as f64 / 1e9,
        MAX_SPLINT_BYTES as f64 / 1e9,
        if at_least {
            format!("a voxel size of {fits} or more is needed")
        } else {
            format!("a voxel size of {fits} or more fits")
        }
    ))
}

/// Field values within ± this many cells of zero are moved outside ([`extract`]).
const SNAP_CELLS: f32 = 1e-3;

/// The closed surface of the wafer, in A's frame.
/// Also returns how many specks apart from the wafer were left out.
pub fn extract(s: &Shape) -> Result<(Mesh, usize)> {
    let h = s.grid.h;
    let [cx, cy] = s.grid.dims;
    // Heights relative to the mid-surface.
    let (mut zlo, mut zhi) = (f64::INFINITY, f64::NEG_INFINITY);
    for k in 0..s.grid.len() {
        if s.keep[k] {
            zlo = zlo.min(s.lower[k] - s.mid[k]);
            zhi = zhi.max(s.upper[k] - s.mid[k]);
        }
    }
    if !(zlo.is_finite() && zhi.is_finite() && zhi > zlo) {
        return Err(Error::InvalidMesh(
            "the splint's height field is empty".into(),
        ));
    }
    // "Outside" padding: one node below each side, two above (surface nets makes no quad
    // on an array's last plane).
    zlo -= h;
    let nz = ((zhi + h - zlo) / h).ceil() as usize + 3;
    let (nx, ny) = (cx + 3, cy + 3);
    let cells = nx as u64 * ny as u64 * nz as u64;
    let kept = s.keep.iter().filter(|k| **k).count() as u64;
    let bytes = cells * GRID_BYTES_PER_CELL + kept * SURFACE_BYTES_PER_COLUMN;
    if bytes > MAX_SPLINT_BYTES || nx > u32::MAX as usize / 2 || nz > u32::MAX as usize / 2 {
        return Err(too_fine(h, bytes, false));
    }
    let clamp = CLAMP_CELLS * h as f32;
    let snap = SNAP_CELLS * h as f32;
    let slice = nx * ny;
    let mut sdf = vec![clamp; slice * nz];
    sdf.par_chunks_mut(slice)
        .enumerate()
        .for_each(|(kz, layer)| {
            if kz == 0 || kz + 2 >= nz {
                return;
            }
            let dz = zlo + kz as f64 * h;
            for j in 1..=cy {
                for i in 1..=cx {
                    let k = (i - 1) + cx * (j - 1);
                    let z = s.mid[k] + dz;
                    // Outside the outline or in a perforation the margin alone decides,
                    // so the wall there stands the whole thickness of the wafer next to it.
                    let side = s.side[k];
                    let g = if side <= 0.0 {
                        side
                    } else if !s.keep[k] {
                        -0.5 * h
                    } else {
                        (z - s.lower[k]).min(s.upper[k] - z).min(side)
                    };
                    // Surface nets: negative inside. A node within a hair of the level set
                    // counts as outside (the hair is material removed, never added): where a
                    // node sits on the level set, every cell around it puts its vertex at the
                    // node, and the surface pinches there into coinciding vertices.
                    let v = (-(g as f32)).clamp(-clamp, clamp);
                    layer[i + nx * j] = if v.abs() < snap { snap } else { v };
                }
            }
        });
    // The opened corners a quarter cell outside (material removed, never added), so that no
    // vertices stack on them.
    untangle(&mut sdf, [nx, ny, nz], 0.25 * h as f32);
    let shape = RuntimeShape::<u32, 3>::new([nx as u32, ny as u32, nz as u32]);
    debug_assert_eq!(shape.size() as usize, sdf.len());
    let mut buf = SurfaceNetsBuffer::default();
    surface_nets(
        &sdf,
        &shape,
        [0, 0, 0],
        [nx as u32 - 1, ny as u32 - 1, nz as u32 - 1],
        &mut buf,
    );
    drop(sdf);
    let o = s.grid.origin;
    let mid_at = |x: f64, y: f64| -> f64 {
        // Bilinear in the column grid, clamped at its border.
        let fx = x.clamp(0.0, (cx - 1) as f64);
        let fy = y.clamp(0.0, (cy - 1) as f64);
        let (i0, j0) = (fx.floor() as usize, fy.floor() as usize);
        let (i1, j1) = ((i0 + 1).min(cx - 1), (j0 + 1).min(cy - 1));
        let (tx, ty) = (fx - i0 as f64, fy - j0 as f64);
        let m = |i: usize, j: usize| s.mid[i + cx * j];
        (m(i0, j0) * (1.0 - tx) + m(i1, j0) * tx) * (1.0 - ty)
            + (m(i0, j1) * (1.0 - tx) + m(i1, j1) * tx) * ty
    };
    let vertices: Vec<DVec3> = buf
        .positions
        .par_iter()
        .map(|p| {
            let (gx, gy) = (p[0] as f64 - 1.0, p[1] as f64 - 1.0);
            let c = DVec3::new(
                o.x + gx * h,
                o.y + gy * h,
                zlo + p[2] as f64 * h + mid_at(gx, gy),
            );
            s.frame.point(c)
        })
        .collect();
    let triangles: Vec<[u32; 3]> = buf
        .indices
        .chunks_exact(3)
        .map(|t| [t[0], t[1], t[2]])
        .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
        .collect();
    let (mut mesh, dropped) = largest_body(Mesh {
        vertices,
        triangles,
    });
    if mesh.signed_volume() < 0.0 {
        mesh.flip();
    }
    Ok((mesh, dropped))
}

/// The largest connected part of `m` (by triangles), and how many parts were left out:
/// specks of a few cells that untangling can cut off the wafer.
fn largest_body(m: Mesh) -> (Mesh, usize) {
    let mut sets = UnionFind::new(m.vertices.len());
    for t in &m.triangles {
        sets.union(t[0], t[1]);
        sets.union(t[1], t[2]);
    }
    let mut size = vec![0usize; m.vertices.len()];
    let roots: Vec<u32> = m.triangles.iter().map(|t| sets.find(t[0])).collect();
    for r in &roots {
        size[*r as usize] += 1;
    }
    let parts = size.iter().filter(|s| **s > 0).count();
    let Some(best) = (0..size.len()).max_by_key(|&r| (size[r], std::cmp::Reverse(r))) else {
        return (m, 0);
    };
    if parts <= 1 {
        return (m, 0);
    }
    let mut remap = vec![u32::MAX; m.vertices.len()];
    let mut vertices = Vec::new();
    let mut triangles = Vec::with_capacity(size[best]);
    for (t, r) in m.triangles.iter().zip(&roots) {
        if *r as usize != best {
            continue;
        }
        triangles.push(t.map(|v| {
            if remap[v as usize] == u32::MAX {
                remap[v as usize] = vertices.len() as u32;
                vertices.push(m.vertices[v as usize]);
            }
            remap[v as usize]
        }));
    }
    (
        Mesh {
            vertices,
            triangles,
        },
        parts - 1,
    )
}
