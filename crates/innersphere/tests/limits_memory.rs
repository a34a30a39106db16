//! Bounded memory on any input file (`docs/RELIABILITY.md`, "Limits"): a gzip bomb, a huge
//! file of zeros given as a mesh or a tree, `/dev/zero` as a tree, and a pipe that lies about
//! its size are refused fast, having allocated a small fraction of their size.
//!
//! The peak of live heap bytes is measured by a counting global allocator, which counts every
//! thread's allocations: each test holds a lock from its first line to its last (its setup
//! allocates too), so that one test's peak never includes another's.

use std::alloc::{GlobalAlloc, Layout, System};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Mutex, MutexGuard};
use std::time::{Duration, Instant};

use innersphere::{Error, Mesh, SphereTree};

struct Peak;

static LIVE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);

fn grew(bytes: usize) {
    let now = LIVE.fetch_add(bytes, Ordering::Relaxed) + bytes;
    PEAK.fetch_max(now, Ordering::Relaxed);
}

unsafe impl GlobalAlloc for Peak {
    unsafe fn alloc(&self, l: Layout) -> *mut u8 {
        grew(l.size());
        unsafe { System.alloc(l) }
    }
    unsafe fn alloc_zeroed(&self, l: Layout) -> *mut u8 {
        grew(l.size());
        unsafe { System.alloc_zeroed(l) }
    }
    unsafe fn realloc(&self, p: *mut u8, l: Layout, n: usize) -> *mut u8 {
        // Counted as the new block appearing before the old one goes (what a moving
        // realloc does).
        grew(n);
        LIVE.fetch_sub(l.size(), Ordering::Relaxed);
        unsafe { System.realloc(p, l, n) }
    }
    unsafe fn dealloc(&self, p: *mut u8, l: Layout) {
        LIVE.fetch_sub(l.size(), Ordering::Relaxed);
        unsafe { System.dealloc(p, l) }
    }
}

#[global_allocator]
static GLOBAL: Peak = Peak;

static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());

const MIB: usize = 1 << 20;

/// Held for the whole of each test, setup included.
fn alone() -> MutexGuard<'static, ()> {
    ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner())
}

/// Runs `f` and returns its result, the heap bytes it held at its peak, and its time (the
/// caller holds [`alone`]).
fn measured<T>(f: impl FnOnce() -> T) -> (T, usize, Duration) {
    let base = LIVE.load(Ordering::Relaxed);
    PEAK.store(base, Ordering::Relaxed);
    let t = Instant::now();
    let out = f();
    let elapsed = t.elapsed();
    (out, PEAK.load(Ordering::Relaxed) - base, elapsed)
}

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

/// A FIFO at `path` fed by a thread with `block` repeated until `total` bytes or the reader
/// goes; `None` where there is no mkfifo.
fn fifo(path: &Path, block: &'static [u8], total: usize) -> Option<std::thread::JoinHandle<()>> {
    let made = std::process::Command::new("mkfifo").arg(path).status();
    if !made.is_ok_and(|s| s.success()) {
        return None;
    }
    let path = path.to_path_buf();
    Some(std::thread::spawn(move || {
        let Ok(mut f) = std::fs::OpenOptions::new().write(true).open(&path) else {
            return;
        };
        let mut sent = 0;
        while sent < total && f.write_all(block).is_ok() {
            sent += block.len();
        }
    }))
}

/// Teeth-axes files (`ist occlusion-map --teeth-a/-b`, `ist view`, `ist occlude
/// --landmarks`): devices, a sparse 100 MB file and a FIFO of endless JSON-like text are
/// refused after at most the 1 MiB limit (plus a 64 KiB chunk), naming the limit.
#[test]
fn teeth_files_are_read_within_their_limit() {
    use innersphere::contact_map::Teeth;
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
