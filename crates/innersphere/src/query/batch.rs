//! Many poses at once on all cores: [`distance_many`], [`refined_distance_many`],
//! [`contact_many`], [`penetration_many`], [`mesh_penetration_many`] and the generic [`map`].
//!
//! The poses of B are cut into fixed chunks of [`BatchOptions::chunk`] poses. Each chunk
//! starts from a fresh state ([`Pair::reset`]) and carries the temporal coherence from pose
//! to pose within the chunk, as a haptic loop or `ist replay` would; the chunks run on the
//! worker threads, each worker with a [`Pair`] of its own over the same shared trees. The
//! answers therefore depend on the poses and the chunk size only, never on the number of
//! threads: the same bits on 1 thread as on 64, in input order. (Distance and first contact
//! do not depend on the state at all; the penetration volume's last bits can, through the
//! order of its sums.)

use super::refined::missing_meshes;
use super::{
    ContactResult, Distance, MeshPenetration, Pair, Penetration, PenetrationOptions, RefineOptions,
    RefinedDistance, SharedTree,
};
use crate::error::{Error, Result};
use crate::pose::Pose;
use rayon::prelude::*;

/// How a batch is spread over threads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BatchOptions {
    /// Worker threads; 0 = rayon's global pool (all cores, or `RAYON_NUM_THREADS`).
    pub threads: usize,
    /// Poses per chunk: each chunk starts from a fresh state. 1 answers every pose from a
    /// fresh state (random poses gain nothing from coherence); a motion gains from long
    /// chunks. At least 1.
    pub chunk: usize,
}

/// Most worker threads a batch accepts.
pub const MAX_THREADS: usize = 4096;

impl Default for BatchOptions {
    /// All cores, chunks of 1024 poses.
    fn default() -> Self {
        BatchOptions {
            threads: 0,
            chunk: 1024,
        }
    }
}

impl BatchOptions {
    /// Refuses a chunk of 0 poses and more than [`MAX_THREADS`] threads.
    pub fn validate(&self) -> Result<()> {
        if self.chunk == 0 {
            return Err(Error::InvalidOption("chunk must be at least 1 pose".into()));
        }
        if self.threads > MAX_THREADS {
            return Err(Error::InvalidOption(format!(
                "threads must be at most {MAX_THREADS} (0 = all cores), not {}",
                self.threads
            )));
        }
        Ok(())
    }
}

/// `query(pair, pose_a, pose_b)` for each pose of B in `poses_b`, in order, over the chunks
/// and threads of `opts` (module docs). `poses_a` holds one pose of A for all, or one per
/// pose of B. Fails for bad options or a `poses_a` of another length.
pub fn map<T, F>(
    a: &SharedTree,
    b: &SharedTree,
    poses_a: &[Pose],
    poses_b: &[Pose],
    opts: &BatchOptions,
    query: F,
) -> Result<Vec<T>>
where
    T: Send,
    F: Fn(&mut Pair, &Pose, &Pose) -> T + Sync,
{
    opts.validate()?;
    if poses_a.len() != 1 && poses_a.len() != poses_b.len() {
        return Err(Error::InvalidOption(format!(
            "{} poses of A for {} poses of B: give one, or one per pose of B",
            poses_a.len(),
            poses_b.len()
        )));
    }
    let pose_a = |i: usize| &poses_a[if poses_a.len() == 1 { 0 } else { i }];
    let run = || -> Vec<T> {
        let chunks: Vec<Vec<T>> = poses_b
            .par_chunks(opts.chunk)
            .enumerate()
            .map_init(
                || Pair::new(a.clone(), b.clone()),
                |pair, (c, chunk)| {
                    pair.reset();
                    let first = c * opts.chunk;
                    chunk
                        .iter()
                        .enumerate()
                        .map(|(k, pb)| query(pair, pose_a(first + k), pb))
                        .collect()
                },
            )
            .collect();
        chunks.into_iter().flatten().collect()
    };
    if opts.threads == 0 {
        return Ok(run());
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(opts.threads)
        .build()
        .map_err(|e| Error::InvalidOption(format!("cannot start {} threads: {e}", opts.threads)))?;
    Ok(pool.install(run))
}

/// [`Pair::distance`] for each pose of B ([`map`]).
pub fn distance_many(
    a: &SharedTree,
    b: &SharedTree,
    poses_a: &[Pose],
    poses_b: &[Pose],
    opts: &BatchOptions,
) -> Result<Vec<Distance>> {
    map(a, b, poses_a, poses_b, opts, |p, pa, pb| p.distance(pa, pb))
}

/// [`Pair::refined_distance_with`] for each pose of B ([`map`]): the distance between the
/// meshes, for accuracy sweeps and data sets. Fails up front, before any query, for bad
/// options or trees without their meshes ([`SharedTree::with_mesh`]).
pub fn refined_distance_many(
    a: &SharedTree,
    b: &SharedTree,
    poses_a: &[Pose],
    poses_b: &[Pose],
    query: &RefineOptions,
    opts: &BatchOptions,
) -> Result<Vec<RefinedDistance>> {
    query.check()?;
    if a.mesh().is_none() || b.mesh().is_none() {
        return Err(missing_meshes("the refined distance"));
    }
    map(a, b, poses_a, poses_b, opts, |p, pa, pb| {
        p.refined_distance_with(pa, pb, query)
    })?
    .into_iter()
    .collect()
}

/// [`Pair::contact`] for each pose of B ([`map`]).
pub fn contact_many(
    a: &SharedTree,
    b: &SharedTree,
    poses_a: &[Pose],
    poses_b: &[Pose],
    opts: &BatchOptions,
) -> Result<Vec<ContactResult>> {
    map(a, b, poses_a, poses_b, opts, |p, pa, pb| p.contact(pa, pb))
}

/// [`Pair::penetration_with`] for each pose of B ([`map`]).
pub fn penetration_many(
    a: &SharedTree,
    b: &SharedTree,
    poses_a: &[Pose],
    poses_b: &[Pose],
    query: &PenetrationOptions,
    opts: &BatchOptions,
) -> Result<Vec<Penetration>> {
    map(a, b, poses_a, poses_b, opts, |p, pa, pb| {
        p.penetration_with(pa, pb, query)
    })
}

/// [`Pair::mesh_penetration_with`] for each pose of B ([`map`]): the meshes' own penetration,
/// for accuracy sweeps and data sets. Fails up front, before any query, for bad options or
/// trees without their meshes ([`SharedTree::with_mesh`]). The patches of a batch are not
/// kept.
pub fn mesh_penetration_many(
    a: &SharedTree,
    b: &SharedTree,
    poses_a: &[Pose],
    poses_b: &[Pose],
    query: &PenetrationOptions,
    opts: &BatchOptions,
) -> Result<Vec<MeshPenetration>> {
    query.check()?;
    if a.mesh().is_none() || b.mesh().is_none() {
        return Err(missing_meshes("the meshes' penetration"));
    }
    map(a, b, poses_a, poses_b, opts, |p, pa, pb| {
        p.mesh_penetration_with(pa, pb, query)
    })?
    .into_iter()
    .collect()
}
