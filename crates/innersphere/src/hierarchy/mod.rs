//! The hierarchy over the inner spheres: top-down batch neural gas clustering ([`bng`]),
//! minimal enclosing spheres ([`enclosing`]) and the flat breadth-first layout
//! ([`Hierarchy`]) that the build's tree stage turns into a
//! [`SphereTree`](crate::tree::SphereTree) with its meta.
//!
//! Every node is split into at most `fanout` groups by BNG until each leaf holds exactly one
//! inner sphere (no depth cap). A node's sphere is the minimal sphere enclosing the leaf
//! spheres below it (or its children's spheres, where that is smaller): every node encloses
//! every leaf below it, which is what the queries rely on, but not necessarily its children's
//! spheres. Spheres are rounded to f32 conservatively: leaves shrink (they stay inside the
//! mesh and disjoint), parents are computed from the rounded leaves and rounded up (they
//! still enclose them).

pub(crate) mod bng;
pub(crate) mod enclosing;

use crate::packing::Sphere;
use crate::tree::NO_PARENT;
use enclosing::Ball;
use glam::DVec3;

/// Options of the hierarchy.
#[derive(Debug, Clone, Copy)]
pub struct HierarchyOptions {
    /// Maximum children per inner node (2..=32).
    pub fanout: u32,
    /// BNG settings.
    pub bng: bng::BngOptions,
}

impl Default for HierarchyOptions {
    fn default() -> Self {
        HierarchyOptions {
            fanout: 4,
            bng: bng::BngOptions::default(),
        }
    }
}

/// Facts about a built hierarchy.
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct HierarchyStats {
    /// Mean over inner nodes of (node radius / exact minimal radius enclosing its children),
    /// the exact value from subset enumeration; below 1 where the sphere around the leaves
    /// below is smaller than any sphere around the children.
    pub enclosing_ratio_mean: f64,
    /// Largest such ratio.
    pub enclosing_ratio_max: f64,
    /// Inner nodes whose split fell back to a median split because BNG put every sphere in
    /// one group.
    pub fallback_splits: usize,
}

/// The clustered spheres: the hierarchy's nodes laid out breadth-first in flat `f32` arrays,
/// as a [`SphereTree`](crate::tree::SphereTree) holds them (see there for their meaning),
/// and facts about the clustering.
#[derive(Debug, Clone)]
pub(crate) struct Hierarchy {
    /// Sphere centre x of each node.
    pub x: Vec<f32>,
    /// Sphere centre y of each node.
    pub y: Vec<f32>,
    /// Sphere centre z of each node.
    pub z: Vec<f32>,
    /// Sphere radius of each node.
    pub r: Vec<f32>,
    /// Index of the first child (0 for leaves).
    pub first_child: Vec<u32>,
    /// Number of children; 0 for leaves.
    pub child_count: Vec<u8>,
    /// Parent index; [`NO_PARENT`] for the root.
    pub parent: Vec<u32>,
    /// Depth below the root (root = 0).
    pub depth: Vec<u16>,
    /// How tight the enclosing spheres are, and how often BNG fell back.
    pub stats: HierarchyStats,
}

impl Hierarchy {
    /// Number of nodes.
    pub(crate) fn len(&self) -> usize {
        self.r.len()
    }
}

/// A node of the tree while it is being built (f64, pointer-free recursion result).
struct Draft {
    ball: Ball,
    children: Vec<Draft>,
}

/// Clusters `spheres` into the hierarchy and lays it out breadth-first: every leaf is one of
/// `spheres` (rounded to `f32` inside it), every inner node's sphere encloses the leaves
/// below it. Refuses an empty sphere set and a fan-out outside `2..=32`.
pub(crate) fn cluster(
    spheres: &[Sphere],
    opts: &HierarchyOptions,
    progress: &dyn crate::progress::Progress,
) -> crate::error::Result<Hierarchy> {
    if spheres.is_empty() {
        return Err(crate::error::Error::InvalidMesh(
            "no inner sphere could be placed (the mesh encloses no volume at this voxel size)"
                .into(),
        ));
    }
    if !(2..=bng::MAX_PROTOTYPES as u32).contains(&opts.fanout) {
        return Err(crate::error::Error::InvalidOption(format!(
            "fanout must be between 2 and {}, got {}",
            bng::MAX_PROTOTYPES,
            opts.fanout
        )));
    }
    progress.start("clustering (BNG)", spheres.len() as u64);
    // Leaf balls rounded to f32 conservatively first; all enclosing happens on those.
    let leaves: Vec<Ball> = spheres
        .iter()
        .map(|s| round_leaf(s.center, s.radius))
        .collect();
    let mut idx: Vec<u32> = (0..spheres.len() as u32).collect();
    let fallbacks = std::sync::atomic::AtomicUsize::new(0);
    let root = split(&leaves, &mut idx, opts, progress, &fallbacks, 0);
    progress.finish();
    let mut h = flatten(root);
    h.stats.fallback_splits = fallbacks.into_inner();
    Ok(h)
}

