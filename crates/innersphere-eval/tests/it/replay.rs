//! Replay statistics on a pair whose answer is known in closed form: two unit balls; which
//! pass each timing statistic comes from, with an injected clock.

use glam::DVec3;
use innersphere::build::{pack_signed_distance, tree_of_spheres, HierarchyOptions, PackingOptions};
use innersphere::exact::ExactMesh;
use innersphere::progress::Silent;
use innersphere::tree::TreeMeta;
use innersphere::Pose;
use innersphere::SharedTree;
use innersphere_eval::motion::{Frame, Motion};
use innersphere_eval::replay::{
    replay, replay_with_clock, KindStats, QueryKind, ReplayOptions, ReplayReport,
};

/// The tree of a unit ball: the grid has a voxel at the centre, so the packing is one sphere,
/// the ball itself.
fn ball_tree() -> SharedTree {
    ball_tree_of(1.0)
}

/// The tree of a ball of radius `r` (one sphere).
fn ball_tree_of(r: f64) -> SharedTree {
    let (lo, hi) = (DVec3::splat(-r), DVec3::splat(r));
    let spheres =
        pack_signed_distance(lo, hi, 0.1, |p| r - p.length(), &PackingOptions::default()).unwrap();
    assert!((spheres[0].radius - r).abs() < 1e-9);
    let meta = TreeMeta {
        mesh_volume: 4.0 / 3.0 * std::f64::consts::PI,
        coverage: 1.0,
        ..TreeMeta::unmeasured(4, 0.1, [-1.0; 3], [1.0; 3])
    };
    SharedTree::new(
        tree_of_spheres(&spheres, &HierarchyOptions::default(), meta, &Silent)
            .unwrap()
            .0,
    )
}

/// Centre distances: separated from 3.0 down to 2.1, then overlapping from 1.9 to 1.0.
fn centres() -> Vec<f64> {
    (0..10)
        .map(|i| 3.0 - 0.1 * i as f64)
        .chain((0..10).map(|i| 1.9 - 0.1 * i as f64))
        .collect()
}

/// B's centre moving along the x axis through `centre`, at 1 kHz.
fn motion_of(centre: &[f64]) -> Motion {
    Motion {
        frames: centre
            .iter()
            .enumerate()
            .map(|(i, &d)| Frame {
                t: i as f64 * 1e-3,
                pose: Pose::from_translation(DVec3::new(d, 0.0, 0.0)),
            })
            .collect(),
    }
}

fn percentile(v: &[f64], q: f64) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    s[((s.len() - 1) as f64 * q).round() as usize]
}

/// The statistics of every kind are those of the per-frame arrays: the single-pass ones of
/// `us`, the best-of-passes ones of `best_of_passes_us`, and each frame's best is at most
/// its first pass.
fn check_stats_match_rows(report: &ReplayReport) {
    for (slot, k) in report.kinds.iter().enumerate() {
        let first: Vec<f64> = report.rows.iter().map(|r| r.us[slot]).collect();
        let best: Vec<f64> = report
            .rows
            .iter()
            .map(|r| r.best_of_passes_us[slot])
            .collect();
        assert_eq!(first.len(), k.frames);
        assert!(first.iter().all(|t| t.is_finite() && *t >= 0.0), "{k:?}");
        for (f, b) in first.iter().zip(&best) {
            assert!(b <= f, "best of passes {b} above the first pass {f}: {k:?}");
        }
        let max = first.iter().copied().fold(f64::MIN, f64::max);
        let KindStats {
            p50_us,
            p99_us,
            max_us,
            max_frame,
            frames_over_1ms,
            ..
        } = *k;
        assert_eq!(p50_us, percentile(&first, 0.5), "{k:?}");
        assert_eq!(p99_us, percentile(&first, 0.99), "{k:?}");
        assert_eq!(max_us, max, "{k:?}");
        assert_eq!(first[max_frame], max, "{k:?}");
        assert_eq!(
            frames_over_1ms,
            first.iter().filter(|&&t| t > 1000.0).count()
        );
        assert_eq!(k.best_of_passes_p50_us, percentile(&best, 0.5), "{k:?}");
        assert_eq!(k.best_of_passes_p99_us, percentile(&best, 0.99), "{k:?}");
        assert_eq!(k.best_of_passes_max_us, percentile(&best, 1.0), "{k:?}");
        assert_eq!(
            k.best_of_passes_frames_over_1ms,
            best.iter().filter(|&&t| t > 1000.0).count()
        );
        assert!(k.p50_us <= k.p99_us && k.p99_us <= k.max_us, "{k:?}");
        assert!(k.best_of_passes_max_us <= k.max_us, "{k:?}");
        assert!(k.best_of_passes_p99_us <= k.p99_us, "{k:?}");
        assert!(
            k.best_of_passes_frames_over_1ms <= k.frames_over_1ms,
            "{k:?}"
        );
        assert!(k.passes_agree, "the passes did different work: {k:?}");
    }
}

