//! The block front's expiry scan: which slots of a flat expiry array have expired (expiry
//! ≤ the motion so far), chunk by chunk in a given order; portable and AVX2 twins, the same
//! answers.

#[cfg(all(test, target_arch = "x86_64"))]
use super::simd;

/// Slots per chunk: one depth key per chunk, and a vector's worth of expiries per branch of
/// the scan.
pub(crate) const CHUNK: usize = 8;

/// Sets `due` to the slots of `chunks` (in that order, each chunk's in slot order) whose
/// expiry is ≤ `moved`. Runs over every slot every frame, and nearly all are not due.
#[inline(always)]
/// `AVX`: the AVX2 twin, set only within the `#[target_feature]` code a dispatcher runs when
/// the query's token (`Ctx::simd`) says the CPU has AVX2.
pub(crate) fn due_entries<const AVX: bool>(
    expiry: &[f64],
    chunks: &[u32],
    moved: f64,
    due: &mut Vec<u32>,
) {
    #[cfg(target_arch = "x86_64")]
    if AVX {
        // SAFETY: `AVX` is set only where the query's `Avx2` token proved the CPU has it.
        unsafe { due_entries_avx2(expiry, chunks, moved, due) };
        return;
    }
    due_entries_portable(expiry, chunks, moved, due)
}

/// [`due_entries`] without intrinsics.
#[inline(always)]
fn due_entries_portable(expiry: &[f64], chunks: &[u32], moved: f64, due: &mut Vec<u32>) {
    due.clear();
    for &c in chunks {
        let base = c as usize * CHUNK;
        for (k, &e) in expiry[base..base + CHUNK].iter().enumerate() {
            if e <= moved {
                due.push((base + k) as u32);
            }
        }
    }
}

/// Per 8-bit mask: the positions of its set bits, one per byte, lowest first.
const COMPRESS: [u64; 256] = {
    let mut t = [0u64; 256];
    let mut m = 0;
    while m < 256 {
        let (mut k, mut b, mut x) = (0, 0, 0u64);
        while b < 8 {
            if (m >> b) & 1 == 1 {
                x |= (b as u64) << (8 * k);
                k += 1;
            }
            b += 1;
        }
        t[m] = x;
        m += 1;
    }
    t
};

/// [`due_entries`] in AVX2 intrinsics, branch-free per chunk: the mask of a chunk's eight
/// comparisons picks its due slots' positions from [`COMPRESS`], all eight lanes are
/// stored and the length advances by the mask's popcount. A loop over the mask's bits (one
/// push each) mispredicted its exit on most chunks (BENCHMARKS.md, "Tried and did not pay")).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn due_entries_avx2(expiry: &[f64], chunks: &[u32], moved: f64, due: &mut Vec<u32>) {
    use std::arch::x86_64::*;
    due.clear();
    due.reserve(chunks.len() * CHUNK);
    let out = due.as_mut_ptr();
    let m = _mm256_set1_pd(moved);
    let mut len = 0;
    for &c in chunks {
        let base = c as usize * CHUNK;
        let s = &expiry[base..base + CHUNK];
        // SAFETY: `s` holds 8 values; `len + 8 ≤ 8 · (chunks done + 1) ≤ capacity`.
        unsafe {
            let a = _mm256_cmp_pd::<_CMP_LE_OQ>(_mm256_loadu_pd(s.as_ptr()), m);
            let b = _mm256_cmp_pd::<_CMP_LE_OQ>(_mm256_loadu_pd(s.as_ptr().add(4)), m);
            let bits = (_mm256_movemask_pd(a) | (_mm256_movemask_pd(b) << 4)) as usize;
            let pos = _mm256_cvtepu8_epi32(_mm_cvtsi64_si128(COMPRESS[bits] as i64));
            let idx = _mm256_add_epi32(pos, _mm256_set1_epi32(base as i32));
            _mm256_storeu_si256(out.add(len) as *mut __m256i, idx);
            len += bits.count_ones() as usize;
        }
    }
    // SAFETY: the first `len` values were written above.
    unsafe { due.set_len(len) };
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// The scans find exactly the slots with expiry ≤ `moved`, chunk by chunk in the
        /// given order (AVX2 and portable alike), infinities and NaN included (a NaN expiry
        /// is never due).
        #[test]
        fn due_scan_finds_expired_slots_in_chunk_order(
            v in prop::collection::vec(prop_oneof![
                -10.0f64..10.0,
                Just(f64::INFINITY),
                Just(f64::NEG_INFINITY),
                Just(f64::NAN),
            ], 0..12usize).prop_flat_map(|c| prop::collection::vec(prop_oneof![
                -10.0f64..10.0,
                Just(f64::INFINITY),
                Just(f64::NEG_INFINITY),
                Just(f64::NAN),
            ], c.len() * CHUNK)),
            perm in any::<prop::sample::Index>(),
            moved in -10.0f64..10.0,
        ) {
            let n = (v.len() / CHUNK) as u32;
            let mut chunks: Vec<u32> = (0..n).collect();
            if n > 0 {
                chunks.rotate_left(perm.index(n as usize));
            }
            let want: Vec<u32> = chunks
                .iter()
                .flat_map(|&c| c * CHUNK as u32..(c + 1) * CHUNK as u32)
                .filter(|&i| v[i as usize] <= moved)
                .collect();
            let mut p = vec![7];
            due_entries_portable(&v, &chunks, moved, &mut p);
            prop_assert_eq!(&p, &want);
            #[cfg(target_arch = "x86_64")]
            if simd::detect().is_some() {
                let mut a = vec![7];
                // SAFETY: the CPU has AVX2 (checked just above).
                unsafe { due_entries_avx2(&v, &chunks, moved, &mut a) };
                prop_assert_eq!(&a, &want);
            }
        }

    }
}
