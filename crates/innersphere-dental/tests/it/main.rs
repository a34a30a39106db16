//! The dental crate's integration tests, one binary: one link instead of one per file.
//! `teeth_limits.rs` measures the whole process's heap and is its own binary.

#[path = "../../../innersphere-haptic/tests/it/haptic_util/mod.rs"]
mod haptic_util;

mod bite;
mod bite_status;
mod contact_map_real;
mod crate_layering;
mod occlusion;
mod splint;
mod teeth;
