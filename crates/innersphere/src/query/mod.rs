//! Queries between two Inner Sphere Trees under rigid poses, through one type: [`Pair`].
//!
//! A [`Pair`] shares two trees and holds everything their queries keep from frame to frame.
//! Internally a query works in A's frame: the relative pose of B is converted to f32 once per
//! query and only the B nodes a traversal actually visits are transformed. Traversals read a
//! packed copy of each tree's nodes ([`TreeInfo`], 32 bytes per node, children contiguous);
//! node tests carry a tiny slack covering the f32 rounding, so that an inner-node test never
//! prunes a leaf pair that the exact leaf test (`|Δ|² < (ra + rb)²` in f32) accepts. A query
//! allocates nothing from the first frame and takes no lock (what may still grow, and its
//! bound: [`Pair::new`]).
//!
//! | query | method | answer |
//! |---|---|---|
//! | exact distance of the sphere sets (branch and bound, depth or best first) | [`Pair::distance`] | distance, closest points, leaf pair |
//! | the sphere distance refined to the meshes' triangles near its closest points (ours) | [`Pair::refined_distance`] | distance, closest points on the surfaces, triangles |
//! | first contact from a kinetic front (ours) | [`Pair::contact`] | contact yes/no, a contact, a separation bound |
//! | multipoint (the paper's III-C, or ours from the front) | [`Pair::multipoint`] | up to `k` contacts, one per split-depth node pair |
//! | penetration volume, force, torque, patches (ours) | [`Pair::penetration`] | exact volume of the intersection of the sphere unions |
//! | time-critical penetration volume (ours) | [`Pair::penetration_within`] | volume found within a budget, and an upper bound |
//! | the paper's distance traversal (III-A) and backtracking (III-B) | [`Pair::paper`] | the same as [`Pair::contact`], the seed's baselines |
//!
//! Kinetic front tracking (ours; [`Pair::contact`], [`Pair::penetration`] with [`Tracking`]
//! (automatic by tree size), [`Pair::multipoint`] with `tracking`): the frontier of the
//! overlap traversal is kept from frame to frame and each separated node pair on it is
//! re-tested only once the relative motion since its last test could have closed its
//! separation; its hits are exactly the overlapping leaf pairs.
//!
//! Broad phase and safe motion: every query first rejects on the root spheres, and a query
//! that proved the bodies separated by `d` lets the later traversals skip frames until the
//! relative motion could have closed `d` ([`Pair::safe_separation`]).
//!
//! Inside, imports run one way: `kernel` (pair context, node tests, the 4×4 block step,
//! SIMD with one dispatch point) ← `search` (descents and kinetic fronts) ← one file per
//! query kind, each owning its scratch ← `pair` (the [`Pair`], owning all of it).
//! `docs/ARCHITECTURE.md` maps the files. `brute` (tests only) holds O(n·m) references over all leaf
//! pairs that the tests compare against.

pub mod batch;
mod budgeted;
mod contact;
mod distance;
mod mesh_penetration;
mod multipoint;
mod pair;
mod paper;
mod penetration;
mod refined;
mod search;

// The brute-force references of the tests.
#[cfg(test)]
pub(crate) mod brute;
pub(crate) mod kernel;

pub use batch::BatchOptions;
pub use budgeted::BudgetedVolume;
pub use contact::ContactResult;
pub use distance::{Distance, DistanceOptions};
pub use kernel::geometry::Contact;
// The kernel's types seen by the other crates' tests: not the API.
#[doc(hidden)]
pub use kernel::info::TreeInfo;
#[cfg(test)]
pub(crate) use kernel::lenses::lens_volume;
pub use mesh_penetration::MeshPenetration;
pub use multipoint::{Multipoint, MultipointOptions};
pub use pair::{Pair, Paper, SharedTree};
pub use paper::TraversalOptions;
pub use penetration::{
    ContactStiffness, Patch, Penetration, PenetrationOptions, Tracking, AUTO_FRONT_NODES,
    MAX_STIFFNESS,
};
pub use refined::{RefineOptions, RefinedDistance};
