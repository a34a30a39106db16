//! What the HTTP side sends: the loop state as JSON, meshes and spheres as little-endian
//! binary (a 450k-triangle arch is 8 MB: under a second on the loopback, where JSON text
//! would be several times larger and slower to parse).

use crate::sim::{LoopState, HISTORY};
use innersphere::glam::DVec3;
use innersphere::{Mesh, Patch, SphereTree};
use serde_json::{json, Value};

fn v3(v: DVec3) -> [f64; 3] {
    v.to_array()
}

/// A patch as `ist query --json` writes it.
pub(crate) fn patch(p: &Patch) -> Value {
    json!({
        "point": v3(p.point),
        "normal": v3(p.normal),
        "depth": p.depth,
        "volume": p.volume,
        "pairs": p.pairs,
    })
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
        "contact": s.contact,
        "point_a": v3(s.point_a),
        "point_b": v3(s.point_b),
        "volume": s.volume,
        "max_depth": s.max_depth,
        "force": v3(s.force),
        "torque": v3(s.torque),
        "patches": s.patches[..s.patch_count].iter().map(patch).collect::<Vec<_>>(),
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
