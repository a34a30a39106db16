//! Ray casting against a [`TriangleBvh`]: the first triangle a ray meets.

use glam::DVec3;

use super::bvh::{TriangleBvh, MAX_DEPTH};

/// Where a ray first meets the surface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RayHit {
    /// Distance along the (unit) ray direction.
    pub t: f64,
    /// Index of the triangle hit, in the original mesh.
    pub triangle: u32,
}

impl TriangleBvh {
    /// The first triangle that the ray `origin + t·dir` (`dir` unit, `t_min < t ≤ t_max`)
    /// meets, skipping the triangles for which `skip(mesh index)` holds (e.g. those around
    /// the ray's own origin). Möller–Trumbore per triangle, slab test per box.
    pub fn first_hit(
        &self,
        origin: DVec3,
        dir: DVec3,
        t_min: f64,
        t_max: f64,
        skip: impl Fn(u32) -> bool,
    ) -> Option<RayHit> {
        let mut best: Option<RayHit> = None;
        self.walk(origin, dir, t_min, t_max, |slot, t| {
            let triangle = self.order[slot];
            if skip(triangle) {
                return f64::INFINITY;
            }
            best = Some(RayHit { t, triangle });
            t
        });
        best
    }

    /// How many triangles the ray `origin + t·dir` (`t > 0`) crosses: odd inside a closed
    /// mesh, even outside (for a ray that meets no edge or vertex exactly: pick a direction
    /// off the mesh's axes).
    pub fn crossings(&self, origin: DVec3, dir: DVec3) -> usize {
        let mut count = 0;
        self.walk(origin, dir, 0.0, f64::INFINITY, |_, _| {
            count += 1;
            f64::INFINITY
        });
        count
    }

    /// Calls `hit(slot, t)` for every triangle the ray meets at `t_min < t ≤ cutoff`, where
    /// the cutoff starts at `t_max` and becomes the smaller of itself and what `hit` returns
    /// (infinity: keep it), so that a nearest-hit search prunes what lies beyond its hit.
    fn walk(
        &self,
        origin: DVec3,
        dir: DVec3,
        t_min: f64,
        t_max: f64,
        mut hit: impl FnMut(usize, f64) -> f64,
    ) {
        if self.nodes.is_empty() {
            return;
        }
        let inv = DVec3::ONE / dir;
        let mut cutoff = t_max;
        let mut stack = [0u32; MAX_DEPTH + 2];
        let mut sp = 1usize;
        while sp > 0 {
            sp -= 1;
            let i = stack[sp];
            let n = &self.nodes[i as usize];
            let t0 = (n.lo - origin) * inv;
            let t1 = (n.hi - origin) * inv;
            let enter = t0.min(t1).max_element().max(t_min);
            let exit = t0.max(t1).min_element().min(cutoff);
            // NaN (a zero direction component on the box's face) counts as a hit.
            if enter > exit {
                continue;
            }
            if n.is_leaf() {
                for slot in n.start as usize..(n.start + n.count) as usize {
                    if let Some(t) = intersect(origin, dir, &self.tris[slot]) {
                        if t > t_min && t <= cutoff {
                            cutoff = cutoff.min(hit(slot, t));
                        }
                    }
                }
            } else if sp + 2 <= stack.len() {
                stack[sp] = n.start;
                stack[sp + 1] = i + 1;
                sp += 2;
            }
        }
    }
}

/// Möller–Trumbore: the distance along `dir` to triangle `t`, if the line meets it.
fn intersect(o: DVec3, d: DVec3, t: &[DVec3; 3]) -> Option<f64> {
    let e1 = t[1] - t[0];
    let e2 = t[2] - t[0];
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-300 {
        return None;
    }
    let inv = 1.0 / det;
    let s = o - t[0];
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = d.dot(q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    Some(e2.dot(q) * inv)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes;

    #[test]
    fn rays_through_a_closed_mesh_hit_it_where_brute_force_does() {
        let mesh = shapes::icosphere(3);
        let bvh = TriangleBvh::new(&mesh);
        for k in 0..50 {
            let a = k as f64 * 0.7;
            let dir = DVec3::new(a.cos(), a.sin(), (a * 0.3).cos()).normalize();
            let o = DVec3::new(0.1, -0.2, 0.05);
            let hit = bvh.first_hit(o, dir, 0.0, 10.0, |_| false).unwrap();
            let brute = (0..mesh.triangles.len())
                .filter_map(|t| intersect(o, dir, &mesh.triangle(t)).filter(|x| *x > 0.0))
                .fold(f64::INFINITY, f64::min);
            assert_eq!(hit.t, brute);
            assert!(bvh.first_hit(o, dir, 0.0, hit.t * 0.5, |_| false).is_none());
        }
    }
}
