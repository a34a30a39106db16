//! The build cache: a second build of the same mesh is read back bit for bit; other options
//! are another entry; a truncated or corrupt entry is rebuilt, never trusted, and so is a
//! valid tree under another mesh's key; builders racing on one mesh all succeed and leave one
//! entry; eviction keeps the folder under its bound; the cache touches nothing but its own
//! files in its own subfolder, however full of the user's files the folder it is given.

use innersphere::build::{BuildCache, BuildOptions, CacheOutcome, Preset};
use innersphere::progress::Silent;
use innersphere::{shapes, Mesh, SphereTree};
use std::path::Path;

fn bytes(t: &SphereTree) -> Vec<u8> {
    innersphere::tree::file::to_bytes(t)
}

/// The names in `dir`, sorted.
fn names(dir: &Path) -> Vec<String> {
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

/// The names in the cache's own folder but its tag.
fn entries(cache: &BuildCache) -> Vec<String> {
    let mut v = names(&cache.entries_dir());
    v.retain(|n| n != "CACHEDIR.TAG");
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
    assert_eq!(entries(&cache).len(), 1);
    // Other options: another key, another entry, the tree those options build.
    let other = BuildOptions::preset(Preset::Default, &mesh).unwrap();
    let (t3, o3, _) = cache.get_or_build(&mesh, &other, &Silent).unwrap();
    assert_eq!(o3, CacheOutcome::Built);
    assert_eq!(
        bytes(&t3),
        bytes(&SphereTree::build(&mesh, &other).unwrap())
    );
    assert_eq!(entries(&cache).len(), 2);
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
        let (t, o, r) = cache.get_or_build(&mesh, &opts, &Silent).unwrap();
        assert_eq!(o, CacheOutcome::Rebuilt);
        let warnings = r.unwrap().warnings;
        assert!(
            warnings
                .iter()
                .any(|w| w.contains("was not used: it failed the tree file's checks")),
            "{warnings:?}"
        );
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
        entries(&cache),
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
    let left = entries(&cache);
    let total: u64 = left
        .iter()
        .map(|n| {
            std::fs::metadata(cache.entries_dir().join(n))
                .unwrap()
                .len()
        })
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
    assert_eq!(entries(&tiny), vec![key(&meshes[3])]);
}

/// Files of the user's in a folder, kept to compare byte for byte.
struct UserFiles(Vec<(std::path::PathBuf, Vec<u8>)>);

impl UserFiles {
    /// A patient's folder: tree files (one valid), a mesh, notes, a file named like a cache
    /// entry, a subfolder with a tree, a hidden file named like a temporary of the cache's.
    fn plant(dir: &Path) -> UserFiles {
        let mesh = shapes::molar(2, 0.1);
        let tree = SphereTree::build(&mesh, &fast(&mesh)).unwrap();
        let key = BuildCache::key(&mesh, &fast(&mesh));
        std::fs::create_dir_all(dir.join("scans")).unwrap();
        let files: Vec<(std::path::PathBuf, Vec<u8>)> = vec![
            (dir.join("my_maxilla.ist"), bytes(&tree)),
            (dir.join("other.ist"), b"not a tree".to_vec()),
            (
                dir.join("notes.txt"),
                b"patient 17, bite on the left".to_vec(),
            ),
            (dir.join(format!("{key}.ist")), bytes(&tree)),
            (dir.join(format!(".{key}.ist.abc123.tmp")), b"mine".to_vec()),
            (dir.join("scans").join("mandible.ist"), bytes(&tree)),
        ];
        for (p, b) in &files {
            std::fs::write(p, b).unwrap();
            // Old, as if last used long ago: first in line for a least-recently-used sweep.
            let f = std::fs::File::options().append(true).open(p).unwrap();
            f.set_modified(
                std::time::SystemTime::UNIX_EPOCH + std::time::Duration::from_secs(1e9 as u64),
            )
            .unwrap();
        }
        UserFiles(files)
    }

    fn assert_untouched(&self) {
        for (p, b) in &self.0 {
            let now = std::fs::read(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
            assert!(now == *b, "{} changed", p.display());
        }
    }
}

/// `IST_CACHE=.` in a patient's folder removed the user's `.ist` files (the command's own
/// input among them) as least recently used entries: the cache took every `*.ist` in the
/// folder for its own. Now it keeps its files in its own tagged subfolder and never lists,
/// touches or removes anything else: with a bound of one byte, forcing eviction at every
/// write, the user's files stay byte for byte and the folder gains only the subfolder.
#[test]
fn the_cache_never_touches_the_files_of_the_folder_it_is_given() {
    let dir = tempfile::tempdir().unwrap();
    let user = UserFiles::plant(dir.path());
    let before = names(dir.path());
    let cache = BuildCache::new(dir.path(), 1);
    for k in 0..3 {
        let mesh = shapes::ellipsoid(glam::DVec3::new(1.0, 0.6 + 0.1 * k as f64, 0.4), 2);
        let (t, o, _) = cache.get_or_build(&mesh, &fast(&mesh), &Silent).unwrap();
        assert_eq!(o, CacheOutcome::Built);
        assert_eq!(
            bytes(&t),
            bytes(&SphereTree::build(&mesh, &fast(&mesh)).unwrap())
        );
    }
    user.assert_untouched();
    let mut want = before.clone();
    want.push(innersphere::build::cache::SUBFOLDER.to_string());
    want.sort();
    assert_eq!(names(dir.path()), want);
    // Its own folder: its tag and its last entry (the bound keeps only the newest).
    assert_eq!(entries(&cache).len(), 1, "{:?}", entries(&cache));
    let tag = std::fs::read_to_string(cache.entries_dir().join("CACHEDIR.TAG")).unwrap();
    assert!(tag.starts_with("Signature: 8a477f597d28d172789f06886806bc55"));
}

/// Inside its own folder the cache still removes only its own names: a file the user put
/// there stays; an old temporary file of an interrupted write of its own is removed, a fresh
/// one (a write under way in another process) is not.
#[test]
fn eviction_removes_only_the_caches_own_names_in_its_own_folder() {
    let dir = tempfile::tempdir().unwrap();
    let cache = BuildCache::new(dir.path(), 1);
    cache.prepare().unwrap();
    let own = cache.entries_dir();
    let user = UserFiles::plant(&own);
    let key = "ab".repeat(32);
    let (stale, fresh) = (
        own.join(format!(".{key}.ist.Zx81Qa.tmp")),
        own.join(format!(".{key}.ist.Pq02Rs.tmp")),
    );
    std::fs::write(&stale, b"interrupted").unwrap();
    std::fs::write(&fresh, b"being written").unwrap();
    std::fs::File::options()
        .append(true)
        .open(&stale)
        .unwrap()
        .set_modified(std::time::SystemTime::now() - std::time::Duration::from_secs(7200))
        .unwrap();
    let mesh = shapes::icosphere(2);
    cache.get_or_build(&mesh, &fast(&mesh), &Silent).unwrap();
    // In its own folder, a 64-hex `.ist` and an old `.<that>.<random>.tmp` are the cache's
    // by name (the user's copies planted there go with the bound and the sweep); the rest
    // stays.
    let ours = |p: &Path| {
        let n = p.file_name().unwrap().to_string_lossy();
        n.len() >= 68 && (n.ends_with(".ist") || n.ends_with(".tmp")) && p.parent() == Some(&own)
    };
    for (p, _) in &user.0 {
        assert_eq!(p.exists(), !ours(p), "{}", p.display());
    }
    let kept = UserFiles(user.0.into_iter().filter(|(p, _)| !ours(p)).collect());
    kept.assert_untouched();
    assert!(
        !stale.exists(),
        "an interrupted write's old temporary is cleaned"
    );
    assert!(fresh.exists(), "a write under way is left alone");
}

/// A folder of the cache's subfolder's name that the cache did not make (no tag), and a
/// file where the folder or the subfolder should be: refused with a sentence that names the
/// path and what to do, nothing written or removed.
#[test]
fn a_folder_the_cache_did_not_make_or_a_file_in_its_way_is_refused_clearly() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = shapes::icosphere(1);
    let opts = fast(&mesh);
    // Not its own.
    let foreign = dir.path().join("a");
    let sub = foreign.join(innersphere::build::cache::SUBFOLDER);
    std::fs::create_dir_all(&sub).unwrap();
    let user = UserFiles::plant(&sub);
    let Err(e) = BuildCache::new(&foreign, 1).get_or_build(&mesh, &opts, &Silent) else {
        panic!("a folder the cache did not make was used");
    };
    let e = e.to_string();
    assert!(e.contains(&sub.display().to_string()), "{e}");
    assert!(e.contains("not made by innersphere's build cache"), "{e}");
    user.assert_untouched();
    // A file given as the folder.
    let file = dir.path().join("cache.txt");
    std::fs::write(&file, b"x").unwrap();
    for given in [file.clone(), file.join("deeper")] {
        let e = BuildCache::new(&given, 1)
            .prepare()
            .unwrap_err()
            .to_string();
        assert!(
            e.contains(&file.display().to_string()) && e.contains("is a file, not a folder"),
            "{e}"
        );
        assert!(!e.contains("os error"), "{e}");
    }
    assert_eq!(std::fs::read(&file).unwrap(), b"x");
    // A file with the subfolder's name.
    let blocked = dir.path().join("b");
    std::fs::create_dir_all(&blocked).unwrap();
    std::fs::write(blocked.join(innersphere::build::cache::SUBFOLDER), b"y").unwrap();
    let e = BuildCache::new(&blocked, 1)
        .prepare()
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("a file has the name of the build cache's folder"),
        "{e}"
    );
}

