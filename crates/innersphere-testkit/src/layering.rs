//! The module ladder of a crate: each top-level module on a rung, imports (`crate::…` paths)
//! only from its own rung or below. Each library crate's `tests/crate_layering.rs` gives its
//! ladder.

use std::path::{Path, PathBuf};

/// Every `.rs` file under `dir`, appended to `out`.
pub fn files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// The imports of the crate whose sources are in `src` against the module ladder `layer`
/// (a top-level module's rung; `None` for none): one line per `crate::` path that climbs,
/// goes through the crate root's re-exports or names a module with no rung. Code after a
/// file's first `#[cfg(test)]` is not read (tests may build fixtures from a higher rung).
pub fn imports_against_the_ladder(src: &Path, layer: impl Fn(&str) -> Option<u32>) -> Vec<String> {
    let mut all = vec![];
    files(src, &mut all);
    let mut wrong = vec![];
    for p in &all {
        let rel = p
            .strip_prefix(src)
            .unwrap()
            .to_string_lossy()
            .replace('\\', "/");
        if rel == "lib.rs" {
            continue;
        }
        let top = rel.split('/').next().unwrap().trim_end_matches(".rs");
        let own = layer(top).unwrap_or_else(|| panic!("{rel}: module {top} has no layer"));
        let text = std::fs::read_to_string(p).unwrap();
        let code = text.split("#[cfg(test)]").next().unwrap();
        for (n, line) in code.lines().enumerate() {
            if line.trim_start().starts_with("//") {
                continue;
            }
            for (i, _) in line.match_indices("crate::") {
                let rest = &line[i + "crate::".len()..];
                let name: String = rest
                    .chars()
                    .take_while(|c| c.is_alphanumeric() || *c == '_')
                    .collect();
                let at = format!("{rel}:{}", n + 1);
                if name.starts_with(|c: char| c.is_ascii_uppercase()) || name.is_empty() {
                    wrong.push(format!("{at}: crate::{name} through the crate root"));
                    continue;
                }
                match layer(&name) {
                    Some(l) if l > own => {
                        wrong.push(format!("{at}: {top} imports {name}, a higher layer"))
                    }
                    None => wrong.push(format!("{at}: crate::{name} is no module with a layer")),
                    _ => {}
                }
            }
        }
    }
    wrong
}

/// Fails with every import of the crate at `manifest_dir` (its `src/`) that climbs its ladder
/// `layer` ([`imports_against_the_ladder`]).
pub fn assert_imports_down_the_ladder(manifest_dir: &str, layer: impl Fn(&str) -> Option<u32>) {
    let src = Path::new(manifest_dir).join("src");
    let wrong = imports_against_the_ladder(&src, layer);
    assert!(
        wrong.is_empty(),
        "{} imports against the ladder:\n{}",
        wrong.len(),
        wrong.join("\n")
    );
}
