//! Per-tree facts the queries need beyond the tree itself, computed once per tree.

use crate::tree::SphereTree;
use glam::DVec3;

/// One node in the queries' packed layout: everything a traversal reads about a node in one
/// 32-byte record, so that the children of a node (contiguous) share one or two cache lines.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
#[repr(C, align(32))]
pub(crate) struct Node {
    pub x: f32,
    pub y: f32,
    pub z: f32,
    pub r: f32,
    /// First child (0 for leaves).
    pub first: u32,
    /// Number of children; 0 for leaves.
    pub count: u32,
    /// Parent (`NO_PARENT` for the root).
    pub parent: u32,
    /// Depth below the root.
    pub depth: u32,
}

impl Node {
    #[inline(always)]
    pub(crate) fn is_leaf(&self) -> bool {
        self.count == 0
    }
}

/// Lanes of a [`Block`]: the children of a node side by side, for fan-outs up to 4.
pub(crate) const LANES: usize = 4;

/// An inner node's children side by side (structure of arrays, the spheres in the first
/// cache line, what to descend to in the second), so that a traversal tests all children of
/// one node against all children of another in one vectorised 4×4 step instead of one
/// branchy test per pair. Unused lanes have radius −∞ (never refined).
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C, align(64))]
pub(crate) struct Block {
    pub x: [f32; LANES],
    pub y: [f32; LANES],
    pub z: [f32; LANES],
    pub r: [f32; LANES],
    /// Per child: its block index when it is an inner node, its node index when a leaf.
    pub child: [u32; LANES],
    /// Per child: its node index.
    pub node: [u32; LANES],
    /// Bit `k` set when child `k` is a leaf.
    pub leaf: u32,
    /// Number of children.
    pub count: u32,
}

impl Block {
    /// A block with no children: every lane unused (radius −∞, never refined).
    pub(crate) const EMPTY: Block = Block {
        x: [0.0; LANES],
        y: [0.0; LANES],
        z: [0.0; LANES],
        r: [f32::NEG_INFINITY; LANES],
        child: [0; LANES],
        node: [0; LANES],
        leaf: 0,
        count: 0,
    };

    /// Test block of `count` children with spheres `v[4k..4k + 4]` (radius `|v[4k + 3]|`) and
    /// leaf bits `leaf`.
    #[cfg(test)]
    pub(crate) fn from_spheres(v: &[f32], leaf: u32, count: u32) -> Block {
        let mut k = Block {
            leaf: leaf & ((1 << count) - 1),
            count,
            ..Block::EMPTY
        };
        for l in 0..count as usize {
            (k.x[l], k.y[l], k.z[l], k.r[l]) =
                (v[4 * l], v[4 * l + 1], v[4 * l + 2], v[4 * l + 3].abs());
        }
        k
    }
}

/// Query-side facts about one tree, computed once ([`TreeInfo::new`], O(nodes)) and shared
/// by every [`Pair`](crate::Pair) that involves the tree (through a [`SharedTree`](crate::SharedTree)).
#[derive(Debug, Clone)]
pub struct TreeInfo {
    /// Number of nodes of the tree it was made for.
    pub nodes: usize,
    /// Number of leaves (inner spheres).
    pub leaves: usize,
    /// Largest node depth.
    pub max_depth: u16,
    /// Largest child count of any node.
    pub max_children: usize,
    /// Centre of the root sphere (model frame).
    pub root_center: DVec3,
    /// Largest distance of any point of any leaf sphere from the root centre (≤ root radius):
    /// the body radius of the safe-motion bound.
    pub radius: f64,
    /// Largest `|c| + r` of any node (model frame), for the f32 rounding slack.
    pub extent: f32,
    /// Median leaf radius: the scale a traversal resolves (far poses, where the f32 rounding
    /// of B's transform approaches it, are answered in f64: `kernel/far.rs`).
    pub median_leaf_radius: f64,
    /// Centre of mass of the mesh (model frame), for torques.
    pub center_of_mass: DVec3,
    /// Total volume of the leaf spheres below each node (rounded up to f32), the
    /// time-critical query's per-node upper bound on any intersection volume.
    pub subtree_volume: Vec<f32>,
    /// The tree's nodes in the packed layout the traversals read (same f32 values).
    pub(crate) packed: Vec<Node>,
    /// One [`Block`] per inner node, in node order (the root's is block 0); empty when some
    /// node has more than [`LANES`] children.
    pub(crate) blocks: Vec<Block>,
    /// Block index of every inner node (`u32::MAX` for leaves; empty with `blocks`).
    pub(crate) block_of: Vec<u32>,
}

