//! The bite of a free segment (a tooth-bearing segment cut free, no joint): closed from many
//! places around the start, as a technician wiggles plaster casts into maximal
//! intercuspation, the rest poses clustered and ranked.
//!
//! Why this finds intercuspation:
//! - One closing of a free body (a constant force at its centre of mass, [`occlude`]) rests
//!   where the cusps first catch and the contact balances the push. That is one of several
//!   rest poses. Which one is reached depends on where the closing starts.
//! - Closing from many places around the start (`starts`, spread sideways, forwards and in
//!   yaw) reaches the rest poses near it. A stiff contact (1000 N/mm³: the arches overlap by
//!   less than 0.1 mm) keeps the cusps from sinking into each other and sliding over.
//! - Maximal intercuspation is a rest pose that is reached often (a wide basin: the cusps
//!   guide the arch into it from many places) and holds the arch on both sides (bilateral
//!   and even contacts, as a dentist checks with articulating paper). The candidates are
//!   ranked by `starts × min(left, right) / (1 + |left − right|)`: the starts that ended
//!   there, times the contact patches on the side with fewer, over one plus the imbalance.
//!   One-sided rests, where the arch leans on a few cusps of one side, and rests reached
//!   from a single start rank below.
//!
//! Measured on the real jaw pair from 24 random open starts (1–4 mm open, ±1.5 mm sideways
//! and forwards, ±3° yaw, ±2° roll and pitch; three seeds): every run chose the same pose,
//! 0.39–0.41 mm from the scanned bite at the worst crown centre, in 1–4 s on 2 cores
//! (docs/OCCLUSION.md).

use crate::occlusion::{occlude, unit, Occlusion, OcclusionOptions};
use crate::occlusion_status::{count_statuses, OcclusionStatus, StatusCounts};
use glam::{DMat3, DQuat, DVec3};
use innersphere::error::{num, vec3, Error, Result};
use innersphere::pose::Pose;
use innersphere::query::{Pair, Patch, PenetrationOptions, SharedTree};
use innersphere_haptic::ContactSource;
use rayon::prelude::*;

/// Settings of [`occlude_free`]. Units: mm, N, s.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct FreeOcclusionOptions {
    /// How each start closes: [`OcclusionOptions`] without joints (the default: 5 N along
    /// `closing.axis`, a stiff 1000 N/mm³ contact, 20 s at most). The starts close on the
    /// spheres whatever its `contact`; with [`ContactSource::Mesh`] the chosen rest then
    /// settles on the meshes (the candidates stay the spheres' rests).
    pub closing: OcclusionOptions,
    /// A direction across the arch (world; e.g. the patient's left), perpendicular to the
    /// closing axis or not (its part along the axis is dropped): the starts are spread along
    /// it and the contacts' balance is counted on either side of B's centre of mass.
    pub lateral: DVec3,
    /// Closings in all, the first from the start itself.
    pub starts: usize,
    /// The other starts are spread up to this far sideways and forwards (mm) …
    pub spread: f64,
    /// … and turned up to this much about the closing axis (rad), about B's centre of mass.
    pub spread_angle: f64,
    /// Seed of the spread (the same seed, the same answer).
    pub seed: u64,
    /// Rest poses closer than this (mm) at every probe point of B (its centre of mass and six
    /// points at its radius along the three axes) are one candidate.
    pub same_pose: f64,
}

impl Default for FreeOcclusionOptions {
    /// 120 starts within ±2.5 mm and ±5° of the start, 5 N, 1000 N/mm³, rest poses within
    /// 0.1 mm merged, seed 1.
    fn default() -> Self {
        FreeOcclusionOptions {
            closing: OcclusionOptions {
                contact_stiffness: 1000.0,
                max_seconds: 20.0,
                ..OcclusionOptions::default()
            },
            lateral: DVec3::X,
            starts: 120,
            spread: 2.5,
            spread_angle: 5f64.to_radians(),
            seed: 1,
            same_pose: 0.1,
        }
    }
}

