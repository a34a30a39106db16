//! 6×6 symmetric positive-definite solves for the implicit step (Cholesky, on the stack).
//!
//! Hand-written rather than a linear-algebra crate: one fixed-size solve per tick, no
//! allocation, and glam has no 6×6 type.

/// A 6×6 matrix, row-major.
pub type Mat6 = [[f64; 6]; 6];

/// Solves `A x = b` for symmetric positive-definite `A` by Cholesky; `None` when `A` is not
/// positive definite (to rounding).
// Index form, as the textbook writes Cholesky.
#[allow(clippy::needless_range_loop)]
pub fn solve_spd(a: &Mat6, b: [f64; 6]) -> Option<[f64; 6]> {
    let mut l = [[0.0f64; 6]; 6];
    for i in 0..6 {
        for j in 0..=i {
            let mut s = a[i][j];
            for k in 0..j {
                s -= l[i][k] * l[j][k];
            }
            if i == j {
                if s.is_nan() || s <= 0.0 {
                    return None;
                }
                l[i][i] = s.sqrt();
            } else {
                l[i][j] = s / l[j][j];
            }
        }
    }
    let mut y = [0.0f64; 6];
    for i in 0..6 {
        let mut s = b[i];
        for k in 0..i {
            s -= l[i][k] * y[k];
        }
        y[i] = s / l[i][i];
    }
    let mut x = [0.0f64; 6];
    for i in (0..6).rev() {
        let mut s = y[i];
        for k in i + 1..6 {
            s -= l[k][i] * x[k];
        }
        x[i] = s / l[i][i];
    }
    Some(x)
}

/// `A x`.
pub fn mul(a: &Mat6, x: [f64; 6]) -> [f64; 6] {
    let mut y = [0.0f64; 6];
    for (yi, row) in y.iter_mut().zip(a) {
        *yi = row.iter().zip(&x).map(|(a, x)| a * x).sum();
    }
    y
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solves_a_spd_system() {
        let mut a = [[0.0; 6]; 6];
        for (i, row) in a.iter_mut().enumerate() {
            for (j, v) in row.iter_mut().enumerate() {
                *v = 1.0 / (1.0 + i as f64 + j as f64) + if i == j { 2.0 } else { 0.0 };
            }
        }
        let b = [1.0, -2.0, 3.0, 0.5, -0.25, 4.0];
        let x = solve_spd(&a, b).unwrap();
        let r = mul(&a, x);
        for i in 0..6 {
            assert!((r[i] - b[i]).abs() < 1e-12);
        }
        a[2][2] = -1.0;
        assert!(solve_spd(&a, b).is_none());
    }
}
