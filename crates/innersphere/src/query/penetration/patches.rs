//! Contact patches: the overlapping leaf pairs clustered around seeds, each pair joining the
//! patch whose seed (its first pair's lens centroid) is nearest.

use super::answer::Patch;
use crate::pose::Pose;
use crate::query::kernel::lenses::{Terms4, W};
use glam::DVec3;

/// Patches reserved per pair: `max_patches` up to this allocates nothing.
pub(crate) const RESERVED_PATCHES: usize = 64;

/// The scratch of penetration: the patches being summed and the finished ones.
#[derive(Debug)]
pub(crate) struct PenetrationScratch {
    /// The finished patches of the last query (world frame).
    pub patches: Vec<Patch>,
    /// Running sums of the patches.
    pub acc: Patches,
}

impl PenetrationScratch {
    /// Reserved for up to [`RESERVED_PATCHES`] patches.
    pub(crate) fn new() -> PenetrationScratch {
        PenetrationScratch {
            patches: Vec::with_capacity(RESERVED_PATCHES),
            acc: Patches::new(),
        }
    }
}

/// Running sums of one patch (A's frame).
#[derive(Debug, Clone, Copy, Default)]
struct PatchSums {
    vol: f64,
    vg: DVec3,
    vu: DVec3,
    depth: f64,
    pairs: u32,
}

/// The patches of one query being summed (A's frame). A batch's pairs look for their
/// nearest seed together (a lane per pair, the seeds in order, so each lane finds the first
/// nearest like a scan would); then they join or open patches one by one, in order.
#[derive(Debug)]
pub(crate) struct Patches {
    sx: Vec<f64>,
    sy: Vec<f64>,
    sz: Vec<f64>,
    sums: Vec<PatchSums>,
    /// The patch the last pair joined (`usize::MAX`: none) and its sums, which are summed
    /// here and written back when another patch is joined: consecutive pairs mostly join the
    /// same patch, and summing in memory made every pair wait for the last one's stores.
    cur: usize,
    open: PatchSums,
    max: usize,
    r2: f64,
}

impl Patches {
    fn new() -> Patches {
        Patches {
            sx: Vec::with_capacity(RESERVED_PATCHES),
            sy: Vec::with_capacity(RESERVED_PATCHES),
            sz: Vec::with_capacity(RESERVED_PATCHES),
            sums: Vec::with_capacity(RESERVED_PATCHES),
            cur: usize::MAX,
            open: PatchSums::default(),
            max: 0,
            r2: 0.0,
        }
    }

    /// Empties the patches; up to `max` of them from now on, a pair joining the nearest
    /// seed within `radius` while more may open.
    pub(crate) fn begin(&mut self, max: usize, radius: f64) {
        self.sx.clear();
        self.sy.clear();
        self.sz.clear();
        self.sums.clear();
        self.cur = usize::MAX;
        self.max = max;
        self.r2 = radius * radius;
    }

    /// Adds the first `n` lanes of a batch, in order: each pair (lens volume `v`, centroid
    /// `p`, direction `u`, overlap `depth`) joins the patch with the nearest seed (the first
    /// of equally near ones) when it lies within the radius or no more patches may open;
    /// else it opens a patch seeded at `p`.
    #[inline(always)]
    pub(crate) fn add_batch(&mut self, t: &Terms4, n: usize) {
        if self.max == 0 {
            return;
        }
        let [px, py, pz] = t.p;
        let mut best = [usize::MAX; W];
        let mut bd = [f64::INFINITY; W];
        let seeds = self.sums.len();
        for j in 0..seeds {
            let (x, y, z) = (self.sx[j], self.sy[j], self.sz[j]);
            for l in 0..W {
                let (dx, dy, dz) = (x - px[l], y - py[l], z - pz[l]);
                let dd = dx * dx + dy * dy + dz * dz;
                let nearer = dd < bd[l];
                bd[l] = if nearer { dd } else { bd[l] };
                best[l] = if nearer { j } else { best[l] };
            }
        }
        for l in 0..n {
            let p = DVec3::new(px[l], py[l], pz[l]);
            let (mut best, mut bd) = (best[l], bd[l]);
            // Seeds opened by this batch's earlier pairs.
            for j in seeds..self.sums.len() {
                let (dx, dy, dz) = (self.sx[j] - p.x, self.sy[j] - p.y, self.sz[j] - p.z);
                let dd = dx * dx + dy * dy + dz * dz;
                if dd < bd {
                    (best, bd) = (j, dd);
                }
            }
            if best == usize::MAX || (bd > self.r2 && self.sums.len() < self.max) {
                best = self.open_at(p);
            }
            if best != self.cur {
                if let Some(s) = self.sums.get_mut(self.cur) {
                    *s = self.open;
                }
                self.open = self.sums[best];
                self.cur = best;
            }
            let (v, depth) = (t.v[l], t.depth[l]);
            let u = DVec3::new(t.u[0][l], t.u[1][l], t.u[2][l]);
            let pa = &mut self.open;
            pa.vol += v;
            pa.vg += p * v;
            pa.vu += u * v;
            pa.depth = pa.depth.max(depth);
            pa.pairs += 1;
        }
    }

