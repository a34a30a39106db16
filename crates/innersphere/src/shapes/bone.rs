//! [`arch_pair_with_bone`]: the teeth of [`arch_pair`](super::arch_pair) standing in a solid
//! horseshoe of bone, each arch one closed surface — what a scan segmented as "teeth, roots
//! and bone in one piece" looks like, and the body whose build must follow its surface
//! rather than its volume.
//!
//! The solid is given by an inside test (teeth ∪ block) sampled on a regular grid and
//! extracted with naive surface nets (the `fast-surface-nets` crate, as the splint's
//! surface): shared vertices, so the surface comes out closed, and grid faces whose inside
//! corners lie on one diagonal only are opened first, so every edge has two triangles.

use super::{arch_curve, arch_places, icosphere_levels, molar_radius, ToothPlace};
use crate::mesh::Mesh;
use fast_surface_nets::ndshape::{RuntimeShape, Shape as _};
use fast_surface_nets::{surface_nets, SurfaceNetsBuffer};
use glam::DVec3;
use rayon::prelude::*;

/// Grid spacing of the extraction (millimetres): the surface lies within a few hundredths of
/// a millimetre of the solid, and an arch has about 0.5 M triangles.
const VOXEL: f64 = 0.25;
/// The block follows [`arch_curve`] between x = ±this (mm): where the curve runs steeply
/// back, 2 mm in x is about 6 mm along the arch, a few mm of bone behind the last molars
/// (the teeth stand between ±24).
const BLOCK_END_X: f64 = 26.0;
/// Half the block's width across the arch (mm): 18 mm of bone, twice a tooth's width.
const BLOCK_HALF_WIDTH: f64 = 9.0;
/// The lower block's top (mm, in the lower molars' frame): 1 mm of root shows above the
/// bone, below the crown (which starts at z = 0).
const LOWER_BLOCK_TOP: f64 = -1.0;
/// The block's height (mm): 26 mm of bone below the lower teeth (above the upper ones).
const BLOCK_HEIGHT: f64 = 26.0;
/// Radius of the block's rounded edges (mm).
const BLOCK_ROUNDING: f64 = 2.0;
/// Field values are clamped to ± this many cells: only values near zero place vertices.
const CLAMP_CELLS: f64 = 4.0;

/// A generated dental arch pair with bone (millimetres): the teeth of
/// [`arch_pair(subdivisions, teeth)`](super::arch_pair) — the same molars at the same places,
/// interlocking at the identity pose — with their roots sunk in a solid horseshoe block of
/// bone (18 mm across the arch, 26 mm tall, following the arch 5 mm past the last molars,
/// edges rounded 2 mm): the lower block below the lower teeth, the upper block above the
/// upper ones, 1 mm of root showing between the bone and each crown. Each arch is ONE closed,
/// watertight, 2-manifold, outward-facing surface (teeth ∪ bone, no inner walls), about
/// 70 × 60 × 30 mm, 50,000 mm³ and 0.5 M triangles; returns (upper, lower) like
/// [`arch_pair`](super::arch_pair).
///
/// The surface is extracted at 0.2 mm, so the crowns coincide with those of `arch_pair`
/// within a few hundredths of a millimetre (not triangle for triangle), and the creases
/// where the teeth leave the bone are rounded by about a voxel. Takes well under a second on
/// two cores. Deterministic.
///
/// What it is for: a body that is mostly deep volume while contact only happens near its
/// crowns (the build must follow the surface), and wafers on arches with bone.
pub fn arch_pair_with_bone(subdivisions: u32, teeth: usize) -> (Mesh, Mesh) {
    let places = arch_places(teeth);
    let directions = Directions::new(subdivisions);
    let arch = |upper: bool| extract(&Solid::new(&places, &directions, upper, true));
    rayon::join(|| arch(true), || arch(false))
}

/// The teeth of [`arch_pair_with_bone`] without the bone: the union of
/// [`arch_pair(subdivisions, teeth)`](super::arch_pair)'s teeth per arch, extracted on the same
/// grid, so that the crowns more than a millimetre out of the bone are the bone arch's vertex
/// for vertex (where neighbouring teeth overlap there is one surface, not two shells). For
/// comparing what the bone changes. Returns (upper, lower).
pub fn arch_pair_teeth_extracted(subdivisions: u32, teeth: usize) -> (Mesh, Mesh) {
    let places = arch_places(teeth);
    let directions = Directions::new(subdivisions);
    let arch = |upper: bool| extract(&Solid::new(&places, &directions, upper, false));
    rayon::join(|| arch(true), || arch(false))
}

