//! The depth-first traversal of the node pairs whose bounds overlap, down to the triangle
//! pairs whose boxes overlap: phase one of [`distance`](fn@super::distance), all of
//! [`intersects`](fn@super::intersects), and the crossings of the penetration depth.

use super::frame::{size_sq, tri_box, Frame};
use super::mesh::ExactMesh;
use super::tri_tri;
use crate::mesh::bvh::LEAF_SIZE;
use glam::DVec3;

/// Traverses all pairs of overlapping boxes and calls `leaf(slot_a, slot_b, tri_a, tri_b)`
/// (B's triangle in A's frame) for every triangle pair whose boxes overlap, until it returns
/// true. Tries `first` before anything else. Returns whether it stopped early.
pub(crate) fn overlap_pairs(
    a: &ExactMesh,
    b: &ExactMesh,
    f: &Frame,
    stack: &mut Vec<(u32, u32, f64)>,
    first: Option<(u32, u32)>,
    mut leaf: impl FnMut(u32, u32, &[DVec3; 3], &[DVec3; 3]) -> bool,
) -> bool {
    let (ta, tb) = (a.bvh(), b.bvh());
    if let Some((sa, sb)) = first {
        if let (Some(x), Some(y)) = (ta.tris.get(sa as usize), tb.tris.get(sb as usize)) {
            if leaf(sa, sb, x, &f.tri(y)) {
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
    let mut tb_buf = [[DVec3::ZERO; 3]; LEAF_SIZE];
    let mut bb = [(DVec3::ZERO, DVec3::ZERO); LEAF_SIZE];
    while let Some((ia, ib, _)) = stack.pop() {
        let na = &ta.nodes[ia as usize];
        let nb = &tb.nodes[ib as usize];
        match (na.is_leaf(), nb.is_leaf()) {
            (true, true) => {
                let (sa0, ca) = (na.start as usize, na.count as usize);
                let (sb0, cb) = (nb.start as usize, nb.count as usize);
                let (Some(ta_all), Some(tb_all)) =
                    (ta.tris.get(sa0..sa0 + ca), tb.tris.get(sb0..sb0 + cb))
                else {
                    continue;
                };
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
                            if tri_tri::plane_separates(x, y) || tri_tri::plane_separates(y, x) {
                                continue;
                            }
                            let sb = (sb0 + ci * LEAF_SIZE + j) as u32;
                            if leaf((sa0 + i) as u32, sb, x, y) {
                                stack.clear();
                                return true;
                            }
                        }
                    }
                }
            }
            (la, lb_leaf) => {
                if !la && (lb_leaf || size_sq(na) >= size_sq(nb)) {
                    let sb = f.shape(&b.shapes[ib as usize]);
                    for x in [na.start, ia + 1] {
                        if sb.lower_bound_sq(&a.shapes[x as usize], f.pad) <= 0.0 {
                            stack.push((x, ib, 0.0));
                        }
                    }
                } else {
                    let sa = &a.shapes[ia as usize];
                    for y in [nb.start, ib + 1] {
                        if f.lower_bound_sq(sa, &b.shapes[y as usize]) <= 0.0 {
                            stack.push((ia, y, 0.0));
                        }
                    }
                }
            }
        }
    }
    false
}
