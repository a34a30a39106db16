//! The haptic loop and the occlusion on the real jaw pair (trees with `--preset jaw`): the
//! shipped press trajectory (3 mm open → 1 mm past the bite, hold, ±0.8 mm sideways while
//! pressing, release) with the omega-class defaults at 1 kHz and 4 kHz (the tool within
//! 0.3 mm of overlap, at most 1e-4 J to the hand, force steps at most 5 %, at most one late
//! tick in a thousand, no buzz while held), and the bite found from five open starts within
//! 0.5 mm of the scanned one. The timings themselves are reported by
//! `ist haptic` (docs/HAPTICS.md); here only what the loop guarantees is asserted.

use innersphere_testkit::data as common;

use innersphere::glam::DQuat;
use innersphere::{BuildOptions, Mesh, Pair, Pose, SharedTree, SphereTree};
use innersphere_dental::contact_map::Teeth;
use innersphere_dental::{occlude, occlude_free, FreeOcclusionOptions, Joints, OcclusionOptions};
use innersphere_eval::haptic::{crown_centres, run, Session};
use innersphere_eval::motion::{AnatomicalFrame, Motion};
use innersphere_haptic::{CollisionOptions, DeviceClass, HapticOptions};
use std::sync::OnceLock;

struct Jaw {
    a: SharedTree,
    b: SharedTree,
    frame: AnatomicalFrame,
    meshes: (Mesh, Mesh),
}

fn jaw() -> &'static Jaw {
    static J: OnceLock<Jaw> = OnceLock::new();
    J.get_or_init(|| {
        let load = |rel: &str| Mesh::load(common::data(rel)).unwrap();
        let (ma, mb) = (
            load("jaw/ofj_p26_maxilla_teeth.stl.gz"),
            load("jaw/ofj_p26_mandible_teeth.stl.gz"),
        );
        let build = |m: &Mesh| {
            let opts = BuildOptions::preset(innersphere::build::Preset::Jaw, m).unwrap();
            SharedTree::new(SphereTree::build(m, &opts).unwrap())
        };
        Jaw {
            a: build(&ma),
            b: build(&mb),
            frame: AnatomicalFrame::from_meshes(&ma, &mb).unwrap(),
            meshes: (ma, mb),
        }
    })
}

/// The deepest sphere overlap a press into the bite may reach, mm: the scans' own overlap at
/// the bite (0.30 mm) plus the trees' distance error p95 (0.03 mm).
const BITE_DEPTH_MM: f64 = 0.33;

/// One at a time: the haptic loop wants a core of its own (as on a real device's machine).
fn serial() -> std::sync::MutexGuard<'static, ()> {
    static LOCK: std::sync::Mutex<()> = std::sync::Mutex::new(());
    LOCK.lock().unwrap_or_else(|e| e.into_inner())
}

fn press() -> Motion {
    Motion::load(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/jaw_press_device.csv"
    ))
    .unwrap()
}

#[test]
#[ignore = "real data: run with --ignored"]
fn pressing_the_jaw_into_the_bite_feels_solid_and_passive() {
    let _serial = serial();
    let j = jaw();
    for rate in [1000.0, 4000.0] {
        let mut o = HapticOptions::for_device(DeviceClass::Omega);
        o.rate = rate;
        o.budget = 1.0 / rate;
        let keep = Session {
            keep_ticks: true,
            ..Default::default()
        };
        let r = run(Pair::new(j.a.clone(), j.b.clone()), &press(), o, &keep).unwrap();
        let s = r.summary;
        eprintln!("{rate} Hz: {s:?}");
        assert_eq!(s.ticks, (6.0 * rate) as usize + 1);
        // The device goes 1 mm past the bite; the tool stays within the bite's own overlap
        // (the scans interpenetrate by 0.30 mm there, `ist occlusion-map`'s min_gap) plus the
        // trees' distance error (p95 0.03 mm, docs/RESULTS.md): the spheres lie inside the
        // surfaces, so they let the tool sink by up to their error (0.25 mm with the trees
        // of the global greedy order, 0.32 mm with today's, the force the same 3.6 N).
        assert!(
            s.max_depth_mm <= BITE_DEPTH_MM,
            "{rate} Hz: depth {} mm",
            s.max_depth_mm
        );
        assert!(s.max_force_n > 1.0, "{rate} Hz: the teeth were not felt");
        assert!(
            s.energy_to_user_max_j <= 1e-4,
            "{rate} Hz: {} J",
            s.energy_to_user_max_j
        );
        assert!(
            s.max_force_step_n <= 0.05 * s.max_force_n,
            "{rate} Hz: step {} N of {} N",
            s.max_force_step_n,
            s.max_force_n
        );
        // Deadline: a shared CI machine may preempt a tick; the loop may not overrun.
        assert!(
            s.deadline_misses * 1000 <= s.ticks,
            "{rate} Hz: {} of {} ticks late",
            s.deadline_misses,
            s.ticks
        );
        // While the device is 1 mm inside and held (1.5–2.5 s), the tool rests at the bite.
        let held: Vec<_> = r
            .ticks
            .iter()
            .filter(|t| (1.8..2.5).contains(&t.t))
            .collect();
        let f0 = held[0].tick.force;
        for t in &held {
            assert!(
                (t.tick.force - f0).length() < 0.02 * f0.length(),
                "buzz at {}",
                t.t
            );
        }
    }
}

