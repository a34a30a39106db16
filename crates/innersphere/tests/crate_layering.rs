//! The library's modules import one way, down a ladder: pose ← error ← output, progress ←
//! mesh ← shapes, anatomy, input ← tree ← field ← packing ← hierarchy ← build, exact ← query,
//! contact_map, splint ← haptic
//! (`tree` is the finished tree's type and file, below the pipeline stages that make it). Reads
//! every `crate::…` path in the sources (outside their `#[cfg(test)]` modules, which may
//! build fixtures from a higher layer) and fails on an import from a layer above, or through
//! the crate root's re-exports (`crate::Pose`), which would hide what depends on what.

use std::path::{Path, PathBuf};

/// The layer of a top-level module of the crate.
fn layer(module: &str) -> Option<u32> {
    Some(match module {
        "pose" => 0,
        "error" => 1,
        "output" | "progress" => 2,
        "mesh" => 3,
        "shapes" | "anatomy" | "input" => 4,
        "tree" => 5,
        "field" => 6,
        "packing" => 7,
        "hierarchy" => 8,
        "build" | "exact" => 9,
        "contact_map" => 10,
        "query" | "splint" => 10,
        "haptic" => 11,
        _ => return None,
    })
}

fn files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

#[test]
fn modules_import_down_the_ladder_by_their_own_paths() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut all = vec![];
    files(&src, &mut all);
    let mut wrong = vec![];
    for p in &all {
        let rel = p
            .strip_prefix(&src)
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
    assert!(
        wrong.is_empty(),
        "{} imports against the ladder:\n{}",
        wrong.len(),
        wrong.join("\n")
    );
}
