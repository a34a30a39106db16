//! What the workspace's tests share (a dev-dependency only; not published):
//!
//! - [`data`]: the real-data folder `../shared/data` beside the repository (the tests on
//!   real models are `#[ignore]`d and run by CI with `--ignored`);
//! - [`alloc`]: a counting global allocator (a test binary declares it with
//!   `#[global_allocator] static A: Counting = Counting;`), per-thread counts, and every query
//!   kind and option of the public API to run under it;
//! - [`layering`]: a crate's module ladder, read from its sources;
//! - [`peak`]: the peak of live heap bytes (a global allocator), and a FIFO that never ends;
//! - `splint` (feature `dental`): the checks that a splint seats on both arches.

pub mod alloc;
pub mod data;
pub mod layering;
pub mod peak;
#[cfg(feature = "dental")]
pub mod splint;

pub use data::{data, data_dir};
