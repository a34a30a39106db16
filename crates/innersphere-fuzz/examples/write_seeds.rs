//! Writes the generated seeds of every target ([`innersphere_fuzz::seeds`]) into
//! `fuzz/corpus/<target>/seed-<n>` (beside this crate's manifest), where
//! `cargo fuzz run <target>` starts from them:
//!
//! ```sh
//! cargo run -p innersphere-fuzz --example write_seeds [TARGET ...]
//! ```
//!
//! With names, only those targets' seeds are written.

use std::path::Path;

fn main() -> std::io::Result<()> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fuzz")
        .join("corpus");
    let only: Vec<String> = std::env::args().skip(1).collect();
    for (name, _) in innersphere_fuzz::TARGETS {
        if !only.is_empty() && !only.iter().any(|o| o == name) {
            continue;
        }
        let dir = root.join(name);
        std::fs::create_dir_all(&dir)?;
        let seeds = innersphere_fuzz::seeds::seeds(name);
        for (i, s) in seeds.iter().enumerate() {
            std::fs::write(dir.join(format!("seed-{i}")), s)?;
        }
        println!("{name}: {} seeds in {}", seeds.len(), dir.display());
    }
    Ok(())
}