/// The most closings: the candidates near a start number 70–80 on a real arch (120 starts),
/// and a thousand starts in the spread's box already meet each one many times; more only
/// takes minutes.
pub const MAX_STARTS: usize = 1000;
/// The widest spread sideways and forwards (mm). A bite search looks for the rests near the
/// start, whose basins are a cusp wide (2–5 mm); 10 mm moves B by a whole molar, into the
/// intercuspation one tooth over, which is no longer the bite around the start.
pub const MAX_SPREAD: f64 = 10.0;
/// The widest spread of yaw (degrees): twice [`MAX_SPREAD`] in degrees, as
/// [`bite`](fn@crate::bite) spreads it (20° turns the molars of an arch ±8 mm about its centre).
pub const MAX_SPREAD_DEGREES: f64 = 20.0;

impl FreeOcclusionOptions {
    /// Refuses what the closings cannot start from (joints, no starts or more than
    /// [`MAX_STARTS`], a negative or non-finite spread or same-pose distance, a spread beyond
    /// [`MAX_SPREAD`] or [`MAX_SPREAD_DEGREES`], a lateral direction along the closing axis);
    /// gives the unit closing axis and the unit lateral direction across it. The closing's
    /// own options are [`occlude`]'s to check.
    pub(super) fn check(&self) -> Result<(DVec3, DVec3)> {
        if self.closing.joints.is_some() {
            return Err(Error::InvalidOption(
                "a free segment has no joints: give the closing options without them".into(),
            ));
        }
        if !(1..=MAX_STARTS).contains(&self.starts) {
            return Err(Error::InvalidOption(format!(
                "the starts must be 1 to {MAX_STARTS} (more only takes minutes: the rests near \
                 a start are met many times over by then), not {}",
                self.starts
            )));
        }
        for (what, x) in [
            ("the spread", self.spread),
            ("the spread angle", self.spread_angle),
            ("the same-pose distance", self.same_pose),
        ] {
            if !(x.is_finite() && x >= 0.0) {
                return Err(Error::InvalidOption(format!(
                    "{what} must be finite and at least 0, not {}",
                    num(x)
                )));
            }
        }
        if self.spread > MAX_SPREAD {
            return Err(Error::InvalidOption(format!(
                "the spread must be at most {} mm (a bite search looks around its start: \
                 farther, B lands one tooth over), not {} mm",
                num(MAX_SPREAD),
                num(self.spread)
            )));
        }
        if self.spread_angle > MAX_SPREAD_DEGREES.to_radians() {
            return Err(Error::InvalidOption(format!(
                "the spread angle must be at most {}°, not {}°",
                num(MAX_SPREAD_DEGREES),
                num((self.spread_angle.to_degrees() * 1e3).round() / 1e3)
            )));
        }
        // No axis (the closing refuses it): the lateral direction is taken as given.
        let axis = unit(self.closing.axis).unwrap_or(DVec3::ZERO);
        let lateral = (self.lateral - axis * self.lateral.dot(axis)).normalize_or_zero();
        if lateral == DVec3::ZERO {
            return Err(Error::InvalidOption(format!(
                "the lateral direction must be finite and not along the closing axis, not {}",
                vec3(self.lateral)
            )));
        }
        Ok((axis, lateral))
    }
}

/// One distinct rest pose: where closings converged (at rest in contact).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Candidate {
    /// B's pose.
    pub pose: Pose,
    /// How many starts ended here (the basin: a stability measure of the pose as a whole).
    pub starts: usize,
    /// Contact patches.
    pub contacts: usize,
    /// Patches on the `lateral` side of B's centre of mass, and on the other.
    pub lateral_side: usize,
    /// See `lateral_side`.
    pub other_side: usize,
    /// Contact area (mm²: the areas of the discs where the overlapping spheres meet).
    pub contact_area: f64,
    /// Overlap volume at rest (mm³).
    pub volume: f64,
    /// The smallest stiffness of the contact against a sideways push (N/mm; the smaller
    /// eigenvalue of the contact stiffness in the plane across the closing axis): how firmly
    /// the cusps hold the pose.
    pub lateral_stiffness: f64,
}

