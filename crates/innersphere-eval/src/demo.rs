//! The built-in demo: a generated pair of interlocking tooth-like bodies, their trees, a
//! generated chewing motion replayed frame by frame through every query kind — runs on a fresh
//! clone with no files.

use innersphere::build::{build_tree, BuildOptions, BuildReport};
use innersphere::progress::Progress;
use innersphere::{Mesh, Result, SharedTree};

/// The demo's pair of bodies and their trees.
pub struct DemoPair {
    /// Body A (upper tooth) and its tree.
    pub a: (Mesh, SharedTree, BuildReport),
    /// Body B (lower tooth) and its tree.
    pub b: (Mesh, SharedTree, BuildReport),
}

/// Subdivisions of the demo's generated tooth pair ([`innersphere::shapes::tooth_pair`]).
pub const TOOTH_SUBDIVISIONS: u32 = 5;

/// Generates the tooth pair (see [`innersphere::shapes::tooth_pair`]) and builds both trees.
pub fn build_pair(opts: &BuildOptions, progress: &dyn Progress) -> Result<DemoPair> {
    let (ma, mb) = innersphere::shapes::tooth_pair(TOOTH_SUBDIVISIONS);
    build_pair_from(ma, mb, opts, progress)
}

/// Builds the trees of a given pair of meshes (A fixed, B moved by the motion).
pub fn build_pair_from(
    ma: Mesh,
    mb: Mesh,
    opts: &BuildOptions,
    progress: &dyn Progress,
) -> Result<DemoPair> {
    let (ta, ra) = build_tree(&ma, opts, progress)?;
    let (tb, rb) = build_tree(&mb, opts, progress)?;
    Ok(DemoPair {
        a: (ma, SharedTree::new(ta), ra),
        b: (mb, SharedTree::new(tb), rb),
    })
}

/// The demo's motion of `b` against `a`: a chewing motion of `seconds` (seed 1). It needs
/// only the meshes, so a pair that admits no motion (the same body twice, bodies that never
/// meet) fails here, before any tree is built.
pub fn motion_for(a: &Mesh, b: &Mesh, seconds: f64) -> Result<crate::motion::Motion> {
    crate::motion::generate(crate::motion::Scenario::Chew, seconds, 1, a, b)
}

/// Generates a chewing motion of `seconds` for the pair (seed 1) and replays it through every
/// query kind, with the exact mesh distance as reference on every 10th frame.
pub fn replay_pair(pair: &DemoPair, seconds: f64) -> Result<crate::replay::ReplayReport> {
    let motion = motion_for(&pair.a.0, &pair.b.0, seconds)?;
    replay_motion(pair, &motion)
}

/// Replays `motion` through every query kind, the distance refined to the meshes among
/// them, with the exact mesh distance as reference on every 10th frame.
pub fn replay_motion(
    pair: &DemoPair,
    motion: &crate::motion::Motion,
) -> Result<crate::replay::ReplayReport> {
    let ea = std::sync::Arc::new(innersphere::exact::ExactMesh::new(&pair.a.0)?);
    let eb = std::sync::Arc::new(innersphere::exact::ExactMesh::new(&pair.b.0)?);
    let ta = pair.a.1.clone().with_exact_mesh(ea.clone())?;
    let tb = pair.b.1.clone().with_exact_mesh(eb.clone())?;
    let opts = crate::replay::ReplayOptions {
        kinds: crate::replay::QueryKind::WITH_REFINED.to_vec(),
        every: 10,
        ..Default::default()
    };
    Ok(crate::replay::replay(
        &ta,
        &tb,
        motion,
        Some((&ea, &eb)),
        &opts,
    ))
}
