//! The fuzz crate's integration tests (the corpus replayed, the seeds, the load tests), one
//! binary: one link instead of one per file.

mod corpus;
mod regressions;
mod seeds;
mod under_load;

// The allocation tests count per thread, only inside `counted`: the other tests run beside
// them in this binary unaffected.
#[global_allocator]
static COUNTING: innersphere_testkit::alloc::Counting = innersphere_testkit::alloc::Counting;
