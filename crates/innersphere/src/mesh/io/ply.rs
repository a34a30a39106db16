//! Stanford PLY: the header, and the body in ASCII, binary little endian or binary big
//! endian; reads the `vertex` element's x, y, z and the `face` element's index lists.

use glam::DVec3;

use super::text::{parse_f64, show};
use super::weld::weld_indexed;
use crate::mesh::Mesh;

#[derive(Debug, Clone, Copy)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(name: &str) -> Option<Scalar> {
        Some(match name {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }
}

struct PlyProperty {
    name: String,
    /// The count type when the property is a list.
    list: Option<Scalar>,
    ty: Scalar,
}

struct PlyElement {
    name: String,
    count: u64,
    props: Vec<PlyProperty>,
}

#[derive(Clone, Copy, PartialEq)]
enum PlyEncoding {
    Ascii,
    Binary { big_endian: bool },
}

struct PlyHeader {
    encoding: PlyEncoding,
    elements: Vec<PlyElement>,
    /// Byte offset of the body.
    body: usize,
    /// Number of header lines.
    lines: usize,
}

fn ply_header(b: &[u8]) -> std::result::Result<PlyHeader, String> {
    let mut pos = 0;
    let mut ln = 0;
    let mut encoding = None;
    let mut elements: Vec<PlyElement> = Vec::new();
    loop {
        let rest = &b[pos..];
        let nl = rest
            .iter()
            .position(|&c| c == b'\n')
            .ok_or("the header has no `end_header` line")?;
        let raw = &rest[..nl];
        let raw = raw.strip_suffix(b"\r").unwrap_or(raw);
        pos += nl + 1;
        ln += 1;
        let line = std::str::from_utf8(raw).map_err(|_| format!("header line {ln} is not text"))?;
        let toks: Vec<&str> = line.split_ascii_whitespace().collect();
        if ln == 1 {
            if toks != ["ply"] {
                return Err("the file does not start with `ply`".into());
            }
            continue;
        }
        match toks.first().copied() {
            None | Some("comment") | Some("obj_info") => {}
            Some("format") => {
                encoding = Some(match toks.get(1).copied() {
                    Some("ascii") => PlyEncoding::Ascii,
                    Some("binary_little_endian") => PlyEncoding::Binary { big_endian: false },
                    Some("binary_big_endian") => PlyEncoding::Binary { big_endian: true },
                    _ => return Err(format!("header line {ln}: unknown format `{line}`")),
                });
            }
            Some("element") => {
                let (Some(name), Some(count)) =
                    (toks.get(1), toks.get(2).and_then(|c| c.parse().ok()))
                else {
                    return Err(format!("header line {ln}: bad element line `{line}`"));
                };
                elements.push(PlyElement {
                    name: name.to_string(),
                    count,
                    props: Vec::new(),
                });
            }
            Some("property") => {
                let el = elements
                    .last_mut()
                    .ok_or_else(|| format!("header line {ln}: property before any element"))?;
                let bad = || format!("header line {ln}: bad property line `{line}`");
                let prop = if toks.get(1) == Some(&"list") {
                    match toks[..] {
                        [_, _, count, item, name] => PlyProperty {
                            name: name.to_string(),
                            list: Some(Scalar::parse(count).ok_or_else(bad)?),
                            ty: Scalar::parse(item).ok_or_else(bad)?,
                        },
                        _ => return Err(bad()),
                    }
                } else {
                    match toks[..] {
                        [_, ty, name] => PlyProperty {
                            name: name.to_string(),
                            list: None,
                            ty: Scalar::parse(ty).ok_or_else(bad)?,
                        },
                        _ => return Err(bad()),
                    }
                };
                el.props.push(prop);
            }
            Some("end_header") => break,
            Some(other) => return Err(format!("header line {ln}: unknown keyword `{other}`")),
        }
    }
    Ok(PlyHeader {
        encoding: encoding.ok_or("the header has no `format` line")?,
        elements,
        body: pos,
        lines: ln,
    })
}

/// The body of a PLY file, read one scalar at a time.
trait PlySource {
    /// Reads one value of type `ty`.
    fn read(&mut self, ty: Scalar) -> std::result::Result<f64, String>;
    /// Where the reader is, for error messages.
    fn location(&self) -> String;
}

struct PlyBinary<'a> {
    b: &'a [u8],
    pos: usize,
    big_endian: bool,
}