#[test]
#[ignore = "real data: run with --ignored"]
fn pressing_the_jaw_at_10_khz_with_a_collision_thread_feels_the_same_and_stays_passive() {
    let _serial = serial();
    let j = jaw();
    let o = HapticOptions::for_device(DeviceClass::Omega);
    let exact = run(
        Pair::new(j.a.clone(), j.b.clone()),
        &press(),
        o,
        &Session::default(),
    )
    .unwrap()
    .summary;
    let fast = HapticOptions {
        rate: 10_000.0,
        budget: 1e-4,
        ..o
    };
    // Undelayed, and with each collision query 2 ms late (a slow machine: ≤ 500 models/s).
    for (delay, depth) in [(0.0, BITE_DEPTH_MM), (2e-3, 0.4)] {
        let session = Session {
            realtime: true,
            collision: Some(CollisionOptions {
                delay,
                ..Default::default()
            }),
            keep_ticks: false,
        };
        let s = run(
            Pair::new(j.a.clone(), j.b.clone()),
            &press(),
            fast,
            &session,
        )
        .unwrap()
        .summary;
        eprintln!("10 kHz, collision delay {delay} s: {s:?}");
        let what = format!("delay {delay} s: {s:?}");
        assert_eq!(s.ticks, 60_001);
        assert!(s.energy_to_user_max_j <= 1e-4, "{what}");
        assert!(s.max_force_step_n <= 0.05 * s.max_force_n, "{what}");
        assert!(s.max_depth_mm <= depth, "{what}");
        assert!(
            (s.max_force_n - exact.max_force_n).abs() <= 0.2 * exact.max_force_n,
            "{what}; 1 kHz exact: {} N",
            exact.max_force_n
        );
        // The servo tick is the model's evaluation and the step, whatever the contact: no
        // query ever runs on it, and its median is a few microseconds. Its tail is the
        // machine's: on 2 shared cores with the collision thread beside it, preemption put
        // the p99 at 17 µs once, so the tail is held to half the budget, and the deadline
        // (below) is the bar that matters.
        assert_eq!(s.budgeted_ticks, 0, "{what}");
        assert!(s.compute_p50_us <= 5.0, "{what}");
        assert!(s.compute_p99_us <= 0.5 * s.budget_us, "{what}");
        assert!(s.deadline_misses * 1000 <= s.ticks, "{what}");
        assert!(s.collision_rate_hz.unwrap() > 300.0, "{what}");
    }
}

#[test]
#[ignore = "real data: run with --ignored"]
fn occlusion_finds_the_scanned_bite_from_open_starts() {
    let _serial = serial();
    let j = jaw();
    let (up, left, ant) = (j.frame.up, j.frame.left, j.frame.anterior);
    let mut landmarks = vec![j.frame.incisal];
    landmarks.extend(
        crown_centres(&Teeth::load(&common::data("jaw/ofj_p26_teeth_axes_mandible.json")).unwrap())
            .into_iter()
            .map(|(_, c)| c),
    );
    assert!(landmarks.len() >= 10, "{} landmarks", landmarks.len());
    let deg = 1f64.to_radians();
    let starts = [
        (2.0, 0.0, 0.0, 0.0),
        (3.0, 0.5, deg, 0.0),
        (4.0, -0.5, 0.0, deg),
        (2.5, 0.3, -deg, -deg),
        (3.5, -0.2, 0.5 * deg, deg),
    ];
    let opts = OcclusionOptions {
        axis: up,
        joints: Some(Joints::temporomandibular(&j.frame, &Pose::IDENTITY, 20.0)),
        ..Default::default()
    };
    for (open, side, yaw, roll) in starts {
        let rot = DQuat::from_axis_angle(up, yaw) * DQuat::from_axis_angle(ant, roll);
        let from = Pose::new(up * -open + left * side, rot).unwrap();
        let t = std::time::Instant::now();
        let mut pair = Pair::new(j.a.clone(), j.b.clone());
        let o = occlude(&mut pair, &Pose::IDENTITY, &from, &opts).unwrap();
        let secs = t.elapsed().as_secs_f64();
        assert!(o.converged(), "from {from:?}: {} steps", o.steps);
        assert!(secs <= 10.0, "{secs} s");
        let worst = landmarks
            .iter()
            .map(|p| (o.pose.transform_point(*p) - *p).length())
            .fold(0.0, f64::max);
        eprintln!("open {open} side {side} yaw {yaw} roll {roll}: {} steps, {secs:.2} s, landmarks within {worst:.3} mm", o.steps);
        assert!(worst <= 0.5, "landmark {worst} mm from the scanned bite");
    }
}

