//! Queries between two Inner Sphere Trees under rigid poses.
//!
//! Every query takes the two trees, the world pose of each and the [`PairState`] of the pair
//! (created once per pair with [`PairState::new`]). Internally a query works in A's frame:
//! the relative pose of B is converted to f32 once per query and only the B nodes a traversal
//! actually visits are transformed. Traversals read a packed copy of each tree's nodes
//! ([`TreeInfo`], 32 bytes per node, children contiguous) and keep explicit stacks in the
//! state; node tests carry a tiny slack covering the f32 rounding, so that an inner-node test
//! never prunes a leaf pair that the exact leaf test (`|Δ|² < (ra + rb)²` in f32) accepts.
//! The state carries what temporal coherence needs and all scratch memory, reserved at
//! construction from the trees' sizes, so that a query allocates nothing from the first frame
//! and takes no lock (what may still grow, and its bound: [`PairState::with_info`]); list
//! results are slices borrowed from the state. Trees are immutable and shared freely between
//! threads; one state serves one pair on one thread at a time.
//!
//! | query | function | answer |
//! |---|---|---|
//! | exact proximity of the sphere sets (branch and bound, depth or best first) | [`proximity`] | distance, closest points, leaf pair |
//! | the paper's distance traversal (III-A) | [`distance_traversal`] | contact yes/no, a contact, a separation bound |
//! | the paper's backtracking traversal (III-B, Alg. 1–2) | [`backtracking`] | same, restarting from last frame's contact |
//! | the paper's multipoint traversal (III-C) | [`multipoint`] | up to `k` contacts, one per split-depth node |
//! | first contact from a kinetic front (ours) | [`contact`] | same answer: the recent contact pairs while they overlap, else re-running only the steps the motion could change |
//! | penetration volume, force, torque, patches | [`penetration`] | exact volume of the intersection of the sphere unions |
//! | time-critical penetration volume | [`penetration_budgeted`] | volume found so far and an upper bound |
//!
//! Kinetic front tracking (ours; [`contact`], [`penetration`] with [`Tracking`] (automatic
//! by tree size), [`multipoint`] with `tracking`): the frontier of the overlap traversal is kept from frame to frame and each
//! separated node pair on it is re-tested only once the relative motion since its last test
//! could have closed its separation; its hits are exactly the overlapping leaf pairs.
//!
//! Broad phase and safe motion: every query first rejects on the root spheres, and a query
//! that proved the bodies separated by `d` lets the contact queries skip later frames until
//! the relative motion could have closed `d` ([`PairState::safe_separation`]).
//!
//! [`brute`] holds O(n·m) references over all leaf pairs that the tests compare against.

mod block_front;
pub mod brute;
mod buckets;
mod front;
mod geometry;
mod heap;
mod info;
mod lanes;
mod penetration;
mod proximity;
mod state;
mod traversal;

/// The crate root's [`Pose`], also here for code that imports it with the queries.
pub use crate::pose::Pose;
pub use geometry::{lens_volume, Contact};
pub use info::TreeInfo;
pub use penetration::{
    penetration, penetration_budgeted, BudgetedVolume, Patch, Penetration, PenetrationOptions,
    Tracking, AUTO_FRONT_NODES,
};
pub use proximity::{proximity, Proximity, ProximityOptions};
pub use state::{PairState, SeparationRecord};
pub use traversal::{
    backtracking, contact, distance_traversal, multipoint, ContactOptions, ContactQuery,
    MultipointOptions, MultipointResult,
};
