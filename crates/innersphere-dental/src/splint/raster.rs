//! Operations on 2-D height maps over a [`ColumnGrid`](crate::columns::ColumnGrid):
//! Gaussian smoothing that fills unknown cells, a square minimum filter, the Euclidean
//! distance to a mask and the largest connected part of a mask.
//!
//! Hand-written: each is a few lines over a flat `Vec<f64>`, where an image-processing crate
//! (imageproc) would bring the `image` and `nalgebra` stacks for them.

/// `dims[0] × dims[1]` cells, x fastest.
pub type Dims = [usize; 2];

/// Widths of three box filters whose succession approximates a Gaussian of standard
/// deviation `sigma` cells (Kovesi's construction: the variance of a box of width w is
/// (w² − 1)/12).
fn boxes(sigma: f64) -> [usize; 3] {
    let ideal = (12.0 * sigma * sigma / 3.0 + 1.0).sqrt();
    let mut wl = ideal.floor() as usize;
    if wl & 1 == 0 {
        wl = wl.saturating_sub(1);
    }
    let wl = wl.max(1);
    let wu = wl + 2;
    let m = ((12.0 * sigma * sigma - 3.0 * (wl * wl) as f64 - 12.0 * wl as f64 - 9.0)
        / (-4.0 * wl as f64 - 4.0))
        .round()
        .clamp(0.0, 3.0) as usize;
    [0, 1, 2].map(|i| if i < m { wl } else { wu })
}

/// A running-sum box filter of odd width `w` along one axis (zero outside the map), in
/// place: `n` lines of `len` cells, `stride` apart in a line, `step` between lines.
fn box_pass(v: &mut [f64], w: usize, len: usize, n: usize, stride: usize, step: usize) {
    let r = w / 2;
    let mut line = vec![0.0; len];
    for l in 0..n {
        for (i, c) in line.iter_mut().enumerate() {
            *c = v[l * step + i * stride];
        }
        let mut sum: f64 = line[..r.min(len)].iter().sum();
        for i in 0..len {
            if i + r < len {
                sum += line[i + r];
            }
            if i > r {
                sum -= line[i - r - 1];
            }
            v[l * step + i * stride] = sum / w as f64;
        }
    }
}

/// Gaussian-like smoothing (three box passes per axis; O(1) per cell whatever `sigma`),
/// zero outside the map.
fn convolve(v: &[f64], dims: Dims, sigma: f64) -> Vec<f64> {
    let [nx, ny] = dims;
    let mut out = v.to_vec();
    for w in boxes(sigma) {
        box_pass(&mut out, w, nx, ny, 1, nx);
        box_pass(&mut out, w, ny, nx, nx, 1);
    }
    out
}

/// The two halves of a normalized convolution of the finite cells of `v`: `(G∗(v·m), G∗m)`
/// with `m` the finite cells (σ in cells).
pub fn weighted(v: &[f64], dims: Dims, sigma: f64) -> (Vec<f64>, Vec<f64>) {
    let m: Vec<f64> = v
        .iter()
        .map(|x| f64::from(u8::from(x.is_finite())))
        .collect();
    let vm: Vec<f64> = v
        .iter()
        .map(|x| if x.is_finite() { *x } else { 0.0 })
        .collect();
    (convolve(&vm, dims, sigma), convolve(&m, dims, sigma))
}

/// Gaussian smoothing (σ in cells) of the finite cells of `v` that also fills the others:
/// the normalized convolution `G∗(v·m) / G∗m` with `m` the finite cells. Cells that no
/// finite cell reaches (about 2σ) stay `NaN`.
pub fn smooth_fill(v: &[f64], dims: Dims, sigma: f64) -> Vec<f64> {
    let (num, den) = weighted(v, dims, sigma);
    num.iter()
        .zip(&den)
        .map(|(n, d)| if *d > 1e-9 { n / d } else { f64::NAN })
        .collect()
}

/// The minimum over the `(2r+1)²` square around each cell (infinite cells are ignored
/// unless all are).
pub fn min_filter(v: &[f64], dims: Dims, r: usize) -> Vec<f64> {
    let [nx, ny] = dims;
    let mut tmp = vec![f64::INFINITY; v.len()];
    for j in 0..ny {
        for i in 0..nx {
            let (a, b) = (i.saturating_sub(r), (i + r).min(nx - 1));
            tmp[i + nx * j] = v[a + nx * j..=b + nx * j]
                .iter()
                .fold(f64::INFINITY, |m, x| m.min(*x));
        }
    }
    let mut out = vec![f64::INFINITY; v.len()];
    for j in 0..ny {
        let (a, b) = (j.saturating_sub(r), (j + r).min(ny - 1));
        for i in 0..nx {
            out[i + nx * j] = (a..=b).fold(f64::INFINITY, |m, jj| m.min(tmp[i + nx * jj]));
        }
    }
    out
}

/// Euclidean distance (in cells) from each cell to the nearest cell of `mask` (0 on the
/// mask, infinite when the mask is empty): the exact transform of Felzenszwalb and
/// Huttenlocher, a lower envelope of parabolas per row, then per column.
pub fn distance_to(mask: &[bool], dims: Dims) -> Vec<f64> {
    let [nx, ny] = dims;
    let big = 1e20;
    let mut f: Vec<f64> = mask.iter().map(|m| if *m { 0.0 } else { big }).collect();
    // Rows, then columns: each line replaced by its 1-D transform.
    for (len, lines, stride, step) in [(nx, ny, 1, nx), (ny, nx, nx, 1)] {
        let mut line = vec![0.0; len];
        for l in 0..lines {
            for (i, c) in line.iter_mut().enumerate() {
                *c = f[l * step + i * stride];
            }
            for (i, d) in envelope(&line).into_iter().enumerate() {
                f[l * step + i * stride] = d;
            }
        }
    }
    f.into_iter()
        .map(|d| if d >= big { f64::INFINITY } else { d.sqrt() })
        .collect()
}

