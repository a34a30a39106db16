//! Welding: vertices with bit-identical coordinates merged into one, for every format.

use std::collections::HashMap;

use glam::DVec3;

use crate::mesh::Mesh;

/// Welds vertices with bit-identical coordinates (`-0.0` == `0.0`), in order of first use.
///
/// Hashes with `ahash` (randomly keyed, so crafted files cannot force collisions), which
/// makes welding a jaw arch about twice as fast as the standard SipHash.
pub(super) struct Welder {
    map: HashMap<[u64; 3], u32, ahash::RandomState>,
    vertices: Vec<DVec3>,
}

impl Welder {
    /// A welder with room for `n` vertices.
    pub(super) fn with_capacity(n: usize) -> Self {
        Welder {
            map: HashMap::with_capacity_and_hasher(n, ahash::RandomState::new()),
            vertices: Vec::with_capacity(n),
        }
    }

    /// The index of `v`, added when new; fails beyond 4 billion distinct vertices.
    pub(super) fn add(&mut self, v: DVec3) -> std::result::Result<u32, String> {
        let key = [
            (v.x + 0.0).to_bits(),
            (v.y + 0.0).to_bits(),
            (v.z + 0.0).to_bits(),
        ];
        if let Some(&i) = self.map.get(&key) {
            return Ok(i);
        }
        let i = u32::try_from(self.vertices.len())
            .ok()
            .filter(|&i| i < u32::MAX)
            .ok_or("more than 4 billion distinct vertices")?;
        self.vertices.push(v);
        self.map.insert(key, i);
        Ok(i)
    }

    /// The mesh of the welded vertices and `triangles`.
    pub(super) fn finish(self, triangles: Vec<[u32; 3]>) -> Mesh {
        Mesh {
            vertices: self.vertices,
            triangles,
        }
    }
}

/// Welds an indexed mesh whose indices have been checked against `raw`; only vertices
/// used by a triangle are kept.
pub(super) fn weld_indexed(
    raw: &[DVec3],
    tris: &[[usize; 3]],
) -> std::result::Result<Mesh, String> {
    let mut remap = vec![u32::MAX; raw.len()];
    let mut welder = Welder::with_capacity(raw.len().min(tris.len() * 3));
    let mut triangles = Vec::with_capacity(tris.len());
    for (f, tri) in tris.iter().enumerate() {
        let mut out = [0u32; 3];
        for (k, &i) in tri.iter().enumerate() {
            let (slot, &v) = remap
                .get_mut(i)
                .zip(raw.get(i))
                .ok_or_else(|| format!("triangle {f} refers to missing vertex {i}"))?;
            if *slot == u32::MAX {
                *slot = welder.add(v)?;
            }
            out[k] = *slot;
        }
        triangles.push(out);
    }
    Ok(welder.finish(triangles))
}