/// A valid tree planted under another mesh's key was read back as that mesh's tree: the
/// cache trusted the key. Now an entry is verified against the mesh (and options) it is
/// asked for; one that is another mesh's tree is rebuilt, with a warning, never used.
#[test]
fn a_valid_tree_under_another_meshs_key_is_rebuilt_never_used() {
    let dir = tempfile::tempdir().unwrap();
    let cache = BuildCache::new(dir.path(), u64::MAX);
    let a = shapes::ellipsoid(glam::DVec3::new(1.0, 0.7, 0.5), 3);
    let b = shapes::ellipsoid(glam::DVec3::new(1.0, 0.5, 0.5), 3);
    let c = shapes::molar(2, 0.3);
    for m in [&a, &b, &c] {
        cache.get_or_build(m, &fast(m), &Silent).unwrap();
    }
    let entry = |m: &Mesh, o: &BuildOptions| cache.entry(&BuildCache::key(m, o));
    // A's tree under B's key and under C's key (another box, or only another volume);
    // B's fast tree under B's key for other options.
    let mut other = fast(&b);
    other.hierarchy.fanout = 8;
    let planted: Vec<(&Mesh, BuildOptions, std::path::PathBuf)> = vec![
        (&b, fast(&b), entry(&a, &fast(&a))),
        (&c, fast(&c), entry(&a, &fast(&a))),
        (&b, other, entry(&b, &fast(&b))),
    ];
    for (mesh, opts, from) in planted {
        let to = entry(mesh, &opts);
        std::fs::copy(&from, &to).unwrap();
        innersphere::tree::file::load(&to).expect("a valid tree file");
        let (t, o, r) = cache.get_or_build(mesh, &opts, &Silent).unwrap();
        assert_eq!(o, CacheOutcome::Rebuilt);
        assert_eq!(bytes(&t), bytes(&SphereTree::build(mesh, &opts).unwrap()));
        let warnings = r.unwrap().warnings;
        assert!(
            warnings
                .iter()
                .any(|w| w.contains("was not used: it is not the tree of this mesh")),
            "{warnings:?}"
        );
        // The entry now holds the right tree, and is read back.
        let (t2, o2, _) = cache.get_or_build(mesh, &opts, &Silent).unwrap();
        assert_eq!((o2, bytes(&t2)), (CacheOutcome::Hit, bytes(&t)));
    }
}

