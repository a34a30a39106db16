//! Minimal enclosing sphere of a few spheres (the children of a tree node).
//!
//! The minimal ball enclosing a set of balls is fixed by at most four of them, all touching it
//! from inside. [`enclose`] finds it by pivoting: it keeps such a support set, adds the ball
//! that sticks out farthest, and re-solves the small problem over support ∪ {violator} by
//! enumerating its subsets; the radius grows strictly, so this ends. The final radius is
//! taken as the farthest reach over all balls, so the result always encloses them.
//! `enclose_brute_force` enumerates every subset of at most four balls: slow, exact, and
//! used to report how tight [`enclose`] is.

use glam::DVec3;

/// A ball `(centre, radius)` in f64.
pub(crate) type Ball = (DVec3, f64);

/// The balls tangent from inside to every ball of `support` (1 to 4 balls) whose centre lies
/// in the affine hull of the support centres: at most two candidates.
fn tangent_balls(support: &[Ball], out: &mut Vec<Ball>) {
    out.clear();
    match support.len() {
        1 => out.push(support[0]),
        2 => {
            let (c1, r1) = support[0];
            let (c2, r2) = support[1];
            let d = (c2 - c1).length();
            let radius = (d + r1 + r2) * 0.5;
            if d > 0.0 {
                out.push((c1 + (c2 - c1) * ((radius - r1) / d), radius));
            }
        }
        3 | 4 => {
            let (c1, r1) = support[0];
            let m = support.len() - 1;
            let mut d = [DVec3::ZERO; 3];
            for (k, b) in support[1..].iter().enumerate() {
                d[k] = b.0 - c1;
            }
            // Gram matrix M λ = b/2 + R e, with b_i = |d_i|² − (r_i² − r_1²), e_i = r_i − r_1.
            let mut gram = [[0.0f64; 3]; 3];
            let mut b = [0.0f64; 3];
            let mut e = [0.0f64; 3];
            for i in 0..m {
                for j in 0..m {
                    gram[i][j] = d[i].dot(d[j]);
                }
                let ri = support[i + 1].1;
                b[i] = 0.5 * (d[i].length_squared() - (ri * ri - r1 * r1));
                e[i] = ri - r1;
            }
            let Some(l0) = solve(&gram, &b, m) else {
                return;
            };
            let Some(l1) = solve(&gram, &e, m) else {
                return;
            };
            let mut v0 = DVec3::ZERO;
            let mut v1 = DVec3::ZERO;
            for i in 0..m {
                v0 += d[i] * l0[i];
                v1 += d[i] * l1[i];
            }
            // |v0 + R v1|² = (R − r1)²  →  a R² + 2 b' R + c = 0
            let qa = v1.length_squared() - 1.0;
            let qb = v0.dot(v1) + r1;
            let qc = v0.length_squared() - r1 * r1;
            let mut push = |radius: f64| {
                if radius.is_finite() && radius >= 0.0 {
                    out.push((c1 + v0 + v1 * radius, radius));
                }
            };
            if qa.abs() < 1e-12 {
                if qb.abs() > 0.0 {
                    push(-qc / (2.0 * qb));
                }
            } else {
                let disc = qb * qb - qa * qc;
                if disc >= 0.0 {
                    let s = disc.sqrt();
                    push((-qb + s) / qa);
                    push((-qb - s) / qa);
                }
            }
        }
        _ => {}
    }
}

/// Solves the m×m system (m ≤ 3) by Gaussian elimination with partial pivoting; `None` when
/// (nearly) singular.
fn solve(a: &[[f64; 3]; 3], b: &[f64; 3], m: usize) -> Option<[f64; 3]> {
    let mut a = *a;
    let mut b = *b;
    let scale = (0..m).map(|i| a[i][i].abs()).fold(0.0, f64::max);
    for col in 0..m {
        let piv = (col..m).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))?;
        if a[piv][col].abs() <= 1e-12 * scale.max(f64::MIN_POSITIVE) {
            return None;
        }
        a.swap(col, piv);
        b.swap(col, piv);
        for row in col + 1..m {
            let f = a[row][col] / a[col][col];
            let pivot_row = a[col];
            for (x, p) in a[row][col..m].iter_mut().zip(&pivot_row[col..m]) {
                *x -= f * p;
            }
            b[row] -= f * b[col];
        }
    }
    let mut x = [0.0; 3];
    for row in (0..m).rev() {
        let mut s = b[row];
        for k in row + 1..m {
            s -= a[row][k] * x[k];
        }
        x[row] = s / a[row][row];
    }
    Some(x)
}

/// How far ball `b` reaches beyond the centre `c`: |c_b − c| + r_b.
#[inline]
fn reach(c: DVec3, b: &Ball) -> f64 {
    (b.0 - c).length() + b.1
}

