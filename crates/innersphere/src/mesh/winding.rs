//! The generalized winding number (Jacobson et al. 2013) with fast hierarchical evaluation
//! (Barill et al. 2018).
//!
//! The winding number of a point is the signed solid angle the surface subtends there,
//! divided by 4π: 1 inside and 0 outside a closed outward-facing mesh, and a smooth, robust
//! measure of insideness for meshes with holes. The hierarchy is a [`TriangleBvh`] whose
//! nodes also store an area-weighted centre, a radius and the moments of the area-weighted
//! normals up to second order; a node seen from farther than `beta · radius` contributes the
//! Taylor expansion of its solid angle about its centre (dipole term plus the first- and
//! second-order corrections, as Barill et al.'s order-2 expansion), the leaves near the query
//! point contribute their exact solid angles.

use super::bvh::{TriangleBvh, MAX_DEPTH};
use crate::mesh::Mesh;
use glam::{DMat3, DVec3};
use std::f64::consts::PI;

/// Default accuracy parameter β: nodes farther than β·radius use their far-field expansion.
pub(crate) const DEFAULT_BETA: f64 = 2.0;
/// The accuracy assumed of [`FastWinding`] at [`DEFAULT_BETA`] (second order: errors of
/// about 1e-3, with a margin): how far from ½ a value must be to decide inside or outside.
pub(crate) const WINDING_ACCURACY: f64 = 0.02;

/// Signed solid angle of the triangle `a, b, c` given relative to the viewpoint
/// (Van Oosterom & Strackee 1983). Positive when the triangle is counter-clockwise seen from
/// the side its normal points away from, i.e. from inside a closed outward-facing mesh.
/// Zero (never NaN) when the viewpoint lies on a corner.
#[inline]
pub fn solid_angle(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let (la, lb, lc) = (a.length(), b.length(), c.length());
    let num = a.dot(b.cross(c));
    let den = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
    2.0 * num.atan2(den)
}

#[cfg(test)]
/// The exact generalized winding number of `p`: the O(n) sum over all triangles.
pub(crate) fn exact_winding_number(mesh: &Mesh, p: DVec3) -> f64 {
    (0..mesh.triangles.len())
        .map(|t| {
            let [a, b, c] = mesh.triangle(t);
            solid_angle(a - p, b - p, c - p)
        })
        .sum::<f64>()
        / (4.0 * PI)
}

/// Far-field data of one BVH node.
#[derive(Debug, Clone, Copy)]
struct Moment {
    /// Area-weighted centre of the triangles below the node.
    centre: DVec3,
    /// Radius of a ball around `centre` that holds every triangle below the node.
    radius: f64,
    /// Sum of the area-weighted normals `n = (b - a) × (c - a) / 2`.
    normal: DVec3,
    /// `Σ ∫ n ⊗ (x − centre) dA`: entry `(i, j)` is `Σ n_i ∫ (x − centre)_j`.
    moment: DMat3,
    /// `second[i] = Σ n_i ∫ (x − centre)(x − centre)ᵀ dA` (symmetric).
    second: [DMat3; 3],
}

/// Fast evaluation of the generalized winding number of a mesh.
#[derive(Debug, Clone)]
pub struct FastWinding {
    bvh: TriangleBvh,
    moments: Vec<Moment>,
    beta: f64,
}

impl FastWinding {
    /// Builds the hierarchy with the default β = 2 (errors of about 1e-3).
    pub fn new(mesh: &Mesh) -> Self {
        Self::with_beta(mesh, DEFAULT_BETA)
    }

    /// Builds the hierarchy with accuracy parameter `beta` (larger is slower and more exact;
    /// `f64::INFINITY` gives the exact sum).
    pub(crate) fn with_beta(mesh: &Mesh, beta: f64) -> Self {
        Self::from_bvh(TriangleBvh::new(mesh), beta)
    }

