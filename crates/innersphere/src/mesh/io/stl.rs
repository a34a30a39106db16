//! STL: binary and ASCII reading (binary vs ASCII decided by the file length) and binary
//! writing.

use glam::DVec3;

use super::check_writable;
use super::text::{lines, parse_point, show, tokens};
use super::weld::Welder;
use crate::error::{Error, Result};
use crate::mesh::Mesh;

/// The bytes of a binary STL file of the mesh (what [`save_stl`](super::save_stl) writes,
/// uncompressed). Fails when a coordinate does not fit in `f32`.
pub fn to_stl_bytes(mesh: &Mesh) -> Result<Vec<u8>> {
    check_writable(mesh)?;
    if let Some(i) = mesh.vertices.iter().position(|v| !v.as_vec3().is_finite()) {
        return Err(Error::InvalidMesh(format!(
            "vertex {i} ({}) does not fit in the f32 coordinates of STL",
            mesh.vertices[i]
        )));
    }
    let count = u32::try_from(mesh.triangles.len()).map_err(|_| {
        Error::InvalidMesh(format!(
            "{} triangles do not fit in a binary STL file",
            mesh.triangles.len()
        ))
    })?;
    let mut out = Vec::with_capacity(84 + 50 * mesh.triangles.len());
    // The header must not start with `solid`, so that no reader mistakes it for ASCII.
    let mut header = [b' '; 80];
    let text = b"binary STL written by innersphere";
    header[..text.len()].copy_from_slice(text);
    out.extend_from_slice(&header);
    out.extend_from_slice(&count.to_le_bytes());
    for t in 0..mesh.triangles.len() {
        let [a, b, c] = mesh.triangle(t);
        let n = (b - a).cross(c - a).normalize_or_zero();
        for v in [n, a, b, c] {
            for x in v.to_array() {
                out.extend_from_slice(&(x as f32).to_le_bytes());
            }
        }
        out.extend_from_slice(&[0, 0]);
    }
    Ok(out)
}

/// Whether the first non-blank bytes are `solid` (any case).
fn says_solid(b: &[u8]) -> bool {
    let start = b
        .iter()
        .position(|c| !c.is_ascii_whitespace())
        .unwrap_or(b.len());
    b[start..]
        .get(..5)
        .is_some_and(|s| s.eq_ignore_ascii_case(b"solid"))
}

/// The exact length `84 + 50 · count` of a file that must be binary STL (it does not start
/// with `solid`, or its first bytes hold a NUL, which ASCII STL never does), and the `count`
/// its header declares, from its first 84 bytes or more; `None` when the file may be ASCII
/// or `head` is shorter than the header.
pub(super) fn declared_len(head: &[u8]) -> Option<(u64, u32)> {
    let count_bytes: [u8; 4] = head.get(80..84)?.try_into().ok()?;
    // ASCII STL is text: a head that says `solid` but holds a NUL byte can only be binary.
    if says_solid(head) && !head.contains(&0) {
        return None;
    }
    let count = u32::from_le_bytes(count_bytes);
    Some((84 + 50 * u64::from(count), count))
}

/// Binary when the length is exactly `84 + 50 * count` or the file does not start with
/// `solid`; ASCII otherwise. Many binary exporters write `solid` into the 80-byte header,
/// so the prefix alone decides nothing; the length rule is what real readers use.
pub(super) fn parse_stl(b: &[u8]) -> std::result::Result<Mesh, String> {
    if b.is_empty() {
        return Err("the file is empty".into());
    }
    let says_solid = says_solid(b);
    let Some(count_bytes) = b.get(80..84) else {
        return if says_solid {
            stl_ascii(b)
        } else {
            Err(format!(
                "{} bytes is too short for a binary STL (84-byte header) and it is not ASCII STL",
                b.len()
            ))
        };
    };
    let count = u32::from_le_bytes([
        count_bytes[0],
        count_bytes[1],
        count_bytes[2],
        count_bytes[3],
    ]);
    let needed = 84 + 50 * u64::from(count);
    if needed == b.len() as u64 {
        return stl_binary(&b[84..], count as usize);
    }
    let lie = format!(
        "as binary STL its header claims {count} triangles ({needed} bytes) but the file has {} bytes (truncated or corrupt)",
        b.len()
    );
    if says_solid {
        stl_ascii(b).map_err(|e| {
            // A file of text only is no binary STL: its header's "count" is letters.
            if b.iter()
                .all(|c| c.is_ascii_graphic() || c.is_ascii_whitespace())
            {
                e
            } else {
                format!("not valid ASCII STL ({e}); {lie}")
            }
        })
    } else {
        Err(lie)
    }
}

