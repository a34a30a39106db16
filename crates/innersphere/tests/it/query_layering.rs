//! `query/`'s imports run one way: kernel ← search (descents, fronts) ← query kinds ← pair.
//! Reads every `use` of the module's source files (tests inside them included) and checks
//! that no file imports from a layer above its own, and that the kinds, which may use a
//! sibling's types, import no cycle.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Layer of a file of `query/` by its path relative to `query/` (without `.rs`).
fn layer(module: &str) -> u32 {
    match module.split('/').next().unwrap() {
        "kernel" => 0,
        "search" => 1,
        "pair" => 3,
        "mod" => 4,
        _ => 2,
    }
}

/// `query/`'s module of file `p` (`kernel/mod.rs` → `kernel`, `search/front.rs` →
/// `search/front`).
fn module_of(root: &Path, p: &Path) -> String {
    let rel = p.strip_prefix(root).unwrap().with_extension("");
    let s = rel.to_string_lossy().replace('\\', "/");
    s.strip_suffix("/mod").map(str::to_string).unwrap_or(s)
}

/// The `query/` modules a file imports: every `super::…` and `crate::query::…` path in its
/// `use` lines and paths, resolved to a module of `query/` (the longest prefix that is a
/// file).
fn imports(module: &str, text: &str, known: &BTreeSet<String>) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    // The directory the file's `super` refers to.
    let parts: Vec<&str> = module.split('/').collect();
    // In `a/b.rs` and in `a/b/mod.rs` alike, `super` is `a`.
    let parent: Vec<&str> = parts[..parts.len() - 1].to_vec();
    let resolve = |path: Vec<&str>| -> Option<String> {
        for n in (1..=path.len()).rev() {
            let m = path[..n].join("/");
            if known.contains(&m) {
                return Some(m);
            }
        }
        None
    };
    for (i, _) in text.match_indices("crate::query::") {
        let rest = &text[i + "crate::query::".len()..];
        let path: Vec<&str> = rest
            .split(|c: char| !(c.is_alphanumeric() || c == '_' || c == ':'))
            .next()
            .unwrap()
            .split("::")
            .filter(|s| !s.is_empty())
            .collect();
        if let Some(m) = resolve(path) {
            out.insert(m);
        }
    }
    for (i, _) in text.match_indices("super::") {
        // Only paths that start with `super::` (not `self::super::` inside a word).
        if text[..i].ends_with(|c: char| c.is_alphanumeric() || c == '_' || c == ':') {
            continue;
        }
        let rest = &text[i..];
        let segs: Vec<&str> = rest
            .split(|c: char| !(c.is_alphanumeric() || c == '_' || c == ':'))
            .next()
            .unwrap()
            .split("::")
            .filter(|s| !s.is_empty())
            .collect();
        let mut base = parent.clone();
        let mut k = 0;
        while k < segs.len() && segs[k] == "super" {
            if k > 0 {
                base.pop();
            }
            k += 1;
        }
        // `super::x` inside a `mod tests` of the same file refers to the file itself.
        if segs.get(k).is_none() || segs[k] == "*" {
            continue;
        }
        let mut path = base.clone();
        path.extend(&segs[k..]);
        if let Some(m) = resolve(path) {
            out.insert(m);
        }
    }
    out.remove(module);
    out
}

#[test]
fn query_imports_run_one_way() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("src/query");
    let mut paths = Vec::new();
    innersphere_testkit::layering::files(&root, &mut paths);
    let known: BTreeSet<String> = paths.iter().map(|p| module_of(&root, p)).collect();
    assert!(known.contains("kernel") && known.contains("pair") && known.contains("search"));
    let mut graph: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    let mut bad = Vec::new();
    for p in &paths {
        let m = module_of(&root, p);
        let text = std::fs::read_to_string(p).unwrap();
        let deps = imports(&m, &text, &known);
        for d in &deps {
            // A directory's `mod.rs` declares its children: not an import.
            if d.starts_with(&format!("{m}/")) {
                continue;
            }
            if layer(d) > layer(&m) {
                bad.push(format!(
                    "{m} (layer {}) imports {d} (layer {})",
                    layer(&m),
                    layer(d)
                ));
            }
        }
        graph.insert(m, deps);
    }
    assert!(
        bad.is_empty(),
        "imports against the layering:\n{}",
        bad.join("\n")
    );
    // No cycle among files (depth-first search with colours).
    fn visit(
        m: &str,
        g: &BTreeMap<String, BTreeSet<String>>,
        state: &mut BTreeMap<String, u8>,
        stack: &mut Vec<String>,
    ) -> Option<Vec<String>> {
        match state.get(m) {
            Some(1) => {
                let i = stack.iter().position(|x| x == m).unwrap();
                let mut c = stack[i..].to_vec();
                c.push(m.to_string());
                return Some(c);
            }
            Some(2) => return None,
            _ => {}
        }
        state.insert(m.to_string(), 1);
        stack.push(m.to_string());
        for d in g.get(m).into_iter().flatten() {
            // Parent → child declarations are not imports.
            if d.starts_with(&format!("{m}/")) {
                continue;
            }
            if let Some(c) = visit(d, g, state, stack) {
                return Some(c);
            }
        }
        stack.pop();
        state.insert(m.to_string(), 2);
        None
    }
    let mut state = BTreeMap::new();
    for m in graph.keys() {
        if let Some(c) = visit(m, &graph, &mut state, &mut Vec::new()) {
            panic!("import cycle in query/: {}", c.join(" → "));
        }
    }
}
