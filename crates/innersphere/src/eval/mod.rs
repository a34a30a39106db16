//! Evaluation: the demo, build benchmarks, replay of motions (later: the paper's figures).

pub mod demo;
pub mod bench;
pub mod sysinfo;
