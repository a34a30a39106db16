//! What a closing accepts: forces, stiffnesses and times limited to what a bite can be and
//! what the dynamics can hold, each refusal a sentence naming the limit.
//!
//! Why these limits (docs/OCCLUSION.md has the figures):
//! - **The force**: from [`MIN_FORCE`] (the weight of a plaster segment resting on its
//!   antagonist) to [`MAX_FORCE`] (above the strongest human bite: maximal bite forces are
//!   500–900 N at the molars).
//! - **The force against the contact's stiffness**: the penalty contact carries the force
//!   on the overlap volume `force / stiffness` at rest. A cusp tip of radius `R` sunk `d`
//!   into its antagonist overlaps it by about `π R d²`; three cusp tips of 1 mm radius (the
//!   fewest contacts that hold a body) sunk 0.46 mm (a quarter of a 2 mm cusp) overlap by
//!   2 mm³ ([`MAX_REST_OVERLAP`]). More, and the cusps sink into each other and slide over,
//!   or B goes through A. The default contact (5 N on 10 N/mm³: 0.5 mm³) rests the jaw
//!   pair 0.28 mm deep; up to 20 N with it, and up to 1000 N with a stiff 500 N/mm³.
//! - **The step**: in free flight B closes at `force / damping`; one step moves it at most
//!   [`MAX_STEP_TRAVEL`], a tenth of the deepest overlap the force limit allows, so that no
//!   contact is stepped over (the joints' planner, [`bite`](fn@crate::bite), scales the damping
//!   with the force so that every closing runs at 5 mm/s).
//! - **The contact stiffness** at most [`MAX_CONTACT_STIFFNESS`]: at 1e5 N/mm³ the jaw pair
//!   already rests 0.014 mm deep under 5 N, a seventh of the jaw preset's 0.1 mm voxel, on
//!   one or two leaf pairs; a stiffer contact rests on overlaps the sphere model does not
//!   resolve (a 1e12 N/mm³ contact rested on one patch of no measurable volume) and, far
//!   enough, overflows.
//! - **The joints** at most [`MAX_JOINT_STIFFNESS`] (stiffer than any temporomandibular joint,
//!   which gives millimetres under hundreds of newtons) and stretched at most
//!   [`MAX_JOINT_STRETCH`] at the start (a condyle translates about 20 mm in the widest
//!   opening).
//! - **The time** at most [`MAX_SECONDS`] of simulated time: a closing at 5 mm/s from the
//!   widest start a bite accepts (30 mm open) takes 6 s, and settles within 2 s more.
//!
//! Huge finite values of any of these were what made the dynamics non-finite (a force or
//! stiffness of 1e300, joints stretched 1e15 mm): refused here, they no longer reach them.

use crate::occlusion::{unit, OcclusionOptions};
use innersphere::error::{num, vec3, Error, Result};
use innersphere::pose::Pose;

/// The least closing force (N): the weight of a 50 g plaster segment resting on its
/// antagonist.
pub const MIN_FORCE: f64 = 0.5;
/// The largest closing force (N): above the strongest human bite (500–900 N at the molars).
pub const MAX_FORCE: f64 = 1000.0;
/// The largest overlap volume (mm³) the contact may need at rest to carry the force
/// (`force / contact stiffness`): three cusp tips of 1 mm radius sunk 0.46 mm (see the
/// module docs).
pub const MAX_REST_OVERLAP: f64 = 2.0;
/// The stiffest contact (N/mm³): stiffer rests on overlaps below the sphere model's
/// resolution (see the module docs).
pub const MAX_CONTACT_STIFFNESS: f64 = 1e5;
/// The farthest one step moves B in free flight (mm): `force / damping × step`.
pub const MAX_STEP_TRAVEL: f64 = 0.05;
/// The longest closing (s of simulated time).
pub const MAX_SECONDS: f64 = 60.0;
/// The stiffest joint (N/mm).
pub const MAX_JOINT_STIFFNESS: f64 = 1e4;
/// The farthest a joint's point of B may start from its anchor (mm).
pub const MAX_JOINT_STRETCH: f64 = 100.0;
/// The integration step's range (s).
pub const STEP_RANGE: (f64, f64) = (1e-5, 1e-2);
/// The density's range (kg/mm³): 0.01 to 100 g/cm³ (enamel ~3, dentine and bone ~2).
pub const DENSITY_RANGE: (f64, f64) = (1e-8, 1e-4);
/// The largest rest distance (mm).
pub const MAX_REST_DISTANCE: f64 = 0.1;

/// A computed number as a message writes it: 4 significant digits, then [`num`]'s form
/// (`63.6`, `2.05`, `9.964e14`).
pub(super) fn short(x: f64) -> innersphere::error::Num {
    num(format!("{x:.3e}").parse().unwrap_or(x))
}

