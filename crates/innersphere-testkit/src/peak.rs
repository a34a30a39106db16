//! The peak of live heap bytes of a test binary: a counting global allocator that counts
//! every thread's allocations (a test binary declares it with
//! `#[global_allocator] static GLOBAL: Peak = Peak;`), a lock each measured test holds from
//! its first line to its last (its setup allocates too, so one test's peak never includes
//! another's), and a FIFO fed by a thread (a pipe that never ends).

use std::alloc::{GlobalAlloc, Layout, System};
use std::io::Write;
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Mutex, MutexGuard};
use std::time::{Duration, Instant};

/// The counting allocator (over the system's).
pub struct Peak;

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

static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());

/// One mebibyte.
pub const MIB: usize = 1 << 20;

/// Held for the whole of each test, setup included.
pub fn alone() -> MutexGuard<'static, ()> {
    ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner())
}

/// Runs `f` and returns its result, the heap bytes it held at its peak, and its time (the
/// caller holds [`alone`]).
pub fn measured<T>(f: impl FnOnce() -> T) -> (T, usize, Duration) {
    let base = LIVE.load(Ordering::Relaxed);
    PEAK.store(base, Ordering::Relaxed);
    let t = Instant::now();
    let out = f();
    let elapsed = t.elapsed();
    (out, PEAK.load(Ordering::Relaxed) - base, elapsed)
}

/// A FIFO at `path` fed by a thread with `block` repeated until `total` bytes or the reader
/// goes; `None` where there is no mkfifo.
pub fn fifo(
    path: &Path,
    block: &'static [u8],
    total: usize,
) -> Option<std::thread::JoinHandle<()>> {
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
