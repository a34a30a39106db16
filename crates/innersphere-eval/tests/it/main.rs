//! The evaluation crate's integration tests, one binary: one link instead of one per file.

mod demo;
mod haptic_jaw;
mod motion;
mod paper;
mod query_alloc_jaw;
mod query_golden_jaw;
mod replay;
mod splint_jaw;

// The allocation tests count per thread, only inside `counted`: the other tests run beside
// them in this binary unaffected.
#[global_allocator]
static COUNTING: innersphere_testkit::alloc::Counting = innersphere_testkit::alloc::Counting;