/// What [`occlude_free`] found.
#[derive(Debug, Clone, PartialEq)]
pub struct FreeOcclusion {
    /// The answer: the chosen candidate's closing (its pose, steps, volume, depth, patches;
    /// converged); when no closing converged, the closing from the start itself, whose
    /// status says how it ended.
    pub closing: Occlusion,
    /// The distinct rest poses in contact, best first (empty when no closing converged).
    pub candidates: Vec<Candidate>,
    /// How many closings ended in each status (they add up to the starts): every start is
    /// accounted for.
    pub closings: StatusCounts,
}

/// Where one closing rested (`o.pose`), its contact patches on the lateral side and on the
/// other, and (for a cluster) how many starts ended there.
#[derive(Debug, Clone)]
struct Rest {
    o: Occlusion,
    on: usize,
    off: usize,
    starts: usize,
}

impl Rest {
    /// Reached often, bilateral and even (see the module doc).
    fn score(&self) -> f64 {
        self.starts as f64 * self.on.min(self.off) as f64
            / (1.0 + self.on.abs_diff(self.off) as f64)
    }
}

/// A small deterministic generator of the spread (xorshift64*).
struct Spread(u64);

impl Spread {
    fn unit(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let x = self.0.wrapping_mul(0x2545_f491_4f6c_dd1d);
        (x >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }
}

/// Closes B (tree `b`, from `from`) onto A (tree `a`, fixed at `pose_a`) from `opts.starts`
/// places around `from` and ranks the rest poses (see the module doc). The closings run in
/// parallel (rayon), each on its own [`Pair`]; the answer does not depend on the threads.
/// Only closings that converged (at rest in contact) are candidates; the others are counted
/// by status in [`FreeOcclusion::closings`].
/// Fails on bad options, joints in `opts.closing`, or a tree of B without mass properties.
pub fn occlude_free(
    a: &SharedTree,
    b: &SharedTree,
    pose_a: &Pose,
    from: &Pose,
    opts: &FreeOcclusionOptions,
) -> Result<FreeOcclusion> {
    let (axis, lateral) = opts.check()?;
    if !from.translation.is_finite() || !from.rotation.is_finite() {
        return Err(Error::InvalidOption("the start pose must be finite".into()));
    }
    let anterior = axis.cross(lateral);
    let info = b.info();
    let com = info.center_of_mass;
    let starts = spread_starts(from, com, axis, lateral, opts);
    // The search runs on the spheres (microseconds a step); with mesh contact the chosen rest
    // then settles on the meshes.
    let spheres = OcclusionOptions {
        contact: ContactSource::Spheres,
        ..opts.closing
    };
    let rests: Vec<Result<Rest>> = starts
        .par_iter()
        .map(|s| {
            let mut pair = Pair::new(a, b);
            let o = occlude(&mut pair, pose_a, s, &spheres)?;
            let (on, off) = sides(&o.patches, o.pose.transform_point(com), lateral);
            Ok(Rest {
                o,
                on,
                off,
                starts: 1,
            })
        })
        .collect();
    let probes = Probes::new(com, info.radius);
    let rests = rests.into_iter().collect::<Result<Vec<Rest>>>()?;
    let closings = count_statuses(rests.iter().map(|r| r.o.status));
    let first = rests.first().map(|r| r.o.clone());
    let mut clusters = cluster(rests, &probes, opts.same_pose);
    // Best first (stable: ties keep the start order).
    clusters.sort_by(|x, y| y.score().total_cmp(&x.score()));
    let popts = PenetrationOptions {
        stiffness: opts.closing.contact_stiffness,
        linearize: true,
        ..Default::default()
    };
    let candidates: Vec<Candidate> = clusters
        .par_iter()
        .map(|k| {
            let mut pair = Pair::new(a, b);
            let p = pair.penetration_with(pose_a, &k.o.pose, &popts);
            Candidate {
                pose: k.o.pose,
                starts: k.starts,
                contacts: k.on + k.off,
                lateral_side: k.on,
                other_side: k.off,
                contact_area: p.area,
                volume: p.volume,
                lateral_stiffness: lateral_stiffness(&p.stiffness.linear, lateral, anterior),
            }
        })
        .collect();
    let closing = match clusters.into_iter().next() {
        Some(k) if opts.closing.contact == ContactSource::Mesh => {
            let mut pair = Pair::new(a, b);
            occlude(&mut pair, pose_a, &k.o.pose, &opts.closing)?
        }
        Some(k) => k.o,
        None => first.expect("at least one start"),
    };
    Ok(FreeOcclusion {
        closing,
        candidates,
        closings,
    })
}

/// Where "the same pose" is judged: B's centre of mass and six points at its radius along
/// its model axes.
struct Probes([DVec3; 7]);

impl Probes {
    /// The probes of a body with centre of mass `com` and radius `radius` (model frame).
    fn new(com: DVec3, radius: f64) -> Probes {
        let r = radius.max(1e-9);
        Probes([
            com,
            com + DVec3::X * r,
            com - DVec3::X * r,
            com + DVec3::Y * r,
            com - DVec3::Y * r,
            com + DVec3::Z * r,
            com - DVec3::Z * r,
        ])
    }

