//! Triangle meshes: loading ([`io`]), welding, the defect report ([`report`]), the triangle
//! BVH ([`bvh`]), the generalized winding number ([`winding`]) and mass properties
//! ([`mass`]).

// The geometry kernels under the mesh's queries: public for the other crates of the
// workspace (the wafer, the viewer, the tests), not the API.
#[doc(hidden)]
pub mod bvh;
#[doc(hidden)]
pub mod closest;
pub mod io;
pub mod mass;
#[doc(hidden)]
pub mod ray;
pub mod report;
#[doc(hidden)]
pub mod union_find;
pub mod unit;
#[doc(hidden)]
pub mod untangle;
pub mod winding;

pub use io::{load, load_bytes, save, save_obj, save_stl, Format, SAVED_MESH};
pub use mass::MassProperties;
pub use report::MeshReport;
pub use unit::Unit;

use glam::DVec3;

/// The largest coordinate magnitude accepted anywhere (model units): every loader refuses a
/// vertex with `|x| > MAX_COORDINATE` (or a non-finite one), and so do [`Mesh::validate`], the
/// build and the mesh writers.
///
/// Why 1e9: the tree stores centres and radii as `f32`, and the queries compare squared
/// `f32` distances `|Δ|²`, which overflow to infinity for `|Δ|` above 1.8e19 (measured: a
/// sphere of radius 1e19 answers distance `inf`, one of 1e18 the right value). Within
/// ±1e9 the centres, radii (at most √3·2e9) and squared distances inside one model
/// (at most 12·1e18) stay ten orders of magnitude below that, which leaves room for the
/// poses' translations, and the `f64` side (volumes, the exact predicates' cubes, 1e27)
/// is far from `f64` overflow. A finite `f64` such as 1e39 or 1e300 that `f32` cannot hold
/// at all is refused with the line or vertex that holds it. `docs/RELIABILITY.md` has the
/// whole list of limits.
pub const MAX_COORDINATE: f64 = 1e9;

/// Why a coordinate is refused (`None` when it is accepted), for the loaders' messages.
pub(crate) fn coordinate_problem(x: f64) -> Option<String> {
    if !x.is_finite() {
        Some(format!(
            "is non-finite (coordinates must be finite, within -{MAX_COORDINATE:e} ..= {MAX_COORDINATE:e} model units)"
        ))
    } else if x.abs() > MAX_COORDINATE {
        Some(format!(
            "is outside the supported range -{MAX_COORDINATE:e} ..= {MAX_COORDINATE:e} model units (the tree stores f32 and squares distances; rescale or recentre the mesh)"
        ))
    } else {
        None
    }
}

/// An indexed triangle mesh in f64, with duplicate vertices welded.
///
/// Triangles are counter-clockwise seen from outside when the mesh is outward facing.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions.
    pub vertices: Vec<DVec3>,
    /// Vertex indices of each triangle.
    pub triangles: Vec<[u32; 3]>,
}

impl Mesh {
    /// The BLAKE3 hash of the mesh as loaded (vertex coordinates' bits, then triangle
    /// indices), 64 hex digits: what a tree remembers of the mesh it was built from, and
    /// part of a build cache key.
    pub fn content_hash(&self) -> String {
        let mut h = blake3::Hasher::new();
        h.update(&(self.vertices.len() as u64).to_le_bytes());
        for v in &self.vertices {
            for x in v.to_array() {
                h.update(&x.to_bits().to_le_bytes());
            }
        }
        h.update(&(self.triangles.len() as u64).to_le_bytes());
        for t in &self.triangles {
            for i in t {
                h.update(&i.to_le_bytes());
            }
        }
        h.finalize().to_hex().to_string()
    }

    /// Loads a mesh file: STL (binary or ASCII), OBJ, PLY or OFF by its extension, optionally
    /// gzip-compressed (`.stl.gz`, ...); welded and validated (see [`io::load`]). Coordinates
    /// are kept in the file's own unit (the library is unit-agnostic).
    pub fn load(path: impl AsRef<std::path::Path>) -> crate::error::Result<Mesh> {
        io::load(path.as_ref())
    }

    /// [`Mesh::load`] of a file whose coordinates are in `unit`, converted to millimetres
    /// ([`unit`](mod@unit)): the unit every preset and planning tool assumes. Refused when the
    /// conversion carries a coordinate beyond [`MAX_COORDINATE`].
    pub fn load_in(path: impl AsRef<std::path::Path>, unit: Unit) -> crate::error::Result<Mesh> {
        let mut mesh = io::load(path.as_ref())?;
        mesh.scale(unit.to_mm());
        mesh.validate().map_err(|e| match e {
            crate::error::Error::InvalidMesh(m) => crate::error::Error::InvalidMesh(format!(
                "{} in {unit} converted to mm: {m}",
                path.as_ref().display()
            )),
            e => e,
        })?;
        Ok(mesh)
    }