fn stl_binary(records: &[u8], count: usize) -> std::result::Result<Mesh, String> {
    // `count` matches the length of `records`, so these allocations are bounded by it.
    let mut welder = Welder::with_capacity(count / 2 + 16);
    let mut triangles = Vec::with_capacity(count);
    for (t, rec) in records.chunks_exact(50).enumerate() {
        let mut tri = [0u32; 3];
        for (k, slot) in tri.iter_mut().enumerate() {
            let mut p = [0.0f64; 3];
            for (j, x) in p.iter_mut().enumerate() {
                let o = 12 + 12 * k + 4 * j;
                *x = f64::from(f32::from_le_bytes([
                    rec[o],
                    rec[o + 1],
                    rec[o + 2],
                    rec[o + 3],
                ]));
            }
            let v = DVec3::from_array(p);
            for (axis, x) in ["x", "y", "z"].into_iter().zip(p) {
                if let Some(problem) = crate::mesh::coordinate_problem(x) {
                    return Err(format!(
                        "triangle {t} (byte {}), corner {k}: {axis} coordinate {x:e} {problem}",
                        84 + 50 * t
                    ));
                }
            }
            *slot = welder.add(v)?;
        }
        triangles.push(tri);
    }
    Ok(welder.finish(triangles))
}

fn stl_ascii(b: &[u8]) -> std::result::Result<Mesh, String> {
    let mut welder = Welder::with_capacity(1024);
    let mut triangles = Vec::new();
    // Corners of the open facet, if any.
    let mut facet: Option<Vec<u32>> = None;
    let mut last_line = 0;
    for (ln, line) in lines(b) {
        last_line = ln;
        let mut toks = tokens(line);
        let Some(kw) = toks.next() else { continue };
        let kw = kw.to_ascii_lowercase();
        match kw.as_slice() {
            b"solid" | b"endsolid" => {
                if facet.is_some() {
                    return Err(format!("line {ln}: `{}` inside a facet", show(&kw)));
                }
            }
            b"facet" => {
                if facet.is_some() {
                    return Err(format!("line {ln}: `facet` before `endfacet`"));
                }
                facet = Some(Vec::with_capacity(3));
            }
            b"outer" | b"endloop" => {
                if facet.is_none() {
                    return Err(format!("line {ln}: `{}` outside a facet", show(&kw)));
                }
            }
            b"vertex" => {
                let corners = facet
                    .as_mut()
                    .ok_or_else(|| format!("line {ln}: `vertex` outside a facet"))?;
                if corners.len() == 3 {
                    return Err(format!("line {ln}: more than three vertices in a facet"));
                }
                let p = parse_point(&mut toks, ln)?;
                corners.push(welder.add(p)?);
            }
            b"endfacet" => match facet.take() {
                Some(c) if c.len() == 3 => triangles.push([c[0], c[1], c[2]]),
                Some(c) => {
                    return Err(format!(
                        "line {ln}: facet with {} vertices instead of 3",
                        c.len()
                    ))
                }
                None => return Err(format!("line {ln}: `endfacet` without `facet`")),
            },
            _ => return Err(format!("line {ln}: unexpected `{}`", show(&kw))),
        }
    }
    if facet.is_some() {
        return Err(format!("line {last_line}: file ends inside a facet"));
    }
    Ok(welder.finish(triangles))
}