    /// Opens a patch seeded at `p`; returns its index.
    #[cold]
    fn open_at(&mut self, p: DVec3) -> usize {
        self.sx.push(p.x);
        self.sy.push(p.y);
        self.sz.push(p.z);
        self.sums.push(PatchSums::default());
        self.sums.len() - 1
    }

    /// The finished patches in the world frame (A at `pose_a`).
    pub(crate) fn finish(&mut self, pose_a: &Pose, out: &mut Vec<Patch>) {
        if let Some(s) = self.sums.get_mut(self.cur) {
            *s = self.open;
        }
        self.cur = usize::MAX;
        out.clear();
        for (i, pa) in self.sums.iter().enumerate() {
            let seed = DVec3::new(self.sx[i], self.sy[i], self.sz[i]);
            out.push(Patch {
                point: pose_a.transform_point(if pa.vol > 0.0 { pa.vg / pa.vol } else { seed }),
                normal: pose_a.transform_vector(pa.vu.normalize_or_zero()),
                depth: pa.depth,
                volume: pa.vol,
                pairs: pa.pairs,
            });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The patches of the plain rule: a scan over the seeds in order for the first nearest.
    fn reference(pairs: &[(f64, DVec3, DVec3, f64)], max: usize, r: f64) -> Vec<Patch> {
        let mut seeds: Vec<(DVec3, PatchSums)> = vec![];
        if max == 0 {
            return vec![];
        }
        for &(v, p, u, depth) in pairs {
            let mut best = usize::MAX;
            let mut bd = f64::INFINITY;
            for (i, (s, _)) in seeds.iter().enumerate() {
                let dd = (*s - p).length_squared();
                if dd < bd {
                    bd = dd;
                    best = i;
                }
            }
            if best == usize::MAX || (bd > r * r && seeds.len() < max) {
                seeds.push((p, PatchSums::default()));
                best = seeds.len() - 1;
            }
            let pa = &mut seeds[best].1;
            pa.vol += v;
            pa.vg += p * v;
            pa.vu += u * v;
            pa.depth = pa.depth.max(depth);
            pa.pairs += 1;
        }
        seeds
            .iter()
            .map(|(s, pa)| Patch {
                point: if pa.vol > 0.0 { pa.vg / pa.vol } else { *s },
                normal: pa.vu.normalize_or_zero(),
                depth: pa.depth,
                volume: pa.vol,
                pairs: pa.pairs,
            })
            .collect()
    }

    fn v3() -> impl Strategy<Value = DVec3> {
        // A coarse grid, so that pairs fall at equal distances from two seeds too.
        (-4i32..4, -4i32..4, -4i32..4)
            .prop_map(|(x, y, z)| DVec3::new(x as f64, y as f64, z as f64) * 0.5)
    }

    proptest! {
        /// The batched search gives the plain scan's patches bit for bit, ties (the first
        /// nearest seed wins), seeds opened within a batch and a full set of patches included.
        #[test]
        fn patches_equal_the_plain_scan(
            pairs in prop::collection::vec((0.0f64..1.0, v3(), v3(), 0.0f64..1.0), 0..60),
            max in 0usize..12,
            r in 0.0f64..2.0,
        ) {
            let mut p = Patches::new();
            p.begin(max, r);
            for batch in pairs.chunks(W) {
                let mut t = Terms4::default();
                for (l, &(v, c, u, depth)) in batch.iter().enumerate() {
                    t.v[l] = v;
                    t.depth[l] = depth;
                    for k in 0..3 {
                        t.p[k][l] = c[k];
                        t.u[k][l] = u[k];
                    }
                }
                p.add_batch(&t, batch.len());
            }
            let mut got = vec![];
            p.finish(&Pose::IDENTITY, &mut got);
            prop_assert_eq!(got, reference(&pairs, max, r));
        }
    }
}
