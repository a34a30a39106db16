//! Closed meshes the project generates itself: for tests, benchmarks and the demo, so that a
//! fresh clone needs no data files.

use crate::mesh::Mesh;
use glam::DVec3;

mod bone;
pub use bone::{arch_pair_teeth_extracted, arch_pair_with_bone};

/// A unit icosphere with `subdivisions` loop subdivisions (20·4^s triangles), outward facing.
pub fn icosphere(subdivisions: u32) -> Mesh {
    let (vertices, mut levels) = icosphere_levels(subdivisions);
    Mesh {
        vertices,
        triangles: levels.pop().unwrap_or_default(),
    }
}

/// The unit icosphere's vertices and the triangles of every level `0..=subdivisions`: the
/// children of triangle `t` of one level are triangles `4t..4t + 4` of the next, and their
/// cones from the centre tile the parent's (the midpoints are pushed out to the sphere along
/// the parent's edge planes), which is what [`bone`]'s radial inside test walks down.
fn icosphere_levels(subdivisions: u32) -> (Vec<DVec3>, Vec<Vec<[u32; 3]>>) {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let mut vertices: Vec<DVec3> = [
        (-1.0, t, 0.0),
        (1.0, t, 0.0),
        (-1.0, -t, 0.0),
        (1.0, -t, 0.0),
        (0.0, -1.0, t),
        (0.0, 1.0, t),
        (0.0, -1.0, -t),
        (0.0, 1.0, -t),
        (t, 0.0, -1.0),
        (t, 0.0, 1.0),
        (-t, 0.0, -1.0),
        (-t, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| DVec3::new(x, y, z).normalize())
    .collect();
    let mut levels: Vec<Vec<[u32; 3]>> = vec![vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ]];
    for _ in 0..subdivisions {
        let mut mid = std::collections::HashMap::new();
        let mut midpoint = |a: u32, b: u32, vertices: &mut Vec<DVec3>| -> u32 {
            let key = (a.min(b), a.max(b));
            *mid.entry(key).or_insert_with(|| {
                let m = ((vertices[a as usize] + vertices[b as usize]) * 0.5).normalize();
                vertices.push(m);
                (vertices.len() - 1) as u32
            })
        };
        let triangles = levels.last().map_or(&[][..], |l| &l[..]);
        let mut next = Vec::with_capacity(triangles.len() * 4);
        for &[a, b, c] in triangles {
            let ab = midpoint(a, b, &mut vertices);
            let bc = midpoint(b, c, &mut vertices);
            let ca = midpoint(c, a, &mut vertices);
            next.extend_from_slice(&[[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        levels.push(next);
    }
    (vertices, levels)
}

/// A star-shaped closed mesh: the icosphere with each vertex `v` moved to `f(v)·v`.
/// `f` must be positive, so the result stays closed and free of self-intersections.
pub fn radial(subdivisions: u32, f: impl Fn(DVec3) -> f64) -> Mesh {
    let mut m = icosphere(subdivisions);
    for v in &mut m.vertices {
        *v *= f(*v);
    }
    m
}

/// An axis-aligned ellipsoid with the given semi-axes, centred at the origin.
pub fn ellipsoid(semi_axes: DVec3, subdivisions: u32) -> Mesh {
    let mut m = icosphere(subdivisions);
    for v in &mut m.vertices {
        *v *= semi_axes;
    }
    m
}

/// An axis-aligned box `[-half, half]`, 12 triangles, outward facing.
pub fn cuboid(half: DVec3) -> Mesh {
    let vertices = (0..8)
        .map(|i| {
            DVec3::new(
                if i & 1 == 0 { -half.x } else { half.x },
                if i & 2 == 0 { -half.y } else { half.y },
                if i & 4 == 0 { -half.z } else { half.z },
            )
        })
        .collect();
    let triangles = vec![
        [0, 2, 1],
        [1, 2, 3],
        [4, 5, 6],
        [5, 7, 6],
        [0, 1, 4],
        [1, 5, 4],
        [2, 6, 3],
        [3, 6, 7],
        [0, 4, 2],
        [2, 4, 6],
        [1, 3, 5],
        [3, 7, 5],
    ];
    Mesh {
        vertices,
        triangles,
    }
}

/// A torus around the z axis with major radius `major` and tube radius `minor`.
pub fn torus(major: f64, minor: f64, segments: u32, sides: u32) -> Mesh {
    let (nu, nv) = (segments.max(3), sides.max(3));
    let mut vertices = Vec::with_capacity((nu * nv) as usize);
    for i in 0..nu {
        let u = i as f64 / nu as f64 * std::f64::consts::TAU;
        for j in 0..nv {
            let v = j as f64 / nv as f64 * std::f64::consts::TAU;
            let rr = major + minor * v.cos();
            vertices.push(DVec3::new(rr * u.cos(), rr * u.sin(), minor * v.sin()));
        }
    }
    let id = |i: u32, j: u32| (i % nu) * nv + (j % nv);
    let mut triangles = Vec::with_capacity((2 * nu * nv) as usize);
    for i in 0..nu {
        for j in 0..nv {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            triangles.push([a, b, c]);
            triangles.push([a, c, d]);
        }
    }
    Mesh {
        vertices,
        triangles,
    }
}

/// A molar-like tooth (units: millimetres, about 10 x 10 x 17 mm): a rounded crown with four
/// cusps on top (+z) and a tapering root below, star-shaped and closed.
/// `phase` turns the cusp pattern, so that an upper and a lower tooth can interlock.
pub fn molar(subdivisions: u32, phase: f64) -> Mesh {
    radial(subdivisions, |v| molar_radius(v, phase))
}

/// The molar's distance from its centre along the unit direction `v` ([`molar`]).
fn molar_radius(v: DVec3, phase: f64) -> f64 {
    let (x, y, z) = (v.x, v.y, v.z);
    let az = y.atan2(x) + phase;
    // Crown: wide on top, with four cusps; root: narrower towards -z.
    let width = if z > 0.0 { 5.0 } else { 5.0 * (1.0 + 0.45 * z) };
    let height = if z > 0.0 { 4.0 } else { 12.0 };
    // The cusps fade towards the crown's pole, where the azimuth turns ever faster (else
    // the top would be a pinched point no packing of spheres could follow).
    let rho2 = x * x + y * y;
    let cusps = if z > 0.2 {
        1.0 + 0.22
            * (z - 0.2)
            * (2.0 * az).cos().powi(2)
            * (1.0 - (2.0 * az).sin().abs() * 0.3)
            * (rho2 / (rho2 + 0.05))
    } else {
        1.0
    };
    // Radius of the ellipsoid-like base along direction v, times the cusp factor.
    let base = 1.0 / ((x * x + y * y) / (width * width) + z * z / (height * height)).sqrt();
    base * cusps
}

/// Two interlocking tooth-like bodies for the demo: a lower molar (cusps up) and an upper
/// molar (cusps down, turned by 45°) placed so that, at the identity pose of the second
/// in the frame of the first, the cusps interdigitate with a small overlap — like a bite.
pub fn tooth_pair(subdivisions: u32) -> (Mesh, Mesh) {
    let upper = {
        let mut m = molar(subdivisions, std::f64::consts::FRAC_PI_4);
        for v in &mut m.vertices {
            // Mirror z (cusps down) and lift onto the lower tooth.
            *v = DVec3::new(v.x, v.y, -v.z + 8.1);
        }
        m.flip();
        m
    };
    (upper, molar(subdivisions, 0.0))
}

/// Where one tooth of [`arch_pair`] stands: its molar's frame in the arch.
#[derive(Debug, Clone, Copy)]
struct ToothPlace {
    /// The molar's centre on the arch curve (z = 0).
    at: DVec3,
    /// The curve's direction there (radians from +x).
    angle: f64,
    /// Its position along the arch, 0 at the first tooth (turns the cusps).
    index: usize,
}

/// The teeth of [`arch_pair`] are [`molar`]s scaled by this.
const ARCH_TOOTH_SCALE: f64 = 0.7;
/// The upper arch's molars are mirrored in z and lifted by this (millimetres, the molar's
/// units: 8.1 mm lets the cusps interdigitate with a small overlap).
const ARCH_UPPER_LIFT: f64 = 8.1;

impl ToothPlace {
    /// The cusp pattern's turn of this tooth in the upper or lower arch.
    fn phase(&self, upper: bool) -> f64 {
        let base = if upper {
            std::f64::consts::FRAC_PI_4
        } else {
            0.0
        };
        base + 0.3 * self.index as f64
    }

    /// A point of the molar's frame ([`molar`], unscaled) in the arch's.
    fn to_arch(self, p: DVec3, upper: bool) -> DVec3 {
        let p = p * ARCH_TOOTH_SCALE;
        let p = if upper {
            DVec3::new(p.x, p.y, -p.z + ARCH_UPPER_LIFT * ARCH_TOOTH_SCALE)
        } else {
            p
        };
        let (s, c) = self.angle.sin_cos();
        DVec3::new(
            c * p.x - s * p.y + self.at.x,
            s * p.x + c * p.y + self.at.y,
            p.z,
        )
    }

    /// A point of the arch's frame in the molar's (the inverse of [`Self::to_arch`]).
    fn to_molar(self, p: DVec3, upper: bool) -> DVec3 {
        let (s, c) = self.angle.sin_cos();
        let (x, y) = (p.x - self.at.x, p.y - self.at.y);
        let z = if upper {
            ARCH_UPPER_LIFT * ARCH_TOOTH_SCALE - p.z
        } else {
            p.z
        };
        DVec3::new(c * x + s * y, -s * x + c * y, z) / ARCH_TOOTH_SCALE
    }
}

/// The arch curve of [`arch_pair`]: y = 40 − x²/18 (a 48 mm wide, 40 mm deep arch between
/// x = ±24).
fn arch_curve(x: f64) -> DVec3 {
    DVec3::new(x, 40.0 - x * x / 18.0, 0.0)
}

/// Where the `teeth` (at least 2) teeth of [`arch_pair`] stand: at equal arc steps along
/// [`arch_curve`] between x = ±24.
fn arch_places(teeth: usize) -> Vec<ToothPlace> {
    let n = teeth.max(2);
    let mut pts = vec![arch_curve(-24.0)];
    let mut x = -24.0;
    while x < 24.0 {
        x += 0.01;
        pts.push(arch_curve(x));
    }
    let length: f64 = pts.windows(2).map(|w| (w[1] - w[0]).length()).sum();
    let mut places = Vec::with_capacity(n);
    let (mut walked, mut next) = (0.0, 0usize);
    for w in pts.windows(2) {
        let target = length * (next as f64 + 0.5) / n as f64;
        let step = (w[1] - w[0]).length();
        if walked + step >= target && next < n {
            let dir = (w[1] - w[0]).normalize();
            places.push(ToothPlace {
                at: w[0],
                angle: dir.y.atan2(dir.x),
                index: next,
            });
            next += 1;
        }
        walked += step;
    }
    places
}

/// Tooth numbers (Universal Numbering System) with their crown centres.
pub(crate) type NumberedCentres = Vec<(u32, DVec3)>;

/// The crown centres of [`arch_pair`]`(_, teeth)`'s teeth, numbered as a teeth-axes file
/// numbers them, (upper, lower): each on its tooth's axis, 1.05 mm into the crown from the
/// crown's base (inside it), numbered as a patient's teeth, as many on each side of the
/// midline (the arch's +y is anterior, +z occlusal for the lower arch, so the patient's left
/// is −x: upper 1 is the +x end, lower 17 the −x end), sorted by number. `teeth` is clamped
/// to 2..=16. `contact_map::Teeth::of_arch_pair` makes teeth files of them.
pub fn arch_pair_crowns(teeth: usize) -> (NumberedCentres, NumberedCentres) {
    let n = teeth.clamp(2, 16);
    let skip = ((16 - n) / 2) as u32;
    let crown = 1.5 * ARCH_TOOTH_SCALE;
    let (mut upper, mut lower) = (Vec::with_capacity(n), Vec::with_capacity(n));
    for (k, place) in arch_places(n).iter().enumerate() {
        let (k, at) = (k as u32, place.at);
        upper.push((
            16 - skip - k,
            DVec3::new(at.x, at.y, ARCH_UPPER_LIFT * ARCH_TOOTH_SCALE - crown),
        ));
        lower.push((17 + skip + k, DVec3::new(at.x, at.y, crown)));
    }
    upper.sort_by_key(|t| t.0);
    (upper, lower)
}

/// A generated dental arch pair for tests and examples (millimetres): `teeth` molar-like
/// teeth per arch, 0.7 × the size of [`molar`], standing along a parabolic horseshoe
/// (narrow at the front, +y), the lower arch cusps up and the upper one cusps down, turned
/// so that their cusps interdigitate with a small overlap at the identity pose, like a
/// bite. Each tooth is its own closed shell, as in segmented scans. Returns (upper, lower).
/// [`arch_pair_with_bone`] stands the same teeth in solid bone.
pub fn arch_pair(subdivisions: u32, teeth: usize) -> (Mesh, Mesh) {
    let places = arch_places(teeth);
    let arch = |upper: bool| -> Mesh {
        let mut all = Mesh::default();
        for place in &places {
            let mut m = molar(subdivisions, place.phase(upper));
            for v in &mut m.vertices {
                *v = place.to_arch(*v, upper);
            }
            if upper {
                m.flip();
            }
            let base = all.vertices.len() as u32;
            all.vertices.extend(m.vertices);
            all.triangles
                .extend(m.triangles.iter().map(|t| t.map(|i| i + base)));
        }
        all
    };
    (arch(true), arch(false))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn generated_meshes_are_closed_with_the_expected_volume() {
        let s = icosphere(4);
        let v = s.signed_volume();
        assert!((v - 4.0 / 3.0 * std::f64::consts::PI).abs() < 0.02, "{v}");
        assert!((cuboid(DVec3::new(1.0, 2.0, 3.0)).signed_volume() - 48.0).abs() < 1e-12);
        let t = torus(2.0, 0.5, 64, 32);
        let exact = 2.0 * std::f64::consts::PI.powi(2) * 2.0 * 0.25;
        assert!((t.signed_volume() - exact).abs() / exact < 0.01);
        let (a, b) = tooth_pair(3);
        assert!(a.signed_volume() > 100.0 && b.signed_volume() > 100.0);
    }
}
