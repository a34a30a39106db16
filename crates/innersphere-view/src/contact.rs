//! The contact map: both meshes coloured by their signed gap to each other
//! ([`innersphere_dental::contact_map`]), recomputed as B moves, in a worker thread of its own.
//!
//! The 1 kHz loop knows nothing of it. The worker reads B's drawn pose from the HTTP side's
//! end of the loop's state buffer (the mutex the HTTP handlers take, never the loop), always
//! the newest: poses that come and go while a map is computed are skipped. Each map is
//! published as one `Arc` behind a mutex that only the worker and the HTTP handlers take,
//! already encoded for the page (one band index per vertex, [`encode::contact_bands`]). The
//! per-tooth summaries, when teeth were given, are made from a map's gaps when first asked
//! for ([`MapFrame::teeth`], by an HTTP handler), so that they do not slow the maps down.
//! While the mode is off the worker sleeps; the meshes are prepared ([`ExactMesh`], heavy)
//! the first time it is turned on.

use crate::encode;
use bytes::Bytes;
use innersphere::exact::ExactMesh;
use innersphere::{Mesh, Pose};
use innersphere_dental::contact_map::{summarise, ContactMap, RegionSummary, Teeth};
use std::collections::VecDeque;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Condvar, Mutex, MutexGuard, OnceLock};
use std::time::{Duration, Instant};

/// Gaps above this (mm) are reported as it, which lets the nearest-triangle search prune
/// most of an arch: the next `f64` above 0.5 mm, where the colour scale ends, so that every
/// gap the scale tells apart is exact (0.5 itself is still blue) and every capped one is
/// light grey, as in `ist occlusion-map`'s uncapped PLY files.
pub const CAP: f64 = f64::from_bits(0.5f64.to_bits() + 1);

/// How often the worker looks for a new pose while B stands still.
const POLL: Duration = Duration::from_millis(2);

/// Per-tooth summaries of A and B (each where its teeth were given).
pub(crate) type TeethSummaries = (Option<Vec<RegionSummary>>, Option<Vec<RegionSummary>>);

/// One published map.
pub(crate) struct MapFrame {
    /// 1 for the first map, then one more per map.
    pub seq: u32,
    /// B's pose (in A's frame) the map is of.
    pub pose_b: Pose,
    /// `GET /api/contact-map/bands`'s answer ([`encode::contact_bands`]).
    pub bands: Bytes,
    /// Smallest gap of A's and of B's vertices (mm; [`CAP`] when none is closer).
    pub min_gap_a: f64,
    pub min_gap_b: f64,
    /// Time of the gaps alone, and of the whole map (gaps and bands), ms.
    pub gaps_ms: f64,
    pub compute_ms: f64,
    gaps: ContactMap,
    prepared: Arc<Prepared>,
    teeth: OnceLock<TeethSummaries>,
}

impl MapFrame {
    /// The per-tooth summaries of this map, made on the first call.
    pub(crate) fn teeth(&self) -> &TeethSummaries {
        self.teeth.get_or_init(|| {
            let p = &self.prepared;
            let side = |t: &Option<(Teeth, Vec<u32>)>, mesh: &ExactMesh, gaps: &[f64]| {
                t.as_ref().map(|(t, r)| summarise(mesh.mesh(), gaps, t, r))
            };
            (
                side(&p.teeth_a, &p.a, &self.gaps.gaps_a),
                side(&p.teeth_b, &p.b, &self.gaps.gaps_b),
            )
        })
    }
}

impl std::fmt::Debug for MapFrame {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MapFrame")
            .field("seq", &self.seq)
            .field("pose_b", &self.pose_b)
            .field("min_gap_a", &self.min_gap_a)
            .field("min_gap_b", &self.min_gap_b)
            .field("compute_ms", &self.compute_ms)
            .finish_non_exhaustive()
    }
}

/// Where the worker is.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Status {
    /// Never turned on: the meshes are not prepared.
    Idle,
    /// Preparing the meshes.
    Preparing,
    /// Prepared: maps follow B while the mode is on.
    Ready,
    /// The meshes could not be prepared (the message).
    Failed(String),
}

impl Status {
    pub(crate) fn name(&self) -> &'static str {
        match self {
            Status::Idle => "idle",
            Status::Preparing => "preparing",
            Status::Ready => "ready",
            Status::Failed(_) => "failed",
        }
    }
}

