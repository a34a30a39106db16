//! The servo step alone (`Servo::tick`, no query, no clock in its answers), deterministic:
//! the force and torque sent never pass the device's limits and saturate along the pull;
//! the energy to the user is the work of the held force and torque on the device's motion;
//! a device quaternion q or −q, a rigid re-framing of the whole scene, and interleaving with
//! another servo change nothing; a held device converges to the static force of a contact
//! model.

use glam::{DMat3, DQuat, DVec3};
use innersphere::Pose;
use innersphere_haptic::{ContactModel, DeviceClass, HapticOptions, RigidBody, Servo, Tick};
use proptest::prelude::*;

const RATE: f64 = 1000.0;

fn body(mass: f64, com: DVec3) -> RigidBody {
    // A 10 × 6 × 4 mm box's inertia about its centre.
    let (a, b, c) = (10.0f64, 6.0f64, 4.0f64);
    let i = DVec3::new(b * b + c * c, a * a + c * c, a * a + b * b) * (mass / 12.0);
    RigidBody {
        mass,
        center_of_mass: com,
        inertia: DMat3::from_diagonal(i),
    }
}

/// Omega-class options with a device that renders torque too (50 N·mm), so that both
/// halves of the wrench reach the hand.
fn options() -> HapticOptions {
    let mut o = HapticOptions::for_device(DeviceClass::Omega);
    o.device.max_torque = 50.0;
    o
}

/// A smooth device path from `start` at rest: `amp` mm along `dir` and `turn` rad about
/// `axis`, as `1 − cos` of angular frequency `w`, slow enough that the loop takes every pose
/// as read (within its speed and acceleration limits).
fn path(start: Pose, dir: DVec3, axis: DVec3, amp: f64, turn: f64, w: f64, n: usize) -> Vec<Pose> {
    (1..=n)
        .map(|k| {
            let s = 1.0 - (w * k as f64 / RATE).cos();
            Pose {
                rotation: (DQuat::from_axis_angle(axis.normalize(), turn * s) * start.rotation)
                    .normalize(),
                translation: start.translation + dir.normalize() * (amp * s),
            }
        })
        .collect()
}

fn run(servo: &mut Servo, poses: &[Pose], model: Option<&ContactModel>) -> Vec<Tick> {
    poses
        .iter()
        .enumerate()
        .map(|(k, p)| servo.tick(p, 1.0 / RATE, if k == 0 { model } else { None }))
        .collect()
}

/// The rotation vector from `a` to `b`, the shorter way round.
fn turn(a: DQuat, b: DQuat) -> DVec3 {
    let mut d = b * a.conjugate();
    if d.w < 0.0 {
        d = -d;
    }
    d.to_scaled_axis()
}

fn close(a: DVec3, b: DVec3, tol: f64) -> bool {
    (a - b).length() <= tol * (1.0 + a.length().max(b.length()))
}

fn same_rotation(a: DQuat, b: DQuat, tol: f64) -> bool {
    a.dot(b).abs() >= 1.0 - tol
}

fn unit() -> impl Strategy<Value = DVec3> {
    (-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64)
        .prop_filter("a direction", |(x, y, z)| x * x + y * y + z * z > 0.05)
        .prop_map(|(x, y, z)| DVec3::new(x, y, z).normalize())
}

fn start() -> impl Strategy<Value = Pose> {
    (
        unit(),
        -1.0..1.0f64,
        (-5.0..5.0f64, -5.0..5.0f64, -5.0..5.0f64),
    )
        .prop_map(|(axis, angle, (x, y, z))| Pose {
            rotation: DQuat::from_axis_angle(axis, angle),
            translation: DVec3::new(x, y, z),
        })
}