/// Rounds a leaf sphere to f32 so that the rounded sphere lies inside the original one.
fn round_leaf(c: DVec3, r: f64) -> Ball {
    let c32 = c.as_vec3().as_dvec3();
    let shrunk = r - (c32 - c).length();
    let mut r32 = shrunk.max(0.0) as f32;
    while r32 > 0.0 && r32 as f64 > shrunk {
        r32 = r32.next_down();
    }
    (c32, r32 as f64)
}

/// Rounds an enclosing sphere of `balls` to f32 so that it still encloses them.
fn round_parent(c: DVec3, balls: &[Ball]) -> Ball {
    let c32 = c.as_vec3().as_dvec3();
    let need = balls
        .iter()
        .map(|b| (b.0 - c32).length() + b.1)
        .fold(0.0, f64::max);
    let mut r32 = need as f32;
    while (r32 as f64) < need {
        r32 = r32.next_up();
    }
    (c32, r32 as f64)
}

/// Below this depth BNG splits; deeper (only reached by degenerate, lopsided clusterings)
/// balanced median splits take over, so the depth stays bounded.
const MAX_BNG_DEPTH: u32 = 40;

/// Parallelism threshold: subtrees with fewer spheres are built on one thread.
const PAR_MIN: usize = 2048;

fn split(
    leaves: &[Ball],
    idx: &mut [u32],
    opts: &HierarchyOptions,
    progress: &dyn crate::progress::Progress,
    fallbacks: &std::sync::atomic::AtomicUsize,
    depth: u32,
) -> Draft {
    if idx.len() == 1 {
        progress.advance(1);
        return Draft {
            ball: leaves[idx[0] as usize],
            children: Vec::new(),
        };
    }
    let k = opts.fanout as usize;
    // Group boundaries within idx after partitioning.
    let mut bounds: Vec<usize> = Vec::with_capacity(k + 1);
    if idx.len() <= k {
        bounds.extend(0..=idx.len());
    } else {
        let points: Vec<DVec3> = idx.iter().map(|&i| leaves[i as usize].0).collect();
        let weights: Vec<f64> = idx
            .iter()
            .map(|&i| leaves[i as usize].1.powi(3).max(1e-300))
            .collect();
        let labels = bng::cluster(&points, &weights, k, &opts.bng);
        let mut order: Vec<(u8, u32)> = labels.iter().copied().zip(idx.iter().copied()).collect();
        order.sort_by_key(|&(l, _)| l); // stable: keeps the input order within a group
        for (slot, &(_, i)) in idx.iter_mut().zip(&order) {
            *slot = i;
        }
        bounds.push(0);
        for w in 1..order.len() {
            if order[w].0 != order[w - 1].0 {
                bounds.push(w);
            }
        }
        bounds.push(order.len());
        if bounds.len() == 2 || depth >= MAX_BNG_DEPTH {
            // BNG found one group only (e.g. identical centres), or the tree is already
            // suspiciously deep (a degenerate chain of lopsided splits): median split along
            // the longest axis, k groups of (nearly) equal size, to guarantee progress and a
            // logarithmic depth from here on.
            fallbacks.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            let (lo, hi) = idx.iter().fold(
                (DVec3::splat(f64::MAX), DVec3::splat(f64::MIN)),
                |(l, h), &i| (l.min(leaves[i as usize].0), h.max(leaves[i as usize].0)),
            );
            let axis = (hi - lo).max_position();
            idx.sort_by(|&a, &b| {
                leaves[a as usize].0[axis]
                    .total_cmp(&leaves[b as usize].0[axis])
                    .then(a.cmp(&b))
            });
            bounds.clear();
            let n = idx.len();
            bounds.extend((0..=k).map(|g| g * n / k));
            bounds.dedup();
        }
    }
    // Recurse into the groups (in parallel for big ones; results keep group order).
    let mut groups: Vec<&mut [u32]> = Vec::with_capacity(bounds.len() - 1);
    let mut rest = &mut idx[..];
    let mut taken = 0;
    for w in bounds.windows(2) {
        let (g, r) = rest.split_at_mut(w[1] - taken);
        taken = w[1];
        groups.push(g);
        rest = r;
    }
    let children: Vec<Draft> = if groups.iter().map(|g| g.len()).sum::<usize>() >= PAR_MIN {
        use rayon::prelude::*;
        groups
            .into_par_iter()
            .map(|g| split(leaves, g, opts, progress, fallbacks, depth + 1))
            .collect()
    } else {
        groups
            .into_iter()
            .map(|g| split(leaves, g, opts, progress, fallbacks, depth + 1))
            .collect()
    };
    // The node's sphere: the smaller of the minimal sphere around the children's spheres and
    // the minimal sphere around the leaf spheres below (both enclose every leaf, which is all
    // the queries need). Children's spheres bulge beyond their leaves, and the bulges add up
    // level by level: on the jaw trees the leaf-based sphere is 10–25 % smaller at depths
    // 2–7, and the queries refine 2.5–5× fewer node pairs.
    let balls: Vec<Ball> = children.iter().map(|c| c.ball).collect();
    let (c, _) = enclosing::enclose(&balls);
    let by_children = round_parent(c, &balls);
    let below: Vec<Ball> = idx.iter().map(|&i| leaves[i as usize]).collect();
    let (c, _) = enclosing::enclose(&below);
    let by_leaves = round_parent(c, &below);
    Draft {
        ball: if by_leaves.1 < by_children.1 {
            by_leaves
        } else {
            by_children
        },
        children,
    }
}