/// The 1-D squared distance transform of sampled function `f`.
fn envelope(f: &[f64]) -> Vec<f64> {
    let n = f.len();
    let mut d = vec![0.0; n];
    if n == 0 {
        return d;
    }
    let mut v = vec![0usize; n];
    let mut z = vec![0.0f64; n + 1];
    let mut k = 0usize;
    z[0] = f64::NEG_INFINITY;
    z[1] = f64::INFINITY;
    let inter = |q: usize, p: usize| -> f64 {
        ((f[q] + (q * q) as f64) - (f[p] + (p * p) as f64)) / (2.0 * (q as f64 - p as f64))
    };
    for q in 1..n {
        let mut s = inter(q, v[k]);
        while s <= z[k] {
            k -= 1;
            s = inter(q, v[k]);
        }
        k += 1;
        v[k] = q;
        z[k] = s;
        z[k + 1] = f64::INFINITY;
    }
    k = 0;
    for (q, dq) in d.iter_mut().enumerate() {
        while z[k + 1] < q as f64 {
            k += 1;
        }
        let dx = q as f64 - v[k] as f64;
        *dq = dx * dx + f[v[k]];
    }
    d
}

/// The largest 4-connected part of `mask` (empty when the mask is), and how many parts
/// the mask has.
pub fn largest_part(mask: &[bool], dims: Dims) -> (Vec<bool>, usize) {
    let [nx, ny] = dims;
    let mut label = vec![u32::MAX; mask.len()];
    let mut sizes = Vec::new();
    let mut stack = Vec::new();
    for s in 0..mask.len() {
        if !mask[s] || label[s] != u32::MAX {
            continue;
        }
        let id = sizes.len() as u32;
        let mut size = 0usize;
        label[s] = id;
        stack.push(s);
        while let Some(c) = stack.pop() {
            size += 1;
            let (i, j) = (c % nx, c / nx);
            let mut visit = |n: usize| {
                if mask[n] && label[n] == u32::MAX {
                    label[n] = id;
                    stack.push(n);
                }
            };
            if i > 0 {
                visit(c - 1);
            }
            if i + 1 < nx {
                visit(c + 1);
            }
            if j > 0 {
                visit(c - nx);
            }
            if j + 1 < ny {
                visit(c + nx);
            }
        }
        sizes.push(size);
    }
    let Some(best) = (0..sizes.len()).max_by_key(|&k| (sizes[k], std::cmp::Reverse(k))) else {
        return (vec![false; mask.len()], 0);
    };
    (
        label.iter().map(|l| *l == best as u32).collect(),
        sizes.len(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distance_transform_matches_brute_force() {
        let dims = [23, 17];
        let mask: Vec<bool> = (0..dims[0] * dims[1])
            .map(|k| (k * 7919) % 31 == 0)
            .collect();
        let d = distance_to(&mask, dims);
        for (c, got) in d.iter().enumerate() {
            let (i, j) = ((c % dims[0]) as f64, (c / dims[0]) as f64);
            let want = (0..mask.len())
                .filter(|&m| mask[m])
                .map(|m| {
                    let (a, b) = ((m % dims[0]) as f64, (m / dims[0]) as f64);
                    ((a - i).powi(2) + (b - j).powi(2)).sqrt()
                })
                .fold(f64::INFINITY, f64::min);
            assert!((got - want).abs() < 1e-9, "cell {c}: {got} vs {want}");
        }
    }

    #[test]
    fn smoothing_keeps_a_plane_and_fills_holes() {
        let dims = [30, 20];
        let plane = |k: usize| 0.3 * (k % 30) as f64 + 0.1 * (k / 30) as f64;
        let full: Vec<f64> = (0..600).map(plane).collect();
        let s = smooth_fill(&full, dims, 1.5);
        for j in 6..14 {
            for i in 6..24 {
                assert!((s[i + 30 * j] - plane(i + 30 * j)).abs() < 1e-9);
            }
        }
        let holed: Vec<f64> = (0..600)
            .map(|k| {
                if (10..20).contains(&(k % 30)) {
                    f64::NAN
                } else {
                    plane(k)
                }
            })
            .collect();
        let f = smooth_fill(&holed, dims, 3.0);
        assert!(f.iter().all(|v| v.is_finite() && (0.0..=10.6).contains(v)));
    }

    #[test]
    fn min_filter_and_parts() {
        let dims = [5, 4];
        let mut v = vec![f64::INFINITY; 20];
        v[7] = 2.0;
        v[13] = 1.0;
        let m = min_filter(&v, dims, 1);
        assert_eq!(m[0], f64::INFINITY);
        assert_eq!(m[2], 2.0);
        assert_eq!(m[8], 1.0);
        let mask: Vec<bool> = (0..20)
            .map(|k| k % 5 == 0 || k % 5 == 3 || k == 4)
            .collect();
        let (part, n) = largest_part(&mask, dims);
        assert_eq!(n, 2);
        assert_eq!(part.iter().filter(|p| **p).count(), 5);
    }
}