#[test]
fn the_force_and_torque_sent_saturate_at_the_device_limits_along_the_pull() {
    // A heavy tool (2 kg, 1000 kg·mm²) lags a device that moves 3 mm and turns 0.3 rad in
    // 0.3 s: the
    // coupling stretches far past what the device renders.
    let mut o = options();
    o.device.max_force = 0.1;
    o.device.max_torque = 2.0;
    let com = DVec3::new(0.5, -0.3, 0.2);
    let s0 = Pose::IDENTITY;
    let heavy = RigidBody {
        inertia: DMat3::from_diagonal(DVec3::splat(1000.0)),
        ..body(2.0, com)
    };
    let mut servo = Servo::new(heavy, s0, o).unwrap();
    let poses = path(s0, DVec3::X, DVec3::Z, 1.5, 0.15, 10.0, 300);
    let (mut force_at_limit, mut torque_at_limit) = (0, 0);
    for p in &poses {
        let t = servo.tick(p, 1.0 / RATE, None);
        let (f, tau) = (t.force.length(), t.torque.length());
        assert!(f <= 0.1 * (1.0 + 1e-12), "{f} N sent to a 0.1 N device");
        assert!(
            tau <= 2.0 * (1.0 + 1e-12),
            "{tau} N·mm sent to a 2 N·mm device"
        );
        // The coupling's pull (before the clamp): towards the tool, from the device.
        let stretch = p.transform_point(com) - t.tool.transform_point(com);
        let twist = turn(t.tool.rotation, p.rotation);
        if f >= 0.1 * (1.0 - 1e-12) {
            force_at_limit += 1;
            assert!(t.force.dot(stretch) < -0.9 * f * stretch.length(), "{t:?}");
        }
        if tau >= 2.0 * (1.0 - 1e-12) {
            torque_at_limit += 1;
            assert!(t.torque.dot(twist) < -0.9 * tau * twist.length(), "{t:?}");
        }
    }
    assert!(
        force_at_limit > 50 && torque_at_limit > 50,
        "{force_at_limit} {torque_at_limit}"
    );
}

