//! Batch neural gas (BNG) clustering of sphere centres, weighted by sphere volume
//! (magnification control), as in the paper's equations (1)–(2).
//!
//! Each iteration ranks, for every point, all prototypes by distance (`k_ij`, recomputed every
//! iteration — the paper's original code never updated them), then moves every prototype to
//! the weighted mean `Σ h_λ(k_ij) V_j x_j / Σ h_λ(k_ij) V_j` with `h_λ(k) = exp(−k/λ)` and
//! λ decaying geometrically from `n/2` to `0.01`. Sums are taken over fixed chunks in a fixed
//! order, so the result does not depend on thread scheduling.

use glam::DVec3;
use rayon::prelude::*;

/// Options of one BNG clustering.
#[derive(Debug, Clone, Copy)]
pub struct BngOptions {
    /// Maximum number of iterations.
    pub max_iterations: u32,
    /// Stop when no prototype moves more than this fraction of the point set's extent
    /// (checked only once λ has decayed, after half the iterations).
    pub min_movement: f64,
}

impl Default for BngOptions {
    fn default() -> Self {
        BngOptions {
            max_iterations: 32,
            min_movement: 1e-4,
        }
    }
}

/// Chunk size for deterministic parallel sums; small clusters run on one thread.
const CHUNK: usize = 4096;
/// Most prototypes supported (the fan-out limit of the tree).
pub(crate) const MAX_PROTOTYPES: usize = 32;

/// Clusters `points` (with `weights`) into at most `n` groups; returns for every point the
/// index of its nearest final prototype. Deterministic.
pub(crate) fn cluster(points: &[DVec3], weights: &[f64], n: usize, opts: &BngOptions) -> Vec<u8> {
    let n = n.clamp(1, MAX_PROTOTYPES).min(points.len().max(1));
    let mut protos = initial_prototypes(points, n);
    let (lo, hi) = points.iter().fold(
        (DVec3::splat(f64::MAX), DVec3::splat(f64::MIN)),
        |(l, h), p| (l.min(*p), h.max(*p)),
    );
    let extent = (hi - lo).max_element().max(1e-300);
    let lambda0 = n as f64 / 2.0;
    let lambda_end = 0.01f64;
    let iters = opts.max_iterations.max(1);
    for t in 0..iters {
        let lambda = lambda0 * (lambda_end / lambda0).powf(t as f64 / (iters - 1).max(1) as f64);
        let mut h = [0.0f64; MAX_PROTOTYPES];
        for (k, hk) in h.iter_mut().enumerate().take(n) {
            *hk = (-(k as f64) / lambda).exp();
        }
        // The common fan-outs get loops of a constant length (unrolled): the same sums.
        let accumulate = |range: std::ops::Range<usize>| match n {
            2 => accumulate(points, weights, &protos, &h, range, 2),
            4 => accumulate(points, weights, &protos, &h, range, 4),
            8 => accumulate(points, weights, &protos, &h, range, 8),
            _ => accumulate(points, weights, &protos, &h, range, n),
        };
        let parts: Vec<([DVec3; MAX_PROTOTYPES], [f64; MAX_PROTOTYPES])> = if points.len() > CHUNK {
            (0..points.len().div_ceil(CHUNK))
                .into_par_iter()
                .map(|c| accumulate(c * CHUNK..((c + 1) * CHUNK).min(points.len())))
                .collect()
        } else {
            vec![accumulate(0..points.len())]
        };
        let mut moved = 0.0f64;
        for i in 0..n {
            let mut num = DVec3::ZERO;
            let mut den = 0.0;
            for (pn, pd) in &parts {
                num += pn[i];
                den += pd[i];
            }
            if den > 0.0 {
                let next = num / den;
                moved = moved.max(next.distance(protos[i]));
                protos[i] = next;
            }
        }
        if t >= iters / 2 && moved <= opts.min_movement * extent {
            break;
        }
    }
    points
        .iter()
        .map(|x| {
            let mut best = 0;
            let mut best_d = f64::INFINITY;
            for (i, p) in protos.iter().enumerate() {
                let d = x.distance_squared(*p);
                if d < best_d {
                    best_d = d;
                    best = i;
                }
            }
            best as u8
        })
        .collect()
}

/// One iteration's weighted sums over the points `range`: for each of the `n` prototypes,
/// `Σ h[rank] · w_j · x_j` and `Σ h[rank] · w_j`, the rank being how many prototypes are
/// strictly closer to `x_j` (ties by index).
#[inline(always)]
fn accumulate(
    points: &[DVec3],
    weights: &[f64],
    protos: &[DVec3],
    h: &[f64; MAX_PROTOTYPES],
    range: std::ops::Range<usize>,
    n: usize,
) -> ([DVec3; MAX_PROTOTYPES], [f64; MAX_PROTOTYPES]) {
    let mut num = [DVec3::ZERO; MAX_PROTOTYPES];
    let mut den = [0.0f64; MAX_PROTOTYPES];
    let mut d = [0.0f64; MAX_PROTOTYPES];
    for j in range {
        let x = points[j];
        for i in 0..n {
            d[i] = x.distance_squared(protos[i]);
        }
        for i in 0..n {
            let mut rank = 0;
            for k in 0..n {
                if d[k] < d[i] || (d[k] == d[i] && k < i) {
                    rank += 1;
                }
            }
            let w = h[rank] * weights[j];
            num[i] += x * w;
            den[i] += w;
        }
    }
    (num, den)
}

/// Deterministic farthest-point initialisation: the point farthest from the centroid, then
/// repeatedly the point farthest from all chosen so far.
fn initial_prototypes(points: &[DVec3], n: usize) -> Vec<DVec3> {
    let centroid = points.iter().copied().sum::<DVec3>() / points.len().max(1) as f64;
    let mut first = 0;
    let mut first_d = -1.0;
    for (j, p) in points.iter().enumerate() {
        let d = p.distance_squared(centroid);
        if d > first_d {
            first_d = d;
            first = j;
        }
    }
    let mut protos = vec![points[first]];
    let mut min_d: Vec<f64> = points
        .iter()
        .map(|p| p.distance_squared(protos[0]))
        .collect();
    while protos.len() < n {
        let mut best = 0;
        let mut best_d = -1.0;
        for (j, &d) in min_d.iter().enumerate() {
            if d > best_d {
                best_d = d;
                best = j;
            }
        }
        let p = points[best];
        protos.push(p);
        for (j, q) in points.iter().enumerate() {
            min_d[j] = min_d[j].min(q.distance_squared(p));
        }
    }
    protos
}
