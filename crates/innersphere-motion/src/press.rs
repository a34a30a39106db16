//! A device trajectory for haptic tests: close from open into the bite and beyond it, hold,
//! slide sideways both ways while pressing, hold, release. Smooth (no tremor), so that what a
//! haptic loop does with it is the loop's doing.

use super::csv::{Frame, Motion};
use super::frame::AnatomicalFrame;
use innersphere::{Error, Pose, Result};
use std::f64::consts::PI;

/// The shape of a [`press`] trajectory (model units, seconds).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PressOptions {
    /// How far open it starts and ends, along −up from the bite.
    pub open: f64,
    /// How far past the bite (along up) the device presses.
    pub past: f64,
    /// Sideways excursion (along left) while pressing, each way.
    pub slide: f64,
    /// Frames per second.
    pub rate: f64,
}

impl Default for PressOptions {
    /// 3 mm open, 1 mm past the bite, ±0.8 mm sideways, 1 kHz.
    fn default() -> Self {
        PressOptions {
            open: 3.0,
            past: 1.0,
            slide: 0.8,
            rate: 1000.0,
        }
    }
}

/// Phase boundaries (s): close 0–1.5, hold –2.5, slide –4.5 (left, right, back), hold –5,
/// release –6.
const CLOSE: f64 = 1.5;
const HOLD: f64 = 2.5;
const SLIDE: f64 = 4.5;
const HOLD2: f64 = 5.0;
const END: f64 = 6.0;

/// Smooth step 0 → 1 over `[0, 1]` (zero velocity at both ends).
fn ease(s: f64) -> f64 {
    let s = s.clamp(0.0, 1.0);
    0.5 - 0.5 * (PI * s).cos()
}

/// The 6 s press trajectory of B (the device's pose in A's frame, the bite at the identity).
pub fn press(frame: &AnatomicalFrame, opts: &PressOptions) -> Result<Motion> {
    let ok = |x: f64| x.is_finite() && x >= 0.0;
    let rate_ok = opts.rate.is_finite() && (1.0..=100_000.0).contains(&opts.rate);
    if !(ok(opts.open) && ok(opts.past) && ok(opts.slide) && rate_ok) {
        return Err(Error::InvalidOption(format!(
            "press trajectory: open, past and slide must be finite and not negative, the rate \
             1 to 100000 Hz ({opts:?})"
        )));
    }
    let n = (END * opts.rate).round() as usize;
    let mut frames = Vec::with_capacity(n + 1);
    for i in 0..=n {
        let t = i as f64 / opts.rate;
        let depth = if t < CLOSE {
            -opts.open + (opts.open + opts.past) * ease(t / CLOSE)
        } else if t < HOLD2 {
            opts.past
        } else {
            opts.past - (opts.open + opts.past) * ease((t - HOLD2) / (END - HOLD2))
        };
        let side = if (HOLD..SLIDE).contains(&t) {
            opts.slide * (2.0 * PI * (t - HOLD) / (SLIDE - HOLD)).sin()
        } else {
            0.0
        };
        let pose = Pose::from_translation(frame.up * depth + frame.left * side);
        frames.push(Frame { t, pose });
    }
    Ok(Motion { frames })
}
