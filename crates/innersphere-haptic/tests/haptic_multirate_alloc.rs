//! The multi-rate loop allocates nothing once running: neither the servo tick nor the
//! collision thread's queries and publishing, counted over the whole process (its own test
//! binary, one test: nothing else runs while it counts).

#[path = "it/haptic_util/mod.rs"]
mod haptic_util;

use glam::{DQuat, DVec3};
use haptic_util::{options, slab_and_block};
use innersphere::{Pair, Pose};
use innersphere_haptic::{CollisionOptions, MultirateLoop};
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::{Duration, Instant};

struct Counting;
static ON: AtomicBool = AtomicBool::new(false);
static ALLOCS: AtomicU64 = AtomicU64::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, l: Layout) -> *mut u8 {
        if ON.load(Ordering::Relaxed) {
            ALLOCS.fetch_add(1, Ordering::Relaxed);
        }
        unsafe { System.alloc(l) }
    }
    unsafe fn alloc_zeroed(&self, l: Layout) -> *mut u8 {
        if ON.load(Ordering::Relaxed) {
            ALLOCS.fetch_add(1, Ordering::Relaxed);
        }
        unsafe { System.alloc_zeroed(l) }
    }
    unsafe fn realloc(&self, p: *mut u8, l: Layout, n: usize) -> *mut u8 {
        if ON.load(Ordering::Relaxed) {
            ALLOCS.fetch_add(1, Ordering::Relaxed);
        }
        unsafe { System.realloc(p, l, n) }
    }
    unsafe fn dealloc(&self, p: *mut u8, l: Layout) {
        unsafe { System.dealloc(p, l) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn neither_thread_of_the_multirate_loop_allocates_once_running() {
    let (a, b) = slab_and_block();
    let mut o = options();
    o.rate = 4000.0;
    o.budget = 1.0 / o.rate;
    // Pressing into the slab and sliding over it, turning a little.
    let dev = |i: usize| {
        let s = i as f64 / o.rate;
        Pose::new(
            DVec3::new(
                0.8 * (3.0 * s).sin(),
                0.3 * s,
                2.5 - 1.5 * (s * 2.0).min(1.0),
            ),
            DQuat::from_rotation_z(0.1 * s),
        )
        .unwrap()
    };
    let mut hl = MultirateLoop::spawn(
        Pair::new(a.clone(), b.clone()),
        Pose::IDENTITY,
        dev(0),
        o,
        CollisionOptions {
            history: 1 << 16,
            ..Default::default()
        },
    )
    .unwrap();
    let run = |hl: &mut MultirateLoop, from: usize, to: usize| {
        let start = Instant::now();
        let mut touching = 0;
        for i in from..to {
            let due = start + Duration::from_secs_f64((i - from) as f64 / o.rate);
            while Instant::now() < due {
                std::hint::spin_loop();
            }
            touching += (hl.tick(&dev(i)).volume > 0.0) as usize;
        }
        touching
    };
    // Warm-up: the queries' scratch grows to the contact's size.
    run(&mut hl, 0, 4000);
    let before = hl.collision_queries();
    ON.store(true, Ordering::SeqCst);
    let touching = run(&mut hl, 4000, 8000);
    ON.store(false, Ordering::SeqCst);
    let allocs = ALLOCS.load(Ordering::SeqCst);
    let queries = hl.collision_queries() - before;
    let stats = hl.finish();
    assert_eq!(
        allocs, 0,
        "{allocs} allocations in 4000 servo ticks and {queries} collision queries"
    );
    assert!(touching > 1000, "the tool touched in {touching} ticks");
    assert!(queries > 1000, "{queries} collision queries");
    assert_eq!(stats.times.len() as u64, stats.queries.min(1 << 16));
}