    /// An error unless `pose` is finite and places this mesh within
    /// ±[`MAX_COORDINATE`], the range every mesh is held to: the exact planning tools
    /// (contact map, splint) work in f64 on the placed vertices, and far beyond it their
    /// searches lose their precision (the contact map at 1e17 ran for hours, at 1e300 it
    /// wrote infinite coordinates). `what` names the body.
    pub fn ensure_placed_within_range(
        &self,
        pose: &crate::pose::Pose,
        what: &str,
    ) -> crate::error::Result<()> {
        if !(pose.translation.is_finite() && pose.rotation.is_finite()) {
            return Err(crate::error::Error::InvalidOption(format!(
                "the pose of {what} is not finite: {pose}"
            )));
        }
        let (lo, hi) = self.bbox();
        let far = (0..8)
            .map(|k| {
                let c = DVec3::new(
                    if k & 1 == 0 { lo.x } else { hi.x },
                    if k & 2 == 0 { lo.y } else { hi.y },
                    if k & 4 == 0 { lo.z } else { hi.z },
                );
                pose.transform_point(c).abs().max_element()
            })
            .fold(0.0, f64::max);
        if far.is_finite() && far <= MAX_COORDINATE {
            return Ok(());
        }
        Err(crate::error::Error::InvalidOption(format!(
            "the pose of {what} places it {far:.3e} model units from the origin, beyond the supported ±{MAX_COORDINATE:e} (1000 km in mm): check the pose's translation and its unit"
        )))
    }

    /// Multiplies every coordinate by `factor` (a change of unit).
    pub fn scale(&mut self, factor: f64) {
        if factor != 1.0 {
            for v in &mut self.vertices {
                *v *= factor;
            }
        }
    }

    /// The three corners of triangle `t`.
    #[inline]
    pub fn triangle(&self, t: usize) -> [DVec3; 3] {
        let [a, b, c] = self.triangles[t];
        [
            self.vertices[a as usize],
            self.vertices[b as usize],
            self.vertices[c as usize],
        ]
    }

    /// Axis-aligned bounding box `(min, max)` of the vertices used by triangles.
    pub fn bbox(&self) -> (DVec3, DVec3) {
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        for t in &self.triangles {
            for &i in t {
                let v = self.vertices[i as usize];
                lo = lo.min(v);
                hi = hi.max(v);
            }
        }
        (lo, hi)
    }

    /// Signed enclosed volume (divergence theorem); positive when normals point outward.
    pub fn signed_volume(&self) -> f64 {
        let mut vol = 0.0;
        for t in 0..self.triangles.len() {
            let [a, b, c] = self.triangle(t);
            vol += a.dot(b.cross(c));
        }
        vol / 6.0
    }

    /// Centre of mass of the enclosed solid (uniform density); falls back to the vertex
    /// centroid when the volume is (nearly) zero.
    pub fn center_of_mass(&self) -> DVec3 {
        let mut vol = 0.0;
        let mut acc = DVec3::ZERO;
        for t in 0..self.triangles.len() {
            let [a, b, c] = self.triangle(t);
            let v = a.dot(b.cross(c));
            vol += v;
            acc += v * (a + b + c);
        }
        if vol.abs() > 1e-300 {
            acc / (4.0 * vol)
        } else if self.vertices.is_empty() {
            DVec3::ZERO
        } else {
            self.vertices.iter().copied().sum::<DVec3>() / self.vertices.len() as f64
        }
    }

    /// Reverses the orientation of every triangle (used for inward-facing meshes).
    pub fn flip(&mut self) {
        for t in &mut self.triangles {
            t.swap(1, 2);
        }
    }

    /// Builds a mesh from a triangle soup, welding vertices with identical coordinates.
    pub fn from_soup(soup: &[[DVec3; 3]]) -> Mesh {
        let mut map: std::collections::HashMap<[u64; 3], u32> =
            std::collections::HashMap::with_capacity(soup.len() * 3 / 2);
        let mut vertices = Vec::new();
        let mut triangles = Vec::with_capacity(soup.len());
        for tri in soup {
            let mut idx = [0u32; 3];
            for (k, v) in tri.iter().enumerate() {
                // +0.0 so that -0.0 and 0.0 weld together.
                let key = [
                    (v.x + 0.0).to_bits(),
                    (v.y + 0.0).to_bits(),
                    (v.z + 0.0).to_bits(),
                ];
                idx[k] = *map.entry(key).or_insert_with(|| {
                    vertices.push(*v);
                    (vertices.len() - 1) as u32
                });
            }
            triangles.push(idx);
        }
        Mesh {
            vertices,
            triangles,
        }
    }

    /// Checks that the mesh can be used at all: not empty, finite coordinates within
    /// ±[`MAX_COORDINATE`], valid indices.
    pub fn validate(&self) -> crate::error::Result<()> {
        if self.triangles.is_empty() {
            return Err(crate::error::Error::InvalidMesh(
                "the mesh has no triangles".into(),
            ));
        }
        for (i, v) in self.vertices.iter().enumerate() {
            for (axis, x) in ["x", "y", "z"].into_iter().zip(v.to_array()) {
                if let Some(problem) = coordinate_problem(x) {
                    return Err(crate::error::Error::InvalidMesh(format!(
                        "vertex {i} ({v}): its {axis} coordinate {x:e} {problem}"
                    )));
                }
            }
        }
        let n = self.vertices.len() as u32;
        if let Some(t) = self
            .triangles
            .iter()
            .position(|t| t.iter().any(|&i| i >= n))
        {
            return Err(crate::error::Error::InvalidMesh(format!(
                "triangle {t} refers to a vertex that does not exist"
            )));
        }
        Ok(())
    }
}