/// The tree of an open mesh passes the cache's source check: a second build of an open
/// mesh (a ball with a hole, in metres) is a hit, not a rebuild every time.
#[test]
fn an_open_meshs_entry_is_read_back() {
    let dir = tempfile::tempdir().unwrap();
    let cache = BuildCache::new(dir.path(), u64::MAX);
    let mut mesh = shapes::icosphere(3);
    for v in &mut mesh.vertices {
        *v = glam::DVec3::new(0.03, -0.01, 0.02) + *v * 0.012;
    }
    mesh.triangles
        .retain(|t| t.iter().all(|&i| mesh.vertices[i as usize].z < 0.02 + 0.01));
    let (t1, o1, r1) = cache.get_or_build(&mesh, &fast(&mesh), &Silent).unwrap();
    assert!(!t1.meta.mesh_closed, "{:?}", r1.unwrap().warnings);
    let (t2, o2, _) = cache.get_or_build(&mesh, &fast(&mesh), &Silent).unwrap();
    assert_eq!((o1, o2), (CacheOutcome::Built, CacheOutcome::Hit));
    assert_eq!(bytes(&t1), bytes(&t2));
}

/// The meshes of the soak: small, different, each with its own key.
fn soak_meshes() -> Vec<Mesh> {
    let mut v: Vec<Mesh> = (0..4)
        .map(|k| shapes::ellipsoid(glam::DVec3::new(1.0, 0.5 + 0.1 * k as f64, 0.4), 2))
        .collect();
    v.push(shapes::molar(2, 0.2));
    v.push(shapes::torus(1.0, 0.3, 24, 12));
    v
}