/// The icosphere's triangles of every level and a lookup from directions to the finest
/// level's triangle around them.
struct Directions {
    /// Unit icosphere vertices.
    dirs: Vec<DVec3>,
    /// Triangles per level ([`icosphere_levels`]).
    levels: Vec<Vec<[u32; 3]>>,
    /// The finest triangle whose cone holds the centre of each cube-map texel.
    table: Vec<u32>,
}

/// Texels along a cube-map face's side: a tenth of a finest triangle's width at 5
/// subdivisions, so most lookups land in a texel whose triangle holds the direction.
const TABLE_SIDE: usize = 96;

impl Directions {
    fn new(subdivisions: u32) -> Self {
        let (dirs, levels) = icosphere_levels(subdivisions);
        let mut d = Directions {
            dirs,
            levels,
            table: Vec::new(),
        };
        let n = TABLE_SIDE;
        d.table = (0..6 * n * n)
            .into_par_iter()
            .map(|t| d.descend(texel_centre(t, n)) as u32)
            .collect();
        d
    }

    /// How far inside the cone of triangle `t` the unit direction `d` is (negative: outside).
    fn inside_by(&self, t: [u32; 3], d: DVec3) -> f64 {
        let [a, b, c] = t.map(|i| self.dirs[i as usize]);
        d.dot(a.cross(b))
            .min(d.dot(b.cross(c)))
            .min(d.dot(c.cross(a)))
    }

    /// The finest triangle whose cone holds `d`, level by level (each child's cone tiles its
    /// parent's; the child `d` is deepest inside is taken, so rounding cannot lose it).
    fn descend(&self, d: DVec3) -> usize {
        let best = |range: std::ops::Range<usize>, level: &[[u32; 3]]| -> usize {
            let mut pick = (range.start, f64::NEG_INFINITY);
            for t in range {
                let s = self.inside_by(level[t], d);
                if s > pick.1 {
                    pick = (t, s);
                }
            }
            pick.0
        };
        let mut t = best(0..self.levels[0].len(), &self.levels[0]);
        for level in &self.levels[1..] {
            t = best(4 * t..4 * t + 4, level);
        }
        t
    }

    /// The finest triangle around the unit direction `d`: the table's, when its cone holds
    /// `d`, else found by descending.
    fn around(&self, d: DVec3) -> [u32; 3] {
        let finest = &self.levels[self.levels.len() - 1];
        let guess = finest[self.table[texel_of(d, TABLE_SIDE)] as usize];
        if self.inside_by(guess, d) >= 0.0 {
            guess
        } else {
            finest[self.descend(d)]
        }
    }
}

/// The cube-map texel of a direction: the face of its largest coordinate, then a square
/// grid of `n` × `n` texels over that face.
fn texel_of(d: DVec3, n: usize) -> usize {
    let a = d.abs();
    let (face, u, v, w) = if a.x >= a.y && a.x >= a.z {
        (usize::from(d.x < 0.0), d.y, d.z, a.x)
    } else if a.y >= a.z {
        (2 + usize::from(d.y < 0.0), d.z, d.x, a.y)
    } else {
        (4 + usize::from(d.z < 0.0), d.x, d.y, a.z)
    };
    let cell = |c: f64| (((c / w + 1.0) * 0.5 * n as f64) as usize).min(n - 1);
    face * n * n + cell(u) * n + cell(v)
}

/// The unit direction through the centre of texel `t` ([`texel_of`]'s inverse).
fn texel_centre(t: usize, n: usize) -> DVec3 {
    let (face, rest) = (t / (n * n), t % (n * n));
    let c = |k: usize| (k as f64 + 0.5) / n as f64 * 2.0 - 1.0;
    let (u, v) = (c(rest / n), c(rest % n));
    let s = if face % 2 == 0 { 1.0 } else { -1.0 };
    match face / 2 {
        0 => DVec3::new(s, u, v),
        1 => DVec3::new(v, s, u),
        _ => DVec3::new(u, v, s),
    }
    .normalize()
}

/// One tooth of the solid: its place and the radii of its molar's vertices.
struct Tooth<'a> {
    place: ToothPlace,
    /// The molar's radius along each unit icosphere vertex ([`molar_radius`]).
    radii: Vec<f64>,
    directions: &'a Directions,
    /// Largest radius (molar units): beyond it the molar is outside.
    reach: f64,
}

