//! The C ABI's integration tests from Rust, one binary: one link instead of one per file.
//! `header.rs` (feature `header`) checks the generated header and is its own binary.

mod abi;
mod alloc;
mod answer_fields;