    /// How far apart B is at poses `p` and `q`: the largest distance of a probe.
    fn apart(&self, p: &Pose, q: &Pose) -> f64 {
        self.0
            .iter()
            .map(|x| (p.transform_point(*x) - q.transform_point(*x)).length())
            .fold(0.0, f64::max)
    }
}

/// The rests that converged (at rest in contact), merged into clusters in start order: a
/// rest within `same_pose` of a cluster's first rest ([`Probes::apart`]) counts as one more
/// start of it.
fn cluster(rests: impl IntoIterator<Item = Rest>, probes: &Probes, same_pose: f64) -> Vec<Rest> {
    let mut clusters: Vec<Rest> = Vec::new();
    for rest in rests {
        if rest.o.status != OcclusionStatus::Converged || rest.on + rest.off == 0 {
            continue;
        }
        match clusters
            .iter_mut()
            .find(|k| probes.apart(&k.o.pose, &rest.o.pose) < same_pose)
        {
            Some(k) => k.starts += 1,
            None => clusters.push(rest),
        }
    }
    clusters
}

/// The least stiffness of the contact's linear block `m` (N/mm, world) against a push
/// across the closing axis: the smaller eigenvalue of its symmetric part in the plane of the
/// unit, orthogonal `lateral` and `anterior`.
fn lateral_stiffness(m: &DMat3, lateral: DVec3, anterior: DVec3) -> f64 {
    let (l, f) = (lateral, anterior);
    least_eigenvalue(
        l.dot(*m * l),
        0.5 * (l.dot(*m * f) + f.dot(*m * l)),
        f.dot(*m * f),
    )
}

/// The starts of the closings: `from`, then `opts.starts − 1` poses moved from it by up to
/// `opts.spread` along `lateral` and along `axis × lateral` (both unit, across the unit
/// closing `axis`) and turned by up to `opts.spread_angle` about `axis` through B's centre of
/// mass (`com`, B's model frame), drawn from the seed.
fn spread_starts(
    from: &Pose,
    com: DVec3,
    axis: DVec3,
    lateral: DVec3,
    opts: &FreeOcclusionOptions,
) -> Vec<Pose> {
    let anterior = axis.cross(lateral);
    let c = from.transform_point(com);
    let mut spread = Spread(opts.seed ^ 0x9e37_79b9_7f4a_7c15 | 1);
    (0..opts.starts)
        .map(|i| {
            let (u, v, w) = (spread.unit(), spread.unit(), spread.unit());
            if i == 0 {
                return *from;
            }
            let q = DQuat::from_axis_angle(axis, w * opts.spread_angle);
            let t = (lateral * u + anterior * v) * opts.spread;
            Pose::new(
                q * (from.translation - c) + c + t,
                (q * from.rotation).normalize(),
            )
            .unwrap_or(*from)
        })
        .collect()
}

/// The contact patches on the `lateral` side of the centre of mass `com` (world) and on the
/// other.
fn sides(patches: &[Patch], com: DVec3, lateral: DVec3) -> (usize, usize) {
    let on = patches
        .iter()
        .filter(|p| (p.point - com).dot(lateral) > 0.0)
        .count();
    (on, patches.len() - on)
}

/// The smaller eigenvalue of the symmetric 2×2 matrix `[[xx, xy], [xy, yy]]`.
fn least_eigenvalue(xx: f64, xy: f64, yy: f64) -> f64 {
    let half = 0.5 * (xx + yy);
    let disc = (0.25 * (xx - yy) * (xx - yy) + xy * xy).sqrt();
    half - disc
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_starts_spread_across_the_axis_and_turn_about_it_through_the_centre_of_mass() {
        let from = Pose::new(DVec3::new(1.0, 2.0, -3.0), DQuat::from_rotation_x(0.3)).unwrap();
        let com = DVec3::new(0.5, -4.0, 2.0);
        let (axis, lateral) = (DVec3::Z, DVec3::X);
        let opts = FreeOcclusionOptions {
            starts: 300,
            spread: 1.5,
            spread_angle: 0.1,
            seed: 4,
            ..Default::default()
        };
        let starts = spread_starts(&from, com, axis, lateral, &opts);
        assert_eq!(starts.len(), 300);
        assert_eq!(starts[0], from);
        assert_eq!(starts, spread_starts(&from, com, axis, lateral, &opts));
        for seed in [0, 3, u64::MAX] {
            let other = spread_starts(
                &from,
                com,
                axis,
                lateral,
                &FreeOcclusionOptions { seed, ..opts },
            );
            assert_ne!(other[1], starts[1], "seed {seed}");
        }
        let c = from.transform_point(com);
        // Start 1 from the generator's state for seed 4 (4 ^ 0x9e3779b97f4a7c15, made odd): its
        // draws 4 to 6 move it sideways (x), forwards (y) and turn it (z) about the centre of
        // mass. A seed gives the same starts in every version.
        let mut draws = Spread(0x9e37_79b9_7f4a_7c11);
        let d: Vec<f64> = (0..6).map(|_| draws.unit()).collect();
        let turn = DQuat::from_rotation_z(d[5] * 0.1);
        let want = turn * (from.translation - c) + c + DVec3::new(d[3], d[4], 0.0) * 1.5;
        assert!(
            (starts[1].translation - want).length() < 1e-12,
            "{}",
            starts[1].translation
        );
        assert!((starts[1].rotation - turn * from.rotation).length() < 1e-12);
        let (mut far_x, mut far_y, mut far_turn) = (0.0f64, 0.0f64, 0.0f64);
        for s in &starts[1..] {
            let d = s.transform_point(com) - c;
            // Across the axis only, within the spread.
            assert!(d.z.abs() < 1e-12, "{d}");
            assert!(d.x.abs() <= 1.5 && d.y.abs() <= 1.5, "{d}");
            // A turn about the axis only, within the angle.
            let turn = (s.rotation * from.rotation.inverse()).to_scaled_axis();
            assert!(turn.x.abs() < 1e-12 && turn.y.abs() < 1e-12, "{turn}");
            assert!(turn.z.abs() <= 0.1 + 1e-12, "{turn}");
            // The turn is about the centre of mass: a point turns about it.
            let p = DVec3::new(3.0, 1.0, 2.0);
            let moved = s.transform_point(p) - s.transform_point(com);
            let want = DQuat::from_scaled_axis(turn) * (from.transform_point(p) - c);
            assert!((moved - want).length() < 1e-9);
            far_x = far_x.max(d.x.abs());
            far_y = far_y.max(d.y.abs());
            far_turn = far_turn.max(turn.z.abs());
        }
        // The spread is used in full.
        assert!(
            far_x > 1.4 && far_y > 1.4 && far_turn > 0.09,
            "{far_x} {far_y} {far_turn}"
        );
    }

    #[test]
    fn the_least_eigenvalue_of_a_symmetric_2x2() {
        assert_eq!(least_eigenvalue(3.0, 1.0, 3.0), 2.0);
        assert_eq!(least_eigenvalue(3.0, -1.0, 3.0), 2.0);
        assert_eq!(least_eigenvalue(5.0, 0.0, 2.0), 2.0);
        assert_eq!(least_eigenvalue(2.0, 0.0, 5.0), 2.0);
        // [[4, 2], [2, 1]]: 0 and 5.
        assert!(least_eigenvalue(4.0, 2.0, 1.0).abs() < 1e-12);
    }

    #[test]
    fn rests_rank_by_starts_times_the_weaker_side_over_the_imbalance() {
        let rest = |starts, on, off| Rest {
            starts,
            ..rest_at(0.0, OcclusionStatus::Converged, on, off)
        };
        assert_eq!(rest(3, 4, 2).score(), 2.0);
        assert_eq!(rest(3, 2, 4).score(), 2.0);
        assert_eq!(rest(5, 3, 3).score(), 15.0);
        assert_eq!(rest(5, 0, 6).score(), 0.0);
    }

    #[test]
    fn patches_are_counted_on_either_side_of_the_centre_of_mass() {
        let at = |x: f64| Patch {
            point: DVec3::new(x, 7.0, -2.0),
            normal: DVec3::Z,
            depth: 0.1,
            volume: 0.1,
            pairs: 1,
        };
        let patches = [at(1.5), at(2.5), at(0.5), at(2.0)];
        let com = DVec3::new(2.0, 0.0, 0.0);
        assert_eq!(sides(&patches, com, DVec3::X), (1, 3));
        assert_eq!(sides(&patches, com, -DVec3::X), (2, 2));
        assert_eq!(sides(&[], com, DVec3::X), (0, 0));
    }

    #[test]
    fn the_spread_is_the_same_for_a_seed_and_within_one() {
        let mut s = Spread(7);
        let first: Vec<f64> = (0..4).map(|_| s.unit()).collect();
        assert_eq!(first, GOLDEN);
        let mut s = Spread(12345);
        let draws: Vec<f64> = (0..20_000).map(|_| s.unit()).collect();
        assert!(draws.iter().all(|x| (-1.0..1.0).contains(x)));
        let mean = draws.iter().sum::<f64>() / draws.len() as f64;
        assert!(mean.abs() < 0.02, "{mean}");
        let (lo, hi) = draws
            .iter()
            .fold((1.0f64, -1.0f64), |(l, h), &x| (l.min(x), h.max(x)));
        assert!(lo < -0.999 && hi > 0.999, "{lo} {hi}");
    }

    #[test]
    fn the_options_refuse_what_no_closing_can_start_from() {
        let good = FreeOcclusionOptions {
            lateral: DVec3::new(2.0, 0.0, 5.0),
            ..Default::default()
        };
        // The lateral direction's part along the closing axis (z) is dropped.
        assert_eq!(good.check().unwrap(), (DVec3::Z, DVec3::X));
        // A closing axis too long to square is still a direction.
        let huge = FreeOcclusionOptions {
            closing: OcclusionOptions {
                axis: DVec3::new(0.0, 0.0, 1e300),
                ..good.closing
            },
            ..good
        };
        assert_eq!(huge.check().unwrap(), (DVec3::Z, DVec3::X));
        let edges = FreeOcclusionOptions {
            starts: 1000,
            spread: 0.0,
            spread_angle: 0.0,
            same_pose: 0.0,
            ..good
        };
        assert!(edges.check().is_ok());
        let widest = FreeOcclusionOptions {
            spread: 10.0,
            spread_angle: 20f64.to_radians(),
            ..good
        };
        assert!(widest.check().is_ok());
        assert!(FreeOcclusionOptions { starts: 1, ..good }.check().is_ok());
        let mut bad = vec![
            FreeOcclusionOptions { starts: 0, ..good },
            FreeOcclusionOptions {
                starts: 1001,
                ..good
            },
            FreeOcclusionOptions {
                spread: 10.01,
                ..good
            },
            FreeOcclusionOptions {
                spread: 1000.0,
                ..good
            },
            FreeOcclusionOptions {
                spread_angle: 20.01f64.to_radians(),
                ..good
            },
            FreeOcclusionOptions {
                lateral: DVec3::Z * 3.0,
                ..good
            },
            FreeOcclusionOptions {
                lateral: DVec3::ZERO,
                ..good
            },
            FreeOcclusionOptions {
                lateral: DVec3::new(f64::NAN, 1.0, 0.0),
                ..good
            },
            FreeOcclusionOptions {
                closing: OcclusionOptions {
                    joints: Some(crate::Joints {
                        points: [DVec3::ZERO; 2],
                        anchors: [DVec3::ZERO; 2],
                        stiffness: 1.0,
                    }),
                    ..good.closing
                },
                ..good
            },
        ];
        for x in [-1.0, f64::INFINITY, f64::NAN] {
            bad.push(FreeOcclusionOptions { spread: x, ..good });
            bad.push(FreeOcclusionOptions {
                spread_angle: x,
                ..good
            });
            bad.push(FreeOcclusionOptions {
                same_pose: x,
                ..good
            });
        }
        for o in bad {
            assert!(
                matches!(o.check(), Err(Error::InvalidOption(_))),
                "{o:?} passed"
            );
        }
    }

    #[test]
    fn apart_is_the_largest_move_of_the_centre_of_mass_and_six_points_at_the_radius() {
        let com = DVec3::new(1.0, -2.0, 0.5);
        let probes = Probes::new(com, 3.0);
        let p = Pose::new(DVec3::new(0.3, 0.2, -1.0), DQuat::from_rotation_y(0.4)).unwrap();
        // A shift: every point moves by it.
        let shifted = Pose::new(p.translation + DVec3::new(0.0, 0.3, 0.4), p.rotation).unwrap();
        assert!((probes.apart(&p, &shifted) - 0.5).abs() < 1e-12);
        assert_eq!(probes.apart(&p, &p), 0.0);
        // Poses that differ by turns about the centre of mass and shifts: the largest move of
        // the seven points, whichever moves most.
        let points = [
            com,
            com + DVec3::new(3.0, 0.0, 0.0),
            com - DVec3::new(3.0, 0.0, 0.0),
            com + DVec3::new(0.0, 3.0, 0.0),
            com - DVec3::new(0.0, 3.0, 0.0),
            com + DVec3::new(0.0, 0.0, 3.0),
            com - DVec3::new(0.0, 0.0, 3.0),
        ];
        for (axis, shift) in [
            (DVec3::X, DVec3::new(0.0, -0.2, 0.1)),
            (DVec3::Y, DVec3::new(0.1, 0.0, -0.3)),
            (DVec3::Z, DVec3::new(-0.2, 0.25, 0.0)),
            (
                DVec3::new(1.0, 2.0, -1.0).normalize(),
                DVec3::new(0.05, 0.1, 0.2),
            ),
        ] {
            let turn = DQuat::from_axis_angle(axis, 0.07);
            let c = p.transform_point(com);
            let q = Pose::new(turn * (p.translation - c) + c + shift, turn * p.rotation).unwrap();
            let want = points
                .iter()
                .map(|x| (p.transform_point(*x) - q.transform_point(*x)).length())
                .fold(0.0, f64::max);
            assert_eq!(probes.apart(&p, &q), want, "{axis}");
            assert!(want > shift.length(), "{axis}");
        }
        // A body of no size is probed at its centre of mass (and a point beside it).
        assert!((Probes::new(com, 0.0).apart(&p, &shifted) - 0.5).abs() < 1e-12);
    }

    /// A closing that ended at `x` along x in `status`, with `on` and `off` patches on
    /// either side.
    fn rest_at(x: f64, status: OcclusionStatus, on: usize, off: usize) -> Rest {
        Rest {
            o: Occlusion {
                pose: Pose::new(DVec3::new(x, 0.0, 0.0), DQuat::IDENTITY).unwrap(),
                status,
                steps: 0,
                seconds: 0.0,
                volume: 0.0,
                max_depth: 0.0,
                patches: vec![],
                axis: DVec3::Z,
            },
            on,
            off,
            starts: 1,
        }
    }

    #[test]
    fn converged_rests_within_the_same_pose_distance_of_a_cluster_join_it() {
        use OcclusionStatus::*;
        let probes = Probes::new(DVec3::ZERO, 1.0);
        let rests = [
            rest_at(0.0, Converged, 2, 1),
            // In contact but out of time, through A, away: no rest, not clustered.
            rest_at(0.0625, TimeLimit, 1, 1),
            rest_at(0.0, PassedThrough, 1, 1),
            rest_at(0.0, Escaped, 0, 0),
            // Exactly the distance from the first: a cluster of its own.
            rest_at(0.125, Converged, 3, 3),
            // At rest without contact: not clustered.
            rest_at(5.0, NoContact, 0, 0),
            rest_at(0.1875, Converged, 1, 0),
            rest_at(-0.0625, Converged, 1, 2),
        ];
        let clusters = cluster(rests, &probes, 0.125);
        let got: Vec<(f64, usize, usize)> = clusters
            .iter()
            .map(|k| (k.o.pose.translation.x, k.starts, k.on))
            .collect();
        assert_eq!(got, [(0.0, 2, 2), (0.125, 2, 3)]);
    }

    #[test]
    fn the_lateral_stiffness_is_the_least_stiffness_across_the_axis() {
        // A linear block with couplings, not symmetric (the contact's is not in general).
        let m = DMat3::from_cols(
            DVec3::new(40.0, 7.0, -3.0),
            DVec3::new(-2.0, 25.0, 5.0),
            DVec3::new(9.0, 4.0, 100.0),
        );
        let (l, f) = (
            DVec3::new(1.0, 1.0, 0.0).normalize(),
            DVec3::new(-1.0, 1.0, 0.0).normalize(),
        );
        let got = lateral_stiffness(&m, l, f);
        // The least of u·M·u over the unit pushes u across the axis (z), by brute force.
        let least = (0..36_000)
            .map(|i| {
                let a = i as f64 * std::f64::consts::TAU / 36_000.0;
                let u = DVec3::new(a.cos(), a.sin(), 0.0);
                u.dot(m * u)
            })
            .fold(f64::INFINITY, f64::min);
        assert!((got - least).abs() < 1e-6, "{got} against {least}");
        // The same in any basis of the plane.
        assert!((lateral_stiffness(&m, DVec3::X, DVec3::Y) - got).abs() < 1e-9);
    }

    /// Seed 7's first draws, computed apart from this code (Python, the published
    /// xorshift64*: shifts 12, 25, 27, multiplier 0x2545F4914F6CDD1D, top 53 bits).
    const GOLDEN: [f64; 4] = [
        0.6404933330823976,
        0.8565803130088456,
        -0.8213008144968241,
        -0.7847451468888491,
    ];
}
