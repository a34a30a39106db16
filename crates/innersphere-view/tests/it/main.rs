//! The viewer's integration tests, one binary: one link instead of one per file.

mod api;
mod hostile;
mod soak;
