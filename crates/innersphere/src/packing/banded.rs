//! The greedy packing on many threads: in bands of remaining distance, and within a band in
//! independent blocks of the grid.
//!
//! The global greedy order (always the largest remaining distance next) is one chain. Here
//! the distances are taken in bands `[τ·RATIO, τ)` from the largest down, and within a band
//! the grid is cut into cubic blocks, each packed greedily on its own. Blocks are coloured by
//! the parities of their coordinates (8 colours); blocks of one colour are at least one block
//! apart and are packed at the same time. A block is wide enough that what one block's
//! spheres change (the voxels within their reach) never meets another same-coloured block's
//! voxels or changes, so every block sees exactly the state a serial run of the same order
//! would: the spheres stay inside the mesh and disjoint, and the result does not depend on the
//! number of threads (blocks' spheres are appended in block order).
//!
//! In a band every remaining distance is below τ, so a sphere of radius `r` changes only the
//! voxels within `r + τ` of its centre (farther ones keep a remaining distance below their
//! gap to it); refinement grows a sphere by at most the distance its centre moves (half a
//! voxel a step), which bounds the block size needed.

use super::cells::{cover, Remaining, Rows, Voxels};
use super::queue::Entry;
use super::refine::Refiner;
use super::{exact_distance, Floors, PackingOptions, Sphere};
use crate::mesh::bvh::TriangleBvh;
use rayon::prelude::*;
use std::collections::BinaryHeap;
use std::sync::atomic::{AtomicBool, Ordering::Relaxed};

/// Each band's lower end over its upper end. Narrower bands keep the packing closer to the
/// global order for more rounds: ×0.8 packs the jaw 0.3 s faster, but the free occlusion's
/// ranking on the jaw then fails from 3 of 8 starts (BENCHMARKS.md, "Tried").
const RATIO: f64 = 0.9;

