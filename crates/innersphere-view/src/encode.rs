//! What the HTTP side sends: the loop state as JSON, meshes and spheres as little-endian
//! binary (a 450k-triangle arch is 8 MB: under a second on the loopback, where JSON text
//! would be several times larger and slower to parse), contact maps as one band index per
//! vertex.

use crate::contact::{Snapshot, Status, CAP};
use crate::sim::{LoopState, HISTORY};
use innersphere::glam::DVec3;
use innersphere::{Mesh, Pose, SphereTree};
use innersphere_dental::contact_map::{gap_colour, RegionSummary, LEGEND};
use serde_json::{json, Value};

fn v3(v: DVec3) -> [f64; 3] {
    v.to_array()
}

/// The loop state as the page reads it (`docs/VIEWER.md`).
pub(crate) fn state(s: &LoopState, motion_seconds: Option<f64>) -> Value {
    let history: Vec<f32> = s.history_us[s.history_next..]
        .iter()
        .chain(&s.history_us[..s.history_next])
        .copied()
        .skip(HISTORY.saturating_sub(s.ticks as usize))
        .collect();
    json!({
        "t": s.t,
        "mode": s.mode.name(),
        "pose_b": s.pose_b.to_array(),
        "target_b": s.target_b.to_array(),
        "distance": s.distance,
        "distance_refined": s.distance_refined,
        "contact": s.contact,
        "point_a": v3(s.point_a),
        "point_b": v3(s.point_b),
        "volume": s.volume,
        "max_depth": s.max_depth,
        "contact_source": s.contact_source,
        "force": v3(s.force),
        "torque": v3(s.torque),
        "patches": &s.patches[..s.patch_count],
        "device_force": v3(s.device_force),
        "loop": {
            "rate_hz": s.rate_hz,
            "tick_us": s.tick_us,
            "tick_us_p99": s.tick_us_p99,
            "tick_us_max": s.tick_us_max,
            "ticks": s.ticks,
            "over_1ms": s.over_1ms,
            "history_us": history,
            "realtime": s.realtime,
            "collision_rate_hz": s.collision_rate_hz,
            "model_age_us": s.model_age_us,
        },
        "motion": motion_seconds.map(|len| json!({"playing": s.playing, "t": s.motion_t, "seconds": len})),
    })
}

/// `u32 V, u32 T, V×3 f32 positions, T×3 u32 indices`, little-endian.
pub(crate) fn mesh(m: &Mesh) -> Vec<u8> {
    let mut out = Vec::with_capacity(8 + m.vertices.len() * 12 + m.triangles.len() * 12);
    out.extend_from_slice(&(m.vertices.len() as u32).to_le_bytes());
    out.extend_from_slice(&(m.triangles.len() as u32).to_le_bytes());
    for v in &m.vertices {
        for x in v.to_array() {
            out.extend_from_slice(&(x as f32).to_le_bytes());
        }
    }
    for t in &m.triangles {
        for i in t {
            out.extend_from_slice(&i.to_le_bytes());
        }
    }
    out
}

/// The spheres of `tree` at depth `level` (leaves above it included), `x y z r` as f32.
pub(crate) fn spheres(tree: &SphereTree, level: usize) -> Vec<u8> {
    let mut out = Vec::new();
    for n in 0..tree.len() {
        let d = tree.depth[n] as usize;
        if d == level || (d < level && tree.is_leaf(n)) {
            let (c, r) = tree.sphere(n);
            for x in [c.x, c.y, c.z, r] {
                out.extend_from_slice(&x.to_le_bytes());
            }
        }
    }
    out
}

/// Bytes before the band indices in [`contact_bands`].
pub(crate) const BANDS_HEADER: usize = 72;

/// The band index of a signed gap: `k` for [`LEGEND`]`[k]`, [`FAR_BAND`] beyond the last
/// band. Taken from [`gap_colour`] itself, so that the page colours a vertex exactly as
/// `ist occlusion-map`'s PLY files do.
pub(crate) fn band(gap: f64) -> u8 {
    let c = gap_colour(gap);
    LEGEND
        .iter()
        .position(|l| l.2 == c)
        .map_or(FAR_BAND, |k| k as u8)
}

/// The band of gaps beyond the colour scale (light grey).
pub(crate) const FAR_BAND: u8 = LEGEND.len() as u8;

/// A contact map as the page reads it, little-endian: `u32 seq, u32 Va, u32 Vb, u32 bands
/// (LEGEND's and the far one), 7×f64 B's pose of the map`, then one [`band`] index per
/// vertex of A (`Va` bytes) and of B (`Vb`), in the meshes' vertex order (that of
/// [`mesh`]).
pub(crate) fn contact_bands(seq: u32, pose_b: &Pose, gaps_a: &[f64], gaps_b: &[f64]) -> Vec<u8> {
    let mut out = Vec::with_capacity(BANDS_HEADER + gaps_a.len() + gaps_b.len());
    for n in [
        seq,
        gaps_a.len() as u32,
        gaps_b.len() as u32,
        FAR_BAND as u32 + 1,
    ] {
        out.extend_from_slice(&n.to_le_bytes());
    }
    for x in pose_b.to_array() {
        out.extend_from_slice(&x.to_le_bytes());
    }
    out.extend(gaps_a.iter().chain(gaps_b).map(|&g| band(g)));
    out
}

