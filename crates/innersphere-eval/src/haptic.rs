//! A haptic session over a recorded device trajectory (`ist haptic`): the library's
//! [`HapticLoop`] at a given rate, each tick recorded, and the figures that say whether the
//! loop kept its deadline, stayed passive and rendered a smooth force.

use crate::motion::{AnatomicalFrame, Motion};
use innersphere::glam::DVec3;
use innersphere::haptic::{HapticLoop, HapticOptions, Joints, Tick};
use innersphere::{Error, Pair, Pose, Result};
use std::fmt::Write as _;
use std::time::{Duration, Instant};

/// One recorded tick.
#[derive(Debug, Clone, Copy)]
pub struct TickRecord {
    /// Time (s).
    pub t: f64,
    /// The device's pose that tick.
    pub device: Pose,
    /// What the loop answered.
    pub tick: Tick,
}

/// The figures of a session (units in the names: µs, N, N·mm, mm, mm³, J).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct HapticSummary {
    /// Ticks run.
    pub ticks: usize,
    /// Device ticks per second.
    pub rate_hz: f64,
    /// The tick budget (µs).
    pub budget_us: f64,
    /// Ticks that took longer than the budget.
    pub deadline_misses: usize,
    /// Median tick time (µs).
    pub compute_p50_us: f64,
    /// 99th percentile of the tick time (µs).
    pub compute_p99_us: f64,
    /// Slowest tick (µs).
    pub compute_max_us: f64,
    /// Ticks answered by the time-critical query.
    pub budgeted_ticks: usize,
    /// Largest force sent (N).
    pub max_force_n: f64,
    /// Largest torque sent (N·mm).
    pub max_torque_nmm: f64,
    /// Largest penetration depth of the tool (mm).
    pub max_depth_mm: f64,
    /// Largest penetration volume of the tool (mm³).
    pub max_volume_mm3: f64,
    /// Largest running total of the energy the device delivered to the hand (J); at most 0
    /// up to rounding for a passive loop.
    pub energy_to_user_max_j: f64,
    /// The same total at the end (J).
    pub energy_to_user_end_j: f64,
    /// Largest change of the force sent between two ticks (N).
    pub max_force_step_n: f64,
    /// Whether the ticks were paced at the device rate (else as fast as possible).
    pub realtime: bool,
}

/// A session's ticks and figures.
#[derive(Debug, Clone)]
pub struct HapticRun {
    /// Every tick.
    pub ticks: Vec<TickRecord>,
    /// The figures.
    pub summary: HapticSummary,
}

/// The device's pose at time `t` along `m` (translation interpolated linearly, rotation by
/// slerp; held at the ends).
pub fn sample(m: &Motion, t: f64) -> Pose {
    let f = &m.frames;
    let i = f.partition_point(|x| x.t <= t);
    if i == 0 {
        return f[0].pose;
    }
    if i >= f.len() {
        return f[f.len() - 1].pose;
    }
    let (a, b) = (&f[i - 1], &f[i]);
    let s = ((t - a.t) / (b.t - a.t)).clamp(0.0, 1.0);
    Pose {
        rotation: a.pose.rotation.slerp(b.pose.rotation, s).normalize(),
        translation: a.pose.translation.lerp(b.pose.translation, s),
    }
}

/// Runs the loop over `device` (B's device pose in A's frame, A at the identity) at
/// `opts.rate`, starting with the tool at the first device pose; `realtime` paces the ticks
/// at the rate (spinning), else they run back to back.
pub fn run(pair: Pair, device: &Motion, opts: HapticOptions, realtime: bool) -> Result<HapticRun> {
    if device.frames.is_empty() {
        return Err(Error::InvalidOption(
            "the device trajectory has no frames".into(),
        ));
    }
    let t0 = device.frames[0].t;
    let n = (device.duration() * opts.rate).floor() as usize + 1;
    if n > 50_000_000 {
        return Err(Error::InvalidOption(format!(
            "{n} ticks are too many (at most 5e7)"
        )));
    }
    // Every device pose before the loop starts: the loop itself allocates nothing.
    let poses: Vec<Pose> = (0..n)
        .map(|i| sample(device, t0 + i as f64 / opts.rate))
        .collect();
    let mut hl = HapticLoop::new(pair, Pose::IDENTITY, poses[0], opts)?;
    let mut ticks = Vec::with_capacity(n);
    let start = Instant::now();
    for (i, pose) in poses.iter().enumerate() {
        if realtime {
            let due = start + Duration::from_secs_f64(i as f64 / opts.rate);
            while Instant::now() < due {
                std::hint::spin_loop();
            }
        }
        let tick = hl.tick(pose);
        ticks.push(TickRecord {
            t: t0 + i as f64 / opts.rate,
            device: *pose,
            tick,
        });
    }
    let mut compute: Vec<f64> = ticks.iter().map(|r| r.tick.compute * 1e6).collect();
    compute.sort_by(f64::total_cmp);
    let pct = |q: f64| compute[((compute.len() - 1) as f64 * q).round() as usize];
    let max = |f: &dyn Fn(&TickRecord) -> f64| ticks.iter().map(f).fold(0.0, f64::max);
    let max_force_step_n = ticks
        .windows(2)
        .map(|w| (w[1].tick.force - w[0].tick.force).length())
        .fold(0.0, f64::max);
    let summary = HapticSummary {
        ticks: ticks.len(),
        rate_hz: opts.rate,
        budget_us: opts.budget * 1e6,
        deadline_misses: ticks.iter().filter(|r| r.tick.late).count(),
        compute_p50_us: pct(0.5),
        compute_p99_us: pct(0.99),
        compute_max_us: compute[compute.len() - 1],
        budgeted_ticks: ticks.iter().filter(|r| r.tick.budgeted).count(),
        max_force_n: max(&|r| r.tick.force.length()),
        max_torque_nmm: max(&|r| r.tick.torque.length()),
        max_depth_mm: max(&|r| r.tick.max_depth),
        max_volume_mm3: max(&|r| r.tick.volume),
        energy_to_user_max_j: hl.energy_to_user_max(),
        energy_to_user_end_j: hl.energy_to_user(),
        max_force_step_n,
        realtime,
    };
    Ok(HapticRun { ticks, summary })
}