#[test]
fn a_device_that_renders_no_torque_gets_none() {
    let mut o = options();
    o.device.max_torque = 0.0;
    let s0 = Pose::IDENTITY;
    let mut servo = Servo::new(body(0.05, DVec3::ZERO), s0, o).unwrap();
    for t in run(
        &mut servo,
        &path(s0, DVec3::Y, DVec3::X, 1.0, 0.5, 8.0, 200),
        None,
    ) {
        assert_eq!(t.torque, DVec3::ZERO);
        assert!(t.force.is_finite());
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    #[test]
    fn the_energy_to_the_user_is_the_work_of_the_held_force_and_torque(
        s0 in start(), dir in unit(), axis in unit(),
        amp in 0.2..2.0f64, rot in 0.02..0.3f64, w in 2.0..12.0f64, mass in 0.01..0.5f64,
        (cx, cy, cz) in (-2.0..2.0f64, -2.0..2.0f64, -2.0..2.0f64),
    ) {
        let com = DVec3::new(cx, cy, cz);
        let mut servo = Servo::new(body(mass, com), s0, options()).unwrap();
        let poses = path(s0, dir, axis, amp, rot, w, 400);
        let (mut held, mut last) = ((DVec3::ZERO, DVec3::ZERO), s0);
        let (mut energy, mut top, mut torque_work) = (0.0f64, 0.0f64, 0.0f64);
        for p in &poses {
            let t = servo.tick(p, 1.0 / RATE, None);
            // Zero-order hold: last tick's force and torque over this tick's device motion.
            let dx = p.transform_point(com) - last.transform_point(com);
            let dth = turn(last.rotation, p.rotation);
            energy += (held.0.dot(dx) + held.1.dot(dth)) * 1e-3;
            torque_work += (held.1.dot(dth) * 1e-3).abs();
            top = top.max(energy);
            prop_assert!((servo.energy_to_user() - energy).abs() <= 1e-12 + 1e-9 * energy.abs(),
                "{} vs {energy}", servo.energy_to_user());
            prop_assert!((servo.energy_to_user_max() - top).abs() <= 1e-12 + 1e-9 * top.abs());
            held = (t.force, t.torque);
            last = *p;
        }
        // The torque's share is there to be counted.
        prop_assert!(torque_work > 1e-9, "{torque_work}");
    }

    #[test]
    fn a_device_quaternion_q_or_minus_q_is_the_same_pose(
        s0 in start(), dir in unit(), axis in unit(),
        amp in 0.2..2.0f64, rot in 0.02..0.5f64, w in 2.0..12.0f64,
    ) {
        let poses = path(s0, dir, axis, amp, rot, w, 300);
        let flipped: Vec<Pose> = poses
            .iter()
            .enumerate()
            .map(|(k, p)| Pose { rotation: if k % 2 == 1 { -p.rotation } else { p.rotation }, ..*p })
            .collect();
        let b = body(0.05, DVec3::new(1.0, 0.5, -0.5));
        let mut one = Servo::new(b, s0, options()).unwrap();
        let mut two = Servo::new(b, s0, options()).unwrap();
        for (p, q) in poses.iter().zip(&flipped) {
            let (t, u) = (one.tick(p, 1.0 / RATE, None), two.tick(q, 1.0 / RATE, None));
            prop_assert!(close(t.force, u.force, 1e-9) && close(t.torque, u.torque, 1e-9),
                "{t:?} vs {u:?}");
            prop_assert!(close(t.tool.translation, u.tool.translation, 1e-9));
            prop_assert!(same_rotation(t.tool.rotation, u.tool.rotation, 1e-12));
        }
        prop_assert!((one.energy_to_user() - two.energy_to_user()).abs() <= 1e-12);
    }

    #[test]
    fn a_rigid_reframing_of_the_scene_reframes_the_answers(
        s0 in start(), frame in start(), dir in unit(), axis in unit(), push in unit(),
        amp in 0.2..1.5f64, rot in 0.02..0.3f64, w in 2.0..12.0f64,
        (kx, ky, kz, kr) in (0.5..5.0f64, 0.5..5.0f64, 0.5..5.0f64, 1.0..50.0f64),
    ) {
        // A contact model at the start: a push of 2 N along `push`, a torque, an
        // anisotropic stiffness; in the re-framed scene, the same model rotated.
        let r = DMat3::from_quat(frame.rotation);
        let mut k = [[0.0; 6]; 6];
        for (i, v) in [kx, ky, kz, kr, kr, kr].into_iter().enumerate() {
            k[i][i] = v;
        }
        let model = ContactModel {
            force: push * 2.0,
            torque: DVec3::new(0.3, -0.2, 0.1),
            stiffness: k,
            volume: 0.04,
            ..ContactModel::none(s0)
        };
        let mut k2 = [[0.0; 6]; 6];
        let rb = |i: usize, j: usize| if i / 3 == j / 3 { r.col(j % 3)[i % 3] } else { 0.0 };
        for (i, row) in k2.iter_mut().enumerate() {
            for (j, v) in row.iter_mut().enumerate() {
                // R_b · K · R_bᵀ, R_b = diag(R, R).
                *v = (0..6).flat_map(|a| (0..6).map(move |b| (a, b)))
                    .map(|(a, b)| rb(i, a) * k[a][b] * rb(j, b))
                    .sum();
            }
        }
        let moved = ContactModel {
            pose: frame.then(&s0),
            force: r * model.force,
            torque: r * model.torque,
            stiffness: k2,
            ..model
        };
        let b = body(0.05, DVec3::new(0.7, -0.4, 0.3));
        let poses = path(s0, dir, axis, amp, rot, w, 300);
        let mut one = Servo::new(b, s0, options()).unwrap();
        let mut two = Servo::new(b, frame.then(&s0), options()).unwrap();
        for (k, p) in poses.iter().enumerate() {
            let m = |x| if k == 0 { Some(x) } else { None };
            let t = one.tick(p, 1.0 / RATE, m(&model));
            let u = two.tick(&frame.then(p), 1.0 / RATE, m(&moved));
            prop_assert!(close(r * t.force, u.force, 1e-8), "{k}: {t:?} vs {u:?}");
            prop_assert!(close(r * t.torque, u.torque, 1e-8));
            prop_assert!(close(r * t.contact_force, u.contact_force, 1e-8));
            let back = frame.then(&t.tool);
            prop_assert!(close(back.translation, u.tool.translation, 1e-8));
            prop_assert!(same_rotation(back.rotation, u.tool.rotation, 1e-12));
        }
        prop_assert!((one.energy_to_user() - two.energy_to_user()).abs() <= 1e-10);
    }

    #[test]
    fn servos_share_nothing_whatever_the_order_of_their_ticks(
        s0 in start(), dir in unit(), axis in unit(), amp in 0.2..2.0f64, w in 2.0..12.0f64,
    ) {
        let b = body(0.05, DVec3::new(0.2, 0.1, 0.0));
        let (p, q) = (path(s0, dir, axis, amp, 0.2, w, 200), path(s0, axis, dir, amp, 0.1, w, 200));
        let alone = |poses: &[Pose]| {
            let mut s = Servo::new(b, s0, options()).unwrap();
            run(&mut s, poses, None)
        };
        let (ta, tb) = (alone(&p), alone(&q));
        let mut one = Servo::new(b, s0, options()).unwrap();
        let mut two = Servo::new(b, s0, options()).unwrap();
        for k in 0..p.len() {
            // B's tick first on even ticks, A's first on odd ones.
            let (x, y) = if k % 2 == 0 {
                let y = two.tick(&q[k], 1.0 / RATE, None);
                (one.tick(&p[k], 1.0 / RATE, None), y)
            } else {
                let x = one.tick(&p[k], 1.0 / RATE, None);
                (x, two.tick(&q[k], 1.0 / RATE, None))
            };
            prop_assert_eq!((x.force, x.torque, x.tool), (ta[k].force, ta[k].torque, ta[k].tool));
            prop_assert_eq!((y.force, y.torque, y.tool), (tb[k].force, tb[k].torque, tb[k].tool));
        }
    }

    #[test]
    fn a_held_device_converges_to_the_static_force_of_the_contact(
        s0 in start(), push in unit(), f0 in 0.5..4.0f64, into in 0.2..1.5f64,
        (kx, ky, kz) in (1.0..20.0f64, 1.0..20.0f64, 1.0..20.0f64),
    ) {
        // A linear contact at the start pose pushing along `push`; the device held `into`
        // mm against it. At rest the spring's pull equals the contact's push, which is
        // what the hand feels, and the tool sits where the two balance.
        let o = options();
        let mut k = [[0.0; 6]; 6];
        for (i, v) in [kx, ky, kz, 5.0, 5.0, 5.0].into_iter().enumerate() {
            k[i][i] = v;
        }
        // A small torque too, against a rotational stiffness of 5 N·mm/rad.
        let tau0 = push.cross(DVec3::new(0.3, -0.5, 0.8)) * 0.5;
        let model = ContactModel {
            force: push * f0,
            torque: tau0,
            stiffness: k,
            volume: 0.1,
            ..ContactModel::none(s0)
        };
        let com = DVec3::new(0.3, 0.2, -0.1);
        let mut servo = Servo::new(body(0.02, com), s0, o).unwrap();
        let held = Pose { translation: s0.translation - push * into, ..s0 };
        let mut t = servo.tick(&held, 1.0 / RATE, Some(&model));
        for _ in 0..3000 {
            t = servo.tick(&held, 1.0 / RATE, None);
        }
        let c = t.contact_force.length();
        prop_assert!(c > 0.25 * f0, "{t:?}");
        prop_assert!((t.force - t.contact_force).length() <= 1e-3 * c, "{t:?}");
        prop_assert!(servo.state().velocity.length() < 1e-3, "{:?}", servo.state());
        // The balance: kc·(x_device − x_tool) = f0·n − K·(x_tool − x_start), per axis.
        let kc = o.coupling.stiffness;
        let (xd, x0) = (held.transform_point(com), s0.transform_point(com));
        let kv = DVec3::new(kx, ky, kz);
        let want = (xd * kc + push * f0 + kv * x0) / (kv + kc);
        prop_assert!(close(t.tool.transform_point(com), want, 1e-4), "{:?} vs {want}", t.tool);
        // And the rotation: k_θ·θ = τ₀ − 5·θ (small angles: to their square).
        let theta = turn(s0.rotation, t.tool.rotation);
        let want = tau0 / (o.coupling.angular_stiffness + 5.0);
        prop_assert!((theta - want).length() <= 1e-3 * want.length() + 1e-12, "{theta} vs {want}");
        prop_assert!(servo.energy_to_user_max() <= 1e-9, "{}", servo.energy_to_user_max());
    }
}

#[test]
fn a_body_no_integrator_can_move_is_refused() {
    let good = body(0.05, DVec3::new(0.1, 0.2, 0.3));
    let inertia = |cols: [[f64; 3]; 3]| RigidBody {
        inertia: DMat3::from_cols_array_2d(&cols),
        ..good
    };
    let bad = [
        (
            "mass infinite",
            RigidBody {
                mass: f64::INFINITY,
                ..good
            },
        ),
        (
            "mass NaN",
            RigidBody {
                mass: f64::NAN,
                ..good
            },
        ),
        ("mass zero", RigidBody { mass: 0.0, ..good }),
        ("mass negative", RigidBody { mass: -1.0, ..good }),
        (
            "centre NaN",
            RigidBody {
                center_of_mass: DVec3::new(0.0, f64::NAN, 0.0),
                ..good
            },
        ),
        (
            "inertia infinite",
            inertia([[f64::INFINITY, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]),
        ),
        // Each leading minor alone not positive (Sylvester's criterion): the first, the
        // second (the first and the determinant positive), the determinant, the
        // determinant exactly 0.
        (
            "first minor",
            inertia([[-1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0]]),
        ),
        (
            "second minor",
            inertia([[0.5, -0.6, 0.0], [-0.6, 0.5, 0.0], [0.0, 0.0, -1.0]]),
        ),
        (
            "determinant",
            inertia([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, -1.0]]),
        ),
        (
            "singular",
            inertia([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 0.0]]),
        ),
    ];
    for (what, b) in bad {
        let e = b.check().expect_err(what).to_string();
        assert!(e.contains("mass") && e.contains("inertia"), "{what}: {e}");
        assert!(Servo::new(b, Pose::IDENTITY, options()).is_err(), "{what}");
    }
    // Positive definite with off-diagonal terms is fine.
    assert!(inertia([[2.0, 0.5, 0.1], [0.5, 2.0, 0.2], [0.1, 0.2, 2.0]])
        .check()
        .is_ok());
    assert!(good.check().is_ok());
}

