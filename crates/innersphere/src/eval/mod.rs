//! Evaluation: the demo, build benchmarks, replay of motions (later: the paper's figures).

pub mod bench;
pub mod demo;
pub mod replay;
pub mod sysinfo;
