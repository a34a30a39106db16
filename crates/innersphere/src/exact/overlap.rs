//! The depth-first traversal of the node pairs whose bounds overlap, down to the triangle
//! pairs whose boxes overlap: phase one of [`distance`](fn@super::distance), all of
//! [`intersects`](fn@super::intersects), and the crossings of the penetration depth.

use super::frame::{size_sq, tri_box, Frame};
use super::mesh::ExactMesh;
use super::tri_tri::PlaneSides;
use crate::mesh::bvh::LEAF_SIZE;
use glam::DVec3;

/// The corners of a triangle pair against each other's plane (see [`PlaneSides`]), given to
/// the leaf callbacks with the pair: the crossings' exact tests start from them.
#[derive(Debug, Clone, Copy)]
pub(crate) struct PairSides {
    /// B's corners against A's plane.
    pub(crate) b_on_a: PlaneSides,
    /// A's corners against B's plane.
    pub(crate) a_on_b: PlaneSides,
}

/// Traverses all pairs of overlapping boxes and calls `leaf(slot_a, slot_b, tri_a, tri_b,
/// sides)` (B's triangle in A's frame) for every triangle pair whose boxes overlap, until it
/// returns true. Tries `first` before anything else. Returns whether it stopped early.
pub(crate) fn overlap_pairs(
    a: &ExactMesh,
    b: &ExactMesh,
    f: &Frame,
    stack: &mut Vec<(u32, u32, f64)>,
    first: Option<(u32, u32)>,
    mut leaf: impl FnMut(u32, u32, &[DVec3; 3], &[DVec3; 3], &PairSides) -> bool,
) -> bool {
    let (ta, tb) = (a.bvh(), b.bvh());
    if let Some((sa, sb)) = first {
        if let (Some(x), Some(y)) = (ta.tris.get(sa as usize), tb.tris.get(sb as usize)) {
            let y = f.tri(y);
            let sides = PairSides {
                b_on_a: PlaneSides::new(x, &y),
                a_on_b: PlaneSides::new(&y, x),
            };
            if leaf(sa, sb, x, &y, &sides) {
                return true;
            }
        }
    }
    if ta.nodes.is_empty()
        || tb.nodes.is_empty()
        || a.shapes.len() != ta.nodes.len()
        || b.shapes.len() != tb.nodes.len()
    {
        return false;
    }
    stack.clear();
    if f.lower_bound_sq(&a.shapes[0], &b.shapes[0]) > 0.0 {
        return false;
    }
    stack.push((0, 0, 0.0));
    while let Some((ia, ib, _)) = stack.pop() {
        let na = &ta.nodes[ia as usize];
        let nb = &tb.nodes[ib as usize];
        match (na.is_leaf(), nb.is_leaf()) {
            (true, true) => {
                if leaf_pair(a, b, f, ia, ib, &mut leaf) {
                    stack.clear();
                    return true;
                }
            }
            _ => split_pair(a, b, f, ia, ib, |x, y, lb| {
                if lb <= 0.0 {
                    stack.push((x, y, 0.0));
                }
            }),
        }
    }
    false
}

/// The triangle pairs of the leaf pair (`ia` of A, `ib` of B) whose boxes overlap and whose
/// planes do not separate them, given to `leaf(slot_a, slot_b, tri_a, tri_b, sides)` (B's triangle
/// in A's frame) until it returns true. Returns whether it stopped early.
#[inline]
pub(super) fn leaf_pair(
    a: &ExactMesh,
    b: &ExactMesh,
    f: &Frame,
    ia: u32,
    ib: u32,
    leaf: &mut impl FnMut(u32, u32, &[DVec3; 3], &[DVec3; 3], &PairSides) -> bool,
) -> bool {
    let (ta, tb) = (a.bvh(), b.bvh());
    let (na, nb) = (&ta.nodes[ia as usize], &tb.nodes[ib as usize]);
    let (sa0, ca) = (na.start as usize, na.count as usize);
    let (sb0, cb) = (nb.start as usize, nb.count as usize);
    let (Some(ta_all), Some(tb_all)) = (ta.tris.get(sa0..sa0 + ca), tb.tris.get(sb0..sb0 + cb))
    else {
        return false;
    };
    let mut tb_buf = [[DVec3::ZERO; 3]; LEAF_SIZE];
    let mut bb = [(DVec3::ZERO, DVec3::ZERO); LEAF_SIZE];
    for (ci, chunk) in tb_all.chunks(LEAF_SIZE).enumerate() {
        for (j, t) in chunk.iter().enumerate() {
            tb_buf[j] = f.tri(t);
            bb[j] = tri_box(&tb_buf[j]);
        }
        for (i, x) in ta_all.iter().enumerate() {
            let (alo, ahi) = tri_box(x);
            for j in 0..chunk.len() {
                let (blo, bhi) = bb[j];
                if (alo - bhi).max(blo - ahi).max_element() > 0.0 {
                    continue;
                }
                let y = &tb_buf[j];
                let b_on_a = PlaneSides::new(x, y);
                if b_on_a.separates() {
                    continue;
                }
                let a_on_b = PlaneSides::new(y, x);
                if a_on_b.separates() {
                    continue;
                }
                let sb = (sb0 + ci * LEAF_SIZE + j) as u32;
                let sides = PairSides { b_on_a, a_on_b };
                if leaf((sa0 + i) as u32, sb, x, y, &sides) {
                    return true;
                }
            }
        }
    }
    false
}

/// The children to visit next of the internal pair (`ia`, `ib`): the larger node is split
/// (A's when B's is a leaf, B's when A's is), each child pair given to `visit` with the
/// squared lower bound of its distance (> 0: apart).
#[inline]
pub(super) fn split_pair(
    a: &ExactMesh,
    b: &ExactMesh,
    f: &Frame,
    ia: u32,
    ib: u32,
    mut visit: impl FnMut(u32, u32, f64),
) {
    let (na, nb) = (&a.bvh().nodes[ia as usize], &b.bvh().nodes[ib as usize]);
    if !na.is_leaf() && (nb.is_leaf() || size_sq(na) >= size_sq(nb)) {
        let sb = f.shape(&b.shapes[ib as usize]);
        for x in [na.start, ia + 1] {
            visit(x, ib, sb.lower_bound_sq(&a.shapes[x as usize], f.pad));
        }
    } else {
        let sa = &a.shapes[ia as usize];
        for y in [nb.start, ib + 1] {
            visit(ia, y, f.lower_bound_sq(sa, &b.shapes[y as usize]));
        }
    }
}
