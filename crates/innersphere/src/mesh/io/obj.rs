//! Wavefront OBJ: reading vertex positions and faces (polygons as fans), and writing.

use std::io::Write;

use glam::DVec3;

use super::check_writable;
use super::text::{lines, parse_point, show, strip_comment, tokens};
use super::weld::weld_indexed;
use crate::error::{Error, Result};
use crate::mesh::Mesh;

/// The bytes of an OBJ file of the mesh (what [`save_obj`](super::save_obj) writes,
/// uncompressed).
pub fn to_obj_bytes(mesh: &Mesh) -> Result<Vec<u8>> {
    check_writable(mesh)?;
    let mut out = Vec::with_capacity(40 * mesh.vertices.len() + 24 * mesh.triangles.len());
    let io_err = |e| Error::io("<memory>", e);
    writeln!(out, "# written by innersphere").map_err(io_err)?;
    for v in &mesh.vertices {
        // `{:?}` prints the shortest representation that reads back to the same f64.
        writeln!(out, "v {:?} {:?} {:?}", v.x, v.y, v.z).map_err(io_err)?;
    }
    for [a, b, c] in &mesh.triangles {
        writeln!(out, "f {} {} {}", a + 1, b + 1, c + 1).map_err(io_err)?;
    }
    Ok(out)
}

/// Parses an OBJ file: `v` and `f` lines (1-based or negative vertex references).
pub(super) fn parse_obj(b: &[u8]) -> std::result::Result<Mesh, String> {
    let mut raw: Vec<DVec3> = Vec::new();
    let mut tris: Vec<[usize; 3]> = Vec::new();
    let mut poly: Vec<usize> = Vec::new();
    for (ln, line) in lines(b) {
        let mut toks = tokens(strip_comment(line, b'#'));
        match toks.next() {
            Some(b"v") => raw.push(parse_point(&mut toks, ln)?),
            Some(b"f") => {
                poly.clear();
                for tok in toks {
                    let idx = tok.split(|&c| c == b'/').next().unwrap_or(tok);
                    let i: i64 = std::str::from_utf8(idx)
                        .ok()
                        .and_then(|s| s.parse().ok())
                        .ok_or_else(|| {
                            format!("line {ln}: bad vertex reference `{}`", show(tok))
                        })?;
                    // 1-based; negative counts back from the last vertex read so far.
                    let n = raw.len() as i64;
                    let zero_based = if i > 0 { i - 1 } else { n + i };
                    if i == 0 || zero_based < 0 || zero_based >= n {
                        return Err(format!(
                            "line {ln}: vertex reference {i} out of range ({n} vertices so far)"
                        ));
                    }
                    poly.push(zero_based as usize);
                }
                if poly.len() < 3 {
                    return Err(format!("line {ln}: face with fewer than 3 vertices"));
                }
                for k in 1..poly.len() - 1 {
                    tris.push([poly[0], poly[k], poly[k + 1]]);
                }
            }
            // Normals, texture coordinates, groups, materials, lines, ...: not needed.
            _ => {}
        }
    }
    weld_indexed(&raw, &tris)
}
