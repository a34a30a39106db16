//! Motion files (parsing, errors with line numbers, round trips, no panics on any text),
//! the clearance estimate, the anatomical frame and generated motions: on the generated
//! tooth pair always, on the real jaw pair with `--ignored`.

use innersphere_testkit::data as common;

use glam::{DQuat, DVec3};
use innersphere::Pose;
use innersphere::{Error, Mesh};
use innersphere_eval::motion::generate::LABEL_CAP_TOUCHES;
use innersphere_eval::motion::{
    generate, generate_with, phase_of, AnatomicalFrame, ClearanceEstimator, ClearanceOptions,
    Frame, GenerateOptions, Generated, Motion, Phase, PhaseCounts, Scenario, HEADER,
};
use proptest::prelude::*;
use std::path::Path;
use std::sync::OnceLock;
use std::time::Instant;

// ---------------------------------------------------------------------------------------
// Motion files

fn sample_motion() -> Motion {
    let frames = (0..50)
        .map(|i| {
            let t = i as f64 * 0.001 - 0.01;
            let q = DQuat::from_axis_angle(DVec3::new(1.0, 2.0, -0.5).normalize(), 0.03 * i as f64);
            let pose = Pose::new(DVec3::new(0.1 * i as f64, -3.25, 1e-7 * i as f64), q).unwrap();
            Frame { t, pose }
        })
        .collect();
    Motion { frames }
}

fn assert_same(a: &Motion, b: &Motion) {
    assert_eq!(a.len(), b.len());
    for (x, y) in a.frames.iter().zip(&b.frames) {
        assert_eq!(x.t, y.t);
        assert_eq!(x.pose.translation, y.pose.translation);
        assert!((x.pose.rotation - y.pose.rotation).length() < 1e-15);
    }
}