impl Tooth<'_> {
    /// How far the polyhedral molar's surface lies from its centre along the unit direction
    /// `d` (molar units): the molar's triangle over the icosphere's triangle around `d`, cut
    /// by the ray. The same surface as [`molar`](super::molar), triangle for triangle.
    fn extent(&self, d: DVec3) -> f64 {
        let tri = self.directions.around(d);
        let [a, b, c] = tri.map(|i| self.directions.dirs[i as usize] * self.radii[i as usize]);
        let n = (b - a).cross(c - a);
        n.dot(a) / n.dot(d)
    }

    /// Positive inside the tooth, negative outside: the radial gap to the surface at `p`
    /// (arch frame, mm), a distance-like value for placing the surface between samples.
    fn field(&self, p: DVec3, upper: bool) -> f64 {
        let q = self.place.to_molar(p, upper);
        let r = q.length();
        if r >= self.reach {
            return (self.reach - r) * super::ARCH_TOOTH_SCALE;
        }
        if r <= 0.0 {
            return f64::INFINITY;
        }
        (self.extent(q / r) - r) * super::ARCH_TOOTH_SCALE
    }
}

/// Teeth ∪ block of one arch.
struct Solid<'a> {
    teeth: Vec<Tooth<'a>>,
    /// The arch curve between x = ±[`BLOCK_END_X`], as a polyline.
    curve: Vec<DVec3>,
    /// The block's bottom and top (mm).
    z: (f64, f64),
    upper: bool,
    /// With the block (else the teeth alone).
    bone: bool,
}

impl<'a> Solid<'a> {
    fn new(places: &[ToothPlace], directions: &'a Directions, upper: bool, bone: bool) -> Self {
        let teeth = places
            .iter()
            .map(|&place| {
                let radii: Vec<f64> = directions
                    .dirs
                    .iter()
                    .map(|&v| molar_radius(v, place.phase(upper)))
                    .collect();
                let reach = radii.iter().copied().fold(0.0, f64::max);
                Tooth {
                    place,
                    radii,
                    directions,
                    reach,
                }
            })
            .collect();
        let steps = 120;
        let curve = (0..=steps)
            .map(|k| arch_curve(-BLOCK_END_X + 2.0 * BLOCK_END_X * k as f64 / steps as f64))
            .collect();
        let z = if upper {
            // The lower block mirrored through the plane between the arches' molar frames.
            let lift = super::ARCH_UPPER_LIFT * super::ARCH_TOOTH_SCALE;
            (
                lift - LOWER_BLOCK_TOP,
                lift - LOWER_BLOCK_TOP + BLOCK_HEIGHT,
            )
        } else {
            (LOWER_BLOCK_TOP - BLOCK_HEIGHT, LOWER_BLOCK_TOP)
        };
        Solid {
            teeth,
            curve,
            z,
            upper,
            bone,
        }
    }

    /// Distance in the xy plane from `(x, y)` to the arch curve.
    fn across(&self, x: f64, y: f64) -> f64 {
        let p = DVec3::new(x, y, 0.0);
        self.curve
            .windows(2)
            .map(|w| {
                let (a, b) = (w[0], w[1]);
                let ab = b - a;
                let t = ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0);
                (p - (a + ab * t)).length_squared()
            })
            .fold(f64::INFINITY, f64::min)
            .sqrt()
    }

    /// Positive inside the block: the signed distance to its rounded cross-section, given the
    /// distance `u` across the arch and the height `z`.
    fn block(&self, u: f64, z: f64) -> f64 {
        if !self.bone {
            return f64::NEG_INFINITY;
        }
        let (lo, hi) = self.z;
        let r = BLOCK_ROUNDING;
        let qx = u - (BLOCK_HALF_WIDTH - r);
        let qz = (z - 0.5 * (lo + hi)).abs() - (0.5 * (hi - lo) - r);
        let outside = DVec3::new(qx.max(0.0), qz.max(0.0), 0.0).length();
        -(qx.max(qz).min(0.0) + outside - r)
    }

    /// The box the solid fills.
    fn bbox(&self) -> (DVec3, DVec3) {
        let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        if self.bone {
            for p in &self.curve {
                lo = lo.min(*p - BLOCK_HALF_WIDTH);
                hi = hi.max(*p + BLOCK_HALF_WIDTH);
            }
            lo.z = self.z.0;
            hi.z = self.z.1;
        }
        for t in &self.teeth {
            let r = t.reach * super::ARCH_TOOTH_SCALE;
            let c = t.place.to_arch(DVec3::ZERO, self.upper);
            lo = lo.min(c - r);
            hi = hi.max(c + r);
        }
        (lo, hi)
    }
}

