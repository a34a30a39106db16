//! The servo side on a stale contact model and the multi-rate loop: a servo fed models that
//! are many ticks old stays passive (proptest over stiffness, damping, model age and rate);
//! a model update never steps the force by more than the slew allows; the servo tick never
//! waits for a collision thread that is stuck; a slow collision thread leaves the loop
//! passive, smooth and the tool out of the slab.

use crate::haptic_util;

use glam::{DQuat, DVec3};
use haptic_util::{assert_passive_as_servo, on_slab, options, serial, slab_and_block, swing};
use innersphere::{Pair, PenetrationOptions, Pose};
use innersphere_haptic::{
    CollisionOptions, ContactModel, ContactSource, HapticLoop, HapticOptions, MultirateLoop,
    RigidBody, Servo,
};
use proptest::prelude::*;
use std::collections::VecDeque;
use std::time::{Duration, Instant};

/// The penetration query's options of a loop with `o`.
fn penetration(o: &HapticOptions) -> PenetrationOptions {
    PenetrationOptions {
        stiffness: o.contact_stiffness,
        max_patches: o.max_patches,
        linearize: true,
        ..Default::default()
    }
}

/// One move of the device: to `(x, y, into)` (mm; `into` below the slab's top), turned
/// `(rx, ry)` (rad), in this many ticks.
type Move = ((f64, f64, f64), (f64, f64), usize);

/// A device path: from above the slab, smooth moves to points between 0.5 mm above and
/// 1.5 mm inside it, turned a little, with rests.
fn device_path(moves: &[Move], rest: usize) -> Vec<Pose> {
    let mut out = vec![on_slab(-0.5)];
    for &((x, y, into), (rx, ry), n) in moves {
        let from = *out.last().unwrap();
        let to = Pose::new(
            DVec3::new(x, y, on_slab(into).translation.z),
            DQuat::from_rotation_x(rx) * DQuat::from_rotation_y(ry),
        )
        .unwrap();
        for i in 1..=n {
            let s = i as f64 / n as f64;
            out.push(Pose {
                rotation: from.rotation.slerp(to.rotation, s).normalize(),
                translation: from.translation.lerp(to.translation, s),
            });
        }
        out.extend(std::iter::repeat_n(to, rest));
    }
    out
}

