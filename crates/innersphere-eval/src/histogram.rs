//! Quantiles of a long stream of positive durations in constant memory: a histogram with
//! logarithmic buckets 0.5 % wide, so that a haptic session of any length keeps a few
//! kilobytes, not every tick.

/// Bucket width: each bucket's upper edge is this times its lower one.
const RATIO: f64 = 1.005;
/// The smallest value told apart (below it: the first bucket).
const LOWEST: f64 = 1e-3;
/// Buckets: from `LOWEST` to `LOWEST × RATIO^BUCKETS` ≈ 1e7 (values above: the last bucket).
const BUCKETS: usize = 4620;

/// A histogram of non-negative values (any unit; the buckets cover 1e-3 to 1e7 of it).
#[derive(Debug, Clone)]
pub struct Histogram {
    counts: Vec<u64>,
    total: u64,
    max: f64,
}

impl Default for Histogram {
    fn default() -> Self {
        Histogram {
            counts: vec![0; BUCKETS],
            total: 0,
            max: 0.0,
        }
    }
}

impl Histogram {
    /// Counts `x` (a NaN counts as 0).
    pub fn add(&mut self, x: f64) {
        let x = if x.is_nan() { 0.0 } else { x.max(0.0) };
        let i = if x <= LOWEST {
            0
        } else {
            ((x / LOWEST).ln() / RATIO.ln())
                .floor()
                .min((BUCKETS - 1) as f64) as usize
        };
        self.counts[i] += 1;
        self.total += 1;
        self.max = self.max.max(x);
    }

    /// How many values were counted.
    pub fn count(&self) -> u64 {
        self.total
    }

    /// The largest value counted (exact).
    pub fn max(&self) -> f64 {
        self.max
    }

    /// The `q` quantile (0..=1), within half a bucket (0.25 %) of the value of the same rank
    /// in the sorted values, never above the maximum; 0 when empty.
    pub fn quantile(&self, q: f64) -> f64 {
        if self.total == 0 {
            return 0.0;
        }
        let rank = ((self.total - 1) as f64 * q.clamp(0.0, 1.0)).round() as u64;
        let mut seen = 0;
        for (i, &c) in self.counts.iter().enumerate() {
            seen += c;
            if seen > rank {
                let mid = LOWEST * RATIO.powf(i as f64 + 0.5);
                return if i == 0 {
                    0.0f64.max(mid.min(LOWEST))
                } else {
                    mid
                }
                .min(self.max);
            }
        }
        self.max
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantiles_are_within_a_quarter_percent_of_the_sorted_values() {
        let mut h = Histogram::default();
        let mut v: Vec<f64> = (1..=10_000).map(|i| (i as f64).powf(1.7) * 0.01).collect();
        for x in &v {
            h.add(*x);
        }
        v.sort_by(f64::total_cmp);
        for q in [0.0, 0.1, 0.5, 0.9, 0.99, 0.999, 1.0] {
            let want = v[((v.len() - 1) as f64 * q).round() as usize];
            let got = h.quantile(q);
            assert!((got / want - 1.0).abs() <= 0.0026, "q {q}: {got} vs {want}");
        }
        assert_eq!(h.max(), *v.last().unwrap());
        assert_eq!(h.count(), 10_000);
        assert_eq!(Histogram::default().quantile(0.5), 0.0);
    }
}
