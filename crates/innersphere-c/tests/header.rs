//! The committed header `include/innersphere.h` is what cbindgen makes of this crate now:
//! a change to the C ABI that forgets the header fails here. `INNERSPHERE_BLESS_HEADER=1`
//! writes the fresh header instead. Built with `--features header` only (CI runs it).

use std::path::Path;

#[test]
fn the_committed_header_is_current() {
    let crate_dir = env!("CARGO_MANIFEST_DIR");
    let config = cbindgen::Config::from_file(Path::new(crate_dir).join("cbindgen.toml")).unwrap();
    let mut fresh = Vec::new();
    cbindgen::Builder::new()
        .with_crate(crate_dir)
        .with_config(config)
        .generate()
        .expect("cbindgen")
        .write(&mut fresh);
    let path = Path::new(crate_dir).join("../../include/innersphere.h");
    if std::env::var_os("INNERSPHERE_BLESS_HEADER").is_some() {
        std::fs::write(&path, &fresh).unwrap();
        return;
    }
    let committed = std::fs::read(&path).unwrap_or_default();
    assert!(
        committed == fresh,
        "include/innersphere.h is stale: regenerate it with \
         `INNERSPHERE_BLESS_HEADER=1 cargo test -p innersphere-c --features header --test header` and commit it"
    );
}
