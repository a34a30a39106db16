//! The Python suite run against the extension module this `cargo test` just built: the
//! mutation-testing harness of `docs/TESTING.md`. cargo-mutants mutates this crate's Rust and
//! runs `cargo test`, but the crate's tests are in Python (`tests/*.py`). `cargo test` does
//! not build a cdylib, so this test builds it (`cargo build --lib`, same profile and target
//! folder), puts it beside the package's Python sources in a folder of its own and runs
//! pytest there.
//!
//! Ignored by default (CI runs the suite through `ci.sh`, on the wheel maturin builds). Run
//! it with `cargo test --test python_suite -- --ignored` and, in the environment:
//! `INNERSPHERE_PYTHON` a Python with pytest, numpy and trimesh (and dask for the distributed
//! tests), `IST_BIN` the `ist` the parity tests compare with, optionally
//! `INNERSPHERE_PYTEST_ARGS` (extra pytest arguments, split at spaces, e.g. `-k haptic`).

use std::path::PathBuf;
use std::process::Command;

#[test]
#[ignore = "the mutation harness: needs INNERSPHERE_PYTHON (a Python with pytest) and IST_BIN"]
fn the_python_suite_passes_against_this_build() {
    let python = std::env::var("INNERSPHERE_PYTHON")
        .expect("INNERSPHERE_PYTHON: a Python with pytest, numpy and trimesh");
    let manifest = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    // This test runs from <target>/<profile>/deps/; cargo builds the cdylib in <profile>.
    let exe = std::env::current_exe().unwrap();
    let profile = exe.parent().and_then(|d| d.parent()).unwrap();
    let name = profile.file_name().unwrap().to_str().unwrap();
    let cargo_profile = if name == "debug" { "dev" } else { name };
    let built = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()))
        .current_dir(&manifest)
        .env("CARGO_TARGET_DIR", profile.parent().unwrap())
        .args(["build", "--lib", "--profile", cargo_profile])
        .status()
        .expect("running cargo build");
    assert!(built.success(), "cargo build --lib failed: {built}");
    let lib = [
        "lib_innersphere.so",
        "lib_innersphere.dylib",
        "_innersphere.dll",
    ]
    .iter()
    .map(|n| profile.join(n))
    .find(|p| p.exists())
    .unwrap_or_else(|| panic!("no lib_innersphere built in {}", profile.display()));
    let site = profile.join("python-suite");
    let package = site.join("innersphere");
    let _ = std::fs::remove_dir_all(&site);
    std::fs::create_dir_all(&package).unwrap();
    for entry in std::fs::read_dir(manifest.join("python/innersphere")).unwrap() {
        let path = entry.unwrap().path();
        std::fs::copy(&path, package.join(path.file_name().unwrap())).unwrap();
    }
    let module = if cfg!(windows) {
        "_innersphere.pyd"
    } else {
        "_innersphere.abi3.so"
    };
    std::fs::copy(&lib, package.join(module)).unwrap();
    let extra = std::env::var("INNERSPHERE_PYTEST_ARGS").unwrap_or_default();
    let status = Command::new(python)
        .current_dir(&manifest)
        .env("PYTHONPATH", &site)
        .env("PYTHONDONTWRITEBYTECODE", "1")
        // The local batches' tests only: the cluster's worker processes hung under this
        // harness, and the Rust they reach is the batch calls the local tests cover.
        .env("INNERSPHERE_NO_CLUSTER", "1")
        .args([
            "-m",
            "pytest",
            "-x",
            "-q",
            "-p",
            "no:cacheprovider",
            "tests",
        ])
        .args(extra.split_whitespace())
        .status()
        .expect("running pytest");
    assert!(status.success(), "the Python suite failed: {status}");
}