/// The smallest candidate over all subsets (size 1–4) of `set` that encloses all of `set`,
/// returned with its support (indices into `set`).
fn smallest_over_subsets(set: &[Ball], scratch: &mut Vec<Ball>) -> (Ball, Vec<usize>) {
    let n = set.len();
    let scale = set
        .iter()
        .map(|b| b.0.abs().max_element() + b.1)
        .fold(1e-300, f64::max);
    let tol = 1e-10 * scale;
    let mut best: Option<(Ball, u32)> = None;
    let mut subset = [(DVec3::ZERO, 0.0); 4];
    for mask in 1u32..(1 << n) {
        if mask.count_ones() > 4 {
            continue;
        }
        let mut len = 0;
        for (i, b) in set.iter().enumerate() {
            if mask & (1 << i) != 0 {
                subset[len] = *b;
                len += 1;
            }
        }
        tangent_balls(&subset[..len], scratch);
        for &cand in scratch.iter() {
            if best.as_ref().is_some_and(|(b, _)| cand.1 >= b.1) {
                continue;
            }
            if set.iter().all(|b| reach(cand.0, b) <= cand.1 + tol) {
                best = Some((cand, mask));
            }
        }
    }
    best.map(|(b, mask)| (b, (0..n).filter(|i| mask & (1 << i) != 0).collect()))
        .unwrap_or_else(|| {
            // Cannot happen for a non-empty set (the largest ball's own candidate set includes a
            // valid 2-ball solution); fall back to centroid + farthest reach.
            let c = set.iter().map(|b| b.0).sum::<DVec3>() / n.max(1) as f64;
            let r = set.iter().map(|b| reach(c, b)).fold(0.0, f64::max);
            ((c, r), (0..n).collect())
        })
}

/// Minimal enclosing ball of `balls` (non-empty). The result encloses every ball exactly in
/// f64 (its radius is the farthest reach from its centre).
pub(crate) fn enclose(balls: &[Ball]) -> Ball {
    assert!(!balls.is_empty(), "enclose needs at least one ball");
    let mut scratch = Vec::with_capacity(2);
    // Start from the largest ball.
    let first = (0..balls.len())
        .max_by(|&a, &b| balls[a].1.total_cmp(&balls[b].1).then(b.cmp(&a)))
        .unwrap_or(0);
    let mut support: Vec<Ball> = vec![balls[first]];
    let mut ball = balls[first];
    let scale = balls
        .iter()
        .map(|b| b.0.abs().max_element() + b.1)
        .fold(1e-300, f64::max);
    let tol = 1e-12 * scale;
    for _ in 0..64 {
        // The ball that sticks out farthest.
        let (worst, excess) = balls
            .iter()
            .enumerate()
            .map(|(i, b)| (i, reach(ball.0, b) - ball.1))
            .fold(
                (usize::MAX, tol),
                |acc, x| if x.1 > acc.1 { x } else { acc },
            );
        if worst == usize::MAX {
            break;
        }
        let _ = excess;
        let mut set = support.clone();
        set.push(balls[worst]);
        let (next, idx) = smallest_over_subsets(&set, &mut scratch);
        if next.1 <= ball.1 {
            break; // numerical stall: finish with the exact reach below
        }
        ball = next;
        support = idx.iter().map(|&i| set[i]).collect();
    }
    let radius = balls.iter().map(|b| reach(ball.0, b)).fold(0.0, f64::max);
    (ball.0, radius)
}

/// Exact minimal enclosing ball by enumerating every subset of at most four balls
/// (O(n⁵)): the reference against which [`enclose`] is measured. Use for n ≤ 12.
pub(crate) fn enclose_brute_force(balls: &[Ball]) -> Ball {
    let mut scratch = Vec::new();
    smallest_over_subsets(balls, &mut scratch).0
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn ball() -> impl Strategy<Value = Ball> {
        (-10.0..10.0f64, -10.0..10.0f64, -10.0..10.0f64, 0.0..3.0f64)
            .prop_map(|(x, y, z, r)| (DVec3::new(x, y, z), r))
    }

    proptest! {
        #[test]
        fn encloses_all_and_matches_brute_force(balls in prop::collection::vec(ball(), 1..9)) {
            let (c, r) = enclose(&balls);
            for b in &balls {
                prop_assert!(reach(c, b) <= r * (1.0 + 1e-12) + 1e-12);
            }
            let (_, rb) = enclose_brute_force(&balls);
            prop_assert!(r <= rb * (1.0 + 1e-9) + 1e-9, "pivot {} vs brute force {}", r, rb);
            // Never smaller than the largest ball nor than half the widest pair.
            let biggest = balls.iter().map(|b| b.1).fold(0.0, f64::max);
            prop_assert!(r + 1e-9 >= biggest);
        }
    }

    #[test]
    fn two_and_nested_balls() {
        let (c, r) = enclose(&[(DVec3::ZERO, 1.0), (DVec3::new(4.0, 0.0, 0.0), 1.0)]);
        assert!((r - 3.0).abs() < 1e-12 && (c - DVec3::new(2.0, 0.0, 0.0)).length() < 1e-12);
        let (c, r) = enclose(&[(DVec3::ZERO, 5.0), (DVec3::new(1.0, 0.0, 0.0), 1.0)]);
        assert!((r - 5.0).abs() < 1e-12 && c.length() < 1e-12);
    }
}
