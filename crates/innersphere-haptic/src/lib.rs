//! 6-DOF haptic rendering on top of the [`Pair`](innersphere::Pair) queries: a virtual tool (body
//! B) with mass and inertia, coupled to the device by a spring-damper (virtual coupling) and
//! pushed out of body A by the volume-based penalty wrench of the penetration query, moved
//! by a linearly implicit Euler step so that stiff contact stays stable at the device rate.
//! The same dynamics close a jaw onto its opposing arch in `innersphere-dental`.
//!
//! - [`device`]: device classes, their limits and default coupling;
//! - [`body`]: the tool's mass properties and state;
//! - [`render`]: the loop, one [`HapticLoop::tick`] per device tick, with a deadline;
//! - [`servo`] and [`multirate`]: the device loop and its collision thread at different rates;
//! - [`model`] and [`step`]: the contact model between queries and the implicit step, shared
//!   with the closing of a jaw in `innersphere-dental`.
//!
//! Units: millimetres, newtons, seconds, kilograms. `docs/HAPTICS.md` explains the model,
//! the parameters and why the loop is stable and passive.

#![deny(missing_docs)]

mod blend;
pub mod body;
mod deadline;
pub mod device;
pub mod mat6;
pub mod model;
pub mod multirate;
pub mod realtime;
pub mod render;
pub mod servo;
pub mod step;

pub use body::{BodyState, RigidBody, TOOTH_DENSITY};
pub use device::{Coupling, DeviceClass, DeviceLimits};
pub use model::{ContactModel, ContactSource};
pub use multirate::{CollisionOptions, CollisionStats, MultirateLoop};
pub use render::{check_step, HapticLoop, HapticOptions, Tick, MIN_RATE};
pub use servo::Servo;
pub use step::Wrench;