/// Runs a [`Servo`] along `path` with contact models made `age` ticks late: each tick's
/// model is the exact query at the tool's pose `age` ticks before. Returns the servo and
/// the largest force step between ticks and the largest force.
fn stale_run(o: HapticOptions, path: &[Pose], age: usize) -> (Servo, f64, f64) {
    let (a, b) = slab_and_block();
    let mut pair = Pair::new(a.clone(), b.clone());
    let body = RigidBody::from_tree(b.tree(), o.density).unwrap();
    let mut servo = Servo::new(body, path[0], o).unwrap();
    let pen = penetration(&o);
    let mut asked: VecDeque<Pose> = VecDeque::new();
    let (mut last, mut step, mut max) = (DVec3::ZERO, 0.0f64, 0.0f64);
    for (i, dev) in path.iter().enumerate() {
        asked.push_back(servo.state().pose);
        let model = if asked.len() > age {
            let p = asked.pop_front().unwrap();
            let q = pair.penetration_with(&Pose::IDENTITY, &p, &pen);
            Some(ContactModel::from_penetration(p, &q, Instant::now()))
        } else {
            None
        };
        let t = servo.tick(dev, 1.0 / o.rate, model.as_ref());
        if i > 0 {
            step = step.max((t.force - last).length());
        }
        last = t.force;
        max = max.max(t.force.length());
    }
    (servo, step, max)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(40))]

    /// Whatever the coupling (any stiffness up to the device's, any damping of at least
    /// k·T/2), the contact stiffness, the rate, the tool's mass (5 to 30 g) and how stale the
    /// contact models are (up to 5 ms late), the energy the device has given the hand never
    /// rises above zero, for hand motions up to 60 mm/s. Outside that range a contact the
    /// models learn of late can give energy back: see docs/HAPTICS.md for the measured
    /// figures. (A one-tick jerk into contact gives the hand the coupling spring's energy
    /// under any contact model, the exact one in the tick too: that is the device step's
    /// limit, not the model's.)
    #[test]
    fn a_servo_on_stale_models_is_passive(
        k in 0.2f64..5.0,
        b_factor in 1.0f64..20.0,
        contact in 5.0f64..100.0,
        grams in 5.0f64..30.0,
        rate in prop_oneof![Just(1000.0), Just(4000.0), Just(10000.0)],
        late_ms in 0.1f64..5.0,
        moves in prop::collection::vec(
            ((-2.0f64..2.0, -2.0f64..2.0, -0.3f64..1.5), (-0.05f64..0.05, -0.05f64..0.05), 0.06f64..0.4),
            1..5,
        ),
    ) {
        let _serial = serial();
        let mut o = options();
        o.rate = rate;
        o.budget = 1.0;
        o.contact_stiffness = contact;
        o.coupling.stiffness = k;
        o.coupling.damping = b_factor * k / rate / 2.0;
        o.coupling.angular_stiffness = k * 400.0;
        o.coupling.angular_damping = o.coupling.damping * 400.0;
        // The block is 32 mm³.
        o.density = grams * 1e-3 / 32.0;
        let moves: Vec<_> = moves
            .into_iter()
            .map(|(to, turn, seconds)| (to, turn, (seconds * rate) as usize))
            .collect();
        let rest = (0.05 * rate) as usize;
        let path = device_path(&moves, rest);
        let age = ((late_ms * 1e-3 * rate).round() as usize).max(1);
        let (servo, _, _) = stale_run(o, &path, age);
        prop_assert!(
            servo.energy_to_user_max() <= 1e-9,
            "energy to the hand rose to {} J (k {k} N/mm, b {} N·s/mm, contact {contact} N/mm³, {grams} g, {rate} Hz, {age} ticks late)",
            servo.energy_to_user_max(), o.coupling.damping
        );
    }
}

#[test]
fn stale_models_hold_the_tool_where_fresh_ones_do_without_a_kick() {
    let _serial = serial();
    // Pressing 1 mm into the slab, sliding 2 mm sideways while pressing, letting go; models
    // fresh (1 tick) and 20 ticks (5 ms at 4 kHz) late.
    let mut o = options();
    o.rate = 4000.0;
    o.budget = 1.0;
    let moves = [
        ((0.0, 0.0, 1.0), (0.0, 0.0), 2000),
        ((2.0, 0.0, 1.0), (0.0, 0.02), 2000),
        ((2.0, 0.0, -0.5), (0.0, 0.0), 1000),
    ];
    let path = device_path(&moves, 1000);
    let (fresh, fresh_step, fresh_max) = stale_run(o, &path, 1);
    let (stale, stale_step, stale_max) = stale_run(o, &path, 20);
    for (s, step, max) in [
        (&fresh, fresh_step, fresh_max),
        (&stale, stale_step, stale_max),
    ] {
        assert!(s.energy_to_user_max() <= 1e-9, "{}", s.energy_to_user_max());
        assert!(step <= 0.05 * max, "step {step} N of {max} N");
    }
    assert!(
        (stale_max - fresh_max).abs() <= 0.2 * fresh_max,
        "max force {stale_max} N on stale models, {fresh_max} N on fresh ones"
    );
}