#[test]
fn a_bad_density_is_named_as_such() {
    use innersphere::{shapes, BuildOptions, Resolution, SphereTree};
    let o = BuildOptions {
        resolution: Resolution::Cells(12),
        ..Default::default()
    };
    let tree = SphereTree::build(&shapes::cuboid(DVec3::new(2.0, 1.0, 1.0)), &o).unwrap();
    for d in [0.0, -1.0, f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        let e = RigidBody::from_tree(&tree, d).unwrap_err().to_string();
        assert!(e.contains("the density must be"), "{d}: {e}");
    }
    // The 4 × 2 × 2 mm box: 16 mm³; about its centre, I_xx = m (2² + 2²) / 12, I_yy = I_zz =
    // m (4² + 2²) / 12.
    let b = RigidBody::from_tree(&tree, 2e-6).unwrap();
    let m = 16.0 * 2e-6;
    assert!((b.mass - m).abs() <= 1e-9 * m, "{b:?}");
    let want = DVec3::new(8.0, 20.0, 20.0) * (m / 12.0);
    let got = DVec3::new(b.inertia.x_axis.x, b.inertia.y_axis.y, b.inertia.z_axis.z);
    assert!(
        (got - want).length() <= 1e-9 * want.length(),
        "{got} vs {want}"
    );
}

