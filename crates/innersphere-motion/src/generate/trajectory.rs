//! Trajectory shaping: minimum-jerk (quintic) segments between keyframes, Gaussian
//! smoothing, and the sums of sinusoids of the hand tremor.

use super::scenario::Key;
use crate::rng::Rng;
use std::f64::consts::TAU;

/// `count` sinusoids between 2 and 12 Hz with random phases and an RMS of `sigma` together:
/// `(amplitude, frequency, phase)`.
pub(super) fn sinusoids(rng: &mut Rng, sigma: f64) -> Vec<(f64, f64, f64)> {
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

/// Minimum-jerk profile from 0 to 1 (zero velocity and acceleration at both ends).
pub(super) fn min_jerk(s: f64) -> f64 {
    let s = s.clamp(0.0, 1.0);
    s * s * s * (10.0 + s * (-15.0 + 6.0 * s))
}

/// The keyframe segment containing `t` and the position in it.
pub(super) fn segment(keys: &[Key], t: f64) -> (usize, f64) {
    let j = keys.partition_point(|k| k.t <= t).saturating_sub(1);
    if j + 1 >= keys.len() {
        return (keys.len().saturating_sub(2), 1.0);
    }
    let (t0, t1) = (keys[j].t, keys[j + 1].t);
    (j, ((t - t0) / (t1 - t0)).clamp(0.0, 1.0))
}

/// Lateral shift and protrusion at time `t`.
pub(super) fn lateral(keys: &[Key], t: f64) -> (f64, f64) {
    let (j, s) = segment(keys, t);
    let (a, b) = (keys[j], keys[j + 1]);
    let m = min_jerk(s);
    (a.lat + (b.lat - a.lat) * m, a.pro + (b.pro - a.pro) * m)
}

/// Gaussian smoothing in place with standard deviation `sigma` samples (weights renormalized
/// at the ends, so constants stay constant).
pub(super) fn gaussian_smooth(v: &mut [f64], sigma: f64) {
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

#[cfg(test)]
mod tests {
    use super::*;

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