#[test]
fn the_servo_never_waits_for_a_stuck_collision_thread() {
    let _serial = serial();
    let (a, b) = slab_and_block();
    let o = options();
    // Each collision query sleeps 0.3 s first: a lock shared with the servo would hold the
    // tick for as long.
    let c = CollisionOptions {
        delay: 0.3,
        ..Default::default()
    };
    let mut hl = MultirateLoop::spawn(
        Pair::new(a.clone(), b.clone()),
        Pose::IDENTITY,
        on_slab(-0.5),
        o,
        c,
    )
    .unwrap();
    let start = Instant::now();
    let mut worst = 0.0f64;
    let mut ticks = 0;
    while start.elapsed() < Duration::from_millis(250) {
        let t = hl.tick(&on_slab(-0.4));
        worst = worst.max(t.compute);
        ticks += 1;
    }
    assert!(ticks > 1000, "{ticks} ticks in 0.25 s");
    // A shared lock would hold a tick for the query's 0.3 s; a loaded machine may preempt a
    // tick for milliseconds (5.4 ms seen with builds running beside it).
    assert!(worst < 0.1, "a servo tick took {worst} s");
    // The collision thread was stuck in its delay all along.
    assert_eq!(hl.collision_queries(), 0);
    let stats = hl.finish();
    assert!(stats.queries <= 1, "{stats:?}");
}

/// Runs `hl.tick` along `path` paced at `rate` in real time (sleep, then spin).
fn paced(
    path: &[Pose],
    rate: f64,
    mut tick: impl FnMut(&Pose) -> innersphere_haptic::Tick,
) -> Vec<innersphere_haptic::Tick> {
    let start = Instant::now();
    let mut out = Vec::with_capacity(path.len());
    for (i, p) in path.iter().enumerate() {
        let due = start + Duration::from_secs_f64(i as f64 / rate);
        if let Some(left) = due.checked_duration_since(Instant::now()) {
            if left > Duration::from_micros(100) {
                std::thread::sleep(left - Duration::from_micros(100));
            }
        }
        while Instant::now() < due {
            std::hint::spin_loop();
        }
        out.push(tick(p));
    }
    out
}

#[test]
fn a_slow_collision_thread_keeps_the_loop_passive_smooth_and_out_of_the_slab() {
    let _serial = serial();
    let (a, b) = slab_and_block();
    let mut o = options();
    o.rate = 2000.0;
    o.budget = 1.0 / o.rate;
    let moves = [
        ((0.0, 0.0, 1.0), (0.0, 0.0), 1000),
        ((1.5, 0.5, 1.0), (0.02, 0.0), 1000),
        ((1.5, 0.5, -0.5), (0.0, 0.0), 600),
    ];
    let path = device_path(&moves, 400);
    // The reference: the exact query in the tick.
    let mut exact = HapticLoop::new(
        Pair::new(a.clone(), b.clone()),
        Pose::IDENTITY,
        path[0],
        HapticOptions { budget: 1.0, ..o },
    )
    .unwrap();
    let reference: Vec<_> = path.iter().map(|p| exact.tick(p)).collect();
    let ref_max = reference
        .iter()
        .map(|t| t.force.length())
        .fold(0.0, f64::max);
    let ref_low = reference
        .iter()
        .map(|t| t.tool.translation.z)
        .fold(f64::INFINITY, f64::min);
    for delay in [0.0, 2e-3] {
        let mut hl = MultirateLoop::spawn(
            Pair::new(a.clone(), b.clone()),
            Pose::IDENTITY,
            path[0],
            o,
            CollisionOptions {
                delay,
                ..Default::default()
            },
        )
        .unwrap();
        let ticks = paced(&path, o.rate, |p| hl.tick(p));
        let max = ticks.iter().map(|t| t.force.length()).fold(0.0, f64::max);
        let step = ticks
            .windows(2)
            .map(|w| (w[1].force - w[0].force).length())
            .fold(0.0, f64::max);
        let low = ticks
            .iter()
            .map(|t| t.tool.translation.z)
            .fold(f64::INFINITY, f64::min);
        let age = ticks.iter().map(|t| t.model_age).fold(0.0, f64::max);
        let energy = hl.energy_to_user_max();
        let stats = hl.finish();
        let what = format!(
            "delay {delay} s: max force {max} N (exact {ref_max}), step {step} N, lowest z {low} (exact {ref_low}), oldest model {age} s, energy {energy} J, {} models",
            stats.queries
        );
        assert!(energy <= 1e-9, "{what}");
        assert!(step <= 0.05 * max, "{what}");
        assert!((max - ref_max).abs() <= 0.2 * ref_max, "{what}");
        assert!(low >= ref_low - 0.1, "{what}");
        assert!(stats.queries > 100, "{what}");
    }
}

