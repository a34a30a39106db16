//! A fast estimate of the signed clearance between two bodies at a pose, for planning and
//! labelling motions (not a query of the trees).
//!
//! The clearance is the minimum signed distance of sample points of one body to the
//! surface of the other: positive is the gap, negative the deepest overlap (a sample inside
//! the other body, by its generalized winding number). The samples are a spatially even
//! subset of B's vertices (against A's surface) and, by default, of A's vertices (against
//! B's surface), optionally densified where the bodies meet
//! ([`ClearanceEstimator::add_contact_samples`]).
//!
//! Along a motion most samples need no work: the signed distance is 1-Lipschitz, so a
//! sample whose last computed value minus how far it has moved since is not below the
//! current minimum cannot be the minimum (groups of 32 nearby samples are skipped at once
//! the same way). Samples are resolved only to a little beyond the current minimum, with
//! the previous closest triangle as the search's starting bound; the side (inside or out)
//! comes from the closest triangle's normal when the closest point lies inside it, from the
//! sample's history when it cannot have crossed the surface, and otherwise from the winding
//! number (cached per grid cell for points away from the surface). A frame of a 1 kHz motion
//! of the jaw pair costs some tens of closest-point queries.

use glam::{DQuat, DVec3};
use innersphere::mesh::winding::FastWinding;
use innersphere::Mesh;
use innersphere::Pose;
use rayon::prelude::*;
use std::collections::{HashMap, HashSet};

/// Clearance within ±this is [`Phase::Touching`] by default (0.1, millimetres for the jaws).
pub const DEFAULT_TOUCH: f64 = 0.1;

/// The contact phase of a frame, from its clearance.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Phase {
    /// Clearance above the touch threshold: a gap.
    Separated,
    /// Clearance within ± the touch threshold: light contact.
    Touching,
    /// Clearance below minus the touch threshold: the bodies interpenetrate.
    Overlap,
}

impl Phase {
    /// All phases, in order.
    pub const ALL: [Phase; 3] = [Phase::Separated, Phase::Touching, Phase::Overlap];

    /// `separated`, `touching` or `overlap`.
    pub fn name(self) -> &'static str {
        match self {
            Phase::Separated => "separated",
            Phase::Touching => "touching",
            Phase::Overlap => "overlap",
        }
    }
}

impl std::fmt::Display for Phase {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// The phase of a clearance: separated above `touch`, touching within `[-touch, touch]`,
/// overlap below `-touch` (and for NaN).
pub fn phase_of(clearance: f64, touch: f64) -> Phase {
    if clearance > touch {
        Phase::Separated
    } else if clearance >= -touch {
        Phase::Touching
    } else {
        Phase::Overlap
    }
}

/// How many frames are in each phase.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct PhaseCounts {
    /// Frames with a gap.
    pub separated: usize,
    /// Frames in light contact.
    pub touching: usize,
    /// Frames that interpenetrate.
    pub overlap: usize,
}

impl PhaseCounts {
    /// Counts the phases.
    pub fn of(phases: &[Phase]) -> PhaseCounts {
        let mut c = PhaseCounts::default();
        for p in phases {
            match p {
                Phase::Separated => c.separated += 1,
                Phase::Touching => c.touching += 1,
                Phase::Overlap => c.overlap += 1,
            }
        }
        c
    }

    /// True when every phase occurs.
    pub fn all_present(&self) -> bool {
        self.separated > 0 && self.touching > 0 && self.overlap > 0
    }
}

/// Options of [`ClearanceEstimator`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClearanceOptions {
    /// About how many vertices of each body to sample (all when a body has fewer).
    pub samples: usize,
    /// Also sample A's vertices against B's surface (catches A's tips poking into B between
    /// B's samples; builds a second winding hierarchy).
    pub symmetric: bool,
}

impl Default for ClearanceOptions {
    fn default() -> Self {
        ClearanceOptions {
            samples: 4096,
            symmetric: true,
        }
    }
}

/// Last evaluation of one sample: where it was (in the surface's frame) and a lower bound
/// of its signed distance there.
#[derive(Debug, Clone, Copy)]
struct Known {
    at: DVec3,
    lower: f64,
    /// The surface triangle (BVH slot) that was closest, `u32::MAX` if none.
    slot: u32,
}

const UNKNOWN: Known = Known {
    at: DVec3::ZERO,
    lower: f64::NEG_INFINITY,
    slot: u32::MAX,
};

