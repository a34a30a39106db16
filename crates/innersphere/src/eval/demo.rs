//! The built-in demo: a generated pair of interlocking tooth-like bodies, their trees, and the
//! facts of the build — runs on a fresh clone with no files.

use crate::build::{build_tree, BuildOptions, BuildReport};
use crate::progress::Progress;
use crate::{Mesh, Result, SphereTree};

/// The demo's pair of bodies and their trees.
pub struct DemoPair {
    /// Body A (upper tooth) and its tree.
    pub a: (Mesh, SphereTree, BuildReport),
    /// Body B (lower tooth) and its tree.
    pub b: (Mesh, SphereTree, BuildReport),
}

/// Generates the tooth pair (see [`crate::shapes::tooth_pair`]) and builds both trees.
pub fn build_pair(opts: &BuildOptions, progress: &dyn Progress) -> Result<DemoPair> {
    let (ma, mb) = crate::shapes::tooth_pair(5);
    let (ta, ra) = build_tree(&ma, opts, progress)?;
    let (tb, rb) = build_tree(&mb, opts, progress)?;
    Ok(DemoPair {
        a: (ma, ta, ra),
        b: (mb, tb, rb),
    })
}