impl PlySource for PlyBinary<'_> {
    fn read(&mut self, ty: Scalar) -> std::result::Result<f64, String> {
        let n = ty.size();
        let bytes = self
            .b
            .get(self.pos..self.pos.saturating_add(n))
            .ok_or_else(|| format!("unexpected end of data at byte {}", self.pos))?;
        self.pos += n;
        let mut a = [0u8; 8];
        a[..n].copy_from_slice(bytes);
        if self.big_endian {
            a[..n].reverse();
        }
        // `a` is now little endian.
        Ok(match ty {
            Scalar::I8 => f64::from(a[0] as i8),
            Scalar::U8 => f64::from(a[0]),
            Scalar::I16 => f64::from(i16::from_le_bytes([a[0], a[1]])),
            Scalar::U16 => f64::from(u16::from_le_bytes([a[0], a[1]])),
            Scalar::I32 => f64::from(i32::from_le_bytes([a[0], a[1], a[2], a[3]])),
            Scalar::U32 => f64::from(u32::from_le_bytes([a[0], a[1], a[2], a[3]])),
            Scalar::F32 => f64::from(f32::from_le_bytes([a[0], a[1], a[2], a[3]])),
            Scalar::F64 => f64::from_le_bytes(a),
        })
    }

    fn location(&self) -> String {
        format!("byte {}", self.pos)
    }
}

struct PlyAscii<'a> {
    b: &'a [u8],
    pos: usize,
    line: usize,
}

impl PlySource for PlyAscii<'_> {
    fn read(&mut self, _ty: Scalar) -> std::result::Result<f64, String> {
        while let Some(&c) = self.b.get(self.pos) {
            if !c.is_ascii_whitespace() {
                break;
            }
            if c == b'\n' {
                self.line += 1;
            }
            self.pos += 1;
        }
        let start = self.pos;
        while self
            .b
            .get(self.pos)
            .is_some_and(|c| !c.is_ascii_whitespace())
        {
            self.pos += 1;
        }
        let tok = &self.b[start..self.pos];
        if tok.is_empty() {
            return Err(format!("line {}: unexpected end of data", self.line));
        }
        parse_f64(tok).ok_or_else(|| format!("line {}: `{}` is not a number", self.line, show(tok)))
    }

    fn location(&self) -> String {
        format!("line {}", self.line)
    }
}

/// Whether the header at the start of `head` is an ASCII PLY's (its body is text); the
/// header's error when it cannot be read from `head`.
pub(super) fn is_ascii(head: &[u8]) -> std::result::Result<bool, String> {
    ply_header(head).map(|h| h.encoding == PlyEncoding::Ascii)
}

/// The most bytes a binary PLY file can have, from its header in `head`: the header plus,
/// per element, its count times the largest record its properties allow (a list's length is
/// bounded by its count type: 255 items for `uchar`, 65535 for `ushort`). `None` for ASCII,
/// a header not complete in `head`, or a list counted by a 32-bit type (no useful bound).
pub(super) fn max_len(head: &[u8]) -> Option<u64> {
    let header = ply_header(head).ok()?;
    if header.encoding == PlyEncoding::Ascii {
        return None;
    }
    let mut total = header.body as u64;
    for el in &header.elements {
        let mut record: u64 = 0;
        for p in &el.props {
            let size = match p.list {
                None => p.ty.size() as u64,
                Some(count) => {
                    let most: u64 = match count {
                        Scalar::U8 => 255,
                        Scalar::I8 => 127,
                        Scalar::U16 => 65535,
                        Scalar::I16 => 32767,
                        _ => return None,
                    };
                    count.size() as u64 + most * p.ty.size() as u64
                }
            };
            record += size;
        }
        total = total.checked_add(el.count.checked_mul(record)?)?;
    }
    Some(total)
}

/// Parses a PLY file (any of the three encodings).
pub(super) fn parse_ply(b: &[u8]) -> std::result::Result<Mesh, String> {
    let header = ply_header(b)?;
    let body = &b[header.body..];
    match header.encoding {
        PlyEncoding::Ascii => ply_body(
            &header.elements,
            body.len(),
            &mut PlyAscii {
                b: body,
                pos: 0,
                line: header.lines + 1,
            },
        ),
        PlyEncoding::Binary { big_endian } => ply_body(
            &header.elements,
            body.len(),
            &mut PlyBinary {
                b: body,
                pos: 0,
                big_endian,
            },
        ),
    }
}

/// A list length or vertex index: a non-negative integer.
fn ply_index(v: f64, src: &impl PlySource) -> std::result::Result<usize, String> {
    if v >= 0.0 && v.fract() == 0.0 && v < 9.0e15 {
        Ok(v as usize)
    } else {
        Err(format!(
            "{}: `{v}` is not a valid count or index",
            src.location()
        ))
    }
}