#[derive(Debug)]
struct Inner {
    on: bool,
    status: Status,
    /// The last map's error (a pose no map could be made of), cleared by the next map.
    error: Option<String>,
    frame: Option<Arc<MapFrame>>,
    /// When the recent maps were published (the last second or so, for the rate).
    recent: VecDeque<Instant>,
    prepare_s: f64,
}

/// What the HTTP side and the worker share: whether the mode is on, and the latest map.
#[derive(Debug)]
pub(crate) struct ContactMaps {
    inner: Mutex<Inner>,
    wake: Condvar,
    /// The latest map's `seq`, for the HTTP tasks that wait for a newer map.
    seq: tokio::sync::watch::Sender<u32>,
}

/// A copy of the shared state for one answer.
#[derive(Debug, Clone)]
pub(crate) struct Snapshot {
    pub on: bool,
    pub status: Status,
    pub error: Option<String>,
    pub frame: Option<Arc<MapFrame>>,
    /// Maps published in the last second.
    pub rate_hz: f64,
    /// Seconds the meshes took to prepare (0 until they are).
    pub prepare_s: f64,
}

impl ContactMaps {
    pub(crate) fn new(on: bool) -> ContactMaps {
        ContactMaps {
            inner: Mutex::new(Inner {
                on,
                status: Status::Idle,
                error: None,
                frame: None,
                recent: VecDeque::new(),
                prepare_s: 0.0,
            }),
            wake: Condvar::new(),
            seq: tokio::sync::watch::Sender::new(0),
        }
    }

    /// Tells when a map is published: its receiver's value is the latest map's `seq`.
    pub(crate) fn subscribe(&self) -> tokio::sync::watch::Receiver<u32> {
        self.seq.subscribe()
    }

    fn lock(&self) -> MutexGuard<'_, Inner> {
        self.inner.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Turns the mode on or off (the worker wakes up or goes to sleep).
    pub(crate) fn set_on(&self, on: bool) {
        self.lock().on = on;
        self.wake.notify_all();
    }

    pub(crate) fn snapshot(&self) -> Snapshot {
        let mut g = self.lock();
        let now = Instant::now();
        while g
            .recent
            .front()
            .is_some_and(|t| now.duration_since(*t) > Duration::from_secs(1))
        {
            g.recent.pop_front();
        }
        Snapshot {
            on: g.on,
            status: g.status.clone(),
            error: g.error.clone(),
            frame: g.frame.clone(),
            rate_hz: g.recent.len() as f64,
            prepare_s: g.prepare_s,
        }
    }

    /// Waits while the mode is off (at most `timeout`); true when it is on.
    fn wait_on(&self, timeout: Duration) -> bool {
        let g = self.lock();
        let (g, _) = self
            .wake
            .wait_timeout_while(g, timeout, |i| !i.on)
            .unwrap_or_else(|e| e.into_inner());
        g.on
    }

    fn set_status(&self, status: Status, prepare_s: f64) {
        let mut g = self.lock();
        g.status = status;
        g.prepare_s = prepare_s;
    }

    fn publish(&self, frame: MapFrame) {
        let seq = frame.seq;
        {
            let mut g = self.lock();
            let now = Instant::now();
            g.recent.push_back(now);
            while g.recent.len() > 256 {
                g.recent.pop_front();
            }
            g.frame = Some(Arc::new(frame));
            g.error = None;
        }
        self.seq.send_replace(seq);
    }

    fn fail(&self, error: String) {
        self.lock().error = Some(error);
    }
}

/// Both meshes prepared, and the teeth's regions.
struct Prepared {
    a: ExactMesh,
    b: ExactMesh,
    teeth_a: Option<(Teeth, Vec<u32>)>,
    teeth_b: Option<(Teeth, Vec<u32>)>,
}

impl Prepared {
    fn new(
        a: &Mesh,
        b: &Mesh,
        teeth_a: Option<&Teeth>,
        teeth_b: Option<&Teeth>,
    ) -> innersphere::Result<Prepared> {
        let regions = |t: Option<&Teeth>, m: &Mesh| t.map(|t| (t.clone(), t.regions(&m.vertices)));
        Ok(Prepared {
            a: ExactMesh::new(a)?,
            b: ExactMesh::new(b)?,
            teeth_a: regions(teeth_a, a),
            teeth_b: regions(teeth_b, b),
        })
    }
}

