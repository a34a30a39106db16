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

use super::clearance::{phase_of, ClearanceEstimator, ClearanceOptions, Phase, PhaseCounts};
use super::frame::AnatomicalFrame;
use super::rng::Rng;
use super::{Frame, Motion};
use glam::{DQuat, DVec3};
use innersphere::Pose;
use innersphere::{Error, Mesh, Result};
use std::f64::consts::TAU;

/// A kind of generated motion.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Scenario {
    /// Chewing cycles: open about 10 mm (hinge rotation), close into contact from the working
    /// side, slide into the bite, clench 0.1–0.25 mm beyond it, grind laterally in light
    /// contact, lift and re-open. About 2 s per cycle.
    Chew,
    /// Plain hinge opening (7–12 mm) and closing into the bite, about 1.2 s per cycle.
    OpenClose,
    /// Mostly lateral and protrusive sliding in light contact (excursions up to 3.5 mm), with
    /// an occasional press into overlap (the first right after the first contact) and an
    /// occasional lift-off. Starts slightly open.
    Grind,
}

impl Scenario {
    /// All scenarios.
    pub const ALL: [Scenario; 3] = [Scenario::Chew, Scenario::OpenClose, Scenario::Grind];

    /// `chew`, `open-close` or `grind` (what [`FromStr`](std::str::FromStr) reads).
    pub fn name(self) -> &'static str {
        match self {
            Scenario::Chew => "chew",
            Scenario::OpenClose => "open-close",
            Scenario::Grind => "grind",
        }
    }
}

impl std::fmt::Display for Scenario {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Scenario {
    type Err = Error;
    fn from_str(s: &str) -> Result<Scenario> {
        match s.trim().to_ascii_lowercase().replace('_', "-").as_str() {
            "chew" => Ok(Scenario::Chew),
            "open-close" | "openclose" => Ok(Scenario::OpenClose),
            "grind" => Ok(Scenario::Grind),
            _ => Err(Error::InvalidOption(format!(
                "unknown scenario \"{s}\" (expected chew, open-close or grind)"
            ))),
        }
    }
}

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

/// [`generate`] with options, returning the labels and the plan's anchors too.
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
    // The bite: the identity when the pair overlaps slightly there, else solved along up.
    let c0 = est.clearance(&Pose::IDENTITY);
    let bite = if (-8.0 * touch..=-touch).contains(&c0) {
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
            Error::InvalidOption(
                "cannot generate a motion: the bodies never touch when B moves along the \
                     occlusal direction"
                    .into(),
            )
        })?;
        Pose::from_translation(up * -x)
    };
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

/// `count` sinusoids between 2 and 12 Hz with random phases and an RMS of `sigma` together:
/// `(amplitude, frequency, phase)`.
fn sinusoids(rng: &mut Rng, sigma: f64) -> Vec<(f64, f64, f64)> {
    let mut s: Vec<(f64, f64, f64)> = (0..12)
        .map(|_| {
            (
                rng.range(0.3, 1.0),
                rng.range(2.0, 12.0),
                rng.range(0.0, TAU),
            )
        })
        .collect();
    let power: f64 = s.iter().map(|c| c.0 * c.0 / 2.0).sum();
    let f = sigma / power.sqrt();
    for c in &mut s {
        c.0 *= f;
    }
    s
}

/// The jaw's kinematics around the bite.
struct Kin {
    bite: Pose,
    hinge: DVec3,
    left: DVec3,
    up: DVec3,
    anterior: DVec3,
    /// Distance from the hinge to the incisal point.
    r_inc: f64,
    /// How far any point of the pair moves per unit of incisal opening (at most).
    lip: f64,
}

/// Turn about the vertical per lateral shift, as a fraction of the shift seen at the incisal
/// point.
const BENNETT: f64 = 0.3;

impl Kin {
    /// The pose for an incisal opening `o`, a lateral shift `lat` (to the left) and a
    /// protrusion `pro`.
    fn pose(&self, o: f64, lat: f64, pro: f64) -> Pose {
        let theta = o / self.r_inc;
        let psi = BENNETT * lat / self.r_inc;
        let r = (DQuat::from_axis_angle(self.left, theta) * DQuat::from_axis_angle(self.up, psi))
            .normalize();
        let m = Pose {
            rotation: r,
            translation: self.hinge - r * self.hinge + self.left * lat + self.anterior * pro,
        };
        m.then(&self.bite)
    }
}

/// How deep a keyframe is.
#[derive(Debug, Clone, Copy)]
enum Depth {
    /// Open this far beyond first contact at the keyframe's lateral position.
    Open(f64),
    /// In contact with this target clearance.
    Contact(f64),
}