#[test]
fn replay_of_two_balls_matches_the_closed_form() {
    let a = ball_tree();
    let b = ball_tree();
    let centre = centres();
    let motion = motion_of(&centre);
    let sphere_mesh = innersphere::shapes::icosphere(4);
    let exact = ExactMesh::new(&sphere_mesh).unwrap();
    let report = replay(
        &a,
        &b,
        &motion,
        Some((&exact, &exact)),
        &ReplayOptions::default(),
    );
    assert_eq!(report.frames, 20);
    assert_eq!(report.kinds.len(), QueryKind::ALL.len());
    for k in &report.kinds {
        assert_eq!(k.frames, 20);
    }
    check_stats_match_rows(&report);
    // One pass: best-of-passes is the single pass.
    for k in &report.kinds {
        assert_eq!(
            (k.best_of_passes_p99_us, k.best_of_passes_max_us),
            (k.p99_us, k.max_us)
        );
    }
    for (row, &d) in report.rows.iter().zip(&centre) {
        // Closed form: the sphere sets are the two balls.
        let expect = (d - 2.0).max(0.0);
        assert!((row.distance - expect).abs() < 1e-5, "{row:?} vs {expect}");
        assert_eq!(row.contact, Some(d < 2.0));
        assert_eq!(row.exact_intersecting, Some(d < 2.0));
    }
    let acc = report.accuracy.unwrap();
    assert_eq!(acc.frames, 20);
    assert_eq!(acc.separated_frames, 10);
    assert_eq!(acc.errors.missed_contacts, 0);
    assert_eq!(acc.errors.missed_contacts_max_depth, 0.0);
    assert_eq!(acc.errors.false_contacts, 0);
    // The icosphere is inscribed in the ball: the meshes are a little farther apart than the
    // balls, by at most twice the polyhedron's deviation from the sphere.
    assert!(acc.errors.abs_err_max < 0.005, "{acc:?}");
    assert!(
        acc.errors.abs_err_p50 <= acc.errors.abs_err_p95
            && acc.errors.abs_err_p95 <= acc.errors.abs_err_max
    );
    // The like-for-like speed comparison: our distance p99 over the compared frames (here
    // all 20) is the distance query's own p99, and the speed-up is the ratio of the two p99s.
    let dist = report
        .kinds
        .iter()
        .find(|k| k.kind == QueryKind::Distance)
        .unwrap();
    assert_eq!(acc.distance_p99_us, dist.p99_us);
    assert_eq!(acc.speedup_p99, acc.exact_p99_us / acc.distance_p99_us);
    // The exact method is timed on every compared frame (here all), and its statistics are
    // those of the per-frame times.
    let exact_us: Vec<f64> = report.rows.iter().map(|r| r.exact_us).collect();
    assert!(exact_us.iter().all(|t| t.is_finite() && *t >= 0.0));
    assert_eq!(acc.exact_p99_us, percentile(&exact_us, 0.99));
    assert_eq!(acc.exact_max_us, percentile(&exact_us, 1.0));
    assert_eq!(acc.exact_warm_start_frames, 1);
    assert!(acc.exact_passes_agree);

    // More passes time the same work (each from a fresh state): the same answers on every
    // frame in every pass, the single-pass numbers from the first, and the accuracy
    // unchanged. Compared on every 3rd frame: 0, 3, ..., 18.
    let three = replay(
        &a,
        &b,
        &motion,
        Some((&exact, &exact)),
        &ReplayOptions {
            passes: 3,
            every: 3,
            ..Default::default()
        },
    );
    assert_eq!((report.passes, three.passes), (1, 3));
    for (r1, r3) in report.rows.iter().zip(&three.rows) {
        assert_eq!((r1.distance, r1.contact), (r3.distance, r3.contact));
        assert_eq!(r3.exact_us.is_finite(), r3.frame % 3 == 0, "{r3:?}");
        if r3.frame % 3 == 0 {
            assert_eq!(r1.exact_distance, r3.exact_distance);
        }
    }
    check_stats_match_rows(&three);
    let acc3 = three.accuracy.unwrap();
    assert_eq!(acc3.frames, 7);
    assert_eq!(acc3.exact_warm_start_frames, 3);
    assert!(acc3.exact_passes_agree);
    assert!(acc3.exact_best_of_passes_p99_us <= acc3.exact_p99_us);
    assert!(acc3.exact_best_of_passes_max_us <= acc3.exact_max_us);
    assert!(acc3.errors.abs_err_max <= acc.errors.abs_err_max);
    // Our distance on the compared frames only, single pass.
    let ours: Vec<f64> = three.rows.iter().step_by(3).map(|r| r.us[0]).collect();
    assert_eq!(acc3.distance_p99_us, percentile(&ours, 0.99));
}