#[test]
fn apart_the_loop_moves_the_tool_and_counts_the_energy_as_a_lone_servo_does() {
    let _serial = serial();
    let (a, b) = slab_and_block();
    let o = options();
    // 20 mm above the slab: the collision thread's models are all empty, so the tool's
    // motion and the energy are the servo's alone, whenever the models arrive.
    let start = on_slab(-20.0);
    let mut hl = MultirateLoop::spawn(
        Pair::new(a.clone(), b.clone()),
        Pose::IDENTITY,
        start,
        o,
        CollisionOptions::default(),
    )
    .unwrap();
    let body = RigidBody::from_tree(b.tree(), o.density).unwrap();
    let mut servo = Servo::new(body, start, o).unwrap();
    // The device moves and turns smoothly; the hand does work on the coupling.
    for (i, p) in swing(start, o.rate, 400).iter().enumerate() {
        let t = hl.tick(p);
        let s = servo.tick(p, 1.0 / o.rate, None);
        assert_eq!((t.tool, t.force), (s.tool, s.force), "tick {i}");
        if i % 50 == 10 {
            // Let models arrive mid-run.
            let asked = Instant::now();
            let n = hl.collision_queries();
            while hl.collision_queries() == n && asked.elapsed() < Duration::from_secs(10) {
                std::thread::sleep(Duration::from_micros(100));
            }
        }
    }
    assert!(hl.collision_queries() >= 3, "{}", hl.collision_queries());
    assert_passive_as_servo((hl.energy_to_user(), hl.energy_to_user_max()), &servo);
}

#[test]
fn dropping_the_loop_stops_and_joins_its_collision_thread() {
    let _serial = serial();
    // Trees of its own: the thread's pair is the only other holder of them.
    let a = haptic_util::build(&innersphere::shapes::cuboid(DVec3::splat(2.0)), 12);
    let b = a.clone();
    let before = std::sync::Arc::strong_count(b.tree());
    let hl = MultirateLoop::spawn(
        Pair::new(a.clone(), b.clone()),
        Pose::IDENTITY,
        Pose::from_translation(DVec3::new(0.0, 0.0, 10.0)),
        options(),
        CollisionOptions::default(),
    )
    .unwrap();
    assert!(std::sync::Arc::strong_count(b.tree()) > before);
    drop(hl);
    assert_eq!(std::sync::Arc::strong_count(b.tree()), before);
}

#[test]
fn every_query_out_of_its_budget_is_counted_as_budgeted() {
    let _serial = serial();
    let (a, b) = slab_and_block();
    // Held 0.5 mm into the slab with a nanosecond's budget: the time-critical query has room
    // for one node pair and never completes, so each model is the one in use, capped.
    let mut hl = MultirateLoop::spawn(
        Pair::new(a.clone(), b.clone()),
        Pose::IDENTITY,
        on_slab(0.5),
        options(),
        CollisionOptions {
            budget: 1e-9,
            ..Default::default()
        },
    )
    .unwrap();
    let asked = Instant::now();
    while hl.collision_queries() < 20 && asked.elapsed() < Duration::from_secs(10) {
        hl.tick(&on_slab(0.5));
        std::thread::sleep(Duration::from_micros(200));
    }
    let stats = hl.finish();
    assert!(stats.queries >= 20, "{stats:?}");
    assert_eq!(stats.budgeted, stats.queries);
}