/// The final splint at the bite `occlude` finds from 3 mm open: opened about the hinge just
/// enough for its material (`least_opening`), it seats on both arches.
#[test]
#[ignore = "real data: run with --ignored"]
fn the_final_splint_at_the_found_bite_seats_on_both_arches() {
    let _serial = serial();
    let j = jaw();
    let opts = OcclusionOptions {
        axis: j.frame.up,
        joints: Some(Joints::temporomandibular(&j.frame, &Pose::IDENTITY, 20.0)),
        ..Default::default()
    };
    let from = Pose::from_translation(j.frame.up * -3.0);
    let mut pair = Pair::new(j.a.clone(), j.b.clone());
    let bite = occlude(&mut pair, &Pose::IDENTITY, &from, &opts).unwrap();
    assert!(bite.converged());
    let load = |rel: &str| Mesh::load(common::data(rel)).unwrap();
    let a = load("jaw/ofj_p26_maxilla_teeth.stl.gz");
    let b = load("jaw/ofj_p26_mandible_teeth.stl.gz");
    let s_opts = innersphere_dental::splint::SplintOptions::default();
    let open = innersphere_dental::splint::least_opening(&a, &b, &bite.pose, &s_opts).unwrap();
    assert!(open > 0.5 && open < 5.0, "opened {open} mm");
    let pose = innersphere_dental::splint::opened(&a, &b, &bite.pose, open).unwrap();
    let s = innersphere_dental::splint::make(&a, &b, &pose, &s_opts).unwrap();
    eprintln!("opened {open} mm: {:#?}", s.report);
    innersphere_testkit::splint::assert_seats(&a, &b, &pose, &s_opts, &s);
}

/// The mandible's crown centres (its teeth-axes file).
fn mandible_crowns() -> Vec<innersphere::glam::DVec3> {
    crown_centres(&Teeth::load(&common::data("jaw/ofj_p26_teeth_axes_mandible.json")).unwrap())
        .into_iter()
        .map(|(_, c)| c)
        .collect()
}

/// 8 open starts drawn from `seed` (xorshift64: drawn, not picked): 1–4 mm open along the
/// pair's "up", ±1.5 mm sideways and forwards, ±3° yaw, ±2° roll and pitch about `centre`.
/// Each with how far open it is.
fn open_starts(j: &Jaw, centre: innersphere::glam::DVec3, seed: u64) -> Vec<(f64, Pose)> {
    let (up, left, ant) = (j.frame.up, j.frame.left, j.frame.anterior);
    let mut state = seed;
    let mut draw = |lo: f64, hi: f64| {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        lo + (hi - lo) * ((state >> 11) as f64 / (1u64 << 53) as f64)
    };
    (0..8)
        .map(|_| {
            let open = draw(1.0, 4.0);
            let t = -up * open + left * draw(-1.5, 1.5) + ant * draw(-1.5, 1.5);
            let q = DQuat::from_axis_angle(up, draw(-3.0, 3.0).to_radians())
                * DQuat::from_axis_angle(ant, draw(-2.0, 2.0).to_radians())
                * DQuat::from_axis_angle(left, draw(-2.0, 2.0).to_radians());
            (open, Pose::new(t + centre - q * centre, q).unwrap())
        })
        .collect()
}

/// A free segment (no joints) from 8 random open starts (1–4 mm open along the pair's "up",
/// ±1.5 mm sideways and forwards, ±3° yaw, ±2° roll and pitch about the crowns' centre, drawn
/// from a seed): `occlude_free` chooses a pose with every crown centre of the mandible within
/// 0.5 mm of the scanned bite, each in at most 10 s.
#[test]
#[ignore = "real data: run with --ignored"]
fn free_occlusion_finds_the_scanned_bite_from_random_open_starts() {
    let _serial = serial();
    let j = jaw();
    let (up, left) = (j.frame.up, j.frame.left);
    let crowns = mandible_crowns();
    let centre = crowns.iter().sum::<innersphere::glam::DVec3>() / crowns.len() as f64;
    let opts = FreeOcclusionOptions {
        closing: OcclusionOptions {
            axis: up,
            contact_stiffness: 1000.0,
            max_seconds: 20.0,
            ..Default::default()
        },
        lateral: left,
        ..Default::default()
    };
    for (open, from) in open_starts(j, centre, 0x5eed_0005) {
        let t0 = std::time::Instant::now();
        let f = occlude_free(&j.a, &j.b, &Pose::IDENTITY, &from, &opts).unwrap();
        let secs = t0.elapsed().as_secs_f64();
        let worst = crowns
            .iter()
            .map(|p| (f.closing.pose.transform_point(*p) - *p).length())
            .fold(0.0, f64::max);
        eprintln!(
            "open {open:.2}: {} candidates, chosen reached from {} of {} starts, {secs:.2} s, crowns within {worst:.3} mm",
            f.candidates.len(),
            f.candidates[0].starts,
            opts.starts
        );
        assert!(f.closing.converged());
        assert!(secs <= 10.0, "{secs} s");
        assert!(
            worst <= 0.5,
            "a crown centre {worst} mm from the scanned bite"
        );
    }
}