/// Rounds a non-negative f64 up to the next f32.
fn f32_up(v: f64) -> f32 {
    let f = v as f32;
    if (f as f64) < v {
        f32::from_bits(f.to_bits() + 1)
    } else {
        f
    }
}

impl TreeInfo {
    /// Computes the facts of `tree`.
    pub fn new(tree: &SphereTree) -> TreeInfo {
        let n = tree.len();
        let mut vol = vec![0.0f64; n];
        for i in (0..n).rev() {
            if tree.is_leaf(i) {
                let r = tree.r[i] as f64;
                vol[i] = 4.0 / 3.0 * std::f64::consts::PI * r * r * r;
            } else {
                vol[i] = tree.children(i).map(|c| vol[c]).sum();
            }
        }
        let (root_center, _) = tree.sphere(0);
        let root_center = root_center.as_dvec3();
        let mut radius = 0.0f64;
        let mut extent = 0.0f32;
        let mut leaf_radii = Vec::with_capacity(tree.leaf_count());
        for i in 0..n {
            let (c, r) = tree.sphere(i);
            extent = extent.max(c.length() + r);
            if tree.is_leaf(i) {
                radius = radius.max((c.as_dvec3() - root_center).length() + r as f64);
                leaf_radii.push(r);
            }
        }
        let median_leaf_radius = if leaf_radii.is_empty() {
            0.0
        } else {
            let mid = leaf_radii.len() / 2;
            *leaf_radii.select_nth_unstable_by(mid, f32::total_cmp).1 as f64
        };
        let max_children = tree.child_count.iter().copied().max().unwrap_or(0) as usize;
        let (blocks, block_of) = if max_children <= LANES {
            // Block index of every inner node: its rank among the inner nodes.
            let mut rank = vec![u32::MAX; n];
            let mut next = 0u32;
            for (i, r) in rank.iter_mut().enumerate() {
                if !tree.is_leaf(i) {
                    *r = next;
                    next += 1;
                }
            }
            let mut blocks = Vec::with_capacity(next as usize);
            for i in (0..n).filter(|&i| !tree.is_leaf(i)) {
                let mut b = Block {
                    count: tree.child_count[i] as u32,
                    ..Block::EMPTY
                };
                for (k, ch) in tree.children(i).enumerate() {
                    b.x[k] = tree.x[ch];
                    b.y[k] = tree.y[ch];
                    b.z[k] = tree.z[ch];
                    b.r[k] = tree.r[ch];
                    b.node[k] = ch as u32;
                    if tree.is_leaf(ch) {
                        b.leaf |= 1 << k;
                        b.child[k] = ch as u32;
                    } else {
                        b.child[k] = rank[ch];
                    }
                }
                blocks.push(b);
            }
            (blocks, rank)
        } else {
            (Vec::new(), Vec::new())
        };
        TreeInfo {
            nodes: n,
            leaves: tree.leaf_count(),
            max_depth: tree.max_depth(),
            max_children,
            root_center,
            radius,
            extent,
            median_leaf_radius,
            center_of_mass: DVec3::from_array(tree.meta.center_of_mass),
            subtree_volume: vol.into_iter().map(f32_up).collect(),
            packed: (0..n)
                .map(|i| Node {
                    x: tree.x[i],
                    y: tree.y[i],
                    z: tree.z[i],
                    r: tree.r[i],
                    first: if tree.is_leaf(i) {
                        0
                    } else {
                        tree.first_child[i]
                    },
                    count: tree.child_count[i] as u32,
                    parent: tree.parent[i],
                    depth: tree.depth[i] as u32,
                })
                .collect(),
            blocks,
            block_of,
        }
    }
}
