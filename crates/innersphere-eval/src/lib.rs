//! # innersphere-eval
//!
//! The evaluation harness of [`innersphere`]: what measures the library rather than what a
//! haptic application links. It carries the plotting dependency and the charts' font, so that
//! the core crate has neither.
//!
//! ```text
//! motion/     motion files (CSV), generated jaw motions, anatomical frame, clearance and phases
//! replay      a motion through a pair's state, per query kind timings and accuracy vs exact
//! demo        the generated tooth pair: build, replay (`ist demo`)
//! bench       build benchmarks (`ist bench build`)
//! paper       the paper's figures: sweeps, CSV and charts (`ist bench paper`)
//! plot        PNG line charts (plotters, bundled DejaVu font)
//! sysinfo     process and machine facts for reports
//! ```

pub mod bench;
pub mod demo;
pub mod haptic;
pub mod histogram;
pub mod mesh_reference;
/// Motions (their own crate, [`innersphere_motion`]), re-exported under the name the harness
/// has always used.
pub use innersphere_motion as motion;
pub mod paper;
pub mod plot;
pub mod replay;
pub mod sysinfo;
