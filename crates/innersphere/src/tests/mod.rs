//! The crate's tests that need its internal stages: the brute-force references of the
//! queries (`query::brute`), the field, packing and hierarchy stages, the triangle tests of
//! `exact`. Tests of the public API alone live in `tests/`.
//!
//! A proptest failure is saved under `proptest-regressions/tests/`.

#[path = "../../../innersphere-testkit/src/data.rs"]
mod data;
#[path = "../../tests/it/query_util/mod.rs"]
mod query_util;
mod reference;

mod check_negative;
mod exact_bvh;
mod exact_real;
mod exact_tri;
mod field;
mod packing_hierarchy;
mod query_boundary;
mod query_penetration;
mod query_proximity;
mod query_real;
mod query_reference;
mod query_refined;
mod query_safe_motion;
mod query_traversal;