#[test]
fn device_classes_round_trip_their_names_and_couple_passively_at_every_rate() {
    use innersphere_haptic::DeviceClass;
    for c in DeviceClass::ALL {
        assert_eq!(c.name().parse::<DeviceClass>().unwrap(), c);
        assert_eq!(c.to_string(), c.name());
        assert_eq!(
            format!(" {} ", c.name().to_uppercase())
                .parse::<DeviceClass>()
                .unwrap(),
            c
        );
        assert_eq!(c.coupling(), c.coupling_at(1000.0));
        let l = c.limits();
        for rate in [100.0, 250.0, 500.0, 1000.0, 4000.0, 10000.0] {
            let k = c.coupling_at(rate);
            // Passive with a factor of 4 (b ≥ 4·k·T/2, T at most 1 ms), within the device's
            // stiffness and damping, the angular coupling at the 20 mm lever.
            let period = 1.0 / f64::min(rate, 1000.0);
            assert!(
                k.damping >= 4.0 * k.stiffness * period / 2.0 * (1.0 - 1e-12),
                "{c} {rate}: {k:?}"
            );
            assert!(
                k.stiffness <= 0.6 * l.max_stiffness * (1.0 + 1e-12)
                    && k.damping <= l.max_damping * (1.0 + 1e-12)
            );
            assert!(k.stiffness > 0.0 && k.damping > 0.0);
            let lever2 = |x: f64| x * 20.0 * 20.0;
            assert_eq!(
                (k.angular_stiffness, k.angular_damping),
                (lever2(k.stiffness), lever2(k.damping))
            );
        }
        // Above 1 kHz the coupling is the 1 kHz one; below, a slower loop renders a softer one.
        assert_eq!(c.coupling_at(10000.0), c.coupling());
        assert!(c.coupling_at(100.0).stiffness < c.coupling().stiffness);
    }
    assert!("phantom"
        .parse::<DeviceClass>()
        .unwrap_err()
        .to_string()
        .contains("touch or omega"));
}

