//! The tree file format.
