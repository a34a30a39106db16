//! A contact map as a PLY file: the mesh at its pose with the per-vertex `gap` and its
//! colour.

use super::colour::gap_colour;
use innersphere::mesh::Mesh;
use innersphere::pose::Pose;
use std::io::Write;

/// The names a contact map is written to: binary PLY, gzip-compressed when the name ends in
/// `.gz` ([`save_ply`]).
pub const MAP_FILE: innersphere::output::OutputKind = innersphere::output::OutputKind {
    what: "the contact map (PLY with each vertex's gap and colour)",
    extensions: &["ply", "ply.gz"],
};

/// [`write_ply`] into the file `path` ([`MAP_FILE`]: `.ply`, or `.ply.gz` compressed),
/// written whole or not at all ([`write_atomic`](innersphere::output::write_atomic)).
pub fn save_ply(
    path: &std::path::Path,
    mesh: &Mesh,
    pose: &Pose,
    gaps: &[f64],
) -> innersphere::error::Result<()> {
    MAP_FILE.check(path)?;
    innersphere::output::write_stream(path, |w| write_ply(mesh, pose, gaps, w))
}

/// Writes `mesh` at `pose` as binary little-endian PLY: per vertex `float x y z`, `float
/// gap` (the signed gap, mm) and `uchar red green blue` ([`gap_colour`]); faces as
/// `list uchar int vertex_indices`. `gaps` has one entry per vertex.
pub fn write_ply(
    mesh: &Mesh,
    pose: &Pose,
    gaps: &[f64],
    out: &mut dyn Write,
) -> std::io::Result<()> {
    if gaps.len() != mesh.vertices.len() {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!("{} gaps for {} vertices", gaps.len(), mesh.vertices.len()),
        ));
    }
    write!(
        out,
        "ply\nformat binary_little_endian 1.0\ncomment innersphere contact map: gap = signed distance (mm) to the other mesh, negative inside it\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\nproperty float gap\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nelement face {}\nproperty list uchar int vertex_indices\nend_header\n",
        mesh.vertices.len(),
        mesh.triangles.len()
    )?;
    let mut buf = Vec::with_capacity(19 * mesh.vertices.len() + 13 * mesh.triangles.len());
    for (v, &g) in mesh.vertices.iter().zip(gaps) {
        let p = pose.transform_point(*v);
        for x in [p.x, p.y, p.z, g] {
            buf.extend_from_slice(&(x as f32).to_le_bytes());
        }
        buf.extend_from_slice(&gap_colour(g));
    }
    for t in &mesh.triangles {
        buf.push(3);
        for i in t {
            buf.extend_from_slice(&(*i as i32).to_le_bytes());
        }
    }
    out.write_all(&buf)
}
