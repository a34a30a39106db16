//! The wafer made light enough for a lab: the surface nets give a triangle per grid face
//! (about a million on a full arch), and printer software and labs want a few hundred
//! thousand. meshoptimizer's edge collapses (the `meshopt` crate) remove triangles where the
//! surface stays within an absolute error bound; the flat walls and plates go first, the
//! imprints keep their detail. The wafer is seated again and measured after (the caller).

use glam::DVec3;
use innersphere::error::{Error, Result};
use innersphere::mesh::bvh::TriangleBvh;
use innersphere::mesh::Mesh;

/// Rounds of [`simplify`] at most: each locks the original vertices around the defects of
/// the last.
pub const SIMPLIFY_ROUNDS: usize = 12;

/// `mesh` with at most `max_triangles` triangles where an error of at most `max_error`
/// (model units) allows it (more where it does not). Edge collapses can fold a thin plate onto itself or pinch an edge;
/// where `defects` finds one in the result (as triangles: [`surface_defects`] and what the
/// caller adds), the original vertices within `lock_radius` of them are locked and the
/// simplification runs again from the original, up to [`SIMPLIFY_ROUNDS`] times. Returns
/// the mesh (only the vertices it uses, in their first use's order), the error
/// meshoptimizer reports for it and the defects left (0 unless the rounds ran out).
pub fn simplify(
    mesh: &Mesh,
    max_triangles: usize,
    max_error: f64,
    lock_radius: f64,
    defects: &dyn Fn(&Mesh) -> Result<Vec<[DVec3; 3]>>,
) -> Result<(Mesh, f64, usize)> {
    if mesh.triangles.len() <= max_triangles {
        return Ok((mesh.clone(), 0.0, 0));
    }
    if !(max_error.is_finite() && max_error > 0.0) {
        return Err(Error::InvalidOption(format!(
            "the simplification's error bound must be a positive number, got {max_error}"
        )));
    }
    // Positions in f32 about the centre of the box (meshoptimizer reads f32).
    let (lo, hi) = mesh.vertices.iter().fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), v| (lo.min(*v), hi.max(*v)),
    );
    let centre = (lo + hi) * 0.5;
    let positions: Vec<[f32; 3]> = mesh
        .vertices
        .iter()
        .map(|v| (*v - centre).as_vec3().to_array())
        .collect();
    let indices: Vec<u32> = mesh.triangles.iter().flatten().copied().collect();
    let adapter = meshopt::VertexDataAdapter::new(meshopt::typed_to_bytes(&positions), 12, 0)
        .map_err(|e| Error::InvalidOption(format!("simplifying the wafer: {e}")))?;
    let mut locks = vec![false; mesh.vertices.len()];
    let grid = Grid::new(&mesh.vertices, lock_radius.max(f64::MIN_POSITIVE));
    // What the original already has near a limit (the caller's defects of the original):
    // locked from the start.
    for tri in defects(mesh)? {
        grid.lock_near(&tri, lock_radius, &mesh.vertices, &mut locks);
    }
    let mut last = None;
    for _ in 0..SIMPLIFY_ROUNDS {
        // meshoptimizer collapses the cheapest edges first and stops at the count: the
        // bound only limits how far it may go for it.
        let mut reached = 0.0f32;
        let kept = meshopt::simplify_with_locks(
            &indices,
            &adapter,
            &locks,
            3 * max_triangles,
            max_error as f32,
            // Regular triangles: far fewer folds to repair (70 against 319 on the first
            // round of a generated arch's wafer) for a little more error.
            meshopt::SimplifyOptions::ErrorAbsolute | meshopt::SimplifyOptions::Regularize,
            Some(&mut reached),
        );
        let reached = reached as f64;
        let out = compact(mesh, &kept);
        let bad = defects(&out)?;
        let found = bad.len();
        if found == 0 {
            return Ok((out, reached, 0));
        }
        for tri in bad {
            grid.lock_near(&tri, lock_radius, &mesh.vertices, &mut locks);
        }
        last = Some((out, reached, found));
    }
    Ok(last.expect("at least one round"))
}