/// The packing of [`super::pack_bounded`] in bands and blocks (see the module docs).
// Kept whole (over 120 lines): the bands' loop owns the queue, the refiner and the
// remaining distances that every block of a band reads and writes.
pub(super) fn pack(
    field: Voxels<'_>,
    bounds: &[f64],
    bvh: &TriangleBvh,
    slots: &[u32],
    floors: Floors<'_>,
    opts: &PackingOptions,
    progress: &dyn crate::progress::Progress,
) -> Vec<Sphere> {
    let grid = field.grid;
    let open = field.open;
    let h = grid.h;
    let remaining = Remaining::new(bounds);
    let exact: Vec<AtomicBool> = (0..bounds.len())
        .into_par_iter()
        .map(|_| AtomicBool::new(false))
        .collect();
    let rows = Rows::of(field);
    let floor = floors.floor;
    let mut refiner =
        (opts.refine_steps > 0).then(|| Refiner::new(grid, bvh, opts.refine_steps, open));
    let pad = i64::from(refiner.is_some());
    // Refinement moves a centre at most half a voxel a step, and a sphere grows at most as
    // far as its centre moves: its radius stays below the band's top plus this.
    let growth = if refiner.is_some() {
        0.5 * h * f64::from(opts.refine_steps)
    } else {
        0.0
    };
    let live = |v: f64| v > 0.0 && v >= floor;
    // A voxel stays in the bands while it may still give a sphere.
    let live_at = |p: u32, v: f64| v > 0.0 && !floors.below(p, v);
    // The bands' ends are `floor / RATIO^n`: the same for any upper bounds, so the spheres do
    // not depend on how tight the bounds are (a voxel whose bound lies in a higher band is
    // made exact there and waits for its own band).
    let largest = bounds
        .par_iter()
        .copied()
        .filter(|&v| live(v))
        .reduce(|| 0.0, f64::max);
    let edge = |n: i32| floor / RATIO.powi(n);
    let mut n = 0;
    while edge(n) < largest {
        n += 1;
    }
    // Band `m ≥ 1` is `[edge(m − 1), edge(m))`, the first (`n`) also holds its top; with
    // `n = 0` one band takes everything down to the floor.
    let edges: Vec<f64> = (0..n).map(edge).collect();
    let band_of = |v: f64| band_of(&edges, v);
    // The live voxels by the band of their remaining distance. Distances only shrink, so a
    // voxel only moves to lower bands: each band looks at its own voxels, not at all of them.
    let mut buckets: Vec<Vec<u32>> = vec![Vec::new(); n as usize + 1];
    sort_into(
        &mut buckets,
        bounds.len(),
        |i| i as u32,
        |p| {
            let v = bounds[p as usize];
            live_at(p, v).then(|| band_of(v))
        },
    );
    progress.start("packing spheres", field.inside.len() as u64);
    let mut spheres: Vec<Sphere> = Vec::new();
    for band in (0..=n as usize).rev() {
        let held = std::mem::take(&mut buckets[band]);
        if held.is_empty() {
            continue;
        }
        // Every remaining distance is at most `top`; the band is [low, top].
        let top = edge(band as i32);
        let low = edge(band.saturating_sub(1) as i32);
        let cap = top + growth;
        // Writes reach 2·cap + top + 1.5 voxels from a block's voxels: two same-coloured
        // blocks, one block apart, never meet.
        let side = (((4.0 * cap + 2.0 * top) / h).ceil() as u32 + 4).max(8);
        // The band's voxels, by colour and block.
        let mut entries: Vec<(u64, Entry)> = held
            .par_iter()
            .filter_map(|&p| {
                let v = remaining.get(p as usize);
                (v >= low).then(|| {
                    let [i, j, k] = grid.coords(field.inside[p as usize] as usize);
                    let (bi, bj, bk) = ((i / side) as u64, (j / side) as u64, (k / side) as u64);
                    let colour = (bi & 1) | (bj & 1) << 1 | (bk & 1) << 2;
                    let key = colour << 60 | bk << 40 | bj << 20 | bi;
                    (key, Entry { value: v, cell: p })
                })
            })
            .collect();
        entries.par_sort_unstable_by_key(|e| e.0);
        let all: Vec<&[(u64, Entry)]> = entries.chunk_by(|a, b| a.0 == b.0).collect();
        let mut blocks: &[&[(u64, Entry)]] = &all;
        let mut covered = 0u64;
        for colour in 0..8u64 {
            let n = blocks.partition_point(|b| b[0].0 >> 60 <= colour);
            let (these, rest) = blocks.split_at(n);
            let band = Band {
                field,
                rows: &rows,
                remaining: &remaining,
                exact: &exact,
                bvh,
                slots,
                refiner: refiner.as_ref(),
                floors,
                low,
                top,
                cap,
                pad,
                batch: batch_size(these.len()),
            };
            let placed: Vec<(Vec<Sphere>, u64)> = if band.batch == 1 {
                largest_first(these, |b| band.block(b, &spheres))
            } else {
                these.par_iter().map(|b| band.block(b, &spheres)).collect()
            };
            blocks = rest;
            let first = spheres.len();
            for (local, c) in placed {
                covered += c;
                spheres.extend(local);
            }
            if let Some(r) = refiner.as_mut() {
                r.insert_all(first as u32, &spheres[first..], parallel_registration());
            }
        }
        progress.advance(covered);
        // Every voxel left in this band's range was packed down below `low` (or covered):
        // the live ones move to the bands of their remaining distances.
        sort_into(
            &mut buckets,
            held.len(),
            |i| held[i],
            |p| {
                let v = remaining.get(p as usize);
                live_at(p, v).then(|| band_of(v))
            },
        );
    }
    progress.finish();
    spheres
}

/// The band of a remaining distance `v` (at least the floor, `edges[0]`): band `m ≥ 1` is
/// `[edges[m − 1], edges[m])`, the last one (`edges.len()`) also holds everything above; a
/// value on an edge starts the band above it.
fn band_of(edges: &[f64], v: f64) -> usize {
    edges.partition_point(|&e| e <= v)
}

