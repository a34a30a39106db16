//! The real-data folder beside the repository.

use std::path::PathBuf;

/// The real-data folder `../shared/data` beside the repository (or `$INNERSPHERE_DATA`).
///
/// Tests on real data are `#[ignore]`d so that `cargo test` passes on a user's fresh clone;
/// `.ci/run` runs them with `--ignored`, and then a missing folder fails loudly here.
pub fn data_dir() -> PathBuf {
    let dir = std::env::var_os("INNERSPHERE_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data"));
    assert!(
        dir.join("README.md").is_file(),
        "real test data is missing: expected ../shared/data beside the repository (or set INNERSPHERE_DATA); looked in {}",
        dir.display()
    );
    dir
}

/// A file below the real-data folder.
pub fn data(rel: &str) -> PathBuf {
    let p = data_dir().join(rel);
    assert!(p.is_file(), "real test file is missing: {}", p.display());
    p
}
