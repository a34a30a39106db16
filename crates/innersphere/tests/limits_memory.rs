//! Bounded memory on any input file (`docs/RELIABILITY.md`, "Limits"): a gzip bomb, a huge
//! file of zeros given as a mesh or a tree, `/dev/zero` as a tree, and a pipe that lies about
//! its size are refused fast, having allocated a small fraction of their size.
//!
//! The peak of live heap bytes is measured by a counting global allocator, which counts every
//! thread's allocations: each test holds a lock from its first line to its last (its setup
//! allocates too), so that one test's peak never includes another's.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Duration;

use innersphere::{Error, Mesh, SphereTree};

use innersphere_testkit::peak::{alone, fifo, measured, Peak, MIB};

#[global_allocator]
static GLOBAL: Peak = Peak;

fn tmp(name: &str) -> PathBuf {
    Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("limits_memory_{}_{name}", std::process::id()))
}

/// Writes `bytes` bytes of `fill` gzip-compressed (level 1, like `gzip -1`), streaming.
fn write_gzip_of(path: &Path, fill: u8, bytes: usize) {
    let file = std::fs::File::create(path).unwrap();
    let mut enc =
        flate2::write::GzEncoder::new(std::io::BufWriter::new(file), flate2::Compression::fast());
    let block = vec![fill; MIB];
    for _ in 0..bytes / MIB {
        enc.write_all(&block).unwrap();
    }
    enc.finish().unwrap().flush().unwrap();
}

fn parse_message(r: innersphere::Result<Mesh>) -> String {
    match r {
        Err(Error::Parse { message, .. }) => message,
        other => panic!("expected a parse error, got {other:?}"),
    }
}

#[test]
fn a_gzip_bomb_is_refused_fast_in_little_memory() {
    let _alone = alone();
    // 300 MB of zeros, 1.3 MB compressed: as STL, its header declares 0 triangles, so reading
    // stops after the first 64 KiB; as OBJ, its first NUL byte stops it there too. 300 MB of
    // spaces as OBJ is text with no header to go by: the ratio limit stops it at 64 MiB of
    // output.
    for (name, fill, needle, most) in [
        ("bomb.stl.gz", 0, "0 triangles", 4 * MIB),
        ("bomb.obj.gz", 0, "byte 0 is a NUL byte", 4 * MIB),
        ("spaces.obj.gz", b' ', "gzip bomb", 100 * MIB),
    ] {
        let path = tmp(name);
        write_gzip_of(&path, fill, 300 * MIB);
        let (r, peak, time) = measured(|| Mesh::load(&path));
        std::fs::remove_file(&path).ok();
        let m = parse_message(r);
        assert!(m.contains(needle), "{name}: {m}");
        assert!(
            peak < most,
            "{name}: {} MiB at the peak",
            peak as f64 / MIB as f64
        );
        assert!(time < Duration::from_secs(5), "{name}: {time:?}");
    }
}

#[test]
fn a_large_file_of_zeros_is_refused_before_it_is_read() {
    let _alone = alone();
    // Sparse 300 MB files: cheap to make, and read as zeros.
    for name in ["zeros.stl", "zeros.ist"] {
        let path = tmp(name);
        std::fs::File::create(&path)
            .unwrap()
            .set_len(300 * MIB as u64)
            .unwrap();
        let (e, peak, time) = measured(|| {
            if name.ends_with(".ist") {
                SphereTree::load(&path).map(drop).unwrap_err()
            } else {
                Mesh::load(&path).map(drop).unwrap_err()
            }
        });
        std::fs::remove_file(&path).ok();
        let e = e.to_string();
        assert!(
            e.contains("0 triangles") || e.contains("wrong magic"),
            "{name}: {e}"
        );
        assert!(peak < MIB, "{name}: {peak} bytes at the peak");
        assert!(time < Duration::from_secs(1), "{name}: {time:?}");
    }
}

#[test]
fn dev_zero_is_no_tree() {
    let _alone = alone();
    let path = Path::new("/dev/zero");
    if !path.exists() {
        return;
    }
    let (e, peak, _) = measured(|| SphereTree::load(path).map(drop).unwrap_err());
    assert!(e.to_string().contains("wrong magic"), "{e}");
    assert!(peak < MIB, "{peak} bytes at the peak");
}

