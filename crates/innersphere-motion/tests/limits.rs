//! Motion files are read within their limit ([`innersphere_motion::csv::MAX_FILE_BYTES`], through
//! `innersphere::input`): a device, a sparse file larger than the limit and a gzip file of
//! zeros are refused after one 64 KiB chunk, naming the limit; the bytes allocated are
//! counted by the workspace's counting allocator.

use innersphere_motion::Motion;
use innersphere_testkit::alloc::{counted, Counting};
use std::io::Write;
use std::path::{Path, PathBuf};

#[global_allocator]
static A: Counting = Counting;

const MIB: u64 = 1 << 20;

fn tmp(name: &str) -> PathBuf {
    Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("motion_limits_{}_{name}", std::process::id()))
}

/// Loads `path`; the error's text and the bytes allocated on the way.
fn refused(path: &Path) -> (String, u64) {
    let (_, bytes, r) = counted(|| Motion::load(path));
    (r.unwrap_err().to_string(), bytes)
}

#[test]
fn devices_large_files_and_zeros_are_refused_in_little_memory() {
    let sparse = tmp("sparse.csv");
    std::fs::File::create(&sparse)
        .unwrap()
        .set_len(100 * MIB)
        .unwrap();
    let (e, bytes) = refused(&sparse);
    assert!(e.contains("1073741824"), "{e}");
    assert!(bytes < MIB, "{bytes} bytes");
    std::fs::remove_file(&sparse).ok();
    // Beyond the limit: refused before reading.
    let big = tmp("big.csv");
    std::fs::File::create(&big)
        .unwrap()
        .set_len(innersphere_motion::csv::MAX_FILE_BYTES + 1)
        .unwrap();
    let (e, bytes) = refused(&big);
    assert!(
        e.contains("more than the 1073741824-byte (1 GiB) limit for a motion file"),
        "{e}"
    );
    assert!(bytes < MIB, "{bytes} bytes");
    std::fs::remove_file(&big).ok();
    // 200 MB of zeros, gzip-compressed.
    let gz = tmp("zeros.csv.gz");
    let mut enc = flate2::write::GzEncoder::new(
        std::fs::File::create(&gz).unwrap(),
        flate2::Compression::fast(),
    );
    let block = vec![0u8; MIB as usize];
    for _ in 0..200 {
        enc.write_all(&block).unwrap();
    }
    enc.finish().unwrap();
    let (e, bytes) = refused(&gz);
    assert!(e.contains("1 GiB"), "{e}");
    assert!(bytes < 2 * MIB, "{bytes} bytes");
    std::fs::remove_file(&gz).ok();
    for dev in ["/dev/zero", "/dev/urandom"] {
        if Path::new(dev).exists() {
            let (e, bytes) = refused(Path::new(dev));
            assert!(e.contains("1 GiB"), "{dev}: {e}");
            assert!(bytes < MIB, "{dev}: {bytes} bytes");
        }
    }
}
