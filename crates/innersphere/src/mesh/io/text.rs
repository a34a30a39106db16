//! Tokenizing helpers of the text formats (STL ASCII, OBJ, OFF, PLY ASCII): lines, tokens,
//! comments, numbers, and shortened tokens for error messages.

use glam::DVec3;

/// Lines of a text file as (1-based line number, line without `\r\n`).
pub(super) fn lines(b: &[u8]) -> impl Iterator<Item = (usize, &[u8])> {
    b.split(|&c| c == b'\n').enumerate().map(|(i, l)| {
        let l = l.strip_suffix(b"\r").unwrap_or(l);
        (i + 1, l)
    })
}

/// Whitespace-separated tokens of a line.
pub(super) fn tokens(line: &[u8]) -> impl Iterator<Item = &[u8]> {
    line.split(|c| c.is_ascii_whitespace())
        .filter(|t| !t.is_empty())
}

/// The part of a line before a comment character.
pub(super) fn strip_comment(line: &[u8], comment: u8) -> &[u8] {
    match line.iter().position(|&c| c == comment) {
        Some(p) => &line[..p],
        None => line,
    }
}

pub(super) fn show(tok: &[u8]) -> String {
    let s = String::from_utf8_lossy(tok);
    if s.chars().count() > 40 {
        format!("{}...", s.chars().take(40).collect::<String>())
    } else {
        s.into_owned()
    }
}

pub(super) fn parse_f64(tok: &[u8]) -> Option<f64> {
    std::str::from_utf8(tok).ok()?.parse().ok()
}

pub(super) fn parse_u64(tok: &[u8]) -> Option<u64> {
    std::str::from_utf8(tok).ok()?.parse().ok()
}

/// Three coordinates from the first three tokens, which must be finite numbers within
/// ±[`MAX_COORDINATE`](crate::mesh::MAX_COORDINATE).
pub(super) fn parse_point<'a>(
    toks: &mut impl Iterator<Item = &'a [u8]>,
    line: usize,
) -> std::result::Result<DVec3, String> {
    let mut p = [0.0; 3];
    for x in &mut p {
        let tok = toks
            .next()
            .ok_or_else(|| format!("line {line}: expected three coordinates"))?;
        *x = parse_f64(tok)
            .ok_or_else(|| format!("line {line}: `{}` is not a number", show(tok)))?;
        if let Some(problem) = crate::mesh::coordinate_problem(*x) {
            return Err(format!("line {line}: coordinate `{}` {problem}", show(tok)));
        }
    }
    Ok(DVec3::from_array(p))
}