    /// Builds the far-field moments on an existing triangle tree.
    pub(crate) fn from_bvh(bvh: TriangleBvh, beta: f64) -> Self {
        let nodes = &bvh.nodes;
        let mut moments = vec![
            Moment {
                centre: DVec3::ZERO,
                radius: 0.0,
                normal: DVec3::ZERO,
                moment: DMat3::ZERO,
                second: [DMat3::ZERO; 3],
            };
            nodes.len()
        ];
        // Area sums per node, then centres; children follow their parents, so a reverse
        // sweep sees children first.
        let mut area = vec![0.0f64; nodes.len()];
        for i in (0..nodes.len()).rev() {
            let n = &nodes[i];
            let box_centre = (n.lo + n.hi) * 0.5;
            if n.is_leaf() {
                let tris = &bvh.tris[n.start as usize..(n.start + n.count) as usize];
                let mut nsum = DVec3::ZERO;
                let mut csum = DVec3::ZERO;
                let mut asum = 0.0;
                for &[a, b, c] in tris {
                    let nrm = (b - a).cross(c - a) * 0.5;
                    let ar = nrm.length();
                    nsum += nrm;
                    csum += (a + b + c) * (ar / 3.0);
                    asum += ar;
                }
                let centre = if asum > 0.0 && (csum / asum).is_finite() {
                    csum / asum
                } else {
                    box_centre
                };
                let radius = tris
                    .iter()
                    .flatten()
                    .map(|v| (*v - centre).length())
                    .fold(0.0, f64::max);
                let mut moment = DMat3::ZERO;
                let mut second = [DMat3::ZERO; 3];
                for &[a, b, c] in tris {
                    let nrm = (b - a).cross(c - a) * 0.5;
                    let (ua, ub, uc) = (a - centre, b - centre, c - centre);
                    let s = ua + ub + uc;
                    moment += outer(nrm, s / 3.0);
                    // ∫ u uᵀ dA = (1/12)(Σ u_v u_vᵀ + s sᵀ) per unit area.
                    let cov = (outer(ua, ua) + outer(ub, ub) + outer(uc, uc) + outer(s, s)) / 12.0;
                    for (k, t) in second.iter_mut().enumerate() {
                        *t += cov * nrm[k];
                    }
                }
                moments[i] = Moment {
                    centre,
                    radius,
                    normal: nsum,
                    moment,
                    second,
                };
                area[i] = asum;
            } else {
                let (l, r) = (i + 1, n.start as usize);
                let asum = area[l] + area[r];
                let c = (moments[l].centre * area[l] + moments[r].centre * area[r]) / asum;
                let centre = if asum > 0.0 && c.is_finite() {
                    c
                } else {
                    box_centre
                };
                // Two bounds on the enclosing radius: via the children's balls and via the
                // farthest box corner.
                let via_children = [l, r]
                    .iter()
                    .map(|&k| (moments[k].centre - centre).length() + moments[k].radius)
                    .fold(0.0, f64::max);
                let far_corner = (centre - n.lo).abs().max((n.hi - centre).abs()).length();
                // Shift the children's moments to the new centre: x − c = (x − c_k) + δ.
                let mut moment = DMat3::ZERO;
                let mut second = [DMat3::ZERO; 3];
                for ch in [&moments[l], &moments[r]] {
                    let delta = ch.centre - centre;
                    moment += ch.moment + outer(ch.normal, delta);
                    for (k, t) in second.iter_mut().enumerate() {
                        let row = ch.moment.row(k);
                        *t += ch.second[k]
                            + outer(row, delta)
                            + outer(delta, row)
                            + outer(delta, delta) * ch.normal[k];
                    }
                }
                moments[i] = Moment {
                    centre,
                    radius: via_children.min(far_corner),
                    normal: moments[l].normal + moments[r].normal,
                    moment,
                    second,
                };
                area[i] = asum;
            }
        }
        FastWinding { bvh, moments, beta }
    }

    /// The triangle tree the evaluation runs on.
    pub fn bvh(&self) -> &TriangleBvh {
        &self.bvh
    }

    /// The generalized winding number at `p` (≈ 1 inside, ≈ 0 outside a closed outward mesh).
    pub fn winding_number(&self, p: DVec3) -> f64 {
        if self.bvh.nodes.is_empty() {
            return 0.0;
        }
        let beta_sq = self.beta * self.beta;
        let mut sum = 0.0;
        let mut stack = [0u32; MAX_DEPTH + 2];
        let mut sp = 1usize;
        while sp > 0 {
            sp -= 1;
            let i = stack[sp] as usize;
            let m = &self.moments[i];
            let d = m.centre - p;
            let dsq = d.length_squared();
            if dsq > beta_sq * m.radius * m.radius {
                sum += far_field(m, d, dsq);
                continue;
            }
            let n = &self.bvh.nodes[i];
            if n.is_leaf() {
                for &[a, b, c] in &self.bvh.tris[n.start as usize..(n.start + n.count) as usize] {
                    sum += solid_angle(a - p, b - p, c - p);
                }
            } else {
                stack[sp] = n.start;
                stack[sp + 1] = i as u32 + 1;
                sp += 2;
            }
        }
        sum / (4.0 * PI)
    }
}

