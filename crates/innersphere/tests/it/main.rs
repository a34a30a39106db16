//! The core's integration tests (its public API), one binary: one link instead of one per
//! file. `limits_memory.rs` measures the whole process's heap and is its own binary; the tests
//! of the internal stages are unit tests in `src/tests/`.

mod query_util;

mod answer_forms;
mod batch;
mod bone_arch;
mod build_cache;
mod build_pipeline;
mod crate_layering;
mod exact_volume;
mod files_and_outputs;
mod limits;
mod mass;
mod mesh_io;
mod pose;
mod query_alloc;
mod query_far;
mod query_layering;
mod query_stiffness;

// The allocation tests count per thread, only inside `counted`: the other tests run beside
// them in this binary unaffected.
#[global_allocator]
static COUNTING: innersphere_testkit::alloc::Counting = innersphere_testkit::alloc::Counting;