/// Appends each of the `count` voxels `voxel(0..count)` to the bucket `band(voxel)` gives
/// (none: dropped), on all threads; the order within a bucket is of no consequence (a band's
/// voxels are sorted by block, and a block's queue orders them totally).
fn sort_into(
    buckets: &mut [Vec<u32>],
    count: usize,
    voxel: impl Fn(usize) -> u32 + Sync,
    band: impl Fn(u32) -> Option<usize> + Sync,
) {
    // Enough chunks for every thread (a band's voxels can be few), none so small that its
    // local buckets cost more than its voxels.
    let chunk = (count / (4 * rayon::current_num_threads())).clamp(1 << 12, 1 << 16);
    let n = buckets.len();
    let parts: Vec<Vec<Vec<u32>>> = (0..count.div_ceil(chunk))
        .into_par_iter()
        .map(|c| {
            let mut local = vec![Vec::new(); n];
            for i in c * chunk..((c + 1) * chunk).min(count) {
                let p = voxel(i);
                if let Some(b) = band(p) {
                    local[b].push(p);
                }
            }
            local
        })
        .collect();
    // Each bucket appends its parts on a thread of its own.
    let mut adds: Vec<Vec<Vec<u32>>> = vec![Vec::new(); n];
    for part in parts {
        for (to, add) in adds.iter_mut().zip(part) {
            if !add.is_empty() {
                to.push(add);
            }
        }
    }
    buckets
        .par_iter_mut()
        .zip(adds)
        .for_each(|(bucket, mut adds)| {
            if bucket.is_empty() && adds.len() == 1 {
                *bucket = adds.pop().unwrap_or_default();
                return;
            }
            bucket.reserve(adds.iter().map(Vec::len).sum());
            for add in adds {
                bucket.extend_from_slice(&add);
            }
        });
}

/// `f` of every block, in block order, run on all threads with the blocks of most voxels
/// taken first: a colour ends with its slowest block, and one started late runs alone. (On
/// the lent 16-core Xeon the jaw's blocks kept 49 % of the threads busy in block order, 63 %
/// taken largest first; one profile each, `docs/results/build_profile_16core.txt`.) Each
/// thread takes the next block from a shared counter; `f` should not wait on other rayon
/// tasks (a blocked thread could take up another taker).
fn largest_first<T: Send>(
    blocks: &[&[(u64, Entry)]],
    f: impl Fn(&[(u64, Entry)]) -> T + Sync,
) -> Vec<T> {
    use std::sync::atomic::AtomicUsize;
    let mut order: Vec<usize> = (0..blocks.len()).collect();
    order.sort_by_key(|&i| std::cmp::Reverse(blocks[i].len()));
    let next = AtomicUsize::new(0);
    let takers = rayon::current_num_threads().min(blocks.len());
    let mut done: Vec<(usize, T)> = (0..takers)
        .into_par_iter()
        .map(|_| {
            let mut mine = Vec::new();
            loop {
                let k = next.fetch_add(1, Relaxed);
                let Some(&i) = order.get(k) else { break };
                mine.push((i, f(blocks[i])));
            }
            mine
        })
        .flatten()
        .collect();
    done.sort_unstable_by_key(|&(i, _)| i);
    done.into_iter().map(|(_, t)| t).collect()
}

/// What the blocks of one band share.
struct Band<'a> {
    field: Voxels<'a>,
    rows: &'a Rows,
    remaining: &'a Remaining,
    exact: &'a [AtomicBool],
    bvh: &'a TriangleBvh,
    slots: &'a [u32],
    refiner: Option<&'a Refiner<'a>>,
    floors: Floors<'a>,
    /// The band is `[low, top)`.
    low: f64,
    top: f64,
    /// The largest radius refinement can reach (a safeguard: it never binds).
    cap: f64,
    pad: i64,
    /// How many voxels a block makes exact at once, on several threads (1: one at a time).
    batch: usize,
}

/// The exact distances a block computes at once where a colour has fewer blocks than there
/// are threads (the top bands: 1–30 blocks, whose exact distances of deep voxels are most of
/// their time and would otherwise run on one thread each). Batches add almost no exact
/// distances (the jaw's top bands: 1,092 against 1,092 in the first, 2,079 against 2,052 in
/// the ninth).
fn batch_size(blocks: usize) -> usize {
    const MOST: usize = 16;
    /// Below this many threads batches do not pay (2 threads: 0-3 % slower packing).
    const MIN_THREADS: usize = 8;
    let threads = rayon::current_num_threads();
    if threads < MIN_THREADS {
        return 1;
    }
    threads.div_ceil(blocks.max(1)).clamp(1, MOST)
}

/// Whether a colour's new spheres are registered for refinement on all threads: from 8
/// threads (on 2 the slabs' passes over the spheres cost more than they share).
fn parallel_registration() -> bool {
    rayon::current_num_threads() >= 8
}

