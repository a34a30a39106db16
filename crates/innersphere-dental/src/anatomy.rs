//! The anatomical frame of a jaw pair, found from the meshes themselves.
//!
//! - **up** (occlusal direction, from the lower body B to the upper body A): the principal
//!   axis of the vertices of both bodies that is best aligned with the line between their
//!   centroids — for a dental arch, which is flat, the smallest axis; for a pair of single
//!   teeth, the long axis. Its sign points from B's centroid to A's.
//! - **anterior** and **left**: the principal axes of B's vertices in the plane across up.
//!   A dental arch is U-shaped: along the anterior–posterior axis its width changes (narrow
//!   at the front), across it the arch is mirror-symmetric; the axis along which the
//!   spread of the other coordinate changes most is anterior–posterior, and anterior is
//!   where the arch is narrow. left = up × anterior.
//! - **incisal point**: on B's midline, at the highest of B's front vertices (those within
//!   3 mm of the front near the midline) — the lower incisal tip of a jaw.
//! - **hinge**: [`HINGE_BEHIND`] behind and [`HINGE_ABOVE`] above the incisal point (times
//!   the [`scale`](AnatomicalFrame::scale)); the opening rotation turns about the axis
//!   through it along left.

use glam::DVec3;
use innersphere::error::{Error, Result};
use innersphere::mesh::Mesh;
use innersphere::pose::Pose;

/// Distance of the opening hinge behind the lower incisal tip, in millimetres at scale 1.
pub const HINGE_BEHIND: f64 = 95.0;
/// Height of the opening hinge above the lower incisal tip, in millimetres at scale 1.
pub const HINGE_ABOVE: f64 = 20.0;
/// Two principal spreads within this ratio are alike ([`AnatomicalFrame::from_points`]): a
/// dental arch, crowns only, is several times wider than tall, but two arches with their bone
/// stacked spread about as much along up as front to back.
const ALIKE_SPREADS: f64 = 1.5;
/// The height of B along up that has scale 1: the lower dental arch (crowns and roots) of
/// the project's jaw pair, 24.5 mm.
pub const REFERENCE_HEIGHT: f64 = 24.5;

/// An anatomical frame of a pair of bodies, in A's frame with B at the identity pose.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AnatomicalFrame {
    /// Unit occlusal direction, from B towards A.
    pub up: DVec3,
    /// Unit left–right axis, `up × anterior`.
    pub left: DVec3,
    /// Unit anterior direction (towards the incisors).
    pub anterior: DVec3,
    /// The lower incisal point (see the [module docs](self)).
    pub incisal: DVec3,
    /// A point on the opening hinge axis, which runs along [`left`](Self::left).
    pub hinge: DVec3,
    /// Size of B relative to a human lower dental arch: its height along up divided by
    /// [`REFERENCE_HEIGHT`]. Motion amplitudes (opening, excursions, tremor) scale with it.
    pub scale: f64,
}

impl AnatomicalFrame {
    /// Finds the frame of `a` (upper body) and `b` (lower body); see the
    /// [module docs](self). Fails on invalid meshes or a body without extent.
    pub fn from_meshes(a: &Mesh, b: &Mesh) -> Result<AnatomicalFrame> {
        a.validate()?;
        b.validate()?;
        Self::from_points(&a.vertices, &b.vertices)
    }

