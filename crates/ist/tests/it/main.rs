//! `ist`'s integration tests (the binary run as a user runs it), one test binary: one link
//! instead of one per file.

mod support;

mod build_cache;
mod cli;
mod occlude;
mod parity;
mod plan;
mod robust;
mod teeth;
mod units;