/// With an injected clock that makes every timed call last a known, different time, the
/// single-pass statistics are exactly the first pass's times, in motion order, and the
/// best-of-passes ones each frame's minimum; the exact method is timed once per compared
/// frame and pass, and nothing else is timed.
#[test]
fn single_pass_statistics_come_from_the_first_pass() {
    let a = ball_tree();
    let b = ball_tree();
    let motion = motion_of(&centres());
    let sphere_mesh = innersphere::shapes::icosphere(2);
    let exact = ExactMesh::new(&sphere_mesh).unwrap();
    let (n, passes, every) = (20usize, 3usize, 3usize);
    let compared = n.div_ceil(every);
    let kinds = vec![QueryKind::Contact, QueryKind::Distance];
    // The j-th timed call lasts d(j) µs: a scramble, a third of them over 1 ms, so that
    // neither the first nor the last pass is always the slowest or fastest.
    let d = |j: usize| 10.0 + ((j * 7919 + 13) % 1601) as f64;
    let mut calls = 0usize;
    let mut now = 0.0;
    let mut clock = || {
        if calls % 2 == 1 {
            now += d(calls / 2);
        }
        calls += 1;
        now
    };
    let opts = ReplayOptions {
        kinds: kinds.clone(),
        passes,
        every,
        ..Default::default()
    };
    let report = replay_with_clock(&a, &b, &motion, Some((&exact, &exact)), &opts, &mut clock);
    // Two clock reads per timed call: kinds × passes × frames, then passes × compared frames.
    assert_eq!(calls, 2 * (kinds.len() * passes * n + passes * compared));
    assert_eq!(report.passes, passes);
    for (slot, k) in report.kinds.iter().enumerate() {
        assert_eq!((k.kind, k.frames), (kinds[slot], n));
        let at = |p: usize, i: usize| d((slot * passes + p) * n + i);
        for (i, r) in report.rows.iter().enumerate() {
            assert_eq!(r.us[slot], at(0, i), "frame {i}");
            let best = (0..passes).map(|p| at(p, i)).fold(f64::INFINITY, f64::min);
            assert_eq!(r.best_of_passes_us[slot], best, "frame {i}");
        }
        let first: Vec<f64> = (0..n).map(|i| at(0, i)).collect();
        assert_eq!(k.p99_us, percentile(&first, 0.99));
        assert_eq!(k.max_us, percentile(&first, 1.0));
        assert_eq!(
            k.frames_over_1ms,
            first.iter().filter(|&&t| t > 1000.0).count()
        );
        assert!(k.frames_over_1ms > 0 && k.frames_over_1ms < n, "{k:?}");
        assert!(k.best_of_passes_max_us < k.max_us, "{k:?}");
    }
    check_stats_match_rows(&report);
    let base = kinds.len() * passes * n;
    let acc = report.accuracy.unwrap();
    assert_eq!(acc.frames, compared);
    let exact_first: Vec<f64> = (0..compared).map(|j| d(base + j)).collect();
    for (j, r) in report.rows.iter().step_by(every).enumerate() {
        assert_eq!(r.exact_us, exact_first[j], "compared frame {j}");
    }
    let exact_best: Vec<f64> = (0..compared)
        .map(|j| {
            (0..passes)
                .map(|p| d(base + p * compared + j))
                .fold(f64::INFINITY, f64::min)
        })
        .collect();
    assert_eq!(acc.exact_p99_us, percentile(&exact_first, 0.99));
    assert_eq!(acc.exact_max_us, percentile(&exact_first, 1.0));
    assert_eq!(
        acc.exact_best_of_passes_p99_us,
        percentile(&exact_best, 0.99)
    );
    assert_eq!(
        acc.exact_best_of_passes_max_us,
        percentile(&exact_best, 1.0)
    );
    // Our distance (slot 1) on the compared frames, first pass.
    let ours: Vec<f64> = (0..compared).map(|j| d(passes * n + j * every)).collect();
    assert_eq!(acc.distance_p99_us, percentile(&ours, 0.99));
    assert_eq!(acc.speedup_p99, acc.exact_p99_us / acc.distance_p99_us);
}