/// The mesh of `kept` (indices into `mesh`'s vertices): only the vertices used, in their
/// first use's order, in the original f64 coordinates.
fn compact(mesh: &Mesh, kept: &[u32]) -> Mesh {
    let mut map = vec![u32::MAX; mesh.vertices.len()];
    let mut vertices = Vec::new();
    let triangles = kept
        .chunks_exact(3)
        .map(|t| {
            [t[0], t[1], t[2]].map(|i| {
                let m = &mut map[i as usize];
                if *m == u32::MAX {
                    *m = vertices.len() as u32;
                    vertices.push(mesh.vertices[i as usize]);
                }
                *m
            })
        })
        .collect();
    Mesh {
        vertices,
        triangles,
    }
}

/// `m` with its coordinates rounded to `f32`, as an STL holds them.
pub fn rounded_to_f32(m: &Mesh) -> Mesh {
    Mesh {
        vertices: m.vertices.iter().map(|v| v.as_vec3().as_dvec3()).collect(),
        triangles: m.triangles.clone(),
    }
}

/// The triangles of `m` with a defect: in a pair that meets away from a shared corner
/// (exact), or on an edge not used exactly once in each direction. `bvh` is `m`'s. Asked of
/// the mesh as written ([`rounded_to_f32`]: two sheets closer than that rounding cross once
/// written).
pub fn surface_defects(m: &Mesh, bvh: &TriangleBvh) -> Result<Vec<[DVec3; 3]>> {
    let mut bad: Vec<u32> = innersphere::exact::mesh_self_intersections(m, bvh, 10_000)?
        .into_iter()
        .flatten()
        .collect();
    let mut edges: std::collections::HashMap<(u32, u32), (u32, u32)> =
        std::collections::HashMap::with_capacity(3 * m.triangles.len());
    for (t, tri) in m.triangles.iter().enumerate() {
        for k in 0..3 {
            let e = edges
                .entry((tri[k], tri[(k + 1) % 3]))
                .or_insert((0, t as u32));
            e.0 += 1;
        }
    }
    for (&(a, b), &(n, t)) in &edges {
        if n != 1 || edges.get(&(b, a)).map(|e| e.0) != Some(1) {
            bad.push(t);
        }
    }
    bad.sort_unstable();
    bad.dedup();
    Ok(bad
        .into_iter()
        .map(|t| m.triangles[t as usize].map(|i| m.vertices[i as usize]))
        .collect())
}

/// The original vertices in cells of `cell` (a hash grid), to lock those near a defect.
struct Grid {
    cell: f64,
    cells: std::collections::HashMap<[i64; 3], Vec<u32>>,
}

impl Grid {
    fn key(p: DVec3, cell: f64) -> [i64; 3] {
        (p / cell).floor().as_i64vec3().to_array()
    }

    fn new(vertices: &[DVec3], cell: f64) -> Grid {
        let mut cells: std::collections::HashMap<[i64; 3], Vec<u32>> =
            std::collections::HashMap::new();
        for (i, v) in vertices.iter().enumerate() {
            cells.entry(Self::key(*v, cell)).or_default().push(i as u32);
        }
        Grid { cell, cells }
    }