#[derive(Debug, Clone, Copy)]
struct Key {
    t: f64,
    lat: f64,
    pro: f64,
    depth: Depth,
}

/// Minimum-jerk profile from 0 to 1 (zero velocity and acceleration at both ends).
fn min_jerk(s: f64) -> f64 {
    let s = s.clamp(0.0, 1.0);
    s * s * s * (10.0 + s * (-15.0 + 6.0 * s))
}

/// The keyframe segment containing `t` and the position in it.
fn segment(keys: &[Key], t: f64) -> (usize, f64) {
    let j = keys.partition_point(|k| k.t <= t).saturating_sub(1);
    if j + 1 >= keys.len() {
        return (keys.len().saturating_sub(2), 1.0);
    }
    let (t0, t1) = (keys[j].t, keys[j + 1].t);
    (j, ((t - t0) / (t1 - t0)).clamp(0.0, 1.0))
}

/// Lateral shift and protrusion at time `t`.
fn lateral(keys: &[Key], t: f64) -> (f64, f64) {
    let (j, s) = segment(keys, t);
    let (a, b) = (keys[j], keys[j + 1]);
    let m = min_jerk(s);
    (a.lat + (b.lat - a.lat) * m, a.pro + (b.pro - a.pro) * m)
}

struct Planner<'a> {
    est: &'a mut ClearanceEstimator,
    kin: &'a Kin,
    k: f64,
    touch: f64,
    /// Last solved opening (the next solve starts there).
    guess: f64,
}

impl Planner<'_> {
    /// The opening with clearance `target` at the lateral position, if any.
    fn contact(&mut self, lat: f64, pro: f64, target: f64) -> Option<f64> {
        let cap = 10.0 * self.touch + target.max(0.0);
        let (est, kin) = (&mut *self.est, self.kin);
        let mut f = |o: f64| est.clearance_capped(&kin.pose(o, lat, pro), cap) - target;
        let f0 = f(self.guess);
        let o = solve(
            &mut f,
            self.guess,
            f0,
            kin.lip,
            0.002 * self.k,
            -8.0 * self.k,
            40.0 * self.k,
            0.02 * self.touch,
        )?;
        self.guess = o;
        Some(o)
    }

    /// Opening of a keyframe; falls back to the last solution when there is no contact.
    fn key_opening(&mut self, key: &Key) -> f64 {
        match key.depth {
            Depth::Open(d) => self.contact(key.lat, key.pro, 0.0).unwrap_or(self.guess) + d,
            Depth::Contact(c) => self.contact(key.lat, key.pro, c).unwrap_or(self.guess),
        }
    }

    /// The opening of every frame.
    fn opening(&mut self, keys: &[Key], n: usize, rate: f64) -> Result<Vec<f64>> {
        if keys.len() < 2 {
            return Err(Error::InvalidOption("motion plan without keyframes".into()));
        }
        let ko: Vec<f64> = keys.iter().map(|k| self.key_opening(k)).collect();
        // Dense solves along slides in contact: (time, opening) knots per segment.
        let mut knots: Vec<Vec<(f64, f64)>> = vec![Vec::new(); keys.len() - 1];
        let last_t = n as f64 / rate;
        for j in 0..keys.len() - 1 {
            let (a, b) = (keys[j], keys[j + 1]);
            if a.t > last_t {
                break;
            }
            let (Depth::Contact(ca), Depth::Contact(cb)) = (a.depth, b.depth) else {
                continue;
            };
            let moves = (b.lat - a.lat).abs() + (b.pro - a.pro).abs();
            if moves <= 0.02 * self.k {
                continue;
            }
            let steps = ((b.t - a.t) / 0.02).ceil().max(1.0) as usize;
            self.guess = ko[j];
            let mut pts = vec![(a.t, ko[j])];
            for m in 1..steps {
                let t = a.t + (b.t - a.t) * m as f64 / steps as f64;
                let (lat, pro) = lateral(keys, t);
                let s = min_jerk((t - a.t) / (b.t - a.t));
                let c = ca + (cb - ca) * s;
                let o = self.contact(lat, pro, c).unwrap_or(self.guess);
                pts.push((t, o));
            }
            pts.push((b.t, ko[j + 1]));
            knots[j] = pts;
        }
        let mut o: Vec<f64> = (0..n)
            .map(|i| {
                let t = i as f64 / rate;
                let (j, s) = segment(keys, t);
                let pts = &knots[j];
                if pts.len() >= 2 {
                    let m = pts.partition_point(|p| p.0 <= t).clamp(1, pts.len() - 1);
                    let (p, q) = (pts[m - 1], pts[m]);
                    let u = ((t - p.0) / (q.0 - p.0)).clamp(0.0, 1.0);
                    p.1 + (q.1 - p.1) * u
                } else {
                    ko[j] + (ko[j + 1] - ko[j]) * min_jerk(s)
                }
            })
            .collect();
        gaussian_smooth(&mut o, 0.008 * rate);
        Ok(o)
    }
}

