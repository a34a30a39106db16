//! Every query of the library's `Pair` reaches every door: the C ABI (`include/innersphere.h`),
//! the Python module (its stubs, which `mypy.stubtest` checks against the module in CI) and
//! `ist query --query`. The queries are read from `Pair`'s own source, so that a new kind
//! cannot be added to the library and forgotten at a door.

use std::process::Command;

fn read(rel: &str) -> String {
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/../..");
    std::fs::read_to_string(format!("{root}/{rel}")).unwrap_or_else(|e| panic!("{rel}: {e}"))
}

/// Methods of `Pair` that take both poses but are measuring instruments, not collision
/// queries: the penetration query's output-sensitive floor (its overlapping leaf pairs, and
/// its answer summed over given leaf pairs with no search), for `benches/queries.rs`. They
/// answer nothing `penetration` does not (the same sums, found slower in all), so they stay
/// in the library.
const INSTRUMENTS: [&str; 2] = ["overlapping_leaves", "penetration_of_leaves"];

/// The query kinds of `Pair` (and of `pair.paper()`): its public methods that take `&mut
/// self` and both poses, an options variant (`…_with`) counted as its kind.
fn kinds() -> Vec<String> {
    let src = read("crates/innersphere/src/query/pair.rs");
    let mut out: Vec<String> = vec![];
    let mut rest = src.as_str();
    while let Some(i) = rest.find("pub fn ") {
        rest = &rest[i + "pub fn ".len()..];
        let name: String = rest
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect();
        let sig = &rest[..rest.find('{').unwrap_or(rest.len())];
        if sig.contains("&mut self")
            && sig.contains("pose_a: &Pose")
            && sig.contains("pose_b: &Pose")
        {
            let kind = name.strip_suffix("_with").unwrap_or(&name).to_string();
            if !out.contains(&kind) {
                out.push(kind);
            }
        }
    }
    out
}

#[test]
fn every_query_of_pair_reaches_c_python_and_ist_query() {
    let kinds = kinds();
    for k in [
        "distance",
        "contact",
        "multipoint",
        "penetration",
        "penetration_within",
        "distance_traversal",
        "backtracking",
    ] {
        assert!(
            kinds.iter().any(|x| x == k),
            "{k} not found in Pair: {kinds:?}"
        );
    }
    let header = read("include/innersphere.h");
    let stubs = read("crates/innersphere-py/python/innersphere/_innersphere.pyi");
    let help = Command::new(env!("CARGO_BIN_EXE_ist"))
        .args(["query", "--help"])
        .output()
        .expect("ist runs");
    let help = String::from_utf8_lossy(&help.stdout);
    let mut missing = vec![];
    for k in kinds.iter().filter(|k| !INSTRUMENTS.contains(&k.as_str())) {
        if !header.contains(&format!(" ist_{k}(")) {
            missing.push(format!("C: ist_{k}"));
        }
        if !stubs.contains(&format!("def {k}(")) {
            missing.push(format!("Python: Pair.{k}"));
        }
        if !help.contains(&format!("- {}:", k.replace('_', "-"))) {
            missing.push(format!("ist query --query {}", k.replace('_', "-")));
        }
    }
    assert!(
        missing.is_empty(),
        "queries of Pair missing at a door: {missing:?}"
    );
}

/// The planning tools of the dental crate (offline: meshes in, files and measurements out) reach
/// `ist` and the Python module. Not the C ABI: a C or C++ program links the library for its
/// servo loop and queries; the planning tools read and write files and take seconds, and a C
/// program runs `ist` for them (its JSON is the interface).
#[test]
fn every_planning_tool_reaches_ist_and_python() {
    let stubs = read("crates/innersphere-py/python/innersphere/_innersphere.pyi");
    let lib = read("crates/innersphere-dental/src/lib.rs");
    let help = Command::new(env!("CARGO_BIN_EXE_ist"))
        .arg("--help")
        .output()
        .expect("ist runs");
    let help = String::from_utf8_lossy(&help.stdout);
    // (library module, ist subcommand, Python function)
    for (module, cmd, py) in [
        ("contact_map", "occlusion-map", "contact_map"),
        ("splint", "splint", "splint"),
        ("bite", "occlude", "occlude"),
        ("case", "plan", "plan"),
    ] {
        assert!(lib.contains(&format!("pub mod {module};")), "{module}");
        assert!(help.contains(&format!("  {cmd} ")), "ist {cmd} missing");
        assert!(stubs.contains(&format!("def {py}(")), "Python {py} missing");
    }
}

/// Every batch of the library (`query::batch`'s `…_many`) reaches the C ABI, the Python
/// module and `ist bench batch --query`. Read from the batch module's source.
#[test]
fn every_batch_reaches_c_python_and_ist_bench_batch() {
    let src = read("crates/innersphere/src/query/batch.rs");
    let header = read("include/innersphere.h");
    let stubs = read("crates/innersphere-py/python/innersphere/_innersphere.pyi");
    let bench = read("crates/innersphere-eval/src/bench.rs");
    let batches: Vec<&str> = src
        .split("pub fn ")
        .skip(1)
        .map(|s| s.split('(').next().unwrap_or(""))
        .filter(|n| n.ends_with("_many"))
        .collect();
    assert_eq!(batches.len(), 5, "{batches:?}");
    for k in batches {
        assert!(header.contains(&format!(" ist_{k}(")), "C: ist_{k}");
        assert!(stubs.contains(&format!("def {k}(")), "Python: Pair.{k}");
        let kind = k.trim_end_matches("_many").replace('_', "-");
        assert!(
            bench.contains(&format!("\"{kind}\" =>")) && bench.contains(&format!("batch::{k}(")),
            "ist bench batch --query {kind}"
        );
    }
}