/// Samples per group.
const GROUP: usize = 32;
/// The inside/outside cache is emptied when it grows beyond this many cells.
const MAX_CELLS: usize = 1 << 20;

/// A run of spatially close samples with a common lower bound, so that groups far from the
/// minimum are skipped without looking at their samples.
#[derive(Debug, Clone, Copy)]
struct Group {
    start: u32,
    end: u32,
    /// Centre and radius of a ball around the samples (model coordinates).
    centre: DVec3,
    radius: f64,
    /// Lower bound of the samples' signed distances at the pose of the last visit...
    lower: f64,
    /// ...whose rotation was this, and which put the centre here.
    rotation: DQuat,
    at: DVec3,
}

/// Sample points of one body against the surface of the other.
#[derive(Debug, Clone)]
struct Side {
    surface: FastWinding,
    lo: DVec3,
    hi: DVec3,
    /// Samples in their own body's model coordinates, in groups of nearby ones.
    samples: Vec<DVec3>,
    known: Vec<Known>,
    groups: Vec<Group>,
    /// Inside/outside of grid cells of size `cell` (each cell's centre by its winding
    /// number): exact for points farther than `cell` from the surface.
    cells: HashMap<[i64; 3], bool>,
    cell: f64,
    /// Scratch: (lower bound now, sample, position now) and the groups visited.
    cand: Vec<(f64, u32, DVec3)>,
    visited: Vec<u32>,
}