/// The first root of the function `f` from `x0` (where `f(x0) = f0`) in the direction
/// where `|f|` falls: `f` must change by at most `lip` per unit of `x` (a Lipschitz bound),
/// so steps of `|f| / lip` (at least `h0`) cannot pass the root. Once a step crosses,
/// Illinois regula falsi finishes until `|f| <= ftol`. `None` when `[xmin, xmax]` holds no
/// root that way.
#[allow(clippy::too_many_arguments)]
fn solve(
    f: &mut impl FnMut(f64) -> f64,
    x0: f64,
    f0: f64,
    lip: f64,
    h0: f64,
    xmin: f64,
    xmax: f64,
    ftol: f64,
) -> Option<f64> {
    if !f0.is_finite() {
        return None;
    }
    if f0.abs() <= ftol {
        return Some(x0);
    }
    // f rises with x near the roots we look for (the clearance grows as the jaw opens).
    let dir = if f0 > 0.0 { -1.0 } else { 1.0 };
    let (mut x, mut fx) = (x0, f0);
    let mut crossed = None;
    for _ in 0..1000 {
        let step = (fx.abs() / lip).max(h0);
        let xn = (x + dir * step).clamp(xmin, xmax);
        let fxn = f(xn);
        if fxn.abs() <= ftol {
            return Some(xn);
        }
        if (fxn > 0.0) != (fx > 0.0) {
            crossed = Some((xn, fxn));
            break;
        }
        if xn == xmin || xn == xmax || !fxn.is_finite() {
            return None;
        }
        (x, fx) = (xn, fxn);
    }
    let (xn, fxn) = crossed?;
    let ((mut lo, mut flo), (mut hi, mut fhi)) = if fx > 0.0 {
        ((xn, fxn), (x, fx))
    } else {
        ((x, fx), (xn, fxn))
    };
    if lo > hi {
        std::mem::swap(&mut lo, &mut hi);
        std::mem::swap(&mut flo, &mut fhi);
    }
    // Regula falsi on [lo, hi] with f(lo) and f(hi) of opposite signs.
    let mut side = 0i8;
    let xtol = 1e-12 * (1.0 + lo.abs().max(hi.abs()));
    for _ in 0..100 {
        let width = hi - lo;
        if width <= xtol {
            break;
        }
        let mut m = (lo * fhi - hi * flo) / (fhi - flo);
        if !(m > lo + 1e-3 * width && m < hi - 1e-3 * width) {
            m = 0.5 * (lo + hi);
        }
        let fm = f(m);
        if fm.abs() <= ftol {
            return Some(m);
        }
        if (fm > 0.0) == (fhi > 0.0) {
            (hi, fhi) = (m, fm);
            if side == 1 {
                flo *= 0.5;
            }
            side = 1;
        } else {
            (lo, flo) = (m, fm);
            if side == -1 {
                fhi *= 0.5;
            }
            side = -1;
        }
    }
    Some(if flo.abs() < fhi.abs() { lo } else { hi })
}

/// Gaussian smoothing in place with standard deviation `sigma` samples (weights renormalized
/// at the ends, so constants stay constant).
fn gaussian_smooth(v: &mut [f64], sigma: f64) {
    if sigma.is_nan() || sigma < 0.5 || v.len() < 3 {
        return;
    }
    let r = (4.0 * sigma).ceil() as isize;
    let w: Vec<f64> = (-r..=r)
        .map(|i| (-(i * i) as f64 / (2.0 * sigma * sigma)).exp())
        .collect();
    let src = v.to_vec();
    let n = src.len() as isize;
    for (i, out) in v.iter_mut().enumerate() {
        let (mut acc, mut ws) = (0.0, 0.0);
        for (d, wk) in (-r..=r).zip(&w) {
            let j = i as isize + d;
            if (0..n).contains(&j) {
                acc += wk * src[j as usize];
                ws += wk;
            }
        }
        *out = acc / ws;
    }
}