    /// The frame from points of each body (vertices, or the centres of a tree's leaf
    /// spheres when no mesh is at hand); the same method as [`from_meshes`](Self::from_meshes).
    // Over 120 lines: one derivation (centroids, covariance, up, the principal axes across
    // it, which of them is anterior, the scale), each step a few lines reading the last's
    // vectors; split, each piece would take and return most of them.
    pub fn from_points(a: &[DVec3], b: &[DVec3]) -> Result<AnatomicalFrame> {
        if a.is_empty() || b.is_empty() {
            return Err(Error::InvalidMesh(
                "the anatomical frame needs points of both bodies".into(),
            ));
        }
        let ca = centroid(a);
        let cb = centroid(b);
        let centre = (ca * a.len() as f64 + cb * b.len() as f64) / (a.len() + b.len()) as f64;
        let mut cov = [[0.0f64; 3]; 3];
        for v in a.iter().chain(b) {
            let d = (*v - centre).to_array();
            for (i, row) in cov.iter_mut().enumerate() {
                for (j, c) in row.iter_mut().enumerate() {
                    *c += d[i] * d[j];
                }
            }
        }
        let (values, axes) = symmetric_eigen(cov);
        let dc = ca - cb;
        let size = bbox_diagonal(a).max(bbox_diagonal(b));
        if !(size.is_finite() && size > 0.0) {
            return Err(Error::InvalidMesh(
                "the bodies have no extent; cannot find an anatomical frame".into(),
            ));
        }
        // Eigenvalues ascending: axes[0] is the smallest.
        let mut up = if dc.length() > 1e-9 * size {
            let d = dc.normalize();
            let k = (0..3)
                .max_by(|&p, &q| axes[p].dot(d).abs().total_cmp(&axes[q].dot(d).abs()))
                .unwrap_or(0);
            // Axes whose spreads are alike are no particular directions (their eigenvectors
            // turn freely in their plane): arches with their bone, stacked, spread as much
            // along up as across it. Then up is the centroids' line within their span.
            let alike = |i: usize| {
                let (x, y) = (values[i].max(0.0), values[k].max(0.0));
                x.max(y) <= ALIKE_SPREADS * x.min(y)
            };
            let span: DVec3 = (0..3)
                .filter(|&i| alike(i))
                .map(|i| axes[i] * axes[i].dot(d))
                .sum();
            if (0..3).filter(|&i| alike(i)).count() > 1 && span.length() > 1e-9 {
                span.normalize()
            } else {
                axes[k]
            }
        } else {
            axes[0]
        };
        if up.dot(dc) < 0.0 {
            up = -up;
        }
        // Principal axes of B across up.
        let (e1, e2) = plane_basis(up);
        let cb2 = (cb.dot(e1), cb.dot(e2));
        let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
        for v in b {
            let x = v.dot(e1) - cb2.0;
            let y = v.dot(e2) - cb2.1;
            sxx += x * x;
            sxy += x * y;
            syy += y * y;
        }
        let angle = 0.5 * (2.0 * sxy).atan2(sxx - syy);
        let f1 = e1 * angle.cos() + e2 * angle.sin();
        let f2 = up.cross(f1).normalize();
        // Which one is anterior–posterior: the one along which the spread across it changes.
        let width_trend = |ax: DVec3, across: DVec3| -> f64 {
            let xs: Vec<(f64, f64)> = b
                .iter()
                .map(|v| ((*v - cb).dot(ax), (*v - cb).dot(across).abs()))
                .collect();
            correlation(&xs)
        };
        let c1 = width_trend(f1, f2);
        let c2 = width_trend(f2, f1);
        let (ap, corr) = if c1.abs() >= c2.abs() {
            (f1, c1)
        } else {
            (f2, c2)
        };
        // Narrow towards the front: the width decreases along +anterior.
        let anterior = if corr <= 0.0 { ap } else { -ap };
        let left = up.cross(anterior).normalize();
        let anterior = left.cross(up).normalize();

        // Coordinates of B's vertices in the frame.
        let coords: Vec<[f64; 3]> = b
            .iter()
            .map(|v| [v.dot(left), v.dot(anterior), v.dot(up)])
            .collect();
        let (umin, umax) = coords
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), c| {
                (lo.min(c[2]), hi.max(c[2]))
            });
        let height = umax - umin;
        if height.is_nan() || height <= 0.0 {
            return Err(Error::InvalidMesh(
                "body B is flat across the occlusal direction; cannot find an anatomical frame"
                    .into(),
            ));
        }
        let scale = height / REFERENCE_HEIGHT;
        let lmid = cb.dot(left);
        let mut midline: Vec<&[f64; 3]> = coords
            .iter()
            .filter(|c| (c[0] - lmid).abs() <= 4.0 * scale)
            .collect();
        if midline.is_empty() {
            midline = coords.iter().collect();
        }
        let afront = midline
            .iter()
            .map(|c| c[1])
            .fold(f64::NEG_INFINITY, f64::max);
        // The highest of the front vertices: the incisal edge (its depth too, not the
        // labial face in front of it).
        let tip = midline
            .iter()
            .filter(|c| c[1] >= afront - 3.0 * scale)
            .max_by(|p, q| p[2].total_cmp(&q[2]))
            .map_or([lmid, afront, umax], |c| **c);
        let incisal = left * lmid + anterior * tip[1] + up * tip[2];
        let hinge = incisal - anterior * (HINGE_BEHIND * scale) + up * (HINGE_ABOVE * scale);
        Ok(AnatomicalFrame {
            up,
            left,
            anterior,
            incisal,
            hinge,
            scale,
        })
    }

    /// The frame moved with body B by `pose` (directions turn, points move).
    pub fn moved(&self, pose: &Pose) -> AnatomicalFrame {
        AnatomicalFrame {
            up: pose.transform_vector(self.up),
            left: pose.transform_vector(self.left),
            anterior: pose.transform_vector(self.anterior),
            incisal: pose.transform_point(self.incisal),
            hinge: pose.transform_point(self.hinge),
            scale: self.scale,
        }
    }

    /// The rigid motion that opens the jaw by `opening` at the incisal point: a rotation
    /// about the hinge axis (through [`hinge`](Self::hinge), along [`left`](Self::left))
    /// that moves the incisal point that far along its arc, downwards for a positive
    /// opening. Compose it after B's pose: `frame.opening(o).then(&pose)`.
    pub fn opening(&self, opening: f64) -> Pose {
        let r_inc = (self.incisal - self.hinge).length();
        let theta = if r_inc > 0.0 { opening / r_inc } else { 0.0 };
        let rotation = glam::DQuat::from_axis_angle(self.left, theta);
        Pose {
            rotation,
            translation: self.hinge - rotation * self.hinge,
        }
    }

    /// Coordinates `(left, anterior, up)` of a point relative to the incisal point.
    pub fn coordinates(&self, p: DVec3) -> DVec3 {
        let d = p - self.incisal;
        DVec3::new(d.dot(self.left), d.dot(self.anterior), d.dot(self.up))
    }
}

