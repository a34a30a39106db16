//! The one runtime CPU-dispatch point of the queries.
//!
//! Every AVX2 kernel has a portable twin that gives bit for bit the same numbers (no FMA, the
//! same operation order; property tests compare them), so the answers never depend on the
//! CPU. Whether the AVX2 twin runs is decided here and only here.

use std::sync::atomic::{AtomicU8, Ordering};

/// 0: no, 1: yes, 2: not yet detected.
static AVX2: AtomicU8 = AtomicU8::new(2);

/// True when the AVX2 kernels (and the POPCNT and BMI1 instructions the block front's scan
/// uses beside them) may run on this CPU. One relaxed load after the first call: the blocked
/// steps ask once per step.
#[inline(always)]
pub(crate) fn avx2() -> bool {
    match AVX2.load(Ordering::Relaxed) {
        0 => false,
        1 => true,
        _ => detect(),
    }
}

#[cold]
fn detect() -> bool {
    #[cfg(target_arch = "x86_64")]
    let yes = std::arch::is_x86_feature_detected!("avx2")
        && std::arch::is_x86_feature_detected!("popcnt")
        && std::arch::is_x86_feature_detected!("bmi1");
    #[cfg(not(target_arch = "x86_64"))]
    let yes = false;
    AVX2.store(yes as u8, Ordering::Relaxed);
    yes
}
