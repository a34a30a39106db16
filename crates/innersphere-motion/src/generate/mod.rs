//! Generated motions that look hand-recorded: a surgeon moving the lower body B against the
//! upper body A with a haptic device at 1 kHz.
//!
//! The motion is planned in the pair's [`AnatomicalFrame`]: an opening rotation about the
//! hinge axis (measured as the opening `o` at the incisal point), lateral and protrusive
//! shifts (with a slight turn about the vertical, like a Bennett movement), all relative to
//! the *bite* — the identity pose when the bodies overlap slightly there (as a real bite
//! does), otherwise the pose along up where they overlap by 1.5 × the touch threshold.
//!
//! A scenario is a list of keyframes with either an opening (relative to first contact at
//! that lateral position) or a target clearance (light contact, the bite, a clench). Every
//! contact keyframe is solved for its opening with the [`ClearanceEstimator`] (bracketing
//! and Illinois regula falsi along the closing rotation); slides in contact are solved every
//! 20 ms. The keyframes are joined by minimum-jerk (quintic) segments, like point-to-point
//! hand movements, and the opening is lightly smoothed (Gaussian, σ = 8 ms), so the motion
//! is C2 and free of jumps. On top comes hand tremor: sums of sinusoids between 2 and 12 Hz
//! with random phases, about 0.013 mm RMS at scale 1 (plus a little rotation). All
//! randomness comes from the seed; the same inputs give the same motion bit for bit.
//!
//! The files: `scenario` (the scenarios and their keyframe plans), `kinematics` (the pose
//! for an opening and a lateral position), `contact` (solving keyframes for contact with
//! the clearance estimate, and the opening of every frame), `trajectory` (minimum-jerk
//! segments, smoothing, tremor); this one checks the options and puts the motion together.

mod contact;
mod kinematics;
mod scenario;
mod trajectory;

pub use scenario::Scenario;

use super::clearance::{phase_of, ClearanceEstimator, ClearanceOptions, Phase, PhaseCounts};
use super::frame::AnatomicalFrame;
use super::rng::Rng;
use super::{Frame, Motion};
use contact::{solve, Planner};
use glam::{DQuat, DVec3};
use innersphere::Pose;
use innersphere::{Error, Mesh, Result};
use kinematics::Kin;
use scenario::{plan_chew, plan_contact, plan_grind, plan_open_close};
use std::f64::consts::TAU;
use trajectory::{lateral, sinusoids};

/// Options of [`generate_with`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GenerateOptions {
    /// Frames per second (1000).
    pub rate: f64,
    /// Size of the motion relative to a human jaw; `None`: [`AnatomicalFrame::scale`].
    pub scale: Option<f64>,
    /// Touch threshold of the phases; `None`: 0.1 × scale.
    pub touch: Option<f64>,
    /// RMS of the tremor's translation; `None`: drawn from 0.010–0.016 × scale.
    pub tremor: Option<f64>,
    /// The clearance estimate used for planning and labels.
    pub clearance: ClearanceOptions,
}

impl Default for GenerateOptions {
    fn default() -> Self {
        GenerateOptions {
            rate: 1000.0,
            scale: None,
            touch: None,
            tremor: None,
            clearance: ClearanceOptions::default(),
        }
    }
}

/// Clearances are labelled up to this many touch thresholds (larger gaps read as this).
pub const LABEL_CAP_TOUCHES: f64 = 15.0;

/// A generated motion with what went into it and its labels.
#[derive(Debug, Clone)]
pub struct Generated {
    /// The motion.
    pub motion: Motion,
    /// The anatomical frame of the pair (B at the identity).
    pub frame: AnatomicalFrame,
    /// The scale the motion was made at.
    pub scale: f64,
    /// The touch threshold of the labels.
    pub touch: f64,
    /// The bite pose (identity for a pair that overlaps slightly there).
    pub bite: Pose,
    /// The estimated clearance at the bite.
    pub bite_clearance: f64,
    /// RMS of the tremor's translation.
    pub tremor_rms: f64,
    /// The estimated clearance of each frame, capped at [`LABEL_CAP_TOUCHES`] × touch.
    pub clearance: Vec<f64>,
    /// The phase of each frame ([`phase_of`] with [`touch`](Self::touch)).
    pub phases: Vec<Phase>,
    /// Number of clearance samples the estimate used.
    pub samples: usize,
}

impl Generated {
    /// How many frames are in each phase.
    pub fn counts(&self) -> PhaseCounts {
        PhaseCounts::of(&self.phases)
    }