#[test]
fn a_bounded_model_reports_its_volume_bound_and_caps_the_push() {
    // A model of the time-critical query: its force capped at 0.5 N (a volume bound of
    // 0.5 / stiffness), though its linearised push is 3 N.
    let o = options();
    let s0 = Pose::IDENTITY;
    let model = ContactModel {
        force: DVec3::new(0.0, 0.0, 3.0),
        stiffness: [[0.0; 6]; 6],
        volume: 0.3,
        force_cap: 0.5,
        ..ContactModel::none(s0)
    };
    let mut servo = Servo::new(body(0.02, DVec3::ZERO), s0, o).unwrap();
    let mut t = servo.tick(&s0, 1.0 / RATE, Some(&model));
    for _ in 0..200 {
        t = servo.tick(&s0, 1.0 / RATE, None);
        assert!(t.contact_force.length() <= 0.5 * (1.0 + 1e-12), "{t:?}");
    }
    assert!(t.budgeted);
    assert_eq!(t.volume_bound, 0.5 / o.contact_stiffness);
    assert_eq!(t.volume, 0.3);
    assert!((t.contact_force.length() - 0.5).abs() < 1e-9, "{t:?}");
    // An exact model: the bound is its volume.
    let exact = ContactModel {
        force_cap: f64::INFINITY,
        ..model
    };
    let t = servo.tick(&s0, 1.0 / RATE, Some(&exact));
    assert!(!t.budgeted && t.volume_bound == 0.3, "{t:?}");
}

#[test]
fn the_energy_a_contact_gives_back_reaches_the_hand_and_its_peak_is_kept() {
    // The device presses the tool 0.5 mm into a contact pushing along +z, holds, then lets
    // it push the hand back out past the start: the contact's stored energy flows to the
    // hand, so the running energy to the hand rises above zero and its peak is kept.
    let s0 = Pose::IDENTITY;
    let mut k = [[0.0; 6]; 6];
    for (i, v) in [5.0, 5.0, 5.0, 2.0, 2.0, 2.0].into_iter().enumerate() {
        k[i][i] = v;
    }
    let model = ContactModel {
        force: DVec3::new(0.0, 0.0, 2.0),
        stiffness: k,
        volume: 0.1,
        ..ContactModel::none(s0)
    };
    let com = DVec3::new(0.2, 0.0, -0.1);
    let mut servo = Servo::new(body(0.02, com), s0, options()).unwrap();
    let z = |k: usize| {
        let s = |a: f64, b: f64, n: f64, i: f64| {
            a + (b - a) * 0.5 * (1.0 - (std::f64::consts::PI * i / n).cos())
        };
        match k {
            0..300 => s(0.0, -0.5, 300.0, k as f64),
            300..800 => -0.5,
            _ => s(-0.5, 0.3, 600.0, (k - 800).min(600) as f64),
        }
    };
    let (mut held, mut last, mut energy, mut top) = (DVec3::ZERO, s0, 0.0f64, 0.0f64);
    for k in 1..1600 {
        let p = Pose::from_translation(DVec3::new(0.0, 0.0, z(k)));
        let t = servo.tick(&p, 1.0 / RATE, if k == 1 { Some(&model) } else { None });
        energy += held.dot(p.transform_point(com) - last.transform_point(com)) * 1e-3;
        top = top.max(energy);
        assert!((servo.energy_to_user() - energy).abs() <= 1e-12 + 1e-9 * energy.abs());
        assert!((servo.energy_to_user_max() - top).abs() <= 1e-12 + 1e-9 * top);
        held = t.force;
        last = p;
    }
    assert!(top > 1e-5, "{top} J");
}

#[test]
fn a_tick_past_its_budget_is_late() {
    let s0 = Pose::IDENTITY;
    let mut o = options();
    o.budget = 1e-12;
    let mut servo = Servo::new(body(0.02, DVec3::ZERO), s0, o).unwrap();
    assert!(servo.tick(&s0, 1.0 / RATE, None).late);
    o.budget = 10.0;
    let mut servo = Servo::new(body(0.02, DVec3::ZERO), s0, o).unwrap();
    assert!(!servo.tick(&s0, 1.0 / RATE, None).late);
}

