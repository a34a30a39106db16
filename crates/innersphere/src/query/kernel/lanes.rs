//! The 4×4 sphere-pair step the blocked traversals share: every child of one node against
//! every child of another, squared centre distances and radius sums, in AVX2 where the CPU has
//! it. Hand-written intrinsics because the compiler's vectorisation of the portable loops was
//! slower (BENCHMARKS.md, "Tried and did not pay")); both give bit-for-bit the same numbers (no FMA, the same
//! operation order, checked by property tests), so the answers do not depend on the CPU.

use super::info::LANES;

/// Bit `4·row + col` set when lane `row` of the row side and lane `col` of the column side
/// are both leaves (their pair gets no rounding slack).
#[inline(always)]
pub(crate) fn leaf_pairs_mask(row_leaf: u32, col_leaf: u32) -> u32 {
    ROWS[(row_leaf & 0xF) as usize] as u32 & ((col_leaf & 0xF) * 0x1111)
}

/// Per 4-bit row mask: each set bit widened to its row's four pair bits (a lookup where the
/// loop cost ≈ 14 instructions a step under cachegrind).
const ROWS: [u16; 16] = {
    let mut t = [0u16; 16];
    let mut m = 0;
    while m < 16 {
        let mut l = 0;
        while l < LANES {
            if (m >> l) & 1 == 1 {
                t[m] |= 0xF << (l * LANES);
            }
            l += 1;
        }
        m += 1;
    }
    t
};

/// Bit `4·row + col` set when both lanes are in use (`row < row_count`, `col < col_count`).
#[inline(always)]
pub(crate) fn valid_mask(row_count: u32, col_count: u32) -> u32 {
    let cols = ((1u32 << col_count.min(4)) - 1) * 0x1111;
    let rows = (1u32 << (4 * row_count.min(4))) - 1;
    rows & cols
}

/// Squared centre distances `d2` and radius sums `sr` (+ `slack` unless the pair is a leaf
/// pair, `ll`) of the 16 pairs of `rows` × `cols` (each `[x, y, z, r]` by lane, in one
/// frame), pair `4·row + col`: per axis `d = row − col`, `d2 = (dx·dx + dy·dy) + dz·dz`,
/// `sr = (r_row + r_col) + slack`. The portable twin of [`pairs_avx2`].
#[allow(clippy::needless_range_loop)] // two lane indices into four arrays each
#[inline(always)]
pub(crate) fn pairs(
    rows: [&[f32; LANES]; 4],
    cols: [&[f32; LANES]; 4],
    ll: u32,
    slack: f32,
    d2: &mut [f32; 16],
    sr: &mut [f32; 16],
) {
    for l in 0..LANES {
        for i in 0..LANES {
            let q = l * LANES + i;
            let dx = rows[0][l] - cols[0][i];
            let dy = rows[1][l] - cols[1][i];
            let dz = rows[2][l] - cols[2][i];
            d2[q] = dx * dx + dy * dy + dz * dz;
            let rs = if (ll >> q) & 1 != 0 { 0.0 } else { slack };
            sr[q] = (rows[3][l] + cols[3][i]) + rs;
        }
    }
}

/// Squared centre distances and radius sums (+ `slack` unless the pair is a leaf pair, `ll`)
/// of the 16 pairs of `rows` × `cols` (each `[x, y, z, r]` by lane, in one frame), as two
/// 8-lane vectors: lanes `0..8` are rows 0–1, lanes `8..16` rows 2–3, columns innermost.
/// Per lane: `d = row − col` per axis, `d2 = (dx·dx + dy·dy) + dz·dz`,
/// `s = (r_row + r_col) + slack`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
pub(crate) unsafe fn pairs_avx2(
    rows: [&[f32; LANES]; 4],
    cols: [&[f32; LANES]; 4],
    ll: u32,
    slack: f32,
) -> [(std::arch::x86_64::__m256, std::arch::x86_64::__m256); 2] {
    use std::arch::x86_64::*;
    let dup = |v: &[f32; LANES]| {
        let v = _mm_loadu_ps(v.as_ptr());
        _mm256_insertf128_ps::<1>(_mm256_castps128_ps256(v), v)
    };
    let wide = |v: &[f32; LANES]| _mm256_castps128_ps256(_mm_loadu_ps(v.as_ptr()));
    let (cx, cy, cz, cr) = (dup(cols[0]), dup(cols[1]), dup(cols[2]), dup(cols[3]));
    let (rx, ry, rz, rr) = (wide(rows[0]), wide(rows[1]), wide(rows[2]), wide(rows[3]));
    let bits = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
    let slack = _mm256_set1_ps(slack);
    let half = |h: usize| {
        let idx = if h == 0 {
            _mm256_setr_epi32(0, 0, 0, 0, 1, 1, 1, 1)
        } else {
            _mm256_setr_epi32(2, 2, 2, 2, 3, 3, 3, 3)
        };
        let dx = _mm256_sub_ps(_mm256_permutevar8x32_ps(rx, idx), cx);
        let dy = _mm256_sub_ps(_mm256_permutevar8x32_ps(ry, idx), cy);
        let dz = _mm256_sub_ps(_mm256_permutevar8x32_ps(rz, idx), cz);
        let d2 = _mm256_add_ps(
            _mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy)),
            _mm256_mul_ps(dz, dz),
        );
        let llv = _mm256_set1_epi32(((ll >> (8 * h)) & 0xFF) as i32);
        let is_ll = _mm256_castsi256_ps(_mm256_cmpeq_epi32(_mm256_and_si256(llv, bits), bits));
        let rs = _mm256_andnot_ps(is_ll, slack);
        let s = _mm256_add_ps(_mm256_add_ps(_mm256_permutevar8x32_ps(rr, idx), cr), rs);
        (d2, s)
    };
    [half(0), half(1)]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn leaf_mask_table_equals_the_loop() {
        for row in 0..16u32 {
            for col in 0..16u32 {
                let mut rows = 0u32;
                for l in 0..LANES {
                    rows |= (((row >> l) & 1) * 0xF) << (l * LANES);
                }
                assert_eq!(leaf_pairs_mask(row, col), rows & (col * 0x1111));
            }
        }
    }

    #[test]
    fn masks_by_hand() {
        // Rows 0 and 2 leaves, columns 1 and 3 leaves.
        let ll = leaf_pairs_mask(0b0101, 0b1010);
        assert_eq!(ll, (0b1010) | (0b1010 << 8));
        assert_eq!(valid_mask(4, 4), 0xFFFF);
        assert_eq!(valid_mask(1, 1), 1);
        assert_eq!(valid_mask(2, 3), 0b0111_0111);
    }
}
