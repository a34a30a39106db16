//! Batches on many threads (`query::batch`): the same bits on any number of threads, in
//! input order; chunks start from a fresh state and carry it within; bad options refused.

use crate::query_util;

use glam::DVec3;
use innersphere::query::batch::{self, BatchOptions};
use innersphere::{Pair, PenetrationOptions, Pose, SharedTree};
use query_util::{motion, trees};

/// A motion between two of the test trees (A moving too): (poses of A, poses of B).
fn poses() -> (SharedTree, SharedTree, Vec<Pose>, Vec<Pose>) {
    let t = trees();
    let (a, b) = (t[0].clone(), t[2].clone());
    let m = motion(
        &a,
        &b,
        DVec3::new(1.0, 0.3, 0.2),
        DVec3::Y,
        DVec3::new(0.2, 1.0, 0.3),
        0.02,
        300,
    );
    let (pa, pb) = m.into_iter().unzip();
    (SharedTree::new(a), SharedTree::new(b), pa, pb)
}

fn bits(p: &innersphere::Penetration) -> Vec<u64> {
    let mut v = vec![p.volume.to_bits(), p.max_depth.to_bits(), p.pairs as u64];
    for x in [p.force, p.torque_b, p.torque_a, p.normal] {
        v.extend(x.to_array().map(f64::to_bits));
    }
    v
}

#[test]
fn every_thread_count_gives_the_same_bits_in_input_order() {
    let (a, b, pa, pb) = poses();
    let q = PenetrationOptions::default();
    for chunk in [1, 7, 64, 1024] {
        let at = |threads| BatchOptions { threads, chunk };
        let d1 = batch::distance_many(&a, &b, &pa, &pb, &at(1)).unwrap();
        let c1 = batch::contact_many(&a, &b, &pa, &pb, &at(1)).unwrap();
        let p1 = batch::penetration_many(&a, &b, &pa, &pb, &q, &at(1)).unwrap();
        assert_eq!(d1.len(), pb.len());
        assert!(c1.iter().any(|c| c.in_contact()) && !c1.iter().all(|c| c.in_contact()));
        for threads in [2, 3, 8, 0] {
            let d = batch::distance_many(&a, &b, &pa, &pb, &at(threads)).unwrap();
            let c = batch::contact_many(&a, &b, &pa, &pb, &at(threads)).unwrap();
            let p = batch::penetration_many(&a, &b, &pa, &pb, &q, &at(threads)).unwrap();
            for i in 0..pb.len() {
                assert_eq!(
                    d[i].distance.to_bits(),
                    d1[i].distance.to_bits(),
                    "chunk {chunk}, {threads} threads, pose {i}"
                );
                assert_eq!(c[i].in_contact(), c1[i].in_contact());
                assert_eq!(
                    bits(&p[i]),
                    bits(&p1[i]),
                    "chunk {chunk}, {threads} threads, pose {i}"
                );
            }
        }
    }
}

#[test]
fn a_chunk_is_one_pair_carried_from_a_fresh_state() {
    let (a, b, pa, pb) = poses();
    let q = PenetrationOptions::default();
    let chunk = 50;
    let got =
        batch::penetration_many(&a, &b, &pa, &pb, &q, &BatchOptions { threads: 4, chunk }).unwrap();
    let dist = batch::distance_many(&a, &b, &pa, &pb, &BatchOptions { threads: 4, chunk }).unwrap();
    let mut pair = Pair::new(a.clone(), b.clone());
    for (i, (x, y)) in pa.iter().zip(&pb).enumerate() {
        if i % chunk == 0 {
            pair.reset();
        }
        assert_eq!(
            bits(&got[i]),
            bits(&pair.penetration_with(x, y, &q)),
            "pose {i}"
        );
        assert_eq!(
            dist[i].distance.to_bits(),
            pair.distance(x, y).distance.to_bits()
        );
    }
    // One pose of A for all.
    let one = [pa[0]];
    let d = batch::distance_many(&a, &b, &one, &pb, &BatchOptions::default()).unwrap();
    let mut fresh = Pair::new(a.clone(), b.clone());
    for (i, y) in pb.iter().enumerate() {
        fresh.reset();
        assert_eq!(
            d[i].distance.to_bits(),
            fresh.distance(&pa[0], y).distance.to_bits()
        );
    }
}

#[test]
fn bad_batches_are_refused() {
    let (a, b, pa, pb) = poses();
    let err = |o: BatchOptions, pa: &[Pose]| {
        batch::distance_many(&a, &b, pa, &pb, &o)
            .unwrap_err()
            .to_string()
    };
    assert!(err(
        BatchOptions {
            chunk: 0,
            ..Default::default()
        },
        &pa
    )
    .contains("chunk"));
    assert!(err(
        BatchOptions {
            threads: 1 << 20,
            ..Default::default()
        },
        &pa
    )
    .contains("threads"));
    assert!(err(BatchOptions::default(), &pa[..3]).contains("poses of A"));
    assert!(
        batch::distance_many(&a, &b, &pa[..0], &pb[..0], &BatchOptions::default())
            .unwrap()
            .is_empty()
    );
}