const SOAK_DIR: &str = "INNERSPHERE_SOAK_DIR";
const SOAK_BOUND: &str = "INNERSPHERE_SOAK_BOUND";
const SOAK_SEED: &str = "INNERSPHERE_SOAK_SEED";

/// One soak worker: asks the cache for every soak mesh three times in an order of its own
/// (mesh 0 first: the planted one), printing `index outcome blake3-of-the-tree` per answer.
fn soak_worker(dir: &Path, bound: u64, seed: u64, out: &mut dyn std::io::Write) {
    let meshes = soak_meshes();
    let cache = BuildCache::new(dir, bound);
    let mut order: Vec<usize> = vec![0];
    let mut x = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    for _ in 0..3 {
        let mut round: Vec<usize> = (0..meshes.len()).collect();
        for i in (1..round.len()).rev() {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            round.swap(i, (x % (i as u64 + 1)) as usize);
        }
        order.extend(round);
    }
    for i in order {
        let m = &meshes[i];
        let (t, o, r) = cache.get_or_build(m, &fast(m), &Silent).unwrap();
        let warned = r.is_some_and(|r| {
            r.warnings
                .iter()
                .any(|w| w.contains("it is not the tree of this mesh"))
        });
        writeln!(
            out,
            "{i} {o:?} {warned} {}",
            blake3::hash(&bytes(&t)).to_hex()
        )
        .unwrap();
    }
}

/// The soak's child process: a worker when the soak started it, else nothing.
#[test]
#[ignore = "a child process of build_cache_soak"]
fn build_cache_soak_child() {
    let (Some(dir), Some(bound), Some(seed)) = (
        std::env::var_os(SOAK_DIR),
        std::env::var(SOAK_BOUND).ok(),
        std::env::var(SOAK_SEED).ok(),
    ) else {
        return;
    };
    let mut out =
        std::fs::File::create(Path::new(&dir).join(format!("../answers-{seed}"))).unwrap();
    soak_worker(
        Path::new(&dir),
        bound.parse().unwrap(),
        seed.parse().unwrap(),
        &mut out,
    );
}