#[test]
fn tree_headers_declaring_too_much_are_refused_before_reading_on() {
    let _alone = alone();
    let tree = SphereTree::build(
        &innersphere::shapes::icosphere(1),
        &innersphere::BuildOptions {
            resolution: innersphere::Resolution::Cells(8),
            ..Default::default()
        },
    )
    .unwrap();
    let good = innersphere::tree::file::to_checked_bytes(&tree).unwrap();
    let with_nodes = |n: u64| {
        let mut b = good.clone();
        b[16..24].copy_from_slice(&n.to_le_bytes());
        b
    };
    let path = tmp("lying.ist");
    for (n, needle) in [
        (
            innersphere::tree::file::MAX_NODES + 1,
            "more than a tree file may hold",
        ),
        (1 << 30, "promises 1073741824 nodes"),
    ] {
        std::fs::write(&path, with_nodes(n)).unwrap();
        let (e, peak, _) = measured(|| SphereTree::load(&path).map(drop).unwrap_err());
        assert!(e.to_string().contains(needle), "{e}");
        assert!(peak < MIB, "{peak} bytes at the peak");
    }
    std::fs::remove_file(&path).ok();
}

#[test]
fn a_pipe_is_read_only_as_far_as_the_tree_header_declares() {
    let _alone = alone();
    // A FIFO has no length to check: the reader takes the declared size (here 2^30 nodes,
    // 27 GiB) but allocates only as the bytes arrive, and fails when they end.
    let path = tmp("pipe.ist");
    let made = std::process::Command::new("mkfifo").arg(&path).status();
    if !made.is_ok_and(|s| s.success()) {
        return; // no mkfifo here
    }
    let mut header = Vec::new();
    header.extend_from_slice(&innersphere::tree::file::MAGIC);
    header.extend_from_slice(&innersphere::tree::file::VERSION.to_le_bytes());
    header.extend_from_slice(&2u32.to_le_bytes());
    header.extend_from_slice(&(1u64 << 30).to_le_bytes());
    let writer_path = path.clone();
    let writer = std::thread::spawn(move || {
        let mut f = std::fs::OpenOptions::new()
            .write(true)
            .open(&writer_path)
            .unwrap();
        f.write_all(&header).unwrap();
        // 8 MiB of body, then the end.
        let block = vec![0u8; MIB];
        for _ in 0..8 {
            if f.write_all(&block).is_err() {
                break;
            }
        }
    });
    let (e, peak, _) = measured(|| SphereTree::load(&path).map(drop).unwrap_err());
    writer.join().unwrap();
    std::fs::remove_file(&path).ok();
    assert!(e.to_string().contains("promises 1073741824 nodes"), "{e}");
    assert!(
        peak < 100 * MIB,
        "{} MiB at the peak",
        peak as f64 / MIB as f64
    );
}

/// `/dev/zero` and random bytes given as a text-format mesh (OBJ, OFF, PLY: no header that
/// bounds the length) are refused at their first NUL byte or missing PLY header, not read to
/// the 4 GiB limit; a pipe of zeros behind a valid OBJ head too.
#[test]
fn devices_as_text_meshes_are_refused_after_the_first_chunk() {
    let _alone = alone();
    for dev in ["/dev/zero", "/dev/urandom"] {
        if !Path::new(dev).exists() {
            continue;
        }
        for (ext, needle) in [
            ("obj", "NUL byte"),
            ("off", "NUL byte"),
            ("ply", "no PLY header within the first 65536 bytes"),
        ] {
            let link = tmp(&format!("dev.{ext}"));
            std::os::unix::fs::symlink(dev, &link).unwrap();
            let (e, peak, time) = measured(|| Mesh::load(&link).map(drop).unwrap_err());
            std::fs::remove_file(&link).ok();
            let e = e.to_string();
            assert!(e.contains(needle), "{dev} as .{ext}: {e}");
            assert!(peak < MIB, "{dev} as .{ext}: {peak} bytes at the peak");
            assert!(time < Duration::from_secs(1), "{dev} as .{ext}: {time:?}");
        }
    }
    let pipe = tmp("pipe.obj");
    static HEAD_THEN_ZEROS: [u8; 4096] = {
        let mut b = [0u8; 4096];
        let v = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
        let mut i = 0;
        while i < v.len() {
            b[i] = v[i];
            i += 1;
        }
        b
    };
    if let Some(writer) = fifo(&pipe, &HEAD_THEN_ZEROS, 300 * MIB) {
        let (e, peak, _) = measured(|| Mesh::load(&pipe).map(drop).unwrap_err());
        writer.join().unwrap();
        std::fs::remove_file(&pipe).ok();
        assert!(e.to_string().contains("byte 32 is a NUL byte"), "{e}");
        assert!(peak < MIB, "{peak} bytes at the peak");
    }
}
