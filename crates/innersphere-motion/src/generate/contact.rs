//! The contact search: the opening at which B meets A with a target clearance at a lateral
//! position (a Lipschitz-stepped bracket and Illinois regula falsi on the clearance
//! estimate), for every keyframe and densely along slides in contact, and from those the
//! opening of every frame.

use super::kinematics::Kin;
use super::scenario::{Depth, Key};
use super::trajectory::{gaussian_smooth, lateral, min_jerk, segment};
use crate::clearance::ClearanceEstimator;
use innersphere::{Error, Result};

/// Solves keyframes for their opening along the closing rotation (see [`solve`]).
pub(super) struct Planner<'a> {
    pub(super) est: &'a mut ClearanceEstimator,
    pub(super) kin: &'a Kin,
    pub(super) k: f64,
    pub(super) touch: f64,
    /// Last solved opening (the next solve starts there).
    pub(super) guess: f64,
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
    pub(super) fn opening(&mut self, keys: &[Key], n: usize, rate: f64) -> Result<Vec<f64>> {
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
pub(super) fn solve(
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
}
