//! The generated bodies and settings of the haptic tests: a slab and a block, the block's
//! pose on the slab, omega-class options with a stiff contact, and a lock that runs the
//! tests of one file one at a time (some time their ticks or run in real time).
#![allow(dead_code)]

use glam::DVec3;
use innersphere::{shapes, BuildOptions, Mesh, Pose, Resolution, SharedTree, SphereTree};
use innersphere_haptic::{DeviceClass, HapticOptions, Servo};
use std::sync::OnceLock;

/// One test at a time.
pub fn serial() -> std::sync::MutexGuard<'static, ()> {
    static LOCK: std::sync::Mutex<()> = std::sync::Mutex::new(());
    LOCK.lock().unwrap_or_else(|e| e.into_inner())
}

/// The tree of `mesh` at `cells` voxels along its longest side.
pub fn build(mesh: &Mesh, cells: u32) -> SharedTree {
    SharedTree::new(
        SphereTree::build(
            mesh,
            &BuildOptions {
                resolution: Resolution::Cells(cells),
                ..Default::default()
            },
        )
        .unwrap(),
    )
}

/// A 20 × 20 × 2 mm slab (A, top face at z = 1) and a 4 × 4 × 2 mm block (B, centred on
/// its model origin).
pub fn slab_and_block() -> &'static (SharedTree, SharedTree) {
    static T: OnceLock<(SharedTree, SharedTree)> = OnceLock::new();
    T.get_or_init(|| {
        (
            build(&shapes::cuboid(DVec3::new(10.0, 10.0, 1.0)), 96),
            build(&shapes::cuboid(DVec3::new(2.0, 2.0, 1.0)), 32),
        )
    })
}

/// The block resting on the slab with its bottom `into` below the slab's top.
pub fn on_slab(into: f64) -> Pose {
    Pose::from_translation(DVec3::new(0.0, 0.0, 2.0 - into))
}

/// Omega-class defaults with a 50 N/mm³ contact.
pub fn options() -> HapticOptions {
    let mut o = HapticOptions::for_device(DeviceClass::Omega);
    o.contact_stiffness = 50.0;
    o
}

/// `n` device poses at `rate` Hz from `start` at rest: up to 2 mm along x and 0.6 rad about
/// y, as `1 − cos` at 12 rad/s (smooth, within the loop's speed limits).
pub fn swing(start: Pose, rate: f64, n: usize) -> Vec<Pose> {
    (0..n)
        .map(|i| {
            let s = 1.0 - (12.0 * i as f64 / rate).cos();
            Pose {
                rotation: glam::DQuat::from_rotation_y(0.3 * s),
                translation: start.translation + DVec3::new(s, 0.0, 0.0),
            }
        })
        .collect()
}

/// A loop's energy to the user and its largest (`got`) are a lone `Servo`'s (`servo`) bit
/// for bit, and passive: below 0 (not the −1 a broken sum would give), the largest at least
/// the last.
pub fn assert_passive_as_servo(got: (f64, f64), servo: &Servo) {
    let (e, e_max) = (servo.energy_to_user(), servo.energy_to_user_max());
    assert_eq!(got, (e, e_max));
    assert!(
        e < 0.0 && e != -1.0 && e_max >= e,
        "{e} J, largest {e_max} J"
    );
}