/// A finite number, or null.
fn finite(x: f64) -> Value {
    if x.is_finite() {
        json!(x)
    } else {
        Value::Null
    }
}

/// The colour scale for `/api/info`: LEGEND's bands (`below`: the band's upper end, mm)
/// and the far colour, in band-index order.
pub(crate) fn contact_legend() -> Value {
    let mut bands: Vec<Value> = LEGEND
        .iter()
        .map(|(hi, name, rgb)| json!({"below": hi, "name": name, "rgb": rgb}))
        .collect();
    let last = LEGEND[LEGEND.len() - 1].0;
    bands.push(json!({
        "below": null,
        "name": format!("far (> {last})"),
        "rgb": gap_colour(f64::INFINITY),
    }));
    Value::Array(bands)
}

/// Per-tooth summaries as `ist occlusion-map --json` writes them, with the [`band`] of each
/// tooth's minimum gap (null for a tooth without vertices).
pub(crate) fn teeth(t: &[RegionSummary]) -> Value {
    Value::Array(
        t.iter()
            .map(|s| {
                json!({
                    "tooth": s.tooth,
                    "vertices": s.vertices,
                    "min_gap": finite(s.min_gap),
                    "band": (s.vertices > 0).then(|| band(s.min_gap)),
                    "area_within_0_1": s.area_within_0_1,
                    "area_within_0_2": s.area_within_0_2,
                    "spots": s.spots,
                })
            })
            .collect(),
    )
}

/// The contact map's state (the `contact_map` of `/api/state`); with `full`, also the
/// map's pose, gaps and per-tooth summaries (`GET /api/contact-map`).
pub(crate) fn contact_map(s: &Snapshot, full: bool) -> Value {
    let f = s.frame.as_deref();
    let mut v = json!({
        "on": s.on,
        "status": s.status.name(),
        "error": match &s.status {
            Status::Failed(e) => Some(e.clone()),
            _ => s.error.clone(),
        },
        "seq": f.map_or(0, |f| f.seq),
        "rate_hz": s.rate_hz,
        "compute_ms": f.map(|f| f.compute_ms),
        "gaps_ms": f.map(|f| f.gaps_ms),
        "prepare_s": s.prepare_s,
    });
    if full {
        v["cap"] = json!(CAP);
        v["pose_b"] = json!(f.map(|f| f.pose_b.to_array()));
        v["min_gap"] = json!(f.map(|f| json!({"a": f.min_gap_a, "b": f.min_gap_b})));
        let t = f.map(|f| f.teeth());
        v["teeth"] = json!({
            "a": t.and_then(|t| t.0.as_deref()).map(teeth),
            "b": t.and_then(|t| t.1.as_deref()).map(teeth),
        });
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bands_are_the_library_s_colour_scale() {
        let palette: Vec<[u8; 3]> = contact_legend()
            .as_array()
            .unwrap()
            .iter()
            .map(|b| serde_json::from_value(b["rgb"].clone()).unwrap())
            .collect();
        assert_eq!(palette.len(), FAR_BAND as usize + 1);
        for k in -2000..2000 {
            let g = k as f64 * 0.0005;
            assert_eq!(palette[band(g) as usize], gap_colour(g), "{g}");
        }
        for g in [
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            0.0,
            -0.0,
            0.5,
            CAP,
        ] {
            assert_eq!(palette[band(g) as usize], gap_colour(g), "{g}");
        }
        assert_eq!(band(0.5), FAR_BAND - 1);
        assert_eq!(band(CAP), FAR_BAND);
        const { assert!(CAP > 0.5 && CAP < 0.5 + 1e-15) };
        assert_eq!(band(0.51), FAR_BAND);
    }

    #[test]
    fn contact_bands_layout() {
        let pose = Pose::from_array([1.0, 2.0, 3.0, 1.0, 0.0, 0.0, 0.0]).unwrap();
        let b = contact_bands(7, &pose, &[-1.0, 0.01, 0.6], &[0.25]);
        assert_eq!(b.len(), BANDS_HEADER + 4);
        let u = |k: usize| u32::from_le_bytes(b[4 * k..4 * k + 4].try_into().unwrap());
        assert_eq!([u(0), u(1), u(2), u(3)], [7, 3, 1, FAR_BAND as u32 + 1]);
        let f = |k: usize| f64::from_le_bytes(b[16 + 8 * k..24 + 8 * k].try_into().unwrap());
        assert_eq!((0..7).map(f).collect::<Vec<_>>(), pose.to_array());
        assert_eq!(&b[BANDS_HEADER..], &[0, 1, FAR_BAND, 4]);
    }
}
