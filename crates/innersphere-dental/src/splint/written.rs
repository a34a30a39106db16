//! The wafer as a file holds it: STL stores `f32` coordinates, and every reader (trimesh,
//! printer software, this library's loader) joins the corners that have the same
//! coordinates into one vertex. Two vertices of the extracted surface that round to the same
//! `f32` point would become one, and the edges around them would be used by four triangles:
//! a watertight mesh in memory, a broken one on disk. So the coordinates are rounded to what
//! the file holds first, vertices that coincide are moved apart by a few `f32` steps (a few
//! millionths of a millimetre), and the mesh is then read back from its STL bytes: the
//! report measures that mesh, not the one in memory.

use std::collections::HashMap;
use std::path::Path;

use glam::DVec3;

use innersphere::error::Result;
use innersphere::mesh::io::{load_bytes, to_stl_bytes, Format};
use innersphere::mesh::Mesh;

/// `mesh` rounded to `f32` with coinciding vertices moved apart, as read back from its STL
/// bytes; and how many vertices were moved apart.
pub fn as_written(mut mesh: Mesh) -> Result<(Mesh, usize)> {
    let mut seen: HashMap<[u32; 3], u32> = HashMap::with_capacity(mesh.vertices.len());
    let mut moved = 0;
    for (i, v) in mesh.vertices.iter_mut().enumerate() {
        let mut bits = v.to_array().map(|x| (x as f32).to_bits());
        if seen.contains_key(&bits) {
            moved += 1;
            // Step x by whole f32 units until the point is free: deterministic, and far
            // below any tolerance (1 unit is 4e-6 at 60 mm).
            let mut k = 1u32;
            loop {
                let x = f32::from_bits(bits[0]);
                let stepped = if x >= 0.0 {
                    f32::from_bits(x.to_bits() + k)
                } else {
                    f32::from_bits(x.to_bits() - k)
                };
                let candidate = [stepped.to_bits(), bits[1], bits[2]];
                if !seen.contains_key(&candidate) {
                    bits = candidate;
                    break;
                }
                k += 1;
            }
        }
        seen.insert(bits, i as u32);
        let [x, y, z] = bits.map(f32::from_bits);
        *v = DVec3::new(x as f64, y as f64, z as f64);
    }
    let bytes = to_stl_bytes(&mesh)?;
    let read = load_bytes(&bytes, Format::Stl, Path::new("the splint's STL"))?;
    Ok((read, moved))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn coinciding_vertices_stay_apart_in_the_file() {
        // Two tetrahedra sharing no vertex, but with one corner each at the same point
        // (within f32): as read back they must stay two bodies of 4 vertices each.
        // At 50 mm from the origin f32 steps are 4e-6: 1e-9 apart is one f32 point.
        let q = DVec3::new(50.0, 0.0, 0.0);
        let p = [
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
            DVec3::new(0.0, 0.0, 1.0),
        ];
        let mut vertices: Vec<DVec3> = p.iter().map(|v| q + *v).collect();
        vertices.extend(p.iter().map(|v| q + DVec3::new(1e-9, 0.0, 0.0) - *v));
        let tet = [[0u32, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
        let mut triangles: Vec<[u32; 3]> = tet.to_vec();
        triangles.extend(tet.iter().map(|t| [t[0] + 4, t[2] + 4, t[1] + 4]));
        let m = Mesh {
            vertices,
            triangles,
        };
        let naive = load_bytes(&to_stl_bytes(&m).unwrap(), Format::Stl, Path::new("x")).unwrap();
        assert_eq!(naive.vertices.len(), 7, "the corners weld without the fix");
        let (w, moved) = as_written(m).unwrap();
        assert_eq!((w.vertices.len(), moved), (8, 1));
        let r = w.report();
        assert!(r.watertight && r.components == 2, "{r:?}");
    }
}
