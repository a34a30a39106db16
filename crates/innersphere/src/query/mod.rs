//! Queries between two Inner Sphere Trees under rigid poses.

pub mod pose;

pub use pose::Pose;
