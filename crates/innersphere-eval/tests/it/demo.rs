//! The demo (`ist demo`) on the generated tooth pair: both trees build, the generated chew
//! replays through every query kind, and the accuracy against the exact distance is sane.

use innersphere::build::{BuildOptions, Resolution};
use innersphere::progress::Silent;
use innersphere_eval::demo;

#[test]
fn the_demo_builds_and_replays_the_generated_tooth_pair() {
    let pair = demo::build_pair(
        &BuildOptions {
            resolution: Resolution::Cells(48),
            ..Default::default()
        },
        &Silent,
    )
    .unwrap();
    assert!(pair.a.2.spheres > 100 && pair.b.2.spheres > 100);
    let rep = demo::replay_pair(&pair, 1.2).unwrap();
    assert_eq!(rep.frames, 1200);
    assert_eq!(rep.kinds.len(), 5);
    let acc = rep.accuracy.unwrap();
    assert!(acc.frames >= 100 && acc.separated_frames > 0, "{acc:?}");
    assert_eq!(
        acc.errors.false_contacts, 0,
        "inner spheres never reach outside the meshes"
    );
    // The distance refined to the meshes: far nearer than the spheres', never a contact
    // where the meshes are apart.
    let r = acc.refined.clone().unwrap();
    assert_eq!(r.errors.false_contacts, 0);
    assert!(
        r.errors.abs_err_p95 < 0.2 * acc.errors.abs_err_p95,
        "refined {r:?} against the spheres' {acc:?}"
    );
}
