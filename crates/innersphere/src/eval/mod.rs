//! Evaluation: the demo, build benchmarks, replay of motions, the paper's figures.

pub mod bench;
pub mod demo;
pub mod paper;
pub mod plot;
pub mod replay;
pub mod sysinfo;
