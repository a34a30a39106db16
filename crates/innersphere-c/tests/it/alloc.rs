//! The per-tick C calls allocate nothing after warm-up: every query and the haptic tick,
//! called through the exported functions, counted by a per-thread counting allocator.

use innersphere::glam::DVec3;
use innersphere::{shapes, BuildOptions, Resolution, SphereTree};
use innersphere_c::*;
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

struct Counting;

thread_local! {
    static ON: Cell<bool> = const { Cell::new(false) };
    static COUNT: Cell<u64> = const { Cell::new(0) };
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, l: Layout) -> *mut u8 {
        if ON.with(|c| c.get()) {
            COUNT.with(|n| n.set(n.get() + 1));
        }
        unsafe { System.alloc(l) }
    }
    unsafe fn dealloc(&self, p: *mut u8, l: Layout) {
        unsafe { System.dealloc(p, l) }
    }
    unsafe fn realloc(&self, p: *mut u8, l: Layout, n: usize) -> *mut u8 {
        if ON.with(|c| c.get()) {
            COUNT.with(|c| c.set(c.get() + 1));
        }
        unsafe { System.realloc(p, l, n) }
    }
}

// Per thread, only inside `counted`: the other tests of this binary run beside it unaffected.
#[global_allocator]
static GLOBAL: Counting = Counting;

fn counted(f: impl FnOnce()) -> u64 {
    COUNT.with(|n| n.set(0));
    ON.with(|c| c.set(true));
    f();
    ON.with(|c| c.set(false));
    COUNT.with(|n| n.get())
}

fn pose(z: f64, x: f64) -> ist_pose {
    ist_pose {
        t: [x, 0.0, z],
        q: [1.0, 0.0, 0.0, 0.0],
    }
}

#[test]
fn per_tick_calls_allocate_nothing() {
    let dir = std::env::temp_dir().join(format!("innersphere_c_alloc_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let opts = BuildOptions {
        resolution: Resolution::Cells(32),
        ..Default::default()
    };
    let paths = [dir.join("a.ist"), dir.join("b.ist")];
    SphereTree::build(&shapes::cuboid(DVec3::new(3.0, 3.0, 0.5)), &opts)
        .unwrap()
        .save(&paths[0])
        .unwrap();
    SphereTree::build(&shapes::icosphere(3), &opts)
        .unwrap()
        .save(&paths[1])
        .unwrap();
    let c = |p: &std::path::Path| std::ffi::CString::new(p.to_str().unwrap()).unwrap();
    let (pa, pb) = (c(&paths[0]), c(&paths[1]));
    unsafe {
        let a = ist_tree_load(pa.as_ptr());
        let b = ist_tree_load(pb.as_ptr());
        assert!(!a.is_null() && !b.is_null());
        let pair = ist_pair_new(a, b);
        let mut hp = std::mem::zeroed::<ist_haptic_params>();
        assert_eq!(ist_haptic_params_default(IST_DEVICE_OMEGA, &mut hp), IST_OK);
        hp.start = pose(2.0, 0.0);
        let h = ist_haptic_new(pair, &hp);
        assert!(!h.is_null());
        let id = ist_pose_identity();
        let mut d = ist_distance_result::default();
        let mut p = ist_penetration_result::default();
        let mut patch = ist_patch::default();
        let mut cs = [ist_contact_point::default(); 16];
        let mut n = 0usize;
        let mut inc = 0;
        let mut out = std::mem::zeroed::<ist_haptic_output>();
        let mut run = |i: usize| {
            let s = i as f64 * 1e-3;
            let pb = pose(1.6 - 0.3 * s.min(1.0), 0.5 * (3.0 * s).sin());
            assert_eq!(ist_distance(pair, &id, &pb, &mut d), IST_OK);
            assert_eq!(ist_contact(pair, &id, &pb, &mut inc), IST_OK);
            assert_eq!(ist_penetration(pair, &id, &pb, &mut p), IST_OK);
            if p.patch_count > 0 {
                assert_eq!(ist_penetration_patch(pair, 0, &mut patch), IST_OK);
            }
            assert_eq!(
                ist_multipoint(pair, &id, &pb, 16, cs.as_mut_ptr(), &mut n),
                IST_OK
            );
            assert_eq!(ist_haptic_tick(h, &pb, 0.001, &mut out), IST_OK);
        };
        for i in 0..200 {
            run(i);
        }
        let allocations = counted(|| {
            for i in 200..1200 {
                run(i);
            }
        });
        assert!(
            p.volume > 0.0 || out.volume > 0.0,
            "no contact was exercised"
        );
        assert_eq!(allocations, 0, "allocations in 1000 ticks of every call");
        ist_haptic_free(h);
        ist_pair_free(pair);
        ist_tree_free(a);
        ist_tree_free(b);
    }
    std::fs::remove_dir_all(&dir).ok();
}