impl Side {
    fn new(surface: FastWinding, samples: Vec<DVec3>, cell: f64) -> Side {
        let (lo, hi) = surface
            .bvh()
            .bounds()
            .unwrap_or((DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)));
        let mut side = Side {
            surface,
            lo,
            hi,
            samples: Vec::new(),
            known: Vec::new(),
            groups: Vec::new(),
            cells: HashMap::new(),
            cell,
            cand: Vec::new(),
            visited: Vec::new(),
        };
        side.add(&samples);
        side
    }

    fn inside_box(&self, p: DVec3) -> bool {
        p.cmpge(self.lo).all() && p.cmple(self.hi).all()
    }

    fn winding_inside(&self, p: DVec3) -> bool {
        self.inside_box(p) && self.surface.winding_number(p).abs() >= 0.5
    }

    /// Inside test of a point known to be farther than `cell` from the surface.
    fn far_inside(&mut self, p: DVec3) -> bool {
        if !self.inside_box(p) {
            return false;
        }
        let c = (p / self.cell).floor();
        let key = [c.x as i64, c.y as i64, c.z as i64];
        if let Some(&inside) = self.cells.get(&key) {
            return inside;
        }
        let centre = (c + 0.5) * self.cell;
        let inside = self.winding_inside(centre);
        if self.cells.len() >= MAX_CELLS {
            self.cells.clear();
        }
        self.cells.insert(key, inside);
        inside
    }

    /// Signed distance of `p`, exact when within `bound` of the surface or inside;
    /// otherwise `bound` (a lower bound). `hint` is the slot of a triangle that was closest
    /// to a nearby point (it only speeds the search up); the answer's slot is returned too.
    /// `side` is whether `p` is inside, when already known.
    fn signed(&mut self, p: DVec3, bound: f64, hint: u32, side: Option<bool>) -> (f64, u32) {
        let bvh = self.surface.bvh();
        // (distance, slot, side by the closest triangle's normal when the closest point lies
        // inside the triangle — then the offset runs along the normal), or a lower bound.
        let upper = (bound * bound).min(bvh.slot_distance_sq(p, hint));
        let found = match bvh.closest_point_or_bound(p, upper) {
            Ok(c) => {
                let d = c.dist_sq.sqrt();
                let [ta, tb, tc] = bvh.tris[c.slot as usize];
                let n = (tb - ta).cross(tc - ta);
                let along = (p - c.point).dot(n);
                let by_normal =
                    (along.abs() >= 0.9999 * d * n.length() && d > 0.0).then_some(along < 0.0);
                Ok((d, c.slot, by_normal))
            }
            Err(lower_sq) => Err(lower_sq.sqrt()),
        };
        match found {
            Ok((d, slot, by_normal)) => {
                let inside = match side.or(by_normal) {
                    Some(inside) => inside,
                    None if d > self.cell => self.far_inside(p),
                    None => self.winding_inside(p),
                };
                (if inside { -d } else { d }, slot)
            }
            Err(lower) => {
                let inside = match side {
                    Some(inside) => inside,
                    None if lower > self.cell => self.far_inside(p),
                    None => self.winding_inside(p),
                };
                if inside {
                    match self.surface.bvh().closest_point(p, f64::INFINITY) {
                        Some(c) => (-c.dist_sq.sqrt(), c.slot),
                        None => (f64::NEG_INFINITY, u32::MAX),
                    }
                } else {
                    (lower, u32::MAX)
                }
            }
        }
    }

    /// Lowers `best` to the minimum signed distance of the samples when it is below.
    /// Samples are resolved to `|best| + margin`.
    fn update(&mut self, to_surface: &Pose, mut best: f64, margin: f64, evals: &mut u64) -> f64 {
        let bound = |best: f64| {
            if best.is_finite() {
                best.abs() + margin
            } else {
                f64::INFINITY
            }
        };
        self.cand.clear();
        self.visited.clear();
        let rot = to_surface.rotation;
        for (gi, g) in self.groups.iter().enumerate() {
            let cos = rot.dot(g.rotation).abs().min(1.0);
            let turn = 2.0 * (1.0 - cos * cos).max(0.0).sqrt();
            let moved = (to_surface.transform_point(g.centre) - g.at).length() + g.radius * turn;
            if g.lower - moved >= best {
                continue;
            }
            self.visited.push(gi as u32);
            for i in g.start as usize..g.end as usize {
                let k = &self.known[i];
                let p = to_surface.transform_point(self.samples[i]);
                let lower = k.lower - (p - k.at).length();
                if lower < best {
                    self.cand.push((lower, i as u32, p));
                }
            }
        }
        // Resolve the most promising samples first, which usually leaves few below `best`.
        while self.cand.len() > 32 {
            let Some(m) = (0..self.cand.len()).min_by(|&x, &y| {
                let (a, b) = (&self.cand[x], &self.cand[y]);
                a.0.total_cmp(&b.0).then(a.1.cmp(&b.1))
            }) else {
                break;
            };
            let (lower, i, p) = self.cand.swap_remove(m);
            if lower >= best {
                self.cand.clear();
                break;
            }
            best = best.min(self.resolve(i, p, lower, bound(best), evals));
            let before = self.cand.len();
            self.cand.retain(|c| c.0 < best);
            if self.cand.len() * 4 > before * 3 {
                break;
            }
        }
        self.cand
            .sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        for j in 0..self.cand.len() {
            let (lower, i, p) = self.cand[j];
            if lower >= best {
                break;
            }
            best = best.min(self.resolve(i, p, lower, bound(best), evals));
        }
        // The visited groups' bounds at this pose.
        for &gi in &self.visited {
            let g = &mut self.groups[gi as usize];
            let mut lower = f64::INFINITY;
            for i in g.start as usize..g.end as usize {
                let k = &self.known[i];
                let p = to_surface.transform_point(self.samples[i]);
                lower = lower.min(k.lower - (p - k.at).length());
            }
            g.lower = lower;
            g.rotation = rot;
            g.at = to_surface.transform_point(g.centre);
        }
        best
    }

    /// Computes sample `i` at its position `p` (where `lower` bounds it from below), records
    /// it and returns its signed distance (or `bound` when it is farther).
    fn resolve(&mut self, i: u32, p: DVec3, lower: f64, bound: f64, evals: &mut u64) -> f64 {
        let k = self.known[i as usize];
        // The sample cannot have crossed the surface if it moved less than its distance.
        let moved = (p - k.at).length();
        let side = if lower > 0.0 {
            Some(false)
        } else if k.lower.is_finite() && k.lower < 0.0 && moved < -k.lower {
            Some(true)
        } else {
            None
        };
        let (s, slot) = self.signed(p, bound, k.slot, side);
        *evals += 1;
        self.known[i as usize] = Known {
            at: p,
            lower: s,
            slot,
        };
        s
    }

    /// Adds the points (skipping ones already sampled) and regroups all samples along a
    /// Morton curve.
    fn add(&mut self, points: &[DVec3]) {
        let mut have: HashSet<[u64; 3]> = self.samples.iter().map(|p| key(*p)).collect();
        let mut all: Vec<(DVec3, Known)> = self
            .samples
            .iter()
            .copied()
            .zip(self.known.iter().copied())
            .collect();
        for &p in points {
            if have.insert(key(p)) {
                all.push((p, UNKNOWN));
            }
        }
        let (lo, hi) = all.iter().fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), (p, _)| (lo.min(*p), hi.max(*p)),
        );
        let ext = (hi - lo).max_element();
        let scale = if ext > 0.0 { 1023.0 / ext } else { 0.0 };
        let mut keyed: Vec<(u32, usize)> = all
            .iter()
            .enumerate()
            .map(|(i, (p, _))| {
                let q = ((*p - lo) * scale).clamp(DVec3::ZERO, DVec3::splat(1023.0));
                (morton(q.x as u32, q.y as u32, q.z as u32), i)
            })
            .collect();
        keyed.sort_unstable();
        self.samples = keyed.iter().map(|&(_, i)| all[i].0).collect();
        self.known = keyed.iter().map(|&(_, i)| all[i].1).collect();
        self.groups = self
            .samples
            .chunks(GROUP)
            .enumerate()
            .map(|(c, pts)| {
                let (lo, hi) = pts.iter().fold(
                    (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
                    |(lo, hi), p| (lo.min(*p), hi.max(*p)),
                );
                let centre = (lo + hi) * 0.5;
                let radius = pts
                    .iter()
                    .map(|p| (*p - centre).length())
                    .fold(0.0, f64::max);
                Group {
                    start: (c * GROUP) as u32,
                    end: (c * GROUP + pts.len()) as u32,
                    centre,
                    radius,
                    lower: f64::NEG_INFINITY,
                    rotation: DQuat::IDENTITY,
                    at: DVec3::ZERO,
                }
            })
            .collect();
    }
}