#[test]
fn a_tool_pushed_out_of_a_contact_gives_the_rising_hand_energy_and_the_largest_is_kept() {
    let _serial = serial();
    let (a, b) = slab_and_block();
    let o = options();
    // As haptic.rs's test of the same name, with the query in its thread: paced in real
    // time, so that the models arrive as the tool rises.
    let mut hl = MultirateLoop::spawn(
        Pair::new(a.clone(), b.clone()),
        Pose::IDENTITY,
        on_slab(0.5),
        o,
        CollisionOptions::default(),
    )
    .unwrap();
    let path: Vec<Pose> = (0..400).map(|i| on_slab(0.5 - i as f64 / 400.0)).collect();
    let mut top = 0.0f64;
    paced(&path, o.rate, |p| {
        let t = hl.tick(p);
        top = top.max(hl.energy_to_user());
        t
    });
    assert!(top > 0.0, "{top} J");
    assert_eq!(hl.energy_to_user_max(), top);
}

/// The multi-rate loop on the meshes' own contact: refused without the meshes; with them,
/// a block pressed 1 mm into a slab by the device rests on the slab's top (the meshes'
/// exact volume is `16 mm² × depth`, so at 50 N/mm³ the coupling's pull sinks it by
/// microns), passive, smooth, and the force the coupling's.
#[test]
fn mesh_contact_rests_the_block_on_the_slab_passively() {
    let _serial = serial();
    let (a, b) = slab_and_block();
    let mut o = options();
    o.rate = 2000.0;
    o.budget = 1.0 / o.rate;
    let mesh = CollisionOptions {
        contact: ContactSource::Mesh,
        ..Default::default()
    };
    let err = MultirateLoop::spawn(
        Pair::new(a.clone(), b.clone()),
        Pose::IDENTITY,
        on_slab(-0.5),
        o,
        mesh,
    )
    .unwrap_err();
    assert!(err.to_string().contains("meshes"), "{err}");

    let slab = innersphere::shapes::cuboid(DVec3::new(10.0, 10.0, 1.0));
    let block = innersphere::shapes::cuboid(DVec3::new(2.0, 2.0, 1.0));
    let (a, b) = (
        a.clone().with_mesh(&slab).unwrap(),
        b.clone().with_mesh(&block).unwrap(),
    );
    let path = device_path(
        &[
            ((0.0, 0.0, 1.0), (0.0, 0.0), 1000),
            ((0.7, 0.3, 1.0), (0.0, 0.0), 600),
            ((0.7, 0.3, -0.5), (0.0, 0.0), 400),
        ],
        400,
    );
    let mut hl = MultirateLoop::spawn(Pair::new(a, b), Pose::IDENTITY, path[0], o, mesh).unwrap();
    let ticks = paced(&path, o.rate, |p| hl.tick(p));
    let max = ticks.iter().map(|t| t.force.length()).fold(0.0, f64::max);
    let step = ticks
        .windows(2)
        .map(|w| (w[1].force - w[0].force).length())
        .fold(0.0, f64::max);
    let low = ticks
        .iter()
        .map(|t| t.tool.translation.z)
        .fold(f64::INFINITY, f64::min);
    let energy = hl.energy_to_user_max();
    let stats = hl.finish();
    let what = format!(
        "max force {max} N, step {step} N, lowest z {low}, energy {energy} J, {} models",
        stats.queries
    );
    assert!(energy <= 1e-9, "{what}");
    assert!(step <= 0.05 * max, "{what}");
    // 1 mm of device depth on the coupling's 60 % of omega's 5 N/mm: about 3 N, the block
    // at most 0.05 mm into the slab (the model is a few ticks old when it lands).
    assert!((2.0..=3.5).contains(&max), "{what}");
    assert!(low >= on_slab(0.05).translation.z, "{what}");
    assert!(stats.queries > 100, "{what}");
}
