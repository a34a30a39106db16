//! Teeth-axes files read within their limit, measured by the peak of live heap bytes.

use innersphere_testkit::peak::{alone, fifo, measured, Peak, MIB};
use std::path::{Path, PathBuf};
use std::time::Duration;

#[global_allocator]
static GLOBAL: Peak = Peak;

fn tmp(name: &str) -> PathBuf {
    Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("teeth_limits_{}_{name}", std::process::id()))
}

/// Teeth-axes files (`ist occlusion-map --teeth-a/-b`, `ist view`, `ist occlude
/// --landmarks`): devices, a sparse 100 MB file and a FIFO of endless JSON-like text are
/// refused after at most the 1 MiB limit (plus a 64 KiB chunk), naming the limit.
#[test]
fn teeth_files_are_read_within_their_limit() {
    use innersphere_dental::contact_map::Teeth;
    let _alone = alone();
    let sparse = tmp("sparse.json");
    std::fs::File::create(&sparse)
        .unwrap()
        .set_len(100 * MIB as u64)
        .unwrap();
    let mut cases: Vec<(PathBuf, usize)> = vec![(sparse.clone(), MIB / 4)];
    for dev in ["/dev/zero", "/dev/urandom"] {
        if Path::new(dev).exists() {
            cases.push((PathBuf::from(dev), MIB / 4));
        }
    }
    for (path, most) in cases {
        let (r, peak, time) = measured(|| Teeth::load(&path));
        let e = r.unwrap_err().to_string();
        assert!(e.contains("1048576"), "{}: {e}", path.display());
        assert!(peak < most, "{}: {peak} bytes at the peak", path.display());
        assert!(
            time < Duration::from_secs(1),
            "{}: {time:?}",
            path.display()
        );
    }
    std::fs::remove_file(&sparse).ok();
    // A pipe of text that never ends: read up to the limit, not beyond.
    let pipe = tmp("pipe.json");
    if let Some(writer) = fifo(&pipe, b"{\"1\": {\"c\": [1, 2, 3]}, ", 300 * MIB) {
        let (r, peak, _) = measured(|| Teeth::load(&pipe));
        writer.join().unwrap();
        std::fs::remove_file(&pipe).ok();
        let e = r.unwrap_err().to_string();
        assert!(
            e.contains("larger than the 1048576-byte (1 MiB) limit"),
            "{e}"
        );
        assert!(
            peak < 4 * MIB,
            "{} MiB at the peak",
            peak as f64 / MIB as f64
        );
    }
}