/// `x` positive and at most `hi` (finite), or the error "`what` must be positive and at
/// most `hi` `unit`, not `x`".
fn positive_to(what: &str, x: f64, hi: f64, unit: &str) -> Result<()> {
    if x.is_finite() && x > 0.0 && x <= hi {
        return Ok(());
    }
    Err(Error::InvalidOption(format!(
        "{what} must be positive and at most {} {unit}, not {}",
        num(hi),
        num(x)
    )))
}

/// `x` within `[lo, hi]` (finite), or the error "`what` must be `lo` to `hi` `unit`
/// (`why`), not `x`".
fn within(what: &str, x: f64, (lo, hi): (f64, f64), unit: &str, why: &str) -> Result<()> {
    if x.is_finite() && (lo..=hi).contains(&x) {
        return Ok(());
    }
    let why = if why.is_empty() {
        String::new()
    } else {
        format!(" ({why})")
    };
    Err(Error::InvalidOption(format!(
        "{what} must be {} to {} {unit}{why}, not {}",
        num(lo),
        num(hi),
        num(x)
    )))
}

/// Refuses options (and a start) that cannot make a bite or that the dynamics cannot hold:
/// see the module docs.
pub(super) fn check(o: &OcclusionOptions, from: &Pose) -> Result<()> {
    check_options(o)?;
    check_start(o, from)
}

/// [`check`] without the start: the options alone.
pub(super) fn check_options(o: &OcclusionOptions) -> Result<()> {
    within(
        "the closing force",
        o.force,
        (MIN_FORCE, MAX_FORCE),
        "N",
        "a bite: from a plaster segment's weight to above the strongest human bite, ~900 N",
    )?;
    positive_to(
        "the contact stiffness",
        o.contact_stiffness,
        MAX_CONTACT_STIFFNESS,
        "N/mm³",
    )?;
    let overlap = o.force / o.contact_stiffness;
    if overlap > MAX_REST_OVERLAP {
        return Err(Error::InvalidOption(format!(
            "a closing force of {} N on a contact of {} N/mm³ rests on {} mm³ of overlap, \
             more than the {} mm³ the contact holds before the cusps sink through each other: \
             use at most {} N with this stiffness, or a contact of at least {} N/mm³",
            num(o.force),
            num(o.contact_stiffness),
            short(overlap),
            num(MAX_REST_OVERLAP),
            num(o.contact_stiffness * MAX_REST_OVERLAP),
            num(o.force / MAX_REST_OVERLAP),
        )));
    }
    if !(o.contact_damping.is_finite() && (0.0..=1.0).contains(&o.contact_damping)) {
        return Err(Error::InvalidOption(format!(
            "the contact damping must be 0 to 1 s, not {}",
            num(o.contact_damping)
        )));
    }
    within("the step", o.step, STEP_RANGE, "s", "")?;
    if !(o.damping.is_finite() && o.damping > 0.0) {
        return Err(Error::InvalidOption(format!(
            "the damping must be positive and finite, not {} N·s/mm",
            num(o.damping)
        )));
    }
    let travel = o.force / o.damping * o.step;
    if travel > MAX_STEP_TRAVEL {
        return Err(Error::InvalidOption(format!(
            "a closing force of {} N over a damping of {} N·s/mm moves B {} mm per step of \
             {} s in free flight, more than the {} mm that keeps a step from passing over a \
             contact: use a damping of at least {} N·s/mm",
            num(o.force),
            num(o.damping),
            short(travel),
            num(o.step),
            num(MAX_STEP_TRAVEL),
            num(o.force * o.step / MAX_STEP_TRAVEL),
        )));
    }
    within("the density", o.density, DENSITY_RANGE, "kg/mm³", "")?;
    positive_to(
        "the rest distance",
        o.rest_distance,
        MAX_REST_DISTANCE,
        "mm",
    )?;
    within(
        "the time limit",
        o.max_seconds,
        (o.step, MAX_SECONDS),
        "s",
        "a closing from 30 mm open takes 6 s and settles in 2 s more",
    )?;
    if unit(o.axis).is_none() {
        return Err(Error::InvalidOption(format!(
            "the closing axis must be a finite non-zero vector, not {}",
            vec3(o.axis)
        )));
    }
    if let Some(j) = &o.joints {
        if !j.points.iter().chain(&j.anchors).all(|p| p.is_finite()) {
            return Err(Error::InvalidOption(
                "the joints' points and anchors must be finite".into(),
            ));
        }
        if !(j.stiffness.is_finite() && (0.0..=MAX_JOINT_STIFFNESS).contains(&j.stiffness)) {
            return Err(Error::InvalidOption(format!(
                "the joint stiffness must be finite and 0 to {} N/mm (stiffer than any \
                 temporomandibular joint), not {} N/mm",
                num(MAX_JOINT_STIFFNESS),
                num(j.stiffness)
            )));
        }
    }
    Ok(())
}

