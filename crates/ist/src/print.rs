//! How `ist` prints: JSON on stdout, numbers in short form, the units line of the
//! human-readable output, and an error with its causes on one line.

/// What "units" means in the human-readable output: the library never converts lengths.
pub const UNITS: &str =
    "lengths in model units (the mesh file's own unit: mm for the jaw scans), volumes in units³";

/// `x` with at most 6 significant digits and no trailing zeros (0.1, 0.005208, 1.5e-7).
pub fn short(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return x.to_string();
    }
    let magnitude = x.abs().log10().floor();
    if !(-4.0..=9.0).contains(&magnitude) {
        return format!("{x:.5e}");
    }
    let decimals = (5.0 - magnitude).max(0.0) as usize;
    let text = format!("{x:.decimals$}");
    if text.contains('.') {
        text.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        text
    }
}

/// Prints `value` as pretty JSON on stdout, always ending with a newline (so that
/// `ist ... --json > f.json` gives a complete text file and shells print the prompt on a
/// new line).
pub fn print_json(value: &impl serde::Serialize) -> anyhow::Result<()> {
    use std::io::Write;
    let mut text = serde_json::to_string_pretty(value)?;
    text.push('\n');
    let mut out = std::io::stdout().lock();
    out.write_all(text.as_bytes())?;
    out.flush()?;
    Ok(())
}

/// The error and its causes on one line, each cause once: the library's I/O error already
/// shows its source ("a.ist: No such file or directory"), so a cause whose text the line
/// already holds is not repeated.
pub fn error_text(e: &anyhow::Error) -> String {
    let mut text = String::new();
    for cause in e.chain() {
        let c = cause.to_string();
        if text.contains(&c) {
            continue;
        }
        if !text.is_empty() {
            text += ": ";
        }
        text += &c;
    }
    text
}
