//! The defect report of a mesh (what `ist inspect` prints).