fn temp_path(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("innersphere-motion-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

#[test]
fn motion_round_trips_through_text_and_files() {
    let m = sample_motion();
    let text = m.to_csv();
    assert!(text.starts_with("t,tx,ty,tz,qw,qx,qy,qz\n"));
    assert_eq!(text.lines().count(), m.len() + 1);
    assert_same(&m, &Motion::parse(&text, "mem.csv").unwrap());
    for name in ["m.csv", "m.csv.gz"] {
        let path = temp_path(name);
        m.save(&path).unwrap();
        assert_same(&m, &Motion::load(&path).unwrap());
    }
    assert!((m.duration() - 0.049).abs() < 1e-12);
}

#[test]
fn lenient_about_line_ends_spaces_bom_blank_lines_and_near_unit_quaternions() {
    let text = "\u{feff}t, tx ,ty,tz,qw,qx,qy,qz\r\n\r\n0,1,2,3,1,0,0,0\r\n 0.5 , 1e-3 ,-2,+3, 1.0004,0,0,0 \r\n\n";
    let m = Motion::parse(text, "x.csv").unwrap();
    assert_eq!(m.len(), 2);
    assert_eq!(m.frames[1].t, 0.5);
    assert_eq!(m.frames[1].pose.translation, DVec3::new(1e-3, -2.0, 3.0));
    assert!((m.frames[1].pose.rotation.length() - 1.0).abs() < 1e-15);
}

/// Each malformed file gives an [`Error::Motion`] on the expected line whose message
/// contains the expected words.
#[test]
fn malformed_files_name_the_line() {
    let h = HEADER;
    let good = "0,0,0,0,1,0,0,0";
    let cases: Vec<(String, usize, &str)> = vec![
        (String::new(), 1, "empty file"),
        ("\n\n  \n".into(), 1, "empty file"),
        (format!("{good}\n"), 1, "expected the header"),
        ("t,tx,ty,tz,qx,qy,qz,qw\n".into(), 1, "expected the header"),
        ("t,tx,ty,tz,qw,qx,qy\n".into(), 1, "expected the header"),
        (format!("{h}\n"), 2, "no frames"),
        (format!("{h}\n\n\n"), 4, "no frames"),
        (format!("{h}\n0,1,2,3,1,0,0\n"), 2, "missing columns"),
        (format!("{h}\n{good}\n0.1\n"), 3, "missing columns"),
        (
            format!("{h}\n{good}\n0.1,1,2,3,1,0,0,0,7\n"),
            3,
            "extra columns",
        ),
        (
            format!("{h}\n{good}\n0.1,1,2,3,1,0,0,0,\n"),
            3,
            "extra columns",
        ),
        (
            format!("{h}\n{good}\n\n0.1,1,x,3,1,0,0,0\n"),
            4,
            "ty: \"x\" is not a number",
        ),
        (format!("{h}\n0.1,1,,3,1,0,0,0\n"), 2, "not a number"),
        (format!("{h}\n0.1,1,2,3,1,0,0,0 0\n"), 2, "not a number"),
        (
            format!("{h}\nNaN,1,2,3,1,0,0,0\n"),
            2,
            "t: \"NaN\" is not finite",
        ),
        (format!("{h}\n0,inf,2,3,1,0,0,0\n"), 2, "not finite"),
        (format!("{h}\n0,1,2,3,1,0,0,-infinity\n"), 2, "not finite"),
        (format!("{h}\n0,1,2,3,1e308,1e308,0,0\n"), 2, "norm"),
        (format!("{h}\n{good}\n0.1,1,2,3,2,0,0,0\n"), 3, "norm"),
        (format!("{h}\n0.1,1,2,3,0,0,0,0\n"), 2, "norm"),
        (format!("{h}\n0.1,1,2,3,0.99,0,0,0\n"), 2, "norm"),
        (
            format!("{h}\n{good}\n0,1,2,3,1,0,0,0\n"),
            3,
            "does not increase",
        ),
        (
            format!("{h}\n{good}\n0.5,1,2,3,1,0,0,0\n0.4,1,2,3,1,0,0,0\n"),
            4,
            "does not increase",
        ),
    ];
    for (text, line, words) in cases {
        match Motion::parse(&text, "bad.csv") {
            Err(Error::Motion {
                path,
                line: l,
                message,
            }) => {
                assert_eq!(path, Path::new("bad.csv"));
                assert_eq!(l, line, "{text:?}: {message}");
                assert!(message.contains(words), "{text:?}: {message}");
            }
            other => panic!("{text:?}: expected a motion error, got {other:?}"),
        }
    }
}

#[test]
fn load_reports_missing_files_and_non_utf8_lines() {
    assert!(matches!(
        Motion::load(temp_path("does-not-exist.csv")),
        Err(Error::Io { .. })
    ));
    let path = temp_path("latin1.csv");
    let mut bytes = format!("{HEADER}\n0,0,0,0,1,0,0,0\n").into_bytes();
    bytes.extend_from_slice(b"0.1,0,0,0,1,0,0,0 \xe9\n");
    std::fs::write(&path, bytes).unwrap();
    // Read by the library's one bounded text reader, which names the line.
    match Motion::load(&path) {
        Err(Error::Input { message, .. }) => {
            assert!(
                message.contains("line 3") && message.contains("UTF-8"),
                "{message}"
            );
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn save_refuses_motions_that_would_not_load() {
    let path = temp_path("refused.csv");
    assert!(Motion::default().save(&path).is_err());
    let mut m = sample_motion();
    m.frames[3].t = m.frames[2].t;
    match m.save(&path) {
        Err(Error::Motion { line, .. }) => assert_eq!(line, 5),
        other => panic!("{other:?}"),
    }
    let mut m = sample_motion();
    m.frames[0].pose.translation.x = f64::NAN;
    assert!(m.save(&path).is_err());
}

fn mutated_file() -> impl Strategy<Value = String> {
    let base = sample_motion().to_csv();
    (
        proptest::collection::vec((0usize..4000, any::<char>(), 0u8..4), 0..6),
        any::<bool>(),
    )
        .prop_map(move |(edits, cut)| {
            let mut chars: Vec<char> = base.chars().collect();
            for (pos, c, kind) in edits {
                let pos = pos % (chars.len() + 1);
                match kind {
                    0 => chars.insert(pos, c),
                    1 if pos < chars.len() => {
                        chars.remove(pos);
                    }
                    2 if pos < chars.len() => chars[pos] = c,
                    _ => chars.insert(pos, [',', '\n', '-', '.', 'e', '9'][pos % 6]),
                }
            }
            if cut {
                chars.truncate(chars.len() / 2);
            }
            chars.into_iter().collect()
        })
}

fn check_parsed(text: &str) {
    if let Ok(m) = Motion::parse(text, "p.csv") {
        assert!(!m.is_empty());
        for w in m.frames.windows(2) {
            assert!(w[1].t > w[0].t);
        }
        for f in &m.frames {
            assert!((f.pose.rotation.length() - 1.0).abs() < 1e-12);
            assert!(f.t.is_finite() && f.pose.translation.is_finite());
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    /// Any text: an error or a valid motion, never a panic.
    #[test]
    fn parse_never_panics_on_random_text(text in any::<String>()) {
        check_parsed(&text);
        check_parsed(&format!("{HEADER}\n{text}"));
    }

    /// Near-valid files (a few characters inserted, removed or replaced, or cut short).
    #[test]
    fn parse_never_panics_on_mutated_files(text in mutated_file()) {
        check_parsed(&text);
    }

    /// Lines of random numbers and words.
    #[test]
    fn parse_never_panics_on_random_rows(
        rows in proptest::collection::vec(
            proptest::collection::vec(
                prop_oneof![
                    any::<f64>().prop_map(|x| x.to_string()),
                    (-2.0..2.0f64).prop_map(|x| format!("{x}")),
                    "[a-z]{0,3}",
                ],
                0..10,
            ),
            0..8,
        )
    ) {
        let body: Vec<String> = rows.iter().map(|r| r.join(",")).collect();
        check_parsed(&format!("{HEADER}\n{}", body.join("\n")));
    }
}

// ---------------------------------------------------------------------------------------
// Phases and the clearance estimate

#[test]
fn phases_from_clearance() {
    assert_eq!(phase_of(0.5, 0.1), Phase::Separated);
    assert_eq!(phase_of(0.1, 0.1), Phase::Touching);
    assert_eq!(phase_of(0.0, 0.1), Phase::Touching);
    assert_eq!(phase_of(-0.1, 0.1), Phase::Touching);
    assert_eq!(phase_of(-0.1001, 0.1), Phase::Overlap);
    assert_eq!(phase_of(0.05, 0.01), Phase::Separated);
    let c = PhaseCounts::of(&[Phase::Overlap, Phase::Touching, Phase::Touching]);
    assert_eq!((c.separated, c.touching, c.overlap), (0, 2, 1));
    assert!(!c.all_present());
    assert_eq!(Phase::Overlap.to_string(), "overlap");
}

#[test]
fn clearance_of_two_spheres() {
    let s = innersphere::shapes::icosphere(5);
    let at = |z: f64| Pose::from_translation(DVec3::new(0.0, 0.0, z));
    let mut est = ClearanceEstimator::new(&s, &s, &ClearanceOptions::default());
    // Unit spheres: gap = distance - 2 (the inscribed polyhedron is a hair smaller).
    for (z, expect) in [(3.0, 1.0), (2.2, 0.2), (2.0, 0.0), (1.7, -0.3), (1.2, -0.8)] {
        let c = est.clearance(&at(z));
        assert!((c - expect).abs() < 0.01, "z {z}: {c} vs {expect}");
        assert_eq!(est.clearance_capped(&at(z), 0.5), c.min(0.5));
    }
    let one = innersphere_eval::motion::clearance(&s, &s, &at(2.5));
    assert!((one - 0.5).abs() < 0.01, "{one}");
}

/// Along a motion the remembered estimator answers exactly what a fresh one does.
#[test]
fn coherent_estimate_equals_fresh_estimate() {
    let (a, b) = innersphere::shapes::tooth_pair(3);
    let opts = ClearanceOptions {
        samples: 300,
        symmetric: true,
    };
    let mut coherent = ClearanceEstimator::new(&a, &b, &opts);
    let fresh = ClearanceEstimator::new(&a, &b, &opts);
    for i in 0..300 {
        let s = i as f64 / 300.0;
        let pose = Pose::new(
            DVec3::new(0.8 * (7.0 * s).sin(), 0.5 * (5.0 * s).cos(), -3.0 + 3.6 * s),
            DQuat::from_axis_angle(DVec3::new(0.3, 1.0, 0.2).normalize(), 0.2 * (9.0 * s).sin()),
        )
        .unwrap();
        for cap in [f64::INFINITY, 0.4] {
            let c = coherent.clearance_capped(&pose, cap);
            let f = fresh.clone().clearance_capped(&pose, cap);
            assert_eq!(c, f, "frame {i} cap {cap}");
        }
    }
    assert!(coherent.evaluations() < 300 * 2 * coherent.sample_count() as u64 / 4);
}

// ---------------------------------------------------------------------------------------
// Generated motions on the generated tooth pair

fn teeth() -> &'static (Mesh, Mesh) {
    static T: OnceLock<(Mesh, Mesh)> = OnceLock::new();
    T.get_or_init(|| innersphere::shapes::tooth_pair(4))
}

const SECONDS: f64 = 4.0;

fn generated(s: Scenario) -> &'static Generated {
    static G: OnceLock<Vec<Generated>> = OnceLock::new();
    let all = G.get_or_init(|| {
        let (a, b) = teeth();
        Scenario::ALL
            .iter()
            .map(|&s| generate_with(s, SECONDS, 7, a, b, &GenerateOptions::default()).unwrap())
            .collect()
    });
    &all[Scenario::ALL.iter().position(|&x| x == s).unwrap()]
}

#[test]
fn tooth_pair_frame_points_up_from_the_lower_tooth() {
    let (a, b) = teeth();
    let f = AnatomicalFrame::from_meshes(a, b).unwrap();
    assert!(f.up.dot(DVec3::Z) > 0.99, "{f:?}");
    assert!((f.anterior.cross(f.left) - f.up).length() < 1e-9);
    assert!(f.scale > 0.5 && f.scale < 0.9, "{}", f.scale);
    // The hinge lies behind and above the incisal point.
    let h = f.coordinates(f.hinge);
    assert!(h.y < -50.0 * f.scale && h.z > 10.0 * f.scale, "{h}");
}

#[test]
fn generated_files_are_valid_1khz_motions() {
    for s in Scenario::ALL {
        let g = generated(s);
        let m = &g.motion;
        assert_eq!(m.len(), (SECONDS * 1000.0) as usize);
        for (i, f) in m.frames.iter().enumerate() {
            assert!((f.t - i as f64 * 0.001).abs() < 1e-12);
        }
        let text = m.to_csv();
        assert_eq!(text.lines().next(), Some(HEADER));
        assert_same(m, &Motion::parse(&text, "gen.csv").unwrap());
        assert_eq!(g.clearance.len(), m.len());
        assert_eq!(g.phases.len(), m.len());
        assert_eq!(g.labels_csv().lines().count(), m.len() + 1);
    }
}

/// Points of B move with bounded velocity and acceleration, and the quaternions stay in
/// one hemisphere (no sign flips between frames).
#[test]
fn generated_motions_are_smooth() {
    let (_, b) = teeth();
    let (lo, hi) = b.bbox();
    let pts = [lo, hi, (lo + hi) * 0.5, DVec3::new(lo.x, hi.y, hi.z)];
    for s in Scenario::ALL {
        let g = generated(s);
        let f = &g.motion.frames;
        let (mut vmax, mut amax) = (0.0f64, 0.0f64);
        for p in pts {
            let x: Vec<DVec3> = f.iter().map(|f| f.pose.transform_point(p)).collect();
            for w in x.windows(3) {
                vmax = vmax.max((w[2] - w[1]).length() * 1e3);
                amax = amax.max((w[2] - 2.0 * w[1] + w[0]).length() * 1e6);
            }
        }
        for w in f.windows(2) {
            assert!(w[0].pose.rotation.dot(w[1].pose.rotation) > 0.999);
        }
        // Millimetres at scale ~0.7: peak speeds of a jaw, not jumps.
        assert!(vmax < 150.0 * g.scale, "{s}: max speed {vmax} mm/s");
        assert!(
            amax < 3000.0 * g.scale,
            "{s}: max acceleration {amax} mm/s²"
        );
        assert!(vmax > 5.0 * g.scale, "{s}: hardly moves ({vmax} mm/s)");
    }
}

#[test]
fn generated_motions_pass_through_all_phases() {
    for s in Scenario::ALL {
        let g = generated(s);
        let c = g.counts();
        assert!(c.all_present(), "{s}: {c:?}");
        // Every phase lasts: at least 2% of the frames each.
        let min = g.motion.len() / 50;
        assert!(
            c.separated > min && c.touching > min && c.overlap > min,
            "{s}: {c:?}"
        );
        // Clenches and presses stay shallow: a few touch thresholds beyond the bite.
        let deepest = g.clearance.iter().copied().fold(f64::INFINITY, f64::min);
        assert!(deepest > g.bite_clearance - 4.0 * g.touch, "{s}: {deepest}");
    }
}

/// The labels agree with an independent estimate from every vertex of both bodies.
#[test]
fn labels_agree_with_all_vertices() {
    let (a, b) = teeth();
    let mut all = ClearanceEstimator::new(
        a,
        b,
        &ClearanceOptions {
            samples: usize::MAX,
            symmetric: true,
        },
    );
    for s in Scenario::ALL {
        let g = generated(s);
        let mut seen = [false; 3];
        for (i, f) in g.motion.frames.iter().enumerate().step_by(10) {
            let c = all.clearance_capped(&f.pose, 1.0);
            if c >= 1.0 || g.clearance[i] >= LABEL_CAP_TOUCHES * g.touch {
                // At a cap: only "at least this" is known, far from any contact a label is
                // about.
                continue;
            }
            // The labels' samples are a subset of all vertices: never below the full estimate.
            assert!(
                g.clearance[i] >= c - 1e-12,
                "{s} frame {i}: {} < {c}",
                g.clearance[i]
            );
            assert!(
                g.clearance[i] - c < 0.5 * g.touch,
                "{s} frame {i}: {} vs {c}",
                g.clearance[i]
            );
            seen[Phase::ALL
                .iter()
                .position(|&p| p == phase_of(c, g.touch))
                .unwrap()] = true;
        }
        assert_eq!(seen, [true; 3], "{s}");
    }
}

#[test]
fn short_motions_pass_through_all_phases() {
    let (a, b) = teeth();
    for s in Scenario::ALL {
        for seed in [1, 2] {
            let g = generate_with(s, 1.2, seed, a, b, &GenerateOptions::default()).unwrap();
            assert!(
                g.counts().all_present(),
                "{s} seed {seed}: {:?}",
                g.counts()
            );
        }
    }
}

#[test]
fn generation_is_deterministic_per_seed() {
    let (a, b) = teeth();
    let m1 = generate(Scenario::Grind, 1.0, 42, a, b).unwrap();
    let m2 = generate(Scenario::Grind, 1.0, 42, a, b).unwrap();
    let m3 = generate(Scenario::Grind, 1.0, 43, a, b).unwrap();
    assert_eq!(m1.to_csv(), m2.to_csv());
    assert_ne!(m1.to_csv(), m3.to_csv());
}

/// The tremor alone (the difference to the same motion without it) is 0.01–0.02 mm RMS at
/// scale 1, with most of its power between 2 and 12 Hz (little frame-to-frame jitter).
#[test]
fn tremor_is_small_and_band_limited() {
    let (a, b) = teeth();
    let with = generated(Scenario::OpenClose);
    let opts = GenerateOptions {
        tremor: Some(0.0),
        ..GenerateOptions::default()
    };
    let without = generate_with(Scenario::OpenClose, SECONDS, 7, a, b, &opts).unwrap();
    let p = b.vertices.iter().copied().sum::<DVec3>() / b.vertices.len() as f64;
    let d: Vec<DVec3> = with
        .motion
        .frames
        .iter()
        .zip(&without.motion.frames)
        .map(|(x, y)| x.pose.transform_point(p) - y.pose.transform_point(p))
        .collect();
    let rms = (d.iter().map(|v| v.length_squared()).sum::<f64>() / d.len() as f64).sqrt();
    let k = with.scale;
    assert!(
        rms > 0.008 * k && rms < 0.022 * k,
        "tremor {rms} at scale {k}"
    );
    let step = (d
        .windows(2)
        .map(|w| (w[1] - w[0]).length_squared())
        .sum::<f64>()
        / d.len() as f64)
        .sqrt();
    // A 12 Hz sine moves 2π·12/1000 ≈ 0.075 of its amplitude per frame.
    assert!(step < 0.08 * rms, "jitter {step} vs rms {rms}");
}

/// Generic pairs: bodies apart at the identity, or deep in each other, still get a bite and
/// all phases.
#[test]
fn generic_pairs_get_all_phases() {
    let ball = innersphere::shapes::icosphere(3);
    let lift = |m: &Mesh, d: DVec3| Mesh {
        vertices: m.vertices.iter().map(|v| *v * 5.0 + d).collect(),
        triangles: m.triangles.clone(),
    };
    let lower = innersphere::shapes::ellipsoid(DVec3::new(8.0, 6.0, 3.0), 3);
    for (name, upper) in [
        ("apart", lift(&ball, DVec3::new(0.5, 0.0, 20.0))),
        ("deep", lift(&ball, DVec3::new(0.0, 0.3, 2.0))),
    ] {
        let g = generate_with(
            Scenario::Chew,
            2.5,
            1,
            &upper,
            &lower,
            &GenerateOptions::default(),
        )
        .unwrap();
        let c = g.counts();
        assert!(c.all_present(), "{name}: {c:?}");
        assert!(g.bite != Pose::IDENTITY, "{name}");
        assert!(
            (g.bite_clearance + 1.5 * g.touch).abs() < 0.3 * g.touch,
            "{name}: bite clearance {} (touch {})",
            g.bite_clearance,
            g.touch
        );
    }
}

#[test]
fn bad_requests_are_errors() {
    let (a, b) = teeth();
    for seconds in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        assert!(
            generate(Scenario::Chew, seconds, 1, a, b).is_err(),
            "{seconds}"
        );
    }
    let opts = GenerateOptions {
        rate: 0.0,
        ..GenerateOptions::default()
    };
    assert!(generate_with(Scenario::Chew, 1.0, 1, a, b, &opts).is_err());
    assert!(generate(Scenario::Chew, 1.0, 1, a, &Mesh::default()).is_err());
    // The estimate copes with empty bodies (no samples, no surface): no gap is known.
    let empty = Mesh::default();
    let c = innersphere_eval::motion::clearance(&empty, &empty, &Pose::IDENTITY);
    assert_eq!(c, f64::INFINITY);
    assert_eq!(
        "open-close".parse::<Scenario>().unwrap(),
        Scenario::OpenClose
    );
    assert_eq!("Grind".parse::<Scenario>().unwrap(), Scenario::Grind);
    assert!("walk".parse::<Scenario>().is_err());
    for s in Scenario::ALL {
        assert_eq!(s.name().parse::<Scenario>().unwrap(), s);
    }
}

// ---------------------------------------------------------------------------------------
// The real jaw pair

fn jaws() -> (Mesh, Mesh) {
    let a = innersphere::mesh::io::load(&common::data("jaw/ofj_p26_maxilla_teeth.stl.gz")).unwrap();
    let b =
        innersphere::mesh::io::load(&common::data("jaw/ofj_p26_mandible_teeth.stl.gz")).unwrap();
    (a, b)
}

fn degrees(u: DVec3, v: DVec3) -> f64 {
    u.normalize()
        .dot(v.normalize())
        .clamp(-1.0, 1.0)
        .acos()
        .to_degrees()
}

/// The PCA frame is within a few degrees of the frame the team's demo motion was made in,
/// and a 5 s chew passes through every phase.
#[test]
#[ignore = "real data: run with --ignored"]
fn jaw_frame_and_chew() {
    let (a, b) = jaws();
    let f = AnatomicalFrame::from_meshes(&a, &b).unwrap();
    let up = DVec3::new(0.036, -0.059, 0.998);
    let left = DVec3::new(0.998, 0.053, -0.033);
    let anterior = DVec3::new(0.051, -0.997, -0.061);
    let incisal = DVec3::new(55.67, 4.08, 59.99);
    eprintln!("frame {f:?}");
    assert!(degrees(f.up, up) < 4.0, "up {}", f.up);
    assert!(degrees(f.left, left) < 4.0, "left {}", f.left);
    assert!(
        degrees(f.anterior, anterior) < 4.0,
        "anterior {}",
        f.anterior
    );
    assert!(
        (f.incisal - incisal).length() < 2.0,
        "incisal {}",
        f.incisal
    );
    let hinge = incisal - anterior * 95.0 + up * 20.0;
    assert!(
        (f.hinge - hinge).length() < 6.0,
        "hinge {} vs {hinge}",
        f.hinge
    );
    assert!((f.scale - 1.0).abs() < 0.1, "scale {}", f.scale);

    let start = Instant::now();
    let g = generate_with(Scenario::Chew, 5.0, 1, &a, &b, &GenerateOptions::default()).unwrap();
    let took = start.elapsed();
    let c = g.counts();
    eprintln!(
        "5 s chew on the jaws: {:.2} s, {c:?}, bite clearance {:.3}, {} samples",
        took.as_secs_f64(),
        g.bite_clearance,
        g.samples
    );
    assert!(c.all_present(), "{c:?}");
    assert_eq!(g.bite, Pose::IDENTITY);
    // The bite's own overlap is ~0.3 mm; clenches go 0.1–0.25 mm beyond it.
    assert!(
        g.bite_clearance < -0.2 && g.bite_clearance > -0.4,
        "{}",
        g.bite_clearance
    );
    let deepest = g.clearance.iter().copied().fold(f64::INFINITY, f64::min);
    assert!(
        deepest < g.bite_clearance - 0.05 && deepest > g.bite_clearance - 0.4,
        "{deepest}"
    );
    // The incisal point opens about 10 mm (down, by the hinge rotation).
    let lowest = g
        .motion
        .frames
        .iter()
        .map(|fr| f.coordinates(fr.pose.transform_point(f.incisal)).z)
        .fold(f64::INFINITY, f64::min);
    assert!(lowest < -7.0 && lowest > -13.0, "incisal opening {lowest}");
}

/// The team's demo motion loads, and this crate's clearance estimate agrees with its labels.
#[test]
#[ignore = "real data: run with --ignored"]
fn jaw_demo_motion_and_its_labels() {
    let m = Motion::load(common::data("motion/jaw_chew_demo.csv")).unwrap();
    assert_eq!(m.len(), 3000);
    assert!((m.duration() - 2.999).abs() < 1e-9);
    let (a, b) = jaws();
    let mut est = ClearanceEstimator::new(&a, &b, &ClearanceOptions::default());
    est.add_contact_samples(&a, &b, &Pose::IDENTITY, 1.5, 4096);
    let labels = std::fs::read_to_string(common::data("motion/jaw_chew_demo.phases.csv")).unwrap();
    let (mut n, mut agree, mut diffs) = (0, 0, Vec::new());
    for line in labels.lines().skip(1) {
        let cols: Vec<&str> = line.split(',').collect();
        let i: usize = cols[0].parse().unwrap();
        let theirs: f64 = cols[2].parse().unwrap();
        let ours = est.clearance_capped(&m.frames[i].pose, 1.5);
        n += 1;
        if phase_of(ours, 0.1) == phase_of(theirs, 0.1) {
            agree += 1;
        }
        diffs.push((ours - theirs).abs());
    }
    diffs.sort_by(f64::total_cmp);
    let median = diffs[diffs.len() / 2];
    eprintln!(
        "demo labels: {agree}/{n} phases agree, median |Δclearance| {median:.4} mm, p90 {:.4}",
        diffs[diffs.len() * 9 / 10]
    );
    assert!(agree as f64 > 0.9 * n as f64);
    assert!(median < 0.03);
}
