//! The build cache: a second build of the same mesh is read back bit for bit; other options
//! are another entry; a truncated or corrupt entry is rebuilt, never trusted; builders racing
//! on one mesh all succeed and leave one entry; eviction keeps the folder under its bound.

use innersphere::build::{BuildCache, BuildOptions, CacheOutcome, Preset};
use innersphere::progress::Silent;
use innersphere::{shapes, Mesh, SphereTree};
use std::path::Path;

fn bytes(t: &SphereTree) -> Vec<u8> {
    innersphere::tree::file::to_bytes(t)
}

fn entries(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .map(|r| {
            r.filter_map(|e| e.ok())
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .collect()
        })
        .unwrap_or_default();
    v.sort();
    v
}

fn fast(mesh: &Mesh) -> BuildOptions {
    BuildOptions::preset(Preset::Fast, mesh).unwrap()
}

#[test]
fn a_second_build_is_read_back_and_other_options_are_another_entry() {
    let dir = tempfile::tempdir().unwrap();
    let cache = BuildCache::new(dir.path().join("cache"), u64::MAX);
    let mesh = shapes::molar(3, 0.2);
    let fresh = SphereTree::build(&mesh, &fast(&mesh)).unwrap();
    let (t1, o1, _) = cache.get_or_build(&mesh, &fast(&mesh), &Silent).unwrap();
    let (t2, o2, _) = cache.get_or_build(&mesh, &fast(&mesh), &Silent).unwrap();
    assert_eq!((o1, o2), (CacheOutcome::Built, CacheOutcome::Hit));
    assert_eq!(bytes(&t1), bytes(&fresh));
    assert_eq!(bytes(&t2), bytes(&fresh));
    assert_eq!(entries(cache.dir()).len(), 1);
    // Other options: another key, another entry, the tree those options build.
    let other = BuildOptions::preset(Preset::Default, &mesh).unwrap();
    let (t3, o3, _) = cache.get_or_build(&mesh, &other, &Silent).unwrap();
    assert_eq!(o3, CacheOutcome::Built);
    assert_eq!(
        bytes(&t3),
        bytes(&SphereTree::build(&mesh, &other).unwrap())
    );
    assert_eq!(entries(cache.dir()).len(), 2);
    // Another mesh (one vertex moved by one ulp): another key.
    let mut moved = mesh.clone();
    moved.vertices[0].x = f64::from_bits(moved.vertices[0].x.to_bits() + 1);
    assert_ne!(
        BuildCache::key(&mesh, &fast(&mesh)),
        BuildCache::key(&moved, &fast(&mesh))
    );
}

#[test]
fn truncated_or_corrupt_entries_are_rebuilt() {
    let dir = tempfile::tempdir().unwrap();
    let cache = BuildCache::new(dir.path(), u64::MAX);
    let mesh = shapes::ellipsoid(glam::DVec3::new(1.0, 0.7, 0.5), 3);
    let opts = fast(&mesh);
    let (good, _, _) = cache.get_or_build(&mesh, &opts, &Silent).unwrap();
    let entry = cache.entry(&BuildCache::key(&mesh, &opts));
    let full = std::fs::read(&entry).unwrap();
    let mut flipped = full.clone();
    let mid = flipped.len() / 2;
    flipped[mid] ^= 0x10;
    for damaged in [full[..full.len() / 2].to_vec(), flipped, Vec::new()] {
        std::fs::write(&entry, &damaged).unwrap();
        let (t, o, _) = cache.get_or_build(&mesh, &opts, &Silent).unwrap();
        assert_eq!(o, CacheOutcome::Rebuilt);
        assert_eq!(bytes(&t), bytes(&good));
        assert_eq!(std::fs::read(&entry).unwrap(), full);
    }
}

#[test]
fn builders_racing_on_one_mesh_all_succeed_and_leave_one_entry() {
    let dir = tempfile::tempdir().unwrap();
    let cache = BuildCache::new(dir.path(), u64::MAX);
    let mesh = shapes::torus(1.0, 0.35, 48, 24);
    let opts = fast(&mesh);
    let want = bytes(&SphereTree::build(&mesh, &opts).unwrap());
    let got: Vec<Vec<u8>> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..4)
            .map(|_| s.spawn(|| cache.get_or_build(&mesh, &opts, &Silent).unwrap().0))
            .collect();
        handles
            .into_iter()
            .map(|h| bytes(&h.join().unwrap()))
            .collect()
    });
    assert!(got.iter().all(|g| *g == want));
    // One entry, no temporary file left behind.
    assert_eq!(
        entries(dir.path()),
        vec![format!("{}.ist", BuildCache::key(&mesh, &opts))]
    );
}

#[test]
fn eviction_keeps_the_folder_under_its_bound_least_recently_used_first() {
    let dir = tempfile::tempdir().unwrap();
    let meshes: Vec<Mesh> = (0..4)
        .map(|k| shapes::ellipsoid(glam::DVec3::new(1.0, 0.5 + 0.1 * k as f64, 0.4), 3))
        .collect();
    let size = |m: &Mesh| bytes(&SphereTree::build(m, &fast(m)).unwrap()).len() as u64;
    // Room for about two entries.
    let bound = size(&meshes[0]) + size(&meshes[1]) + 16;
    let cache = BuildCache::new(dir.path(), bound);
    let key = |m: &Mesh| format!("{}.ist", BuildCache::key(m, &fast(m)));
    cache
        .get_or_build(&meshes[0], &fast(&meshes[0]), &Silent)
        .unwrap();
    std::thread::sleep(std::time::Duration::from_millis(20));
    cache
        .get_or_build(&meshes[1], &fast(&meshes[1]), &Silent)
        .unwrap();
    std::thread::sleep(std::time::Duration::from_millis(20));
    // A hit makes mesh 0 the most recently used.
    let (_, o, _) = cache
        .get_or_build(&meshes[0], &fast(&meshes[0]), &Silent)
        .unwrap();
    assert_eq!(o, CacheOutcome::Hit);
    std::thread::sleep(std::time::Duration::from_millis(20));
    cache
        .get_or_build(&meshes[2], &fast(&meshes[2]), &Silent)
        .unwrap();
    let left = entries(dir.path());
    let total: u64 = left
        .iter()
        .map(|n| std::fs::metadata(dir.path().join(n)).unwrap().len())
        .sum();
    assert!(total <= bound, "{total} bytes over {bound}");
    assert!(left.contains(&key(&meshes[2])), "the new entry is kept");
    assert!(
        !left.contains(&key(&meshes[1])),
        "the least recently used went first: {left:?}"
    );
    // An entry larger than the bound alone is still kept (and the rest goes).
    let tiny = BuildCache::new(dir.path(), 1);
    tiny.get_or_build(&meshes[3], &fast(&meshes[3]), &Silent)
        .unwrap();
    assert_eq!(entries(dir.path()), vec![key(&meshes[3])]);
}