/// Interleaves the low 10 bits of three coordinates.
fn morton(x: u32, y: u32, z: u32) -> u32 {
    fn spread(v: u32) -> u32 {
        let mut v = v & 0x3ff;
        v = (v | (v << 16)) & 0x0300_00ff;
        v = (v | (v << 8)) & 0x0300_f00f;
        v = (v | (v << 4)) & 0x030c_30c3;
        (v | (v << 2)) & 0x0924_9249
    }
    spread(x) | (spread(y) << 1) | (spread(z) << 2)
}

fn key(p: DVec3) -> [u64; 3] {
    [
        (p.x + 0.0).to_bits(),
        (p.y + 0.0).to_bits(),
        (p.z + 0.0).to_bits(),
    ]
}

/// Estimates the signed clearance of body B at poses in body A's frame (see the
/// [module docs](self)). Remembers the last values of its samples, so that a sequence of
/// nearby poses (a motion, a bisection) is cheap.
#[derive(Debug, Clone)]
pub struct ClearanceEstimator {
    /// B's samples against A's surface.
    b_in_a: Side,
    /// A's samples against B's surface.
    a_in_b: Option<Side>,
    /// How far beyond the cap samples are resolved, so that they need no work again until
    /// they move that far.
    margin: f64,
    evals: u64,
}

impl ClearanceEstimator {
    /// Builds the winding hierarchies and picks the samples. Both meshes must be valid
    /// (see [`Mesh::validate`]).
    pub fn new(a: &Mesh, b: &Mesh, opts: &ClearanceOptions) -> ClearanceEstimator {
        let n = opts.samples.max(1);
        let ((wa, sb), (wb, sa)) = rayon::join(
            || (FastWinding::new(a), even_sample(b, n)),
            || {
                if opts.symmetric {
                    (Some(FastWinding::new(b)), even_sample(a, n))
                } else {
                    (None, Vec::new())
                }
            },
        );
        let size = {
            let (lo, hi) = a.bbox();
            let (lo2, hi2) = b.bbox();
            (hi - lo).length().max((hi2 - lo2).length())
        };
        let margin = if size.is_finite() && size > 0.0 {
            0.005 * size
        } else {
            1.0
        };
        ClearanceEstimator {
            b_in_a: Side::new(wa, sb, margin),
            a_in_b: wb.map(|w| Side::new(w, sa, margin)),
            margin,
            evals: 0,
        }
    }

    /// Number of sample points (both directions).
    pub fn sample_count(&self) -> usize {
        self.b_in_a.samples.len() + self.a_in_b.as_ref().map_or(0, |s| s.samples.len())
    }

    /// Number of point–surface distance evaluations so far (a cost measure).
    pub fn evaluations(&self) -> u64 {
        self.evals
    }

    /// The estimated signed clearance of B at `pose` in A's frame: positive gap, negative
    /// overlap depth.
    pub fn clearance(&mut self, pose: &Pose) -> f64 {
        self.clearance_capped(pose, f64::INFINITY)
    }