/// The CSV cells of `column` (by header name), one per row.
fn csv_column(csv: &str, column: &str) -> Vec<String> {
    let mut lines = csv.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let i = head
        .iter()
        .position(|h| *h == column)
        .unwrap_or_else(|| panic!("no column {column} in {head:?}"));
    lines
        .map(|l| l.split(',').nth(i).unwrap().to_string())
        .collect()
}

fn csv_of(report: &ReplayReport) -> String {
    let mut out = Vec::new();
    report.write_csv(&mut out).unwrap();
    String::from_utf8(out).unwrap()
}

/// The CSV of a replay that times only the contact query holds the contact answers, not
/// `distance=0,contact=false` on every frame: each kind writes its own answer, and a column
/// nothing computed is absent or empty.
#[test]
fn the_csv_holds_each_kinds_own_answer() {
    let (a, b) = (ball_tree(), ball_tree());
    let centre = centres();
    let motion = motion_of(&centre);
    let only = |kind| ReplayOptions {
        kinds: vec![kind],
        ..Default::default()
    };
    // Contact alone: its own verdict, no distance anywhere.
    let report = replay(&a, &b, &motion, None, &only(QueryKind::Contact));
    let csv = csv_of(&report);
    let head = csv.lines().next().unwrap();
    assert_eq!(
        head,
        "frame,t,contact_in_contact,contact_separation_bound,contact_us_1pass"
    );
    let verdict = csv_column(&csv, "contact_in_contact");
    let bound = csv_column(&csv, "contact_separation_bound");
    for (i, &d) in centre.iter().enumerate() {
        assert_eq!(verdict[i], (d < 2.0).to_string(), "frame {i}");
        let lb: f64 = bound[i].parse().unwrap();
        if d < 2.0 {
            assert_eq!(lb, 0.0);
        } else {
            assert!(lb >= 0.0 && lb <= d - 2.0 + 1e-6, "frame {i}: {lb}");
        }
        let row = &report.rows[i];
        assert!(row.distance.is_nan() && row.contact.is_none());
        assert_eq!(row.answers[0].unwrap().in_contact, d < 2.0);
        assert!(row.answers[1..].iter().all(Option::is_none));
    }

    // Every kind, with the exact reference on every other frame.
    let sphere_mesh = innersphere::shapes::icosphere(4);
    let exact = ExactMesh::new(&sphere_mesh).unwrap();
    let opts = ReplayOptions {
        every: 2,
        ..Default::default()
    };
    let report = replay(&a, &b, &motion, Some((&exact, &exact)), &opts);
    let csv = csv_of(&report);
    let cols = |c: &str| csv_column(&csv, c);
    let (dist, pen, mp, ex) = (
        cols("distance"),
        cols("penetration_volume"),
        cols("multipoint_contacts"),
        cols("exact_intersecting"),
    );
    for (i, &d) in centre.iter().enumerate() {
        for kind in ["distance", "contact", "multipoint", "penetration"] {
            let c = &cols(&format!("{kind}_in_contact"))[i];
            assert_eq!(*c, (d < 2.0).to_string(), "{kind} frame {i}");
        }
        let dd: f64 = dist[i].parse().unwrap();
        assert!((dd - (d - 2.0).max(0.0)).abs() < 1e-5, "frame {i}: {dd}");
        // The lens of two unit balls at centre distance d: π (4 + d) (2 − d)² / 12.
        let v: f64 = pen[i].parse().unwrap();
        let lens = if d < 2.0 {
            std::f64::consts::PI * (4.0 + d) * (2.0 - d).powi(2) / 12.0
        } else {
            0.0
        };
        assert!(
            (v - lens).abs() <= 1e-3 * lens.max(1e-9),
            "frame {i}: {v} vs {lens}"
        );
        assert_eq!(mp[i], if d < 2.0 { "1" } else { "0" }, "frame {i}");
        // The exact columns are empty on the frames not compared.
        if i % 2 == 0 {
            assert_eq!(ex[i], (d < 2.0).to_string());
        } else {
            assert_eq!(ex[i], "", "frame {i}");
        }
    }
    // The distance columns appear once (the timed distance query's).
    let head = csv.lines().next().unwrap();
    assert_eq!(head.split(',').filter(|h| *h == "distance").count(), 1);

    // Contact with the exact reference: the tree distance the accuracy used is written too.
    let opts = ReplayOptions {
        kinds: vec![QueryKind::Contact],
        ..Default::default()
    };
    let report = replay(&a, &b, &motion, Some((&exact, &exact)), &opts);
    let csv = csv_of(&report);
    let dist = csv_column(&csv, "distance");
    for (i, &d) in centre.iter().enumerate() {
        let dd: f64 = dist[i].parse().unwrap();
        assert!((dd - (d - 2.0).max(0.0)).abs() < 1e-5, "frame {i}: {dd}");
    }
}

