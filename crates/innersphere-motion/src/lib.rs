//! Motions of body B against body A: files, sampling in time, generated motions and haptic
//! device trajectories. Its own crate, with no plotting, so that the Python module, the
//! viewer and the fuzz targets read motions without the evaluation harness.
//!
//! - [`Motion`] / [`Frame`]: the motion file format (`t,tx,ty,tz,qw,qx,qy,qz`, the pose of
//!   body B in body A's frame over time), loading with line-numbered errors, saving, and the
//!   pose at any time ([`Motion::pose_at`]).
//! - [`press()`]: a smooth haptic device trajectory into a pair's bite and out.
//! - [`generate()`] / [`generate_with`]: hand-recorded-looking motions of a pair at 1 kHz
//!   ([`Scenario::Chew`], [`Scenario::OpenClose`], [`Scenario::Grind`]) that pass through
//!   separated, touching and interpenetrating phases.
//! - [`AnatomicalFrame`]: up / left / anterior, the incisal point and the opening hinge of a
//!   jaw pair, from the meshes.
//! - [`ClearanceEstimator`], [`clearance()`], [`phase_of`]: a fast signed-clearance estimate
//!   and the phase labels that replays and benchmarks use.

pub mod clearance;
pub mod csv;
/// The anatomical frame of a jaw pair, which lives in the library ([`innersphere_dental::anatomy`]).
pub mod frame {
    pub use innersphere_dental::anatomy::*;
}
pub mod generate;
pub mod press;
mod rng;

pub use clearance::{
    clearance, phase_of, ClearanceEstimator, ClearanceOptions, Phase, PhaseCounts, DEFAULT_TOUCH,
};
pub use csv::{Frame, Motion, HEADER};
pub use frame::AnatomicalFrame;
pub use generate::{generate, generate_with, same_body, GenerateOptions, Generated, Scenario};
pub use press::{press, PressOptions};