/// [`check`]'s part that depends on the start: finite, and the joints stretched at most
/// [`MAX_JOINT_STRETCH`] there.
pub(super) fn check_start(o: &OcclusionOptions, from: &Pose) -> Result<()> {
    if !from.translation.is_finite() || !from.rotation.is_finite() {
        return Err(Error::InvalidOption("the start pose must be finite".into()));
    }
    if let Some(j) = &o.joints {
        for (p, anchor) in j.points.iter().zip(&j.anchors) {
            let stretch = (from.transform_point(*p) - *anchor).length();
            if stretch.is_nan() || stretch > MAX_JOINT_STRETCH {
                return Err(Error::InvalidOption(format!(
                    "the start puts a joint {} mm from where it is held, more than the {} mm \
                     a condyle can move: is the start (or the reference pose) in A's frame?",
                    short(stretch),
                    num(MAX_JOINT_STRETCH)
                )));
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Joints;
    use glam::DVec3;

    fn ok(o: OcclusionOptions) -> bool {
        check(&o, &Pose::IDENTITY).is_ok()
    }

    #[test]
    fn the_options_are_checked_at_their_edges() {
        let base = OcclusionOptions::default();
        assert!(ok(base));
        // The force: 0.5 to 1000 N, with a contact that holds it (the damping and the
        // stiffness raised with it).
        let with_force = |force: f64| OcclusionOptions {
            force,
            contact_stiffness: 1000.0,
            damping: force / 5.0,
            ..base
        };
        for (force, good) in [
            (0.5, true),
            (0.49, false),
            (1000.0, true),
            (1000.5, false),
            (f64::NAN, false),
            (1e300, false),
        ] {
            assert_eq!(ok(with_force(force)), good, "{force} N");
        }
        // The overlap at rest: force / stiffness up to 2 mm³.
        for (stiffness, good) in [(2.5, true), (2.49, false)] {
            let o = OcclusionOptions {
                contact_stiffness: stiffness,
                ..base
            };
            assert_eq!(ok(o), good, "{stiffness} N/mm³");
        }
        let e = check(
            &OcclusionOptions {
                force: 20.5,
                damping: 5.0,
                ..base
            },
            &Pose::IDENTITY,
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("2.05 mm³") && e.contains("at most 20 N") && e.contains("10.25 N/mm³"),
            "{e}"
        );
        // The stiffness: up to 1e5 N/mm³.
        for (stiffness, good) in [(1e5, true), (1.01e5, false), (1e300, false)] {
            let o = OcclusionOptions {
                contact_stiffness: stiffness,
                ..base
            };
            assert_eq!(ok(o), good, "{stiffness} N/mm³");
        }
        // A step's travel in free flight: force / damping × step up to 0.05 mm.
        for (damping, good) in [(0.1, true), (0.099, false), (0.0, false)] {
            let o = OcclusionOptions { damping, ..base };
            assert_eq!(ok(o), good, "{damping} N·s/mm");
        }
        // No contact damping is allowed; a negative or non-finite one is not.
        assert!(ok(OcclusionOptions {
            contact_damping: 0.0,
            ..base
        }));
        for x in [-1.0, f64::INFINITY, f64::NAN, 2.0] {
            assert!(
                !ok(OcclusionOptions {
                    contact_damping: x,
                    ..base
                }),
                "{x}"
            );
        }
        // The time: up to 60 s; the step 10 µs to 10 ms.
        for (max_seconds, step, good) in [
            (60.0, 1e-3, true),
            (60.01, 1e-3, false),
            (1e-5, 1e-5, true),
            (1.0, 0.011, false),
            (1.0, 9e-6, false),
        ] {
            let o = OcclusionOptions {
                max_seconds,
                step,
                damping: 10.0,
                ..base
            };
            assert_eq!(ok(o), good, "{max_seconds} s in steps of {step} s");
        }
    }

    #[test]
    fn joints_are_bounded_in_stiffness_and_stretch() {
        let at = [
            DVec3::new(50.0, -90.0, 20.0),
            DVec3::new(-50.0, -90.0, 20.0),
        ];
        let with = |stiffness: f64, anchors: [DVec3; 2]| OcclusionOptions {
            joints: Some(Joints {
                points: at,
                anchors,
                stiffness,
            }),
            ..OcclusionOptions::default()
        };
        assert!(ok(with(0.0, at)));
        assert!(ok(with(1e4, at)));
        for bad in [-1.0, 1.01e4, f64::NAN, 1e300] {
            let e = check(&with(bad, at), &Pose::IDENTITY).unwrap_err();
            assert!(e.to_string().contains("joint stiffness"), "{e}");
        }
        // Stretched up to 100 mm at the start, not more.
        let moved = [at[0], at[1] + DVec3::Z * 100.0];
        assert!(ok(with(20.0, moved)));
        let far = [at[0], at[1] + DVec3::Z * 100.5];
        let e = check(&with(20.0, far), &Pose::IDENTITY).unwrap_err();
        assert!(
            e.to_string().contains("100.5 mm from where it is held"),
            "{e}"
        );
        // The start counts: the same anchors with B moved 1e15 mm away.
        let e = check(&with(20.0, at), &Pose::from_translation(DVec3::Z * -1e15)).unwrap_err();
        assert!(e.to_string().contains("from where it is held"), "{e}");
    }
}
