//! The one runtime CPU-dispatch point of the queries.
//!
//! Every AVX2 kernel has a portable twin that gives bit for bit the same numbers (no FMA, the
//! same operation order; property tests compare them), so the answers never depend on the
//! CPU. Whether the AVX2 twin runs is decided here and only here.

/// True when the AVX2 kernels (and the POPCNT and BMI1 instructions the block front's scan
/// uses beside them) may run on this CPU. The check is a cached load after the first call.
#[inline(always)]
pub(crate) fn avx2() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx2")
            && std::arch::is_x86_feature_detected!("popcnt")
            && std::arch::is_x86_feature_detected!("bmi1")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}