/// Taylor expansion to second order of `Σ ∫ n·(x − p)/|x − p|³ dA` about the node centre,
/// with `d = centre − p`. With `F(d) = d/|d|³`: the dipole `N·F`, the gradient term
/// `Σ M_ij ∂_j F_i` and the Hessian term `½ Σ T_ijk ∂_j ∂_k F_i`.
#[inline]
fn far_field(m: &Moment, d: DVec3, dsq: f64) -> f64 {
    let inv = 1.0 / dsq;
    let inv3 = inv * inv.sqrt();
    let inv5 = inv3 * inv;
    let mm = &m.moment;
    let trace = mm.x_axis.x + mm.y_axis.y + mm.z_axis.z;
    let order1 = inv3 * (d.dot(m.normal) + trace) - 3.0 * inv5 * d.dot(*mm * d);
    // ∂_j ∂_k F_i = −3(δ_ij d_k + δ_ik d_j + δ_jk d_i)/|d|⁵ + 15 d_i d_j d_k/|d|⁷.
    let mut a1 = 0.0; // Σ_ik T_iik d_k (twice, by symmetry of T in j, k)
    let mut a3 = 0.0; // Σ_i d_i tr T_i
    let mut a4 = 0.0; // Σ_i d_i dᵀ T_i d
    for (k, t) in m.second.iter().enumerate() {
        let td = *t * d;
        a1 += td[k];
        a3 += d[k] * (t.x_axis.x + t.y_axis.y + t.z_axis.z);
        a4 += d[k] * d.dot(td);
    }
    let order2 = 0.5 * (-3.0 * inv5 * (2.0 * a1 + a3) + 15.0 * inv5 * inv * a4);
    order1 + order2
}

/// The outer product `n dᵀ` (entry `(i, j)` is `n_i d_j`).
#[inline]
fn outer(n: DVec3, d: DVec3) -> DMat3 {
    DMat3::from_cols(n * d.x, n * d.y, n * d.z)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes;

    #[test]
    fn sphere_inside_outside_and_exact_agreement() {
        let m = shapes::icosphere(4);
        let fw = FastWinding::new(&m);
        assert!((fw.winding_number(DVec3::ZERO) - 1.0).abs() < 2e-3);
        assert!((exact_winding_number(&m, DVec3::ZERO) - 1.0).abs() < 1e-12);
        assert!(fw.winding_number(DVec3::new(0.3, -0.5, 0.2)) > 0.99);
        assert!(fw.winding_number(DVec3::new(3.0, 0.0, 0.0)).abs() < 1e-2);
        let mut flipped = m.clone();
        flipped.flip();
        assert!((FastWinding::new(&flipped).winding_number(DVec3::ZERO) + 1.0).abs() < 1e-2);
        let mut s = 12345u64;
        let mut rnd = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64 * 4.0 - 2.0
        };
        for _ in 0..500 {
            let p = DVec3::new(rnd(), rnd(), rnd());
            let e = exact_winding_number(&m, p);
            let f = fw.winding_number(p);
            assert!((e - f).abs() < 5e-3, "{p}: exact {e} fast {f}");
            let expect = if p.length() < 0.99 {
                1.0
            } else if p.length() > 1.01 {
                0.0
            } else {
                e
            };
            assert!((e - expect).abs() < 1e-6, "{p}: {e}");
        }
    }

    #[test]
    fn degenerate_and_on_surface_points_are_finite() {
        let m = Mesh {
            vertices: vec![DVec3::ZERO, DVec3::X, DVec3::X * 2.0, DVec3::Y],
            triangles: vec![[0, 1, 2], [0, 0, 0], [0, 1, 3]],
        };
        let fw = FastWinding::new(&m);
        for p in [
            DVec3::ZERO,
            DVec3::X,
            DVec3::new(0.2, 0.2, 0.0),
            DVec3::new(0.2, 0.2, 1e-300),
        ] {
            assert!(fw.winding_number(p).is_finite());
            assert!(exact_winding_number(&m, p).is_finite());
        }
        assert_eq!(
            FastWinding::new(&Mesh::default()).winding_number(DVec3::ZERO),
            0.0
        );
    }
}
