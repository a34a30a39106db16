//! Replays every generated seed, every file of the minimised fuzz corpus
//! (`fuzz/corpus/<target>/`) and every crash the fuzzer found (`regressions/<target>/`)
//! through its target function: what CI runs of the fuzzing, on the stable toolchain.
//! Failures are collected over all files and reported together, each with its path.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};

use innersphere_fuzz::{seeds, Target, TARGETS};

fn files(dir: &Path) -> Vec<PathBuf> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    let mut v: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_file())
        .collect();
    v.sort();
    v
}

/// Runs `target` on `input`; the panic message if it panicked.
fn run(target: Target, input: &[u8]) -> Option<String> {
    let r = catch_unwind(AssertUnwindSafe(|| target(input)));
    r.err().map(|e| {
        e.downcast_ref::<String>()
            .cloned()
            .or_else(|| e.downcast_ref::<&str>().map(|s| s.to_string()))
            .unwrap_or_else(|| "a panic without a message".into())
    })
}

fn crate_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Replays the files under `sub/<target>/` of every target, and the seeds when asked;
/// returns (inputs run, failures).
fn replay(sub: &str, with_seeds: bool) -> (usize, Vec<String>) {
    let mut count = 0;
    let mut failures = Vec::new();
    for &(name, target) in TARGETS {
        let seeds = if with_seeds {
            seeds::seeds(name)
        } else {
            Vec::new()
        };
        for (i, s) in seeds.iter().enumerate() {
            count += 1;
            if let Some(m) = run(target, s) {
                failures.push(format!("{name} seed {i}: {m}"));
            }
        }
        for path in files(&crate_dir().join(sub).join(name)) {
            // A file a running fuzzer has just replaced is gone: skip it.
            let bytes = match std::fs::read(&path) {
                Ok(b) => b,
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => continue,
                Err(e) => panic!("{}: {e}", path.display()),
            };
            count += 1;
            if let Some(m) = run(target, &bytes) {
                failures.push(format!("{name} {}: {m}", path.display()));
            }
        }
    }
    (count, failures)
}

#[test]
fn every_target_has_seeds_and_a_corpus() {
    for (name, _) in TARGETS {
        assert!(!seeds::seeds(name).is_empty(), "{name} has no seeds");
        let corpus = files(&crate_dir().join("fuzz/corpus").join(name));
        assert!(
            !corpus.is_empty(),
            "{name} has no corpus in fuzz/corpus/{name}"
        );
    }
}

#[test]
fn the_corpus_replays_without_failure() {
    let (count, failures) = replay("fuzz/corpus", true);
    eprintln!("replayed {count} seeds and corpus files");
    assert!(
        failures.is_empty(),
        "{} of {count} inputs failed:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

#[test]
fn every_crash_found_replays_without_failure() {
    let (_, failures) = replay("regressions", false);
    assert!(
        failures.is_empty(),
        "{} crashes are back:\n{}",
        failures.len(),
        failures.join("\n")
    );
}