/// Light-contact target clearance.
fn light(rng: &mut Rng, touch: f64) -> f64 {
    -rng.range(0.25, 0.6) * touch
}

struct Plan {
    keys: Vec<Key>,
    t: f64,
}

impl Plan {
    fn at(&mut self, dt: f64, lat: f64, pro: f64, depth: Depth) {
        self.t += dt;
        self.keys.push(Key {
            t: self.t,
            lat,
            pro,
            depth,
        });
    }

    /// Repeats the last keyframe after `dt`.
    fn hold(&mut self, dt: f64) {
        if let Some(&k) = self.keys.last() {
            self.at(dt, k.lat, k.pro, k.depth);
        }
    }

    fn last(&self) -> Key {
        self.keys[self.keys.len() - 1]
    }
}

fn plan_chew(rng: &mut Rng, seconds: f64, k: f64, touch: f64, c_bite: f64) -> Vec<Key> {
    let mut p = Plan {
        keys: Vec::new(),
        t: 0.0,
    };
    let mut side = rng.sign();
    p.at(
        0.0,
        -0.5 * side * k,
        0.0,
        Depth::Open(rng.range(8.5, 11.5) * k),
    );
    p.hold(rng.range(0.06, 0.14));
    while p.t < seconds + 0.5 {
        // Close from the working side, touch, slide into the bite.
        let (lat_c, pro_c) = (side * rng.range(0.3, 0.8) * k, rng.range(0.0, 0.3) * k);
        p.at(
            rng.range(0.30, 0.40),
            lat_c,
            pro_c,
            Depth::Open(rng.range(0.8, 1.2) * k),
        );
        p.at(
            rng.range(0.10, 0.14),
            lat_c,
            pro_c,
            Depth::Contact(light(rng, touch)),
        );
        p.at(rng.range(0.08, 0.12), 0.0, 0.0, Depth::Contact(c_bite));
        // Clench slightly beyond the bite.
        let clench = c_bite - rng.range(1.0, 2.5) * touch;
        p.at(rng.range(0.06, 0.09), 0.0, 0.0, Depth::Contact(clench));
        p.hold(rng.range(0.10, 0.16));
        p.at(
            rng.range(0.08, 0.12),
            0.0,
            0.0,
            Depth::Contact(light(rng, touch)),
        );
        // Grind out to the working side and back in light contact.
        let (lat_g, pro_g) = (side * rng.range(2.5, 4.5) * k, rng.range(0.3, 1.2) * k);
        p.at(
            rng.range(0.25, 0.35),
            lat_g,
            pro_g,
            Depth::Contact(light(rng, touch)),
        );
        let (lat_h, pro_h) = (side * rng.range(0.0, 0.4) * k, rng.range(0.0, 0.3) * k);
        p.at(
            rng.range(0.25, 0.35),
            lat_h,
            pro_h,
            Depth::Contact(light(rng, touch)),
        );
        // Lift, then open wide, drifting to the next cycle's balancing side.
        p.at(
            rng.range(0.10, 0.14),
            lat_h,
            pro_h,
            Depth::Open(rng.range(0.6, 1.0) * k),
        );
        side = -side;
        let open = Depth::Open(rng.range(8.5, 11.5) * k);
        p.at(
            rng.range(0.25, 0.35),
            -0.5 * side * k,
            rng.range(-0.3, 0.3) * k,
            open,
        );
        p.hold(rng.range(0.05, 0.12));
    }
    p.keys
}

fn plan_open_close(rng: &mut Rng, seconds: f64, k: f64, touch: f64, c_bite: f64) -> Vec<Key> {
    let mut p = Plan {
        keys: Vec::new(),
        t: 0.0,
    };
    let open = Depth::Open(rng.range(7.0, 12.0) * k);
    p.at(0.0, rng.range(-0.3, 0.3) * k, 0.0, open);
    p.hold(rng.range(0.04, 0.12));
    while p.t < seconds + 0.5 {
        let lat = rng.range(-0.3, 0.3) * k;
        p.at(
            rng.range(0.30, 0.40),
            lat,
            0.0,
            Depth::Open(rng.range(0.5, 0.9) * k),
        );
        p.at(
            rng.range(0.10, 0.15),
            lat,
            0.0,
            Depth::Contact(light(rng, touch)),
        );
        p.at(rng.range(0.08, 0.12), 0.0, 0.0, Depth::Contact(c_bite));
        p.hold(rng.range(0.10, 0.20));
        p.at(
            rng.range(0.10, 0.14),
            0.0,
            0.0,
            Depth::Open(rng.range(0.5, 0.9) * k),
        );
        let open = Depth::Open(rng.range(7.0, 12.0) * k);
        p.at(rng.range(0.25, 0.35), rng.range(-0.3, 0.3) * k, 0.0, open);
        p.hold(rng.range(0.04, 0.12));
    }
    p.keys
}

