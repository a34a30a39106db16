//! 6-DOF haptic rendering on top of the [`Pair`](crate::Pair) queries: a virtual tool (body
//! B) with mass and inertia, coupled to the device by a spring-damper (virtual coupling) and
//! pushed out of body A by the volume-based penalty wrench of the penetration query, moved
//! by a linearly implicit Euler step so that stiff contact stays stable at the device rate;
//! and automatic occlusion (closing B onto A under a constant force until it rests).
//!
//! - [`device`]: device classes, their limits and default coupling;
//! - [`body`]: the tool's mass properties and state;
//! - [`render`]: the loop, one [`HapticLoop::tick`] per device tick, with a deadline;
//! - [`occlusion`]: the bite found by dynamics, with [`occlusion_limits`] (what a closing
//!   accepts) and [`occlusion_status`] (how it ended); [`free_occlusion`]: a free
//!   segment's, from many starts; [`bite`](mod@bite): either, set up from the jaw pair's own
//!   frame, refusing bodies and poses that cannot bite (`reach`).
//!
//! Units: millimetres, newtons, seconds, kilograms. `docs/HAPTICS.md` explains the model,
//! the parameters and why the loop is stable and passive.

pub mod bite;
mod blend;
pub mod body;
mod contact;
pub mod device;
pub mod free_occlusion;
mod mat6;
pub mod model;
pub mod multirate;
pub mod occlusion;
pub mod occlusion_limits;
pub mod occlusion_status;
mod reach;
pub mod realtime;
pub mod render;
pub mod servo;
mod step;

pub use bite::{bite, frame_of, Bite, BiteOptions, CONDYLE_HALF_SPAN};
pub use body::{BodyState, RigidBody, TOOTH_DENSITY};
pub use device::{Coupling, DeviceClass, DeviceLimits};
pub use free_occlusion::{occlude_free, Candidate, FreeOcclusion, FreeOcclusionOptions};
pub use model::ContactModel;
pub use multirate::{CollisionOptions, CollisionStats, MultirateLoop};
pub use occlusion::{occlude, Joints, Occlusion, OcclusionOptions};
pub use occlusion_status::{count_statuses, OcclusionStatus, StatusCounts};
pub use render::{check_step, HapticLoop, HapticOptions, Tick, MIN_RATE};
pub use servo::Servo;
pub use step::Wrench;