/// The trace as CSV, one row per tick: `t`, the device pose (7), the tool pose (7), force
/// xyz (N), torque xyz (N·mm), volume (mm³), depth (mm), compute_us, budgeted (0/1).
pub fn trace_csv(run: &HapticRun) -> String {
    let mut s = String::from(
        "t,dev_tx,dev_ty,dev_tz,dev_qw,dev_qx,dev_qy,dev_qz,tool_tx,tool_ty,tool_tz,tool_qw,tool_qx,tool_qy,tool_qz,fx,fy,fz,tx,ty,tz,volume,depth,compute_us,budgeted\n",
    );
    for r in &run.ticks {
        let d = r.device.to_array();
        let p = r.tick.tool.to_array();
        let (f, q) = (r.tick.force, r.tick.torque);
        let _ = write!(s, "{}", r.t);
        for x in d.iter().chain(&p) {
            let _ = write!(s, ",{x}");
        }
        let _ = writeln!(
            s,
            ",{},{},{},{},{},{},{},{},{:.2},{}",
            f.x,
            f.y,
            f.z,
            q.x,
            q.y,
            q.z,
            r.tick.volume,
            r.tick.max_depth,
            r.tick.compute * 1e6,
            r.tick.budgeted as u8
        );
    }
    s
}

/// Half the distance between a human's condyles (mm, at the frame's scale 1).
pub const CONDYLE_HALF_SPAN: f64 = 50.0;

/// The temporomandibular joints of a lower jaw B for [`occlude`](innersphere::haptic::occlude):
/// its condyles on the frame's hinge axis, [`CONDYLE_HALF_SPAN`] either side of the midline
/// (times the frame's scale), held by springs of `stiffness` (N/mm) where they are when B is
/// at `reference` (the scanned bite).
pub fn temporomandibular_joints(
    frame: &AnatomicalFrame,
    reference: &Pose,
    stiffness: f64,
) -> Joints {
    let half = frame.left * (CONDYLE_HALF_SPAN * frame.scale);
    let points = [frame.hinge + half, frame.hinge - half];
    Joints {
        points,
        anchors: points.map(|p| reference.transform_point(p)),
        stiffness,
    }
}

/// The crown centres of a teeth-axes JSON (`{"18": {"c": [x, y, z], …}, …}`, as in the
/// Open-Full-Jaw dataset), named `tooth N`.
pub fn crown_centres(path: &std::path::Path) -> Result<Vec<(String, DVec3)>> {
    let bad = |m: String| Error::Parse {
        path: path.to_path_buf(),
        format: "teeth axes JSON",
        message: m,
    };
    let text = std::fs::read_to_string(path).map_err(|e| Error::Io {
        path: path.to_path_buf(),
        source: e,
    })?;
    let v: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| bad(format!("not JSON: {e}")))?;
    let obj = v
        .as_object()
        .ok_or_else(|| bad("expected an object of teeth".into()))?;
    let mut out = Vec::with_capacity(obj.len());
    for (tooth, axes) in obj {
        let c: Option<Vec<f64>> = axes
            .get("c")
            .and_then(|c| c.as_array())
            .map(|c| c.iter().filter_map(|x| x.as_f64()).collect());
        match c {
            Some(c) if c.len() == 3 && c.iter().all(|x| x.is_finite()) => {
                out.push((format!("tooth {tooth}"), DVec3::new(c[0], c[1], c[2])))
            }
            _ => {
                return Err(bad(format!(
                    "tooth {tooth} has no crown centre \"c\": [x, y, z]"
                )))
            }
        }
    }
    Ok(out)
}
