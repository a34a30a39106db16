//! The haptic crate's integration tests, one binary: one link instead of one per file.
//! `haptic_multirate_alloc.rs` counts the allocations of the whole process and is its own
//! binary.

mod haptic_util;

mod crate_layering;
mod haptic;
mod haptic_multirate;
mod haptic_servo;

// The allocation tests count per thread, only inside `counted`: the other tests run beside
// them in this binary unaffected.
#[global_allocator]
static COUNTING: innersphere_testkit::alloc::Counting = innersphere_testkit::alloc::Counting;