fn ply_body(
    elements: &[PlyElement],
    body_len: usize,
    src: &mut impl PlySource,
) -> std::result::Result<Mesh, String> {
    let mut raw: Option<Vec<DVec3>> = None;
    let mut tris: Vec<[usize; 3]> = Vec::new();
    let mut poly: Vec<usize> = Vec::new();
    for el in elements {
        if el.props.is_empty() {
            continue; // nothing to read
        }
        // Every property takes at least one byte, so a count beyond this is a lie.
        if el.count.saturating_mul(el.props.len() as u64) > body_len as u64 {
            return Err(format!(
                "the header claims {} `{}` elements, more than {body_len} bytes of data can hold",
                el.count, el.name
            ));
        }
        let count = el.count as usize; // bounded by body_len
        let find = |name: &str| {
            el.props
                .iter()
                .position(|p| p.name == name && p.list.is_none())
        };
        match el.name.as_str() {
            "vertex" => {
                if raw.is_some() {
                    return Err("more than one `vertex` element".into());
                }
                let (Some(xi), Some(yi), Some(zi)) = (find("x"), find("y"), find("z")) else {
                    return Err("the `vertex` element lacks an x, y or z property".into());
                };
                let mut verts = Vec::with_capacity(count);
                for i in 0..count {
                    let mut p = [0.0; 3];
                    for (k, prop) in el.props.iter().enumerate() {
                        let v = ply_read_property(prop, src, None)?;
                        let slot = if k == xi {
                            0
                        } else if k == yi {
                            1
                        } else if k == zi {
                            2
                        } else {
                            continue;
                        };
                        if let Some(problem) = crate::mesh::coordinate_problem(v) {
                            return Err(format!(
                                "{}: vertex {i}: {} coordinate {v:e} {problem}",
                                src.location(),
                                ["x", "y", "z"][slot]
                            ));
                        }
                        p[slot] = v;
                    }
                    verts.push(DVec3::from_array(p));
                }
                raw = Some(verts);
            }
            "face" => {
                let lists: Vec<usize> = (0..el.props.len())
                    .filter(|&k| el.props[k].list.is_some())
                    .collect();
                let li = el
                    .props
                    .iter()
                    .position(|p| {
                        p.list.is_some() && (p.name == "vertex_indices" || p.name == "vertex_index")
                    })
                    .or(if lists.len() == 1 {
                        Some(lists[0])
                    } else {
                        None
                    })
                    .ok_or("the `face` element has no `vertex_indices` list")?;
                for f in 0..count {
                    for (k, prop) in el.props.iter().enumerate() {
                        if k == li {
                            poly.clear();
                            ply_read_property(prop, src, Some(&mut poly))?;
                        } else {
                            ply_read_property(prop, src, None)?;
                        }
                    }
                    if poly.len() < 3 {
                        return Err(format!(
                            "face {f} has {} vertices (at least 3 needed)",
                            poly.len()
                        ));
                    }
                    for k in 1..poly.len() - 1 {
                        tris.push([poly[0], poly[k], poly[k + 1]]);
                    }
                }
            }
            _ => {
                for _ in 0..count {
                    for prop in &el.props {
                        ply_read_property(prop, src, None)?;
                    }
                }
            }
        }
    }
    let raw = raw.ok_or("no `vertex` element")?;
    if let Some((f, &i)) = tris
        .iter()
        .enumerate()
        .find_map(|(f, t)| t.iter().find(|&&i| i >= raw.len()).map(|i| (f, i)))
    {
        return Err(format!(
            "triangle {f} refers to vertex {i} but there are only {} vertices",
            raw.len()
        ));
    }
    weld_indexed(&raw, &tris)
}

/// Reads one property; a list's items go to `items` when given (as indices), else are
/// skipped. Returns the value of a scalar property (0 for a list).
fn ply_read_property(
    prop: &PlyProperty,
    src: &mut impl PlySource,
    items: Option<&mut Vec<usize>>,
) -> std::result::Result<f64, String> {
    let Some(count_ty) = prop.list else {
        return src.read(prop.ty);
    };
    let n = ply_index(src.read(count_ty)?, src)?;
    match items {
        // Each item read consumes input, so a lying count fails at the end of the data.
        Some(items) => {
            for _ in 0..n {
                let v = src.read(prop.ty)?;
                items.push(ply_index(v, src)?);
            }
        }
        None => {
            for _ in 0..n {
                src.read(prop.ty)?;
            }
        }
    }
    Ok(0.0)
}