/// The build cache under load: four processes (this test binary again) and two threads ask
/// one cache folder for the same six meshes at once, in orders of their own, with a bound of
/// about two and a half trees (eviction at nearly every write); the folder also holds the
/// user's files, and a valid tree planted under another mesh's key. Every answer is the tree
/// a direct build of its mesh gives (the planted one is rebuilt, with a warning), every
/// worker succeeds, the user's files are untouched byte for byte, the cache's folder holds
/// only its own names, and the entries fit the bound at the end.
#[test]
#[ignore = "a few seconds: processes and threads on one cache"]
fn build_cache_soak() {
    let root = tempfile::tempdir().unwrap();
    let dir = root.path().join("patient");
    std::fs::create_dir_all(&dir).unwrap();
    let user = UserFiles::plant(&dir);
    let before = names(&dir);
    let meshes = soak_meshes();
    let direct: Vec<Vec<u8>> = meshes
        .iter()
        .map(|m| bytes(&SphereTree::build(m, &fast(m)).unwrap()))
        .collect();
    let want: Vec<String> = direct
        .iter()
        .map(|b| blake3::hash(b).to_hex().to_string())
        .collect();
    let bound = direct.iter().map(|b| b.len() as u64).max().unwrap() * 5 / 2;
    let cache = BuildCache::new(&dir, bound);
    // Mesh 1's valid tree planted under mesh 0's key.
    cache.prepare().unwrap();
    let planted = SphereTree::build(&meshes[1], &fast(&meshes[1])).unwrap();
    innersphere::tree::file::save(
        &planted,
        &cache.entry(&BuildCache::key(&meshes[0], &fast(&meshes[0]))),
    )
    .unwrap();
    let exe = std::env::current_exe().unwrap();
    let children: Vec<_> = (0..4u64)
        .map(|seed| {
            std::process::Command::new(&exe)
                // A name filter, not --exact: the test's path depends on the binary's layout.
                .args(["build_cache_soak_child", "--ignored", "--test-threads=1"])
                .env(SOAK_DIR, &dir)
                .env(SOAK_BOUND, bound.to_string())
                .env(SOAK_SEED, seed.to_string())
                .stdout(std::process::Stdio::piped())
                .stderr(std::process::Stdio::piped())
                .spawn()
                .unwrap()
        })
        .collect();
    let mut answers: Vec<String> = std::thread::scope(|s| {
        let threads: Vec<_> = (10..12u64)
            .map(|seed| {
                let dir = &dir;
                s.spawn(move || {
                    let mut out = Vec::new();
                    soak_worker(dir, bound, seed, &mut out);
                    String::from_utf8(out).unwrap()
                })
            })
            .collect();
        threads.into_iter().map(|t| t.join().unwrap()).collect()
    });
    for (seed, c) in children.into_iter().enumerate() {
        let out = c.wait_with_output().unwrap();
        assert!(
            out.status.success(),
            "worker {seed}: {}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
        answers.push(std::fs::read_to_string(root.path().join(format!("answers-{seed}"))).unwrap());
    }
    let lines: Vec<&str> = answers.iter().flat_map(|a| a.lines()).collect();
    assert_eq!(lines.len(), 6 * 19, "every worker answered every request");
    let (mut planted_caught, mut built, mut hits) = (0, 0, 0);
    for line in &lines {
        let f: Vec<&str> = line.split(' ').collect();
        let i: usize = f[0].parse().unwrap();
        assert_eq!(f[3], want[i], "mesh {i} got another tree: {line}");
        planted_caught += usize::from(f[2] == "true");
        built += usize::from(f[1] != "Hit");
        hits += usize::from(f[1] == "Hit");
    }
    eprintln!("soak: {built} built, {hits} hits, the planted entry caught {planted_caught} times");
    assert!(planted_caught >= 1, "the planted entry was caught");
    // Eviction made the workers build meshes again, and entries were still read back.
    assert!(
        built > meshes.len() && hits > 0,
        "{built} built, {hits} hits"
    );
    user.assert_untouched();
    let mut expected = before;
    expected.push(innersphere::build::cache::SUBFOLDER.to_string());
    expected.sort();
    assert_eq!(
        names(&dir),
        expected,
        "the folder gained only the cache's subfolder"
    );
    let own = entries(&cache);
    assert!(
        own.iter().all(|n| n.len() == 68
            && n.ends_with(".ist")
            && n[..64].bytes().all(|b| b.is_ascii_hexdigit())),
        "only its own names, no temporary left: {own:?}"
    );
    let total: u64 = own
        .iter()
        .map(|n| {
            std::fs::metadata(cache.entries_dir().join(n))
                .unwrap()
                .len()
        })
        .sum();
    assert!(total <= bound, "{total} bytes over the bound {bound}");
}

/// Builders that find no cache subfolder race to make it: each that saw none and then found
/// another's freshly renamed subfolder refused it as "not made by the cache" (the racing
/// builders' test failed now and then). Eight threads prepare one fresh folder at once, over
/// and over: every one succeeds.
#[test]
fn preparing_one_folder_on_many_threads_at_once_always_succeeds() {
    for _ in 0..300 {
        let root = tempfile::tempdir().unwrap();
        let start = std::sync::Barrier::new(8);
        let results: Vec<_> = std::thread::scope(|s| {
            let workers: Vec<_> = (0..8)
                .map(|_| {
                    s.spawn(|| {
                        start.wait();
                        BuildCache::new(root.path(), 1 << 20).prepare()
                    })
                })
                .collect();
            workers.into_iter().map(|w| w.join().unwrap()).collect()
        });
        for r in results {
            r.unwrap();
        }
    }
}