    /// Locks every vertex within `r` of `tri`'s bounding box.
    fn lock_near(&self, tri: &[DVec3; 3], r: f64, vertices: &[DVec3], locks: &mut [bool]) {
        let lo = tri[0].min(tri[1]).min(tri[2]) - DVec3::splat(r);
        let hi = tri[0].max(tri[1]).max(tri[2]) + DVec3::splat(r);
        let (a, b) = (Self::key(lo, self.cell), Self::key(hi, self.cell));
        // A sliver spanning the whole wafer would visit many cells; a few thousand at most.
        if (0..3).map(|k| (b[k] - a[k] + 1).max(0)).product::<i64>() > 1 << 16 {
            return;
        }
        for x in a[0]..=b[0] {
            for y in a[1]..=b[1] {
                for z in a[2]..=b[2] {
                    for &i in self.cells.get(&[x, y, z]).map_or(&[][..], |v| v.as_slice()) {
                        let p = vertices[i as usize];
                        if p.cmpge(lo).all() && p.cmple(hi).all() {
                            locks[i as usize] = true;
                        }
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashMap;

    /// A box `size` with each face cut into `n` × `n` quads (two triangles each), wound
    /// outwards.
    fn fine_box(size: DVec3, n: u32) -> Mesh {
        let mut m = Mesh {
            vertices: vec![],
            triangles: vec![],
        };
        let mut index: HashMap<[i64; 3], u32> = HashMap::new();
        let mut id = |m: &mut Mesh, p: DVec3| {
            let key = (p * 1e6).round().as_i64vec3().to_array();
            *index.entry(key).or_insert_with(|| {
                m.vertices.push(p);
                m.vertices.len() as u32 - 1
            })
        };
        for axis in 0..3 {
            for side in [0.0, 1.0] {
                let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
                for i in 0..n {
                    for j in 0..n {
                        let corner = |di: u32, dj: u32| {
                            let mut p = DVec3::ZERO;
                            p[axis] = side * size[axis];
                            p[u] = (i + di) as f64 / n as f64 * size[u];
                            p[v] = (j + dj) as f64 / n as f64 * size[v];
                            p
                        };
                        let q = [corner(0, 0), corner(1, 0), corner(1, 1), corner(0, 1)]
                            .map(|p| id(&mut m, p));
                        if side > 0.0 {
                            m.triangles.push([q[0], q[1], q[2]]);
                            m.triangles.push([q[0], q[2], q[3]]);
                        } else {
                            m.triangles.push([q[0], q[2], q[1]]);
                            m.triangles.push([q[0], q[3], q[2]]);
                        }
                    }
                }
            }
        }
        m
    }

    /// The surface's defects as written.
    fn as_written(m: &Mesh) -> Result<Vec<[DVec3; 3]>> {
        let w = rounded_to_f32(m);
        surface_defects(&w, &TriangleBvh::new(&w))
    }

    /// Every edge used once in each direction.
    fn closed(m: &Mesh) -> bool {
        let mut uses: HashMap<(u32, u32), i32> = HashMap::new();
        for t in &m.triangles {
            for k in 0..3 {
                *uses.entry((t[k], t[(k + 1) % 3])).or_default() += 1;
            }
        }
        uses.iter()
            .all(|(&(a, b), &c)| c == 1 && uses.get(&(b, a)) == Some(&1))
    }

    /// A finely tessellated box (flat faces) comes down to the cap, stays closed, and its
    /// volume is kept (flat faces need no detail).
    #[test]
    fn a_fine_box_simplifies_to_the_cap_and_keeps_its_volume() {
        let fine = fine_box(DVec3::new(10.0, 6.0, 4.0), 24);
        assert!(closed(&fine));
        let before = fine.triangles.len();
        let (coarse, err, left) = simplify(&fine, 500, 0.5, 0.1, &as_written).unwrap();
        assert_eq!(left, 0);
        assert!(before > 5000, "{before}");
        assert!(coarse.triangles.len() <= 500, "{}", coarse.triangles.len());
        assert!(err <= 0.5);
        let vol = |m: &Mesh| m.mass_properties().map(|p| p.volume).unwrap_or(0.0);
        assert!((vol(&coarse) - 240.0).abs() < 1e-6, "{}", vol(&coarse));
        assert!(closed(&coarse));
        // Under the cap already: unchanged.
        let (same, e0, _) = simplify(&coarse, 500, 0.5, 0.1, &as_written).unwrap();
        assert_eq!(same, coarse);
        assert_eq!(e0, 0.0);
    }
}