/// Lays the draft tree out breadth-first into flat arrays; also measures how tight the
/// enclosing spheres are (against exact subset enumeration, for nodes with ≤ 8 children).
fn flatten(root: Draft) -> Hierarchy {
    let mut t = Hierarchy {
        x: Vec::new(),
        y: Vec::new(),
        z: Vec::new(),
        r: Vec::new(),
        first_child: Vec::new(),
        child_count: Vec::new(),
        parent: Vec::new(),
        depth: Vec::new(),
        stats: HierarchyStats::default(),
    };
    let push = |t: &mut Hierarchy, b: Ball, parent: u32, depth: u16| {
        t.x.push(b.0.x as f32);
        t.y.push(b.0.y as f32);
        t.z.push(b.0.z as f32);
        t.r.push(b.1 as f32);
        t.first_child.push(0);
        t.child_count.push(0);
        t.parent.push(parent);
        t.depth.push(depth);
    };
    push(&mut t, root.ball, NO_PARENT, 0);
    let mut queue = std::collections::VecDeque::new();
    queue.push_back((0usize, root));
    while let Some((n, draft)) = queue.pop_front() {
        if draft.children.is_empty() {
            continue;
        }
        t.first_child[n] = t.len() as u32;
        t.child_count[n] = draft.children.len() as u8;
        let depth = t.depth[n] + 1;
        for child in draft.children {
            let id = t.len();
            push(&mut t, child.ball, n as u32, depth);
            queue.push_back((id, child));
        }
    }
    (t.stats.enclosing_ratio_mean, t.stats.enclosing_ratio_max) = enclosing_ratios(&t);
    t
}

/// The mean and largest ratio of an inner node's radius to the exact minimal radius
/// enclosing its children (nodes of at most 8 children, by subset enumeration, on all
/// threads; summed in node order). The tree's f32 spheres are the draft's, which were
/// rounded to f32 already.
fn enclosing_ratios(t: &Hierarchy) -> (f64, f64) {
    use rayon::prelude::*;
    let ball = |n: usize| -> Ball {
        (
            DVec3::new(f64::from(t.x[n]), f64::from(t.y[n]), f64::from(t.z[n])),
            f64::from(t.r[n]),
        )
    };
    let ratios: Vec<f64> = (0..t.len())
        .into_par_iter()
        .filter_map(|n| {
            let count = usize::from(t.child_count[n]);
            if count == 0 || count > 8 {
                return None;
            }
            let first = t.first_child[n] as usize;
            let balls: Vec<Ball> = (first..first + count).map(ball).collect();
            let exact = enclosing::enclose_brute_force(&balls).1;
            (exact > 0.0).then(|| ball(n).1 / exact)
        })
        .collect();
    if ratios.is_empty() {
        return (1.0, 1.0);
    }
    let max = ratios.iter().copied().fold(1.0f64, f64::max);
    (ratios.iter().sum::<f64>() / ratios.len() as f64, max)
}