/// The map at B's pose `pose_b` (A at the identity).
fn map(p: &Arc<Prepared>, seq: u32, pose_b: &Pose) -> innersphere::Result<MapFrame> {
    let t0 = Instant::now();
    let m = ContactMap::new(&p.a, &Pose::IDENTITY, &p.b, pose_b, CAP)?;
    let gaps_ms = t0.elapsed().as_secs_f64() * 1e3;
    let bands = encode::contact_bands(seq, pose_b, &m.gaps_a, &m.gaps_b);
    let min = |g: &[f64]| g.iter().copied().fold(CAP, f64::min);
    Ok(MapFrame {
        seq,
        pose_b: *pose_b,
        bands: Bytes::from(bands),
        min_gap_a: min(&m.gaps_a),
        min_gap_b: min(&m.gaps_b),
        gaps_ms,
        compute_ms: t0.elapsed().as_secs_f64() * 1e3,
        gaps: m,
        prepared: p.clone(),
        teeth: OnceLock::new(),
    })
}

/// What the worker maps.
pub(crate) struct Source<'a> {
    pub mesh_a: &'a Mesh,
    pub mesh_b: &'a Mesh,
    pub teeth_a: Option<&'a Teeth>,
    pub teeth_b: Option<&'a Teeth>,
}

