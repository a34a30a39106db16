//! Naive surface nets (the `fast-surface-nets` crate, used by the splint's surface and the
//! generated bone arches) give an edge four triangles where a grid face has its inside
//! corners on one diagonal only; [`untangle`] opens such faces first, so that the surface is a
//! 2-manifold.

use rayon::prelude::*;

/// Moves outside, to the value `outside` (> 0), the inside corners of every grid face whose
/// inside corners lie on one diagonal only, until no such face is left (each pass only
/// removes, so it ends). Each pass finds the faces on all threads (a slice of nodes each)
/// and moves the corners after. `outside` should be a fair part of a cell (the callers use a
/// quarter): a value near zero puts the crossings on the opened corner itself, and the
/// vertices of the cells around it on top of each other.
pub fn untangle(sdf: &mut [f32], [nx, ny, nz]: [usize; 3], outside: f32) {
    let idx = |i: usize, j: usize, k: usize| i + nx * (j + ny * k);
    loop {
        let grid = &*sdf;
        let flips: Vec<usize> = (0..nz - 1)
            .into_par_iter()
            .flat_map_iter(|k| {
                let mut flips = Vec::new();
                for j in 0..ny - 1 {
                    for i in 0..nx - 1 {
                        let p = idx(i, j, k);
                        let near = [
                            grid[p],
                            grid[idx(i + 1, j, k)],
                            grid[idx(i, j + 1, k)],
                            grid[idx(i, j, k + 1)],
                        ];
                        if near.iter().all(|&v| v >= 0.0) {
                            continue; // the common case: outside around this node
                        }
                        // The three faces with this node as their lowest corner.
                        for (u, v) in [
                            (idx(i + 1, j, k), idx(i, j + 1, k)),
                            (idx(i + 1, j, k), idx(i, j, k + 1)),
                            (idx(i, j + 1, k), idx(i, j, k + 1)),
                        ] {
                            let w = u + v - p; // the corner across from p
                            let c = [grid[p] < 0.0, grid[u] < 0.0, grid[v] < 0.0, grid[w] < 0.0];
                            if c[0] && c[3] && !c[1] && !c[2] {
                                flips.extend([p, w]);
                            } else if c[1] && c[2] && !c[0] && !c[3] {
                                flips.extend([u, v]);
                            }
                        }
                    }
                }
                flips
            })
            .collect();
        if flips.is_empty() {
            break;
        }
        for f in flips {
            sdf[f] = outside;
        }
    }
}