/// Trees smaller than their meshes (balls of radius 0.8 for unit icospheres) miss the contacts
/// where the meshes overlap by less than 0.4: each is counted, and the deepest one is reported
/// (here the frame at centre distance 1.7, about 0.3 deep).
#[test]
fn replay_reports_the_deepest_missed_contact() {
    let (a, b) = (ball_tree_of(0.8), ball_tree_of(0.8));
    let centre = [3.0, 1.95, 1.9, 1.8, 1.7];
    let motion = motion_of(&centre);
    let mesh = innersphere::shapes::icosphere(4);
    let exact = ExactMesh::new(&mesh).unwrap();
    let report = replay(
        &a,
        &b,
        &motion,
        Some((&exact, &exact)),
        &ReplayOptions::default(),
    );
    let acc = report.accuracy.unwrap();
    assert_eq!(acc.errors.missed_contacts, 4, "{acc:?}");
    let mut scratch = innersphere::exact::ExactScratch::new();
    let deepest = innersphere::exact::penetration_depth(
        &exact,
        &Pose::IDENTITY,
        &exact,
        &Pose::from_translation(DVec3::new(1.7, 0.0, 0.0)),
        &mut scratch,
    );
    assert_eq!(acc.errors.missed_contacts_max_depth, deepest);
    assert!((0.28..=0.3 + 1e-9).contains(&deepest), "{deepest}");
}
