//! Evaluation: the demo, build benchmarks, replay of motions (later: the paper's figures).

// pub mod demo; (enabled with build)
pub mod sysinfo;