    /// The labels as CSV: `frame,t,clearance,phase`, one line per frame.
    pub fn labels_csv(&self) -> String {
        use std::fmt::Write as _;
        let mut s = String::from("frame,t,clearance,phase\n");
        for (i, ((f, c), p)) in self
            .motion
            .frames
            .iter()
            .zip(&self.clearance)
            .zip(&self.phases)
            .enumerate()
        {
            let _ = writeln!(s, "{i},{},{c:.4},{p}", f.t);
        }
        s
    }
}

/// A hand-recorded-looking motion of B against A (see the [module docs](self)) at 1 kHz,
/// `seconds` long. Every scenario starts separated and reaches light contact and overlap
/// within about its first second.
pub fn generate(scenario: Scenario, seconds: f64, seed: u64, a: &Mesh, b: &Mesh) -> Result<Motion> {
    generate_with(scenario, seconds, seed, a, b, &GenerateOptions::default()).map(|g| g.motion)
}

/// True when `a` and `b` are the same body: equal meshes, or the same triangle count,
/// bounding box and volume (to 1e-9: the same file in another format or vertex order).
pub fn same_body(a: &Mesh, b: &Mesh) -> bool {
    a == b || {
        let ((la, ha), (lb, hb)) = (a.bbox(), b.bbox());
        let tol = 1e-9 * (ha - la).length().max((hb - lb).length());
        let (va, vb) = (a.signed_volume().abs(), b.signed_volume().abs());
        a.triangles.len() == b.triangles.len()
            && (la - lb).abs().max((ha - hb).abs()).max_element() <= tol
            && (va - vb).abs() <= 1e-9 * va.max(vb)
    }
}

/// The bite a generated motion closes into: the identity when the pair overlaps slightly
/// there (by `touch` to 8 `touch`), else B moved along the frame's up until it does (`k`: the
/// pair's scale); an error that says why when no such pose exists.
fn light_bite(
    est: &mut ClearanceEstimator,
    a: &Mesh,
    b: &Mesh,
    frame: &AnatomicalFrame,
    touch: f64,
    k: f64,
) -> Result<Pose> {
    let c0 = est.clearance(&Pose::IDENTITY);
    Ok(if (-8.0 * touch..=-touch).contains(&c0) {
        Pose::IDENTITY
    } else {
        let up = frame.up;
        let target = -1.5 * touch;
        let mut f = |x: f64| est.clearance(&Pose::from_translation(up * -x)) - target;
        let x = solve(
            &mut f,
            0.0,
            c0 - target,
            1.0,
            0.002 * k,
            -1e3 * k,
            1e3 * k,
            0.02 * touch,
        )
        .ok_or_else(|| {
            // Say why: the same body twice, bodies that overlap and never come apart, or
            // bodies that never meet.
            Error::InvalidOption(if same_body(a, b) {
                format!(
                    "cannot generate a motion: body A and body B are the same mesh ({} \
                     triangles, the same bounding box and volume), so they coincide at the \
                     identity pose, and moving B along the occlusal direction finds no light \
                     bite; give two different bodies (an upper and a lower jaw, say)",
                    a.triangles.len()
                )
            } else if c0 < 0.0 {
                format!(
                    "cannot generate a motion: the bodies overlap at the identity pose \
                     (clearance estimate {c0:.3e}) and moving B along the occlusal direction \
                     finds no light bite"
                )
            } else {
                "cannot generate a motion: the bodies never touch when B moves along the \
                 occlusal direction"
                    .into()
            })
        })?;
        Pose::from_translation(up * -x)
    })
}

