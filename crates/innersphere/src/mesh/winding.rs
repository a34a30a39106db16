//! The generalized winding number (Jacobson et al. 2013) with fast hierarchical evaluation.
