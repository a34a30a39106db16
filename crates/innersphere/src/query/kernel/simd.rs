//! The one runtime CPU-dispatch decision of the queries.
//!
//! Every AVX2 kernel has a portable twin that gives bit for bit the same numbers (no FMA, the
//! same operation order; property tests compare them), so the answers never depend on the
//! CPU. Whether the AVX2 twins run is decided once per query, at the `Pair` door, by
//! [`detect`]: its answer, an [`Avx2`] token or none, travels in the query's `Ctx` (and as an
//! argument to the kernels that take no `Ctx`), and each kernel branches on that value.

use std::sync::atomic::{AtomicU8, Ordering};

/// Proof that the AVX2 kernels may run on this CPU (AVX2, and the POPCNT and BMI1 the block
/// front's scan uses beside them): only [`detect`] makes one, so holding one is what makes
/// calling a `#[target_feature(enable = "avx2")]` twin sound.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Avx2(());

/// 0: no, 1: yes, 2: not yet detected.
static AVX2: AtomicU8 = AtomicU8::new(2);

/// The AVX2 token where this CPU has the instructions, else none: the decision a query makes
/// once. One relaxed load after the first call.
#[inline(always)]
pub(crate) fn detect() -> Option<Avx2> {
    let yes = match AVX2.load(Ordering::Relaxed) {
        0 => false,
        1 => true,
        _ => first_detect(),
    };
    yes.then_some(Avx2(()))
}

#[cold]
fn first_detect() -> bool {
    #[cfg(target_arch = "x86_64")]
    let yes = std::arch::is_x86_feature_detected!("avx2")
        && std::arch::is_x86_feature_detected!("popcnt")
        && std::arch::is_x86_feature_detected!("bmi1");
    #[cfg(not(target_arch = "x86_64"))]
    let yes = false;
    AVX2.store(yes as u8, Ordering::Relaxed);
    yes
}
