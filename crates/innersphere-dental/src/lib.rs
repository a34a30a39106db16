//! Dental planning on Inner Sphere Trees: what a surgeon or a dental technician does with two
//! scanned arches.
//!
//! - [`anatomy`]: the anatomical frame of a jaw pair (occlusal up, anterior, hinge);
//! - [`occlusion`]: the bite found by dynamics (the haptic crate's body and step), with
//!   [`occlusion_limits`] (what a closing accepts) and [`occlusion_status`] (how it ended);
//!   [`free_occlusion`]: a free segment's, from many starts; [`bite`](mod@bite): either, set
//!   up from the jaw pair's own frame, refusing bodies and poses that cannot bite (`reach`);
//! - [`contact_map`]: every vertex's signed gap to the other arch, per tooth;
//! - [`case`]: one patient's plan in one file, run from scans to wafers and a report;
//! - [`splint`]: the occlusal splint (surgical wafer) between two arches at a pose, over the
//!   per-column surfaces of [`columns`].
//!
//! Units: millimetres, newtons, seconds (`innersphere::mesh::Unit` converts at load).

#![deny(missing_docs)]

pub mod anatomy;
pub mod bite;
pub mod case;
pub mod columns;
pub mod contact_map;
pub mod free_occlusion;
pub mod occlusion;
pub mod occlusion_limits;
pub mod occlusion_status;
mod reach;
pub mod splint;

pub use bite::{bite, frame_of, Bite, BiteOptions, CONDYLE_HALF_SPAN};
pub use free_occlusion::{occlude_free, Candidate, FreeOcclusion, FreeOcclusionOptions};
pub use occlusion::{occlude, Joints, Occlusion, OcclusionOptions};
pub use occlusion_status::{count_statuses, OcclusionStatus, StatusCounts};
