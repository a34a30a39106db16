//! The library's modules import one way, down a ladder: pose ← error ← output, progress ←
//! mesh ← shapes, input ← tree ← field ← packing ← hierarchy ← build, exact ← query
//! (`tree` is the finished tree's type and file, below the pipeline stages that make it). Reads
//! every `crate::…` path in the sources (outside their `#[cfg(test)]` modules, which may
//! build fixtures from a higher layer) and fails on an import from a layer above, or through
//! the crate root's re-exports (`crate::Pose`), which would hide what depends on what.

use std::path::Path;

/// The layer of a top-level module of the crate.
fn layer(module: &str) -> Option<u32> {
    Some(match module {
        "pose" => 0,
        "error" => 1,
        "output" | "progress" => 2,
        "mesh" => 3,
        "shapes" | "input" => 4,
        "tree" => 5,
        "field" => 6,
        "packing" => 7,
        "hierarchy" => 8,
        "build" | "exact" => 9,
        "query" => 10,
        // The unit tests that need the internal stages (`src/tests/`) sit above everything.
        "tests" => 11,
        _ => return None,
    })
}

#[test]
fn modules_import_down_the_ladder_by_their_own_paths() {
    innersphere_testkit::layering::assert_imports_down_the_ladder(
        env!("CARGO_MANIFEST_DIR"),
        layer,
    );
}

/// The workspace's crates depend one way: the core (`innersphere`) ← `innersphere-haptic` ←
/// `innersphere-dental` ← `innersphere-motion` ← the doors and tools (`ist`, the C ABI,
/// Python, the viewer, eval, fuzz). Reads every crate's `Cargo.toml` (normal, build and
/// target dependencies; dev-dependencies may reach up, as a test of a lower crate may use
/// a test helper) and fails on a dependency on a crate of the same or a higher rung.
#[test]
fn crates_depend_down_the_ladder() {
    fn rung(name: &str) -> Option<u32> {
        Some(match name {
            "innersphere" => 0,
            "innersphere-haptic" => 1,
            "innersphere-dental" => 2,
            "innersphere-motion" => 3,
            "innersphere-testkit" => 4,
            "innersphere-eval" | "innersphere-view" => 5,
            "ist" | "innersphere-c" | "innersphere-py" | "innersphere-fuzz" => 6,
            _ => return None,
        })
    }
    let crates = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut wrong = vec![];
    let mut seen = 0;
    for e in std::fs::read_dir(&crates).unwrap() {
        let manifest = e.unwrap().path().join("Cargo.toml");
        let Ok(text) = std::fs::read_to_string(&manifest) else {
            continue;
        };
        let name = text
            .lines()
            .find_map(|l| l.strip_prefix("name = \""))
            .map(|n| n.trim_end_matches('"').to_string())
            .unwrap();
        let Some(own) = rung(&name) else {
            wrong.push(format!("{name}: a crate with no rung"));
            continue;
        };
        seen += 1;
        let mut section = String::new();
        for line in text.lines() {
            let line = line.trim();
            if line.starts_with('[') {
                section = line.to_string();
                continue;
            }
            let normal = section == "[dependencies]"
                || section == "[build-dependencies]"
                || (section.starts_with("[target.") && section.ends_with(".dependencies]"));
            let dep: String = line
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '-' || *c == '_')
                .collect();
            if let (true, Some(r)) = (normal, rung(&dep)) {
                if r >= own && dep != name {
                    wrong.push(format!(
                        "{name} depends on {dep}, a rung at or above its own"
                    ));
                }
            }
        }
    }
    assert!(
        seen >= 3,
        "found only {seen} crates under {}",
        crates.display()
    );
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
}