/// Opposed bodies' centroids lie at least this share of their mean height apart along up,
/// with B at the identity (in A's frame). Arches in occlusion lie about half their height
/// apart (0.67 for the generated arch pair of [`shapes::arch_pair`](innersphere::shapes::arch_pair),
/// 0.57 for the project's jaw pair), an arch and its own copy 0: their frame's up has no
/// sign, and closing one onto the other bites nothing.
pub const OPPOSED_SEPARATION: f64 = 0.25;

/// Refuses two bodies that do not face each other along `up` (unit, from B towards A) with
/// B at the identity: their centroids must lie at least [`OPPOSED_SEPARATION`] of their
/// mean height (their extent along `up`) apart along it, B's below A's. What a bite of A
/// and B needs before any closing: two upper arches, or an arch and its own copy, fail it.
pub fn check_opposed(a: &[DVec3], b: &[DVec3], up: DVec3) -> Result<()> {
    if a.is_empty() || b.is_empty() {
        return Err(Error::InvalidMesh(
            "the bite needs points of both bodies".into(),
        ));
    }
    let height = |p: &[DVec3]| {
        let (lo, hi) = p
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
                (lo.min(v.dot(up)), hi.max(v.dot(up)))
            });
        hi - lo
    };
    let apart = (centroid(a) - centroid(b)).dot(up);
    let need = OPPOSED_SEPARATION * 0.5 * (height(a) + height(b));
    if apart >= need {
        return Ok(());
    }
    Err(Error::InvalidMesh(format!(
        "the two arches do not face each other along the occlusal axis: with B in A's frame \
         their centres lie {:.1} mm apart along it, where opposed arches lie about half their \
         height apart (at least {:.1} mm here). Is B the lower arch, and is it in A's frame?",
        apart.max(0.0),
        need
    )))
}

fn centroid(v: &[DVec3]) -> DVec3 {
    if v.is_empty() {
        DVec3::ZERO
    } else {
        v.iter().copied().sum::<DVec3>() / v.len() as f64
    }
}

fn bbox_diagonal(p: &[DVec3]) -> f64 {
    let lo = p.iter().fold(DVec3::splat(f64::INFINITY), |m, v| m.min(*v));
    let hi = p
        .iter()
        .fold(DVec3::splat(f64::NEG_INFINITY), |m, v| m.max(*v));
    (hi - lo).length()
}

/// Pearson correlation of the pairs (0 when either side has no spread).
fn correlation(xs: &[(f64, f64)]) -> f64 {
    let n = xs.len() as f64;
    if xs.is_empty() {
        return 0.0;
    }
    let (mx, my) = xs
        .iter()
        .fold((0.0, 0.0), |(a, b), &(x, y)| (a + x / n, b + y / n));
    let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
    for &(x, y) in xs {
        sxy += (x - mx) * (y - my);
        sxx += (x - mx) * (x - mx);
        syy += (y - my) * (y - my);
    }
    let den = (sxx * syy).sqrt();
    if den > 0.0 {
        sxy / den
    } else {
        0.0
    }
}

/// Two unit vectors that complete `n` (unit) to an orthonormal basis.
fn plane_basis(n: DVec3) -> (DVec3, DVec3) {
    let helper = if n.x.abs() < 0.6 { DVec3::X } else { DVec3::Y };
    let e1 = n.cross(helper).normalize();
    (e1, n.cross(e1))
}

