//! How the query kinds find overlapping node pairs, above the kernel: depth-first descents
//! from a node pair (the paper's traversal order, on blocks where the fan-out allows), and
//! the two kinetic fronts that carry a traversal's frontier from frame to frame. Imports only
//! from [`kernel`](super::kernel).

pub(crate) mod block_front;
pub(crate) mod descent;
pub(crate) mod front;