/// [`generate`] with options, returning the labels and the plan's anchors too.
// Over 120 lines: the motion is planned, sampled and given its tremor in one pass over the
// frames; the plan's anchors, the hinge and the random stream are shared by every step.
pub fn generate_with(
    scenario: Scenario,
    seconds: f64,
    seed: u64,
    a: &Mesh,
    b: &Mesh,
    opts: &GenerateOptions,
) -> Result<Generated> {
    if !(seconds.is_finite() && seconds > 0.0 && seconds <= 86_400.0) {
        return Err(Error::InvalidOption(format!(
            "motion length {seconds} s: expected more than 0 and at most 86400"
        )));
    }
    if !(opts.rate.is_finite() && (1.0..=100_000.0).contains(&opts.rate)) {
        return Err(Error::InvalidOption(format!(
            "frame rate {} Hz: expected 1 to 100000",
            opts.rate
        )));
    }
    let n = (seconds * opts.rate).round().max(1.0);
    if n > 5e7 {
        return Err(Error::InvalidOption(format!(
            "{n} frames are too many (at most 5e7)"
        )));
    }
    let n = n as usize;
    let frame = AnatomicalFrame::from_meshes(a, b)?;
    let k = opts.scale.unwrap_or(frame.scale);
    if !(k.is_finite() && k > 0.0) {
        return Err(Error::InvalidOption(format!("scale {k}: expected > 0")));
    }
    let touch = opts.touch.unwrap_or(0.1 * k);
    if !(touch.is_finite() && touch > 0.0) {
        return Err(Error::InvalidOption(format!(
            "touch threshold {touch}: expected > 0"
        )));
    }
    let mut rng = Rng::new(seed);
    // Drawn even when given, so that the tremor's size leaves the rest of the motion alone.
    let drawn = rng.range(0.010, 0.016) * k;
    let tremor_rms = opts.tremor.unwrap_or(drawn);
    if !(tremor_rms.is_finite() && tremor_rms >= 0.0) {
        return Err(Error::InvalidOption(format!(
            "tremor {tremor_rms}: expected >= 0"
        )));
    }

    let mut est = ClearanceEstimator::new(a, b, &opts.clearance);
    let bite = light_bite(&mut est, a, b, &frame, touch, k)?;
    // Finer samples where the bodies meet.
    est.add_contact_samples(a, b, &bite, 1.5 * k, opts.clearance.samples.max(1));
    let bite_clearance = est.clearance(&bite);
    let moved = frame.moved(&bite);
    let kin = Kin {
        bite,
        hinge: moved.hinge,
        left: moved.left,
        up: moved.up,
        anterior: moved.anterior,
        r_inc: (moved.incisal - moved.hinge).length(),
        lip: 1.0,
    };
    // Points turn about the hinge: they move |p - hinge| / r_inc per unit of opening.
    let reach = b
        .vertices
        .iter()
        .map(|v| (bite.transform_point(*v) - kin.hinge).length())
        .fold(0.0, f64::max);
    let kin = Kin {
        lip: (reach / kin.r_inc).max(1.0),
        ..kin
    };

    let keys = match scenario {
        Scenario::Chew => plan_chew(&mut rng, seconds, k, touch, bite_clearance),
        Scenario::OpenClose => plan_open_close(&mut rng, seconds, k, touch, bite_clearance),
        Scenario::Grind => plan_grind(&mut rng, seconds, k, touch, bite_clearance),
        Scenario::Contact => plan_contact(&mut rng, seconds, k, touch, bite_clearance),
    };
    let mut planner = Planner {
        est: &mut est,
        kin: &kin,
        k,
        touch,
        guess: 0.0,
    };
    let o_channel = planner.opening(&keys, n, opts.rate)?;
    let times: Vec<f64> = (0..n).map(|i| i as f64 / opts.rate).collect();
    let lat_pro: Vec<(f64, f64)> = times.iter().map(|&t| lateral(&keys, t)).collect();

    // Tremor: 3 translation and 3 rotation channels.
    let centre = bite.transform_point(
        b.vertices.iter().copied().sum::<DVec3>() / b.vertices.len().max(1) as f64,
    );
    let trans_sigma = tremor_rms / 3f64.sqrt();
    let rot_sigma = 0.25 * tremor_rms / (25.0 * k) / 3f64.sqrt();
    let channels: Vec<Vec<(f64, f64, f64)>> = (0..6)
        .map(|c| sinusoids(&mut rng, if c < 3 { trans_sigma } else { rot_sigma }))
        .collect();
    let tremor = |t: f64, c: usize| -> f64 {
        channels[c]
            .iter()
            .map(|&(amp, f, ph)| amp * (TAU * f * t + ph).sin())
            .sum()
    };

    let mut frames = Vec::with_capacity(n);
    let mut prev = DQuat::IDENTITY;
    for i in 0..n {
        let t = times[i];
        let (lat, pro) = lat_pro[i];
        let planned = kin.pose(o_channel[i], lat, pro);
        let w = DVec3::new(tremor(t, 3), tremor(t, 4), tremor(t, 5));
        let q = DQuat::from_scaled_axis(w);
        let shake = Pose {
            rotation: q,
            translation: centre - q * centre + DVec3::new(tremor(t, 0), tremor(t, 1), tremor(t, 2)),
        };
        let mut pose = shake.then(&planned);
        if pose.rotation.dot(prev) < 0.0 {
            pose.rotation = -pose.rotation;
        }
        prev = pose.rotation;
        frames.push(Frame { t, pose });
    }
    let motion = Motion { frames };
    let clearance = est.clearances(&motion, LABEL_CAP_TOUCHES * touch);
    let phases = clearance.iter().map(|&c| phase_of(c, touch)).collect();
    Ok(Generated {
        motion,
        frame,
        scale: k,
        touch,
        bite,
        bite_clearance,
        tremor_rms,
        clearance,
        phases,
        samples: est.sample_count(),
    })
}