    /// [`clearance`](Self::clearance), but values above `cap` are reported as `cap` — much
    /// cheaper when the bodies are far apart.
    pub fn clearance_capped(&mut self, pose: &Pose, cap: f64) -> f64 {
        let cap = if cap.is_nan() { f64::INFINITY } else { cap };
        let mut best = self.b_in_a.update(pose, cap, self.margin, &mut self.evals);
        if let Some(side) = self.a_in_b.as_mut() {
            best = side.update(&pose.inverse(), best, self.margin, &mut self.evals);
        }
        best
    }

    /// The clearance of every frame of a motion, capped at `cap`.
    pub fn clearances(&mut self, motion: &super::Motion, cap: f64) -> Vec<f64> {
        motion
            .frames
            .iter()
            .map(|f| self.clearance_capped(&f.pose, cap))
            .collect()
    }

    /// Adds samples where the bodies meet at `pose`: the vertices of B within `radius` of
    /// A's surface (and of A within `radius` of B's, when symmetric), thinned evenly to
    /// about `max_per_body` each. Makes the estimate near contact much finer.
    pub fn add_contact_samples(
        &mut self,
        a: &Mesh,
        b: &Mesh,
        pose: &Pose,
        radius: f64,
        max_per_body: usize,
    ) {
        let near = |side: &Side, mesh: &Mesh, tf: &Pose| -> Vec<DVec3> {
            let pts: Vec<DVec3> = mesh
                .vertices
                .par_iter()
                .filter(|v| {
                    side.surface
                        .bvh()
                        .closest_point(tf.transform_point(**v), radius * radius)
                        .is_some()
                })
                .copied()
                .collect();
            thin(&pts, max_per_body)
        };
        let pb = near(&self.b_in_a, b, pose);
        self.b_in_a.add(&pb);
        if let Some(side) = self.a_in_b.as_mut() {
            let pa = near(side, a, &pose.inverse());
            side.add(&pa);
        }
    }
}

/// The estimated signed clearance of B at `pose` in A's frame, from scratch (see
/// [`ClearanceEstimator`] for many poses).
pub fn clearance(a: &Mesh, b: &Mesh, pose: &Pose) -> f64 {
    ClearanceEstimator::new(a, b, &ClearanceOptions::default()).clearance(pose)
}

/// About `n` of the mesh's vertices (those used by triangles), spread evenly over its
/// surface: one per cell of a grid sized from the surface area. All of them when there are
/// at most `n`.
pub fn even_sample(mesh: &Mesh, n: usize) -> Vec<DVec3> {
    let mut used = vec![false; mesh.vertices.len()];
    for t in &mesh.triangles {
        for &i in t {
            if let Some(u) = used.get_mut(i as usize) {
                *u = true;
            }
        }
    }
    let pts: Vec<DVec3> = mesh
        .vertices
        .iter()
        .zip(&used)
        .filter(|(_, &u)| u)
        .map(|(v, _)| *v)
        .collect();
    thin(&pts, n)
}

/// About `n` of the points, one per cell of a grid whose size is tuned to that count (the
/// first point of each cell, so the result depends only on the input).
fn thin(pts: &[DVec3], n: usize) -> Vec<DVec3> {
    let n = n.max(1);
    if pts.len() <= n {
        return pts.to_vec();
    }
    let (lo, hi) = pts.iter().fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    );
    let ext = hi - lo;
    // Start from a cell as if the points covered the box's largest face evenly.
    let face = (ext.x * ext.y).max(ext.y * ext.z).max(ext.z * ext.x);
    let mut h = (face / n as f64).sqrt();
    if !(h.is_finite() && h > 0.0) {
        h = ext.max_element().max(1e-300) / n as f64;
    }
    let mut best: Vec<DVec3> = Vec::new();
    for _ in 0..8 {
        let mut cells = std::collections::HashSet::with_capacity(2 * n);
        let picked: Vec<DVec3> = pts
            .iter()
            .filter(|p| {
                let c = ((**p - lo) / h).floor();
                cells.insert([c.x as i64, c.y as i64, c.z as i64])
            })
            .copied()
            .collect();
        let ratio = picked.len() as f64 / n as f64;
        let better =
            best.is_empty() || (ratio.ln().abs() < (best.len() as f64 / n as f64).ln().abs());
        if better {
            best = picked;
        }
        if (0.85..=1.2).contains(&ratio) {
            break;
        }
        // Cells on a surface: the count goes as 1/h².
        h *= ratio.sqrt().clamp(0.25, 4.0);
    }
    best
}