#[test]
fn a_bad_or_long_tick_step_counts_as_one_period() {
    let s0 = Pose::IDENTITY;
    let poses = path(s0, DVec3::new(1.0, 0.5, 0.0), DVec3::Y, 1.0, 0.2, 8.0, 300);
    let b = body(0.05, DVec3::new(0.3, 0.0, 0.1));
    let run_dt = |dt: f64| {
        let mut s = Servo::new(b, s0, options()).unwrap();
        poses
            .iter()
            .map(|p| s.tick(p, dt, None))
            .map(|t| (t.force, t.torque, t.tool))
            .collect::<Vec<_>>()
    };
    let one = run_dt(1.0 / RATE);
    for dt in [0.0, -1e-3, f64::NAN, f64::INFINITY, 10.5 / RATE] {
        assert!(run_dt(dt) == one, "dt {dt}");
    }
    // Up to ten periods is taken as measured.
    for dt in [2.0 / RATE, 10.0 / RATE] {
        assert!(run_dt(dt) != one, "dt {dt}");
    }
}

#[test]
fn a_device_that_turns_at_once_is_followed_within_the_speed_and_acceleration_limits() {
    // The device read turned by 2.5 rad about z in one tick: the loop takes it at most at
    // max_device_acceleration / 20 mm (rad/s²) and max_device_speed / 20 mm (rad/s), so the
    // tool (which lags it) turns no faster; a second later it is there.
    let o = options();
    let (wmax, amax) = (o.max_device_speed / 20.0, o.max_device_acceleration / 20.0);
    let s0 = Pose::IDENTITY;
    let turned = Pose {
        rotation: DQuat::from_rotation_z(2.5),
        ..s0
    };
    let mut servo = Servo::new(body(0.05, DVec3::new(1.0, 0.0, 0.0)), s0, o).unwrap();
    let h = 1.0 / RATE;
    let (mut bound, mut speed) = (0.0f64, 0.0f64);
    for k in 0..3000 {
        let t = servo.tick(&turned, h, None);
        speed = (speed + amax * h).min(wmax);
        bound += speed * h;
        let angle = turn(s0.rotation, t.tool.rotation).length();
        assert!(
            angle <= bound + 1e-9,
            "tick {k}: {angle} rad, at most {bound}"
        );
        if k == 2999 {
            assert!((angle - 2.5).abs() < 1e-6, "{angle}");
            assert!(t.tool.rotation.dot(turned.rotation).abs() > 1.0 - 1e-12);
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 16, ..ProptestConfig::default() })]

    #[test]
    fn the_wrench_sent_is_the_couplings_pull_on_the_device(
        s0 in start(), dir in unit(), axis in unit(),
        amp in 0.2..2.0f64, rot in 0.02..0.3f64, w in 2.0..12.0f64,
    ) {
        // Within the device's limits the force and torque sent are the coupling spring and
        // damper between the device (its pose and velocity as read) and the tool after the
        // step: −(k·(x_d − x_t) + b·(v_d − v_t)), and the same for the rotation.
        let o = options();
        let c = o.coupling;
        let com = DVec3::new(0.4, -0.2, 0.1);
        let mut servo = Servo::new(body(0.05, com), s0, o).unwrap();
        let h = 1.0 / RATE;
        let mut last = s0;
        for p in path(s0, dir, axis, amp, rot, w, 300) {
            let t = servo.tick(&p, h, None);
            let st = *servo.state();
            prop_assert_eq!(st.pose, t.tool);
            let (xd, xt) = (p.transform_point(com), t.tool.transform_point(com));
            let vd = (xd - last.transform_point(com)) / h;
            let wd = turn(last.rotation, p.rotation) / h;
            let f = -((xd - xt) * c.stiffness + (vd - st.velocity) * c.damping);
            let tau = -(turn(t.tool.rotation, p.rotation) * c.angular_stiffness
                + (wd - st.angular_velocity) * c.angular_damping);
            prop_assert!(f.length() < o.device.max_force && tau.length() < o.device.max_torque);
            prop_assert!(close(t.force, f, 1e-9), "{} vs {f}", t.force);
            prop_assert!(close(t.torque, tau, 1e-9), "{} vs {tau}", t.torque);
            last = p;
        }
    }
}