/// Eigen-decomposition of a symmetric 3×3 matrix by Jacobi rotations: eigenvalues ascending
/// and their unit eigenvectors.
#[allow(clippy::needless_range_loop)] // matrix code reads best with indices
fn symmetric_eigen(m: [[f64; 3]; 3]) -> ([f64; 3], [DVec3; 3]) {
    let mut a = m;
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for _ in 0..64 {
        let (mut p, mut q, mut big) = (0, 1, 0.0f64);
        for i in 0..3 {
            for j in i + 1..3 {
                if a[i][j].abs() > big {
                    big = a[i][j].abs();
                    p = i;
                    q = j;
                }
            }
        }
        let scale = a[0][0].abs() + a[1][1].abs() + a[2][2].abs();
        if !(big > 1e-300 && big > 1e-17 * scale) {
            break;
        }
        let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
        let t = if theta == 0.0 {
            1.0
        } else {
            theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt())
        };
        let c = 1.0 / (t * t + 1.0).sqrt();
        let s = t * c;
        // a ← Jᵀ a J and v ← v J, with J the rotation in the (p, q) plane.
        for k in 0..3 {
            let (akp, akq) = (a[k][p], a[k][q]);
            a[k][p] = c * akp - s * akq;
            a[k][q] = s * akp + c * akq;
        }
        for k in 0..3 {
            let (apk, aqk) = (a[p][k], a[q][k]);
            a[p][k] = c * apk - s * aqk;
            a[q][k] = s * apk + c * aqk;
        }
        for row in v.iter_mut() {
            let (vp, vq) = (row[p], row[q]);
            row[p] = c * vp - s * vq;
            row[q] = s * vp + c * vq;
        }
    }
    let mut idx = [0usize, 1, 2];
    idx.sort_by(|&i, &j| a[i][i].total_cmp(&a[j][j]));
    let vals = idx.map(|i| a[i][i]);
    let vecs = idx.map(|j| DVec3::new(v[0][j], v[1][j], v[2][j]).normalize_or(DVec3::Z));
    (vals, vecs)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn jacobi_diagonalizes() {
        let m = [[4.0, 1.0, 0.5], [1.0, 3.0, 0.2], [0.5, 0.2, 1.0]];
        let (vals, vecs) = symmetric_eigen(m);
        assert!(vals[0] <= vals[1] && vals[1] <= vals[2]);
        for (l, v) in vals.iter().zip(vecs) {
            let mv = DVec3::new(
                m[0][0] * v.x + m[0][1] * v.y + m[0][2] * v.z,
                m[1][0] * v.x + m[1][1] * v.y + m[1][2] * v.z,
                m[2][0] * v.x + m[2][1] * v.y + m[2][2] * v.z,
            );
            assert!((mv - v * *l).length() < 1e-10, "{mv} vs {}", v * *l);
        }
        let (vals, _) = symmetric_eigen([[2.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 2.0]]);
        assert_eq!(vals, [2.0; 3]);
    }

    /// The corners of a box `w` wide (x, y) and `h` high (z), its base at height `z`.
    fn slab(w: f64, h: f64, z: f64) -> Vec<DVec3> {
        let mut p = vec![];
        for i in 0..8 {
            let bit = |k: usize| ((i >> k) & 1) as f64;
            p.push(DVec3::new(w * bit(0), w * bit(1), z + h * bit(2)));
        }
        p
    }

    #[test]
    fn opposed_bodies_lie_a_quarter_of_their_mean_height_apart_along_up() {
        // Two slabs 10 mm high (mean height 10): opposed from 2.5 mm apart along up.
        let b = slab(40.0, 10.0, 0.0);
        for (z, ok) in [
            (8.0, true),
            (2.5, true),
            (2.49, false),
            (0.0, false),
            (-8.0, false),
        ] {
            let a = slab(40.0, 10.0, z);
            assert_eq!(check_opposed(&a, &b, DVec3::Z).is_ok(), ok, "A {z} mm up");
        }
        // The mean height: a 30 mm block over a 10 mm slab needs 5 mm.
        assert!(check_opposed(&slab(40.0, 30.0, -5.01), &b, DVec3::Z).is_err());
        assert!(check_opposed(&slab(40.0, 30.0, -5.0), &b, DVec3::Z).is_ok());
        // A body against its own copy: refused with the sentence a surgeon reads.
        let e = check_opposed(&b, &b, DVec3::Z).unwrap_err().to_string();
        assert!(
            e.contains("do not face each other")
                && e.contains("0.0 mm apart")
                && e.contains("at least 2.5 mm")
                && e.contains("Is B the lower arch"),
            "{e}"
        );
        assert!(check_opposed(&[], &b, DVec3::Z).is_err());
    }
}