/// The free bite on the meshes' own contact (`contact: Mesh`: the search on the spheres, the
/// chosen rest settled on the meshes) from 8 open starts of a seed no other test draws:
/// every crown centre of the mandible within 0.5 mm of the scanned bite (the spheres' bar; the
/// issue's 0.25 mm is not met: docs/OCCLUSION.md). Prints the scanned bite's own overlap of
/// the meshes beside it (2.1 mm³: the scans interpenetrate there, which a stiff contact does
/// not allow) and the distance to that bite opened until it does.
#[test]
#[ignore = "real data: run with --ignored"]
fn free_occlusion_on_the_meshes_finds_the_scanned_bite() {
    let _serial = serial();
    let j = jaw();
    let (a, b) = (
        j.a.clone().with_mesh(&j.meshes.0).unwrap(),
        j.b.clone().with_mesh(&j.meshes.1).unwrap(),
    );
    let (up, left) = (j.frame.up, j.frame.left);
    let crowns = mandible_crowns();
    let centre = crowns.iter().sum::<innersphere::glam::DVec3>() / crowns.len() as f64;
    let scanned = innersphere::Pair::new(&a, &b)
        .mesh_penetration_with(&Pose::IDENTITY, &Pose::IDENTITY, &Default::default())
        .unwrap();
    // The scanned bite opened along "up" until the meshes overlap by no more than the
    // closing force over the contact stiffness (5 N / 1000 N/mm³): the bite a rigid contact
    // can rest in, nearest the scan.
    let rest_volume = 5.0 / 1000.0;
    let mut probe = innersphere::Pair::new(&a, &b);
    let mut volume_at = |s: f64| {
        probe
            .mesh_penetration_with(
                &Pose::IDENTITY,
                &Pose::from_translation(-up * s),
                &Default::default(),
            )
            .unwrap()
            .volume
    };
    let (mut lo, mut hi) = (0.0, 1.0);
    for _ in 0..40 {
        let mid = 0.5 * (lo + hi);
        if volume_at(mid) > rest_volume {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let lifted = Pose::from_translation(-up * hi);
    eprintln!(
        "the scanned bite: the meshes overlap by {:.3} mm³ in {} patches (mean depth up to {:.3} mm); opened {:.3} mm along up they overlap by {rest_volume} mm³",
        scanned.volume, scanned.patch_count, scanned.max_depth, hi
    );
    let opts = FreeOcclusionOptions {
        closing: OcclusionOptions {
            axis: up,
            contact_stiffness: 1000.0,
            max_seconds: 20.0,
            contact: innersphere_haptic::ContactSource::Mesh,
            ..Default::default()
        },
        lateral: left,
        ..Default::default()
    };
    for (open, from) in open_starts(j, centre, 0x5eed_0058) {
        let t0 = std::time::Instant::now();
        let f = occlude_free(&a, &b, &Pose::IDENTITY, &from, &opts).unwrap();
        let secs = t0.elapsed().as_secs_f64();
        let worst = crowns
            .iter()
            .map(|p| (f.closing.pose.transform_point(*p) - *p).length())
            .fold(0.0, f64::max);
        let worst_lifted = crowns
            .iter()
            .map(|p| (f.closing.pose.transform_point(*p) - lifted.transform_point(*p)).length())
            .fold(0.0, f64::max);
        let along = (f.closing.pose.transform_point(centre) - centre).dot(up);
        eprintln!(
            "open {open:.2}: {} candidates, {secs:.2} s, the meshes overlap by {:.3} mm³ at rest, {along:.3} mm along up; crowns within {worst:.3} mm of the scanned bite, {worst_lifted:.3} mm of it opened to rest",
            f.candidates.len(),
            f.closing.volume
        );
        assert!(f.closing.converged(), "{:?}", f.closing.status);
        assert!(
            worst <= 0.5,
            "a crown centre {worst} mm from the scanned bite"
        );
    }
}