/// The closed surface of `solid`, outward facing.
fn extract(solid: &Solid<'_>) -> Mesh {
    let h = VOXEL;
    let (lo, hi) = solid.bbox();
    // At least one node of outside below the box, two above (surface nets makes no quad on
    // an array's last plane). The nodes lie on one lattice for every solid, so that the same
    // teeth with and without bone are sampled at the same points (their crowns come out
    // vertex for vertex the same), off the block's flat faces by an odd fraction of a cell
    // (a face through nodes gives collinear, zero-area triangles).
    let origin = ((lo / h).floor() - 2.0 + 0.37) * h;
    let n = ((hi - lo) / h).ceil().as_uvec3() + 4;
    let [nx, ny, nz] = [n.x as usize, n.y as usize, n.z as usize];
    let at = |i: usize, j: usize, k: usize| origin + DVec3::new(i as f64, j as f64, k as f64) * h;
    let clamp = CLAMP_CELLS * h;
    // Distance across the arch per column.
    let across: Vec<f64> = (0..nx * ny)
        .into_par_iter()
        .map(|c| {
            let p = at(c % nx, c / nx, 0);
            solid.across(p.x, p.y)
        })
        .collect();
    let slice = nx * ny;
    // The block first, then each tooth over its own box; negative inside (surface nets).
    let mut sdf = vec![clamp as f32; slice * nz];
    let boxes: Vec<[usize; 6]> = solid
        .teeth
        .iter()
        .map(|t| {
            let r = t.reach * super::ARCH_TOOTH_SCALE + h;
            let c = t.place.to_arch(DVec3::ZERO, solid.upper);
            let a = ((c - r - origin) / h).floor().max(DVec3::ONE);
            let b = ((c + r - origin) / h).ceil();
            [
                a.x as usize,
                a.y as usize,
                a.z as usize,
                (b.x as usize).min(nx - 3),
                (b.y as usize).min(ny - 3),
                (b.z as usize).min(nz - 3),
            ]
        })
        .collect();
    sdf.par_chunks_mut(slice)
        .enumerate()
        .for_each(|(k, layer)| {
            if k == 0 || k + 2 >= nz {
                return;
            }
            let z = at(0, 0, k).z;
            for j in 1..ny - 2 {
                for i in 1..nx - 2 {
                    let inside = solid.block(across[i + nx * j], z);
                    layer[i + nx * j] = (-inside).clamp(-clamp, clamp) as f32;
                }
            }
            for (t, b) in solid.teeth.iter().zip(&boxes) {
                if k < b[2] || k > b[5] {
                    continue;
                }
                for j in b[1]..=b[4] {
                    for i in b[0]..=b[3] {
                        let cell = &mut layer[i + nx * j];
                        // Deep in the bone (or another tooth) no tooth changes the value.
                        if *cell > -clamp as f32 {
                            let inside = t.field(at(i, j, k), solid.upper);
                            *cell = cell.min((-inside).clamp(-clamp, clamp) as f32);
                        }
                    }
                }
            }
        });
    // The opened corners a quarter cell outside, so that no vertices stack on them.
    crate::mesh::untangle::untangle(&mut sdf, [nx, ny, nz], (0.25 * h) as f32);
    let shape = RuntimeShape::<u32, 3>::new([nx as u32, ny as u32, nz as u32]);
    debug_assert_eq!(shape.size() as usize, sdf.len());
    let mut buf = SurfaceNetsBuffer::default();
    surface_nets(
        &sdf,
        &shape,
        [0, 0, 0],
        [nx as u32 - 1, ny as u32 - 1, nz as u32 - 1],
        &mut buf,
    );
    let vertices = buf
        .positions
        .iter()
        .map(|p| origin + DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64) * h)
        .collect();
    let triangles = buf
        .indices
        .chunks_exact(3)
        .map(|t| [t[0], t[1], t[2]])
        .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
        .collect();
    let mut mesh = Mesh {
        vertices,
        triangles,
    };
    if mesh.signed_volume() < 0.0 {
        mesh.flip();
    }
    mesh
}
