//! Object File Format, ASCII: `OFF`, `COFF`, `NOFF`, `STOFF`, ... headers (or none), vertex
//! and face counts, then vertices and polygon faces.

use super::text::{lines, parse_point, parse_u64, show, strip_comment, tokens};
use super::weld::weld_indexed;
use crate::mesh::Mesh;

/// Parses an ASCII OFF file; counts in the header are checked against the file length
/// before anything is allocated from them.
pub(super) fn parse_off(b: &[u8]) -> std::result::Result<Mesh, String> {
    if b.is_empty() {
        return Err("the file is empty".into());
    }
    let mut content = lines(b)
        .map(|(ln, l)| (ln, strip_comment(l, b'#')))
        .filter(|(_, l)| tokens(l).next().is_some());
    let (ln, first) = content.next().ok_or("no OFF header")?;
    let mut toks = tokens(first).peekable();
    let head = toks.peek().copied().unwrap_or_default();
    let mut counts: Vec<&[u8]> = Vec::new();
    if head.len() >= 3 && head[head.len() - 3..].eq_ignore_ascii_case(b"OFF") {
        let prefix = &head[..head.len() - 3];
        if !prefix
            .iter()
            .all(|c| matches!(c.to_ascii_uppercase(), b'S' | b'T' | b'C' | b'N'))
        {
            return Err(format!(
                "line {ln}: unsupported OFF variant `{}` (only 3D OFF/COFF/NOFF/STOFF)",
                show(head)
            ));
        }
        toks.next();
        if toks
            .peek()
            .is_some_and(|t| t.eq_ignore_ascii_case(b"BINARY"))
        {
            return Err(format!("line {ln}: binary OFF is not supported"));
        }
        counts.extend(toks);
        if counts.is_empty() {
            let (_, l) = content
                .next()
                .ok_or("no vertex and face counts after the header")?;
            counts.extend(tokens(l));
        }
    } else if parse_u64(head).is_some() {
        // Header keyword omitted: the first line holds the counts.
        counts.extend(toks);
    } else {
        return Err(format!("line {ln}: expected `OFF`, found `{}`", show(head)));
    }
    let count = |k: usize, what: &str| {
        counts
            .get(k)
            .and_then(|t| parse_u64(t))
            .ok_or_else(|| format!("missing or bad {what} count in the OFF header"))
    };
    let nv = count(0, "vertex")?;
    let nf = count(1, "face")?;
    // A vertex line takes at least 6 bytes (`0 0 0\n`), a face line at least 8 (`3 0 1 2\n`).
    if nv.saturating_mul(6).saturating_add(nf.saturating_mul(8)) > b.len() as u64 + 8 {
        return Err(format!(
            "the header claims {nv} vertices and {nf} faces, more than a file of {} bytes can hold",
            b.len()
        ));
    }
    // Both counts are now bounded by the file length.
    let (nv, nf) = (nv as usize, nf as usize);
    let mut raw = Vec::with_capacity(nv);
    for i in 0..nv {
        let (ln, l) = content
            .next()
            .ok_or_else(|| format!("file ends after {i} of {nv} vertices"))?;
        raw.push(parse_point(&mut tokens(l), ln)?);
    }
    let mut tris = Vec::with_capacity(nf);
    for f in 0..nf {
        let (ln, l) = content
            .next()
            .ok_or_else(|| format!("file ends after {f} of {nf} faces"))?;
        let toks: Vec<&[u8]> = tokens(l).collect();
        let n = toks
            .first()
            .and_then(|t| parse_u64(t))
            .ok_or_else(|| format!("line {ln}: bad face vertex count"))?;
        if n < 3 {
            return Err(format!(
                "line {ln}: face with {n} vertices (at least 3 needed)"
            ));
        }
        if n >= toks.len() as u64 {
            return Err(format!(
                "line {ln}: face declares {n} vertices but lists {}",
                toks.len() - 1
            ));
        }
        let n = n as usize;
        let idx = |k: usize| -> std::result::Result<usize, String> {
            let tok = toks[k + 1];
            match parse_u64(tok) {
                Some(i) if i < nv as u64 => Ok(i as usize),
                _ => Err(format!(
                    "line {ln}: bad vertex index `{}` ({nv} vertices)",
                    show(tok)
                )),
            }
        };
        let v0 = idx(0)?;
        let mut prev = idx(1)?;
        for k in 2..n {
            let next = idx(k)?;
            tris.push([v0, prev, next]);
            prev = next;
        }
    }
    weld_indexed(&raw, &tris)
}