fn plan_grind(rng: &mut Rng, seconds: f64, k: f64, touch: f64, c_bite: f64) -> Vec<Key> {
    let mut p = Plan {
        keys: Vec::new(),
        t: 0.0,
    };
    p.at(0.0, 0.0, 0.0, Depth::Open(rng.range(1.5, 2.5) * k));
    p.hold(rng.range(0.08, 0.15));
    p.at(
        rng.range(0.25, 0.35),
        0.0,
        0.0,
        Depth::Contact(light(rng, touch)),
    );
    let side = rng.sign();
    let mut step = 0usize;
    while p.t < seconds + 0.5 {
        let c = Depth::Contact(light(rng, touch));
        match step % 8 {
            1 | 3 => {
                let s = if step % 8 == 3 { -side } else { side };
                let (lat, pro) = (s * rng.range(1.5, 3.5) * k, rng.range(0.0, 1.0) * k);
                p.at(rng.range(0.30, 0.45), lat, pro, c);
            }
            2 | 4 | 6 => {
                let (lat, pro) = (rng.range(-0.2, 0.2) * k, rng.range(0.0, 0.2) * k);
                p.at(rng.range(0.25, 0.40), lat, pro, c);
            }
            0 => {
                let press = Depth::Contact(c_bite - rng.range(0.5, 1.5) * touch);
                p.at(rng.range(0.12, 0.18), 0.0, 0.0, press);
                p.hold(rng.range(0.06, 0.10));
                p.at(rng.range(0.10, 0.14), 0.0, 0.0, c);
            }
            5 => {
                let (lat, pro) = (rng.range(-0.5, 0.5) * k, rng.range(2.0, 3.5) * k);
                p.at(rng.range(0.30, 0.45), lat, pro, c);
            }
            _ => {
                let Key { lat, pro, .. } = p.last();
                p.at(
                    rng.range(0.10, 0.14),
                    lat,
                    pro,
                    Depth::Open(rng.range(0.6, 1.2) * k),
                );
                p.hold(rng.range(0.08, 0.15));
                p.at(rng.range(0.12, 0.16), lat, pro, c);
            }
        }
        step += 1;
    }
    p.keys
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solver_finds_roots_and_reports_none() {
        let mut f = |x: f64| x * x * x - 2.0;
        let r = solve(&mut f, 0.0, -2.0, 30.0, 0.01, -100.0, 100.0, 1e-9).unwrap();
        assert!((r - 2f64.cbrt()).abs() < 1e-6, "{r}");
        // Capped far away, like a clearance.
        let mut g = |x: f64| (x - 3.0).min(0.5);
        let r = solve(&mut g, 10.0, 0.5, 1.0, 0.01, -100.0, 100.0, 1e-9).unwrap();
        assert!((r - 3.0).abs() < 1e-6, "{r}");
        // The first root from the start, not a later one.
        let mut w = |x: f64| (x - 1.0).abs() - 0.5;
        let r = solve(&mut w, 4.0, 2.5, 1.0, 0.01, -100.0, 100.0, 1e-9).unwrap();
        assert!((r - 1.5).abs() < 1e-6, "{r}");
        let mut h = |_: f64| 1.0;
        assert!(solve(&mut h, 0.0, 1.0, 1.0, 0.01, -5.0, 5.0, 1e-9).is_none());
    }

    #[test]
    fn smoothing_keeps_constants_and_bounds() {
        let mut v = vec![2.0; 50];
        gaussian_smooth(&mut v, 3.0);
        assert!(v.iter().all(|x| (x - 2.0).abs() < 1e-12));
        let mut s: Vec<f64> = (0..100).map(|i| if i < 50 { 0.0 } else { 1.0 }).collect();
        gaussian_smooth(&mut s, 4.0);
        assert!(s.iter().all(|x| (0.0..=1.0).contains(x)));
        assert!(s.windows(2).all(|w| w[1] >= w[0]));
    }

    #[test]
    fn min_jerk_is_smooth_at_the_ends() {
        assert_eq!(min_jerk(0.0), 0.0);
        assert_eq!(min_jerk(1.0), 1.0);
        let e = 1e-4;
        assert!(min_jerk(e) < 1e-10 && 1.0 - min_jerk(1.0 - e) < 1e-10);
    }
}