#[test]
fn a_new_model_comes_in_at_the_slew() {
    // From no contact to a constant 3 N push (no stiffness): the contact force on the tool
    // rises by at most model_slew · h per tick and then holds.
    let o = options();
    let s0 = Pose::IDENTITY;
    let model = ContactModel {
        force: DVec3::new(0.0, 3.0, 0.0),
        volume: 0.1,
        ..ContactModel::none(s0)
    };
    let mut servo = Servo::new(body(0.05, DVec3::ZERO), s0, o).unwrap();
    let step = o.model_slew / RATE;
    let mut prev = 0.0;
    for k in 0..20 {
        let t = servo.tick(&s0, 1.0 / RATE, if k == 0 { Some(&model) } else { None });
        let f = t.contact_force.length();
        assert!(
            f - prev <= step * (1.0 + 1e-9),
            "tick {k}: {prev} -> {f} N, at most {step}"
        );
        assert!(
            f - prev >= step * (1.0 - 1e-9) || (f - 3.0).abs() < 1e-12,
            "tick {k}: {prev} -> {f}"
        );
        prev = f;
    }
    assert!((prev - 3.0).abs() < 1e-12);
}

#[test]
fn a_device_that_jumps_is_followed_within_the_speed_and_acceleration_limits() {
    // Read 10 mm away along a skew direction in one tick (and, second, infinitely far along
    // +x): the loop takes the device there at most at max_device_acceleration and
    // max_device_speed, so the tool (which lags it) moves no faster, along the jump, and
    // (the finite jump) gets there.
    let o = options();
    let (vmax, amax) = (o.max_device_speed, o.max_device_acceleration);
    let s0 = Pose::IDENTITY;
    let dir = DVec3::new(1.0, -2.0, 0.5).normalize();
    let h = 1.0 / RATE;
    for (target, far) in [
        (dir * 10.0, false),
        (DVec3::new(f64::INFINITY, 0.0, 0.0), true),
    ] {
        let goal = Pose::from_translation(target);
        let along = if far { DVec3::X } else { dir };
        let mut servo = Servo::new(body(0.05, DVec3::ZERO), s0, o).unwrap();
        let (mut bound, mut speed) = (0.0f64, 0.0f64);
        for k in 0..1000 {
            let t = servo.tick(&goal, h, None);
            speed = (speed + amax * h).min(vmax);
            bound += speed * h;
            let x = t.tool.translation;
            // (The tool swings up to 0.04 mm past the device where the device stops speeding up.)
            assert!(
                x.length() <= bound + 0.1,
                "tick {k}: {x} mm, at most {bound}"
            );
            assert!(
                (x - along * x.dot(along)).length() <= 1e-9 * (1.0 + x.length()),
                "tick {k}: {x}"
            );
            if !far && k == 999 {
                assert!((x - target).length() < 1e-6, "{x}");
            }
        }
    }
}

#[test]
fn contact_damping_takes_energy_out_of_a_tool_turning_in_a_contact() {
    // A contact that pushes (1 N along z) and resists rotation only; the device turned
    // 0.2 rad and held. The tool
    // swings after it between the angular coupling and the contact. Contact damping (β·K on
    // the tool's own velocity) must take energy out of that swing, never put it in.
    let o = options();
    let s0 = Pose::IDENTITY;
    let k_turn = 50.0 * o.coupling.angular_stiffness;
    let mut k = [[0.0; 6]; 6];
    for (i, row) in k.iter_mut().enumerate().skip(3) {
        row[i] = k_turn;
    }
    let model = ContactModel {
        force: DVec3::Z,
        stiffness: k,
        volume: 0.1,
        ..ContactModel::none(s0)
    };
    let turned = Pose {
        rotation: DQuat::from_rotation_z(0.2),
        ..s0
    };
    let swing = |beta: f64| -> f64 {
        let mut o = o;
        o.contact_damping = beta;
        let mut servo = Servo::new(body(0.02, DVec3::ZERO), s0, o).unwrap();
        servo.tick(&turned, 1.0 / RATE, Some(&model));
        (0..400)
            .map(|_| {
                servo.tick(&turned, 1.0 / RATE, None);
                servo.state().angular_velocity.length_squared()
            })
            .sum()
    };
    let (undamped, damped) = (swing(0.0), swing(1e-2));
    assert!(
        damped < 0.9 * undamped,
        "{damped} vs {undamped} without contact damping"
    );
}