impl Band<'_> {
    /// Packs one block greedily down to `low`; returns its spheres and the voxels covered.
    ///
    /// The voxel on top is made exact when it is not; with a `batch` above 1, so are the
    /// next non-exact voxels below it, on several threads. Either way the voxel taken is the
    /// first exact one on top: every value is at least its exact one, so that is the largest
    /// exact value (ties: the smaller index) whenever the exact values are computed, and the
    /// spheres are the same for any batch.
    fn block(&self, entries: &[(u64, Entry)], spheres: &[Sphere]) -> (Vec<Sphere>, u64) {
        let grid = self.field.grid;
        let live = |v: f64| v > 0.0 && v >= self.low;
        let mut heap: BinaryHeap<Entry> = entries.iter().map(|e| e.1).collect();
        let mut local = Vec::new();
        let mut covered = 0;
        let mut batch: Vec<u32> = Vec::new();
        let mut made: Vec<(u32, f64)> = Vec::new();
        while let Some(Entry { value, cell }) = heap.pop() {
            let pos = cell as usize;
            let current = self.remaining.get(pos);
            if current != value {
                if live(current) {
                    heap.push(Entry {
                        value: current,
                        cell,
                    });
                }
                continue;
            }
            let [ci, cj, ck] = grid.coords(self.field.inside[pos] as usize);
            let voxel = grid.center(ci, cj, ck);
            if !self.exact[pos].load(Relaxed) {
                batch.clear();
                batch.push(cell);
                while batch.len() < self.batch {
                    let Some(&next) = heap.peek() else { break };
                    let now = self.remaining.get(next.cell as usize);
                    if now != next.value {
                        heap.pop();
                        if live(now) {
                            heap.push(Entry {
                                value: now,
                                cell: next.cell,
                            });
                        }
                    } else if self.exact[next.cell as usize].load(Relaxed) {
                        break;
                    } else {
                        heap.pop();
                        batch.push(next.cell);
                    }
                }
                let exact = |&c: &u32| {
                    let p = c as usize;
                    let [i, j, k] = grid.coords(self.field.inside[p] as usize);
                    let v = self.remaining.get(p);
                    (
                        c,
                        exact_distance(self.bvh, grid.center(i, j, k), self.slots[p], v),
                    )
                };
                if batch.len() == 1 {
                    made.clear();
                    made.push(exact(&cell));
                } else {
                    batch.par_iter().map(exact).collect_into_vec(&mut made);
                }
                for &(c, now) in &made {
                    self.exact[c as usize].store(true, Relaxed);
                    self.remaining.set(c as usize, now);
                    if live(now) {
                        heap.push(Entry {
                            value: now,
                            cell: c,
                        });
                    }
                }
                continue;
            }
            if self.floors.below(cell, value) {
                continue; // a coarse voxel below its own floor: never a sphere
            }
            let (center, radius) = match self.refiner {
                Some(r) => r.refine(voxel, value, spheres, &local, self.cap),
                None => (voxel, value),
            };
            local.push(Sphere { center, radius });
            covered += cover(
                self.field,
                self.rows,
                self.remaining,
                center,
                radius,
                radius + self.top,
                self.pad,
            );
        }
        (local, covered)
    }
}

#[cfg(test)]
mod tests {
    use super::{band_of, batch_size};

    #[test]
    fn batches_share_the_threads_among_the_blocks_from_eight_threads() {
        let on = |threads: usize, blocks: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| batch_size(blocks))
        };
        assert_eq!(on(2, 1), 1);
        assert_eq!(on(7, 1), 1);
        assert_eq!(on(8, 1), 8);
        assert_eq!(on(16, 0), 16);
        assert_eq!(on(16, 3), 6);
        assert_eq!(on(16, 16), 1);
        assert_eq!(on(16, 500), 1);
        assert_eq!(on(64, 1), 16);
    }

    #[test]
    fn a_value_on_an_edge_starts_the_band_above_it() {
        let edges = [0.05, 0.05 / 0.9, 0.05 / 0.81];
        assert_eq!(band_of(&edges, 0.05), 1);
        assert_eq!(band_of(&edges, 0.052), 1);
        assert_eq!(band_of(&edges, 0.05 / 0.9), 2);
        assert_eq!(band_of(&edges, 0.05 / 0.81), 3);
        assert_eq!(band_of(&edges, 4.0), 3);
        assert_eq!(band_of(&[], 4.0), 0);
    }
}