/// The worker: until `stop`, while `maps` is on, maps B at the newest pose `pose_b` gives
/// whenever it differs from the last map's, and publishes each map in `maps`.
pub(crate) fn run(
    src: Source<'_>,
    maps: &ContactMaps,
    mut pose_b: impl FnMut() -> Pose,
    stop: &AtomicBool,
) {
    let mut prepared: Option<Arc<Prepared>> = None;
    let mut last: Option<Pose> = None;
    let mut seq = 0u32;
    while !stop.load(Ordering::Relaxed) {
        if !maps.wait_on(Duration::from_millis(200)) {
            continue;
        }
        let p = match &prepared {
            Some(p) => p,
            None => {
                if matches!(maps.snapshot().status, Status::Failed(_)) {
                    std::thread::sleep(Duration::from_millis(200));
                    continue;
                }
                maps.set_status(Status::Preparing, 0.0);
                let t0 = Instant::now();
                match Prepared::new(src.mesh_a, src.mesh_b, src.teeth_a, src.teeth_b) {
                    Ok(p) => {
                        maps.set_status(Status::Ready, t0.elapsed().as_secs_f64());
                        prepared.insert(Arc::new(p))
                    }
                    Err(e) => {
                        maps.set_status(Status::Failed(e.to_string()), 0.0);
                        continue;
                    }
                }
            }
        };
        let pose = pose_b();
        if last == Some(pose) {
            std::thread::sleep(POLL);
            continue;
        }
        last = Some(pose);
        seq = seq.wrapping_add(1);
        match map(p, seq, &pose) {
            Ok(f) => maps.publish(f),
            Err(e) => maps.fail(format!("no contact map at {pose}: {e}")),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::encode::{band, BANDS_HEADER};
    use innersphere::glam::DVec3;
    use std::sync::atomic::AtomicUsize;

    /// The worker on the generated tooth pair, B's pose from `pose_b`.
    fn worker(
        pose_b: impl FnMut() -> Pose + Send + 'static,
        on: bool,
    ) -> (Arc<ContactMaps>, Arc<AtomicBool>, Teeth) {
        let (a, b) = innersphere::shapes::tooth_pair(3);
        let teeth = Teeth::from_json(
            r#"{"30": {"c": [0, 0, 2]}}"#,
            std::path::Path::new("demo.json"),
        )
        .unwrap();
        let maps = Arc::new(ContactMaps::new(on));
        let stop = Arc::new(AtomicBool::new(false));
        let (m, s, t) = (maps.clone(), stop.clone(), teeth.clone());
        std::thread::spawn(move || {
            let src = Source {
                mesh_a: &a,
                mesh_b: &b,
                teeth_a: None,
                teeth_b: Some(&t),
            };
            run(src, &m, pose_b, &s);
        });
        (maps, stop, teeth)
    }

    fn wait_for(maps: &ContactMaps, what: impl Fn(&Snapshot) -> bool) -> Snapshot {
        let end = Instant::now() + Duration::from_secs(60);
        loop {
            let s = maps.snapshot();
            if what(&s) {
                return s;
            }
            assert!(Instant::now() < end, "timed out: {s:?}");
            std::thread::sleep(Duration::from_millis(5));
        }
    }

    #[test]
    fn maps_follow_the_newest_pose_and_equal_the_library_s() {
        // B's pose changes at every look: the worker must always take the newest, so it
        // makes fewer maps than it sees poses, and each map is of the pose it says.
        let looks = Arc::new(AtomicUsize::new(0));
        let l = looks.clone();
        let pose = move |k: usize| {
            Pose::from_translation(DVec3::new(0.0, 0.0, 0.05 * (k % 20) as f64 - 0.5))
        };
        let (maps, stop, teeth) = worker(move || pose(l.fetch_add(1, Ordering::SeqCst)), false);
        // Off: nothing is prepared, nothing mapped.
        std::thread::sleep(Duration::from_millis(300));
        let s = maps.snapshot();
        assert_eq!((s.status, s.frame.is_none()), (Status::Idle, true));
        assert_eq!(looks.load(Ordering::SeqCst), 0);
        maps.set_on(true);
        let s = wait_for(&maps, |s| s.frame.as_ref().is_some_and(|f| f.seq >= 3));
        assert_eq!(s.status, Status::Ready);
        let f = s.frame.unwrap();
        // The bands are the library's gaps at the map's pose, through the colour scale.
        let (a, b) = innersphere::shapes::tooth_pair(3);
        let (ea, eb) = (ExactMesh::new(&a).unwrap(), ExactMesh::new(&b).unwrap());
        let m = ContactMap::new(&ea, &Pose::IDENTITY, &eb, &f.pose_b, CAP).unwrap();
        let want: Vec<u8> = m.gaps_a.iter().chain(&m.gaps_b).map(|&g| band(g)).collect();
        assert_eq!(&f.bands[BANDS_HEADER..], &want[..]);
        let head = |k: usize| u32::from_le_bytes(f.bands[4 * k..4 * k + 4].try_into().unwrap());
        assert_eq!(
            (head(0), head(1) as usize, head(2) as usize),
            (f.seq, a.vertices.len(), b.vertices.len())
        );
        let regions = teeth.regions(&b.vertices);
        let (ta, tb) = f.teeth();
        assert_eq!(
            tb.as_deref().unwrap(),
            &summarise(&b, &m.gaps_b, &teeth, &regions)[..]
        );
        assert!(ta.is_none());
        // Stale poses were skipped: at least one look per map, and more looks than maps
        // once the worker has been busy for a few maps.
        let s = wait_for(&maps, |s| s.frame.as_ref().is_some_and(|f| f.seq >= 6));
        let seen = looks.load(Ordering::SeqCst);
        assert!(seen as u32 >= s.frame.unwrap().seq, "{seen} looks");
        // Off again: the maps stop.
        maps.set_on(false);
        std::thread::sleep(Duration::from_millis(300));
        let n = maps.snapshot().frame.unwrap().seq;
        std::thread::sleep(Duration::from_millis(300));
        assert_eq!(maps.snapshot().frame.unwrap().seq, n);
        stop.store(true, Ordering::Relaxed);
    }

    #[test]
    fn a_still_body_is_mapped_once() {
        let at = Pose::from_translation(DVec3::new(0.0, 0.0, 0.2));
        let (maps, stop, _) = worker(move || at, true);
        let s = wait_for(&maps, |s| s.frame.is_some());
        std::thread::sleep(Duration::from_millis(200));
        let again = maps.snapshot();
        assert_eq!(again.frame.unwrap().seq, 1);
        assert!(s.prepare_s > 0.0);
        // In contact at this pose: some vertices in the contact bands.
        let f = s.frame.unwrap();
        assert!(
            f.min_gap_a < 0.05 && f.min_gap_b < 0.05,
            "{} {}",
            f.min_gap_a,
            f.min_gap_b
        );
        stop.store(true, Ordering::Relaxed);
    }
}
