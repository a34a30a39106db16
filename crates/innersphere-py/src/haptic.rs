//! `innersphere.Haptic`: the 6-DOF haptic loop (virtual coupling, penalty contact).

use crate::convert::{error, pose, pose44, pose7, pose_or_identity, vec3};
use crate::pair::Pair;
use innersphere_haptic::{CollisionOptions, DeviceClass, HapticLoop, HapticOptions, MultirateLoop};
use numpy::PyArray1;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// What one haptic tick did (units: mm, N, s for the jaw scans in mm).
#[pyclass(module = "innersphere", name = "Tick", frozen)]
pub struct Tick {
    t: innersphere_haptic::Tick,
}

#[pymethods]
impl Tick {
    /// Force to send to the device (N, world), clamped to its maximum, shape (3,).
    #[getter]
    fn force<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec3(py, self.t.force)
    }
    /// Torque to send to the device (N·mm, world), clamped likewise, shape (3,).
    #[getter]
    fn torque<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec3(py, self.t.torque)
    }
    /// The tool's pose after the tick (what to draw): (tx, ty, tz, qw, qx, qy, qz).
    #[getter]
    fn tool<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        pose7(py, &self.t.tool)
    }
    /// The tool's pose after the tick as a 4×4 homogeneous matrix.
    #[getter]
    fn tool_matrix<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        pose44(py, &self.t.tool)
    }
    /// Penalty force of the contact on the tool (N), shape (3,).
    #[getter]
    fn contact_force<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec3(py, self.t.contact_force)
    }
    /// Penetration volume (mm³): exact, or what the time-critical query found.
    #[getter]
    fn volume(&self) -> f64 {
        self.t.volume
    }
    /// Upper bound on the penetration volume (equals volume unless budgeted).
    #[getter]
    fn volume_bound(&self) -> f64 {
        self.t.volume_bound
    }
    /// Deepest leaf-pair overlap (mm).
    #[getter]
    fn max_depth(&self) -> f64 {
        self.t.max_depth
    }
    /// Contact patches (exact path only).
    #[getter]
    fn patches(&self) -> usize {
        self.t.patches
    }
    /// True when the time-critical query answered because the exact one would not fit the
    /// tick's budget.
    #[getter]
    fn budgeted(&self) -> bool {
        self.t.budgeted
    }
    /// Time the tick took (s).
    #[getter]
    fn compute(&self) -> f64 {
        self.t.compute
    }
    /// True when the tick took longer than its budget.
    #[getter]
    fn late(&self) -> bool {
        self.t.late
    }
    /// Age of the contact model the tick used (s): since the tool pose its query answered
    /// for was taken (simulated time without a collision thread, real time with one).
    #[getter]
    fn model_age(&self) -> f64 {
        self.t.model_age
    }
    /// The fields as a dict.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        d.set_item("force", self.force(py))?;
        d.set_item("torque", self.torque(py))?;
        d.set_item("tool", self.tool(py))?;
        d.set_item("contact_force", self.contact_force(py))?;
        d.set_item("volume", self.t.volume)?;
        d.set_item("volume_bound", self.t.volume_bound)?;
        d.set_item("max_depth", self.t.max_depth)?;
        d.set_item("patches", self.t.patches)?;
        d.set_item("budgeted", self.t.budgeted)?;
        d.set_item("compute", self.t.compute)?;
        d.set_item("late", self.t.late)?;
        d.set_item("model_age", self.t.model_age)?;
        Ok(d)
    }
    fn __repr__(&self) -> String {
        format!(
            "Tick(force={:?}, volume={}, max_depth={}, budgeted={})",
            self.t.force.to_array(),
            self.t.volume,
            self.t.max_depth,
            if self.t.budgeted { "True" } else { "False" }
        )
    }
}

/// The 6-DOF haptic loop: a virtual tool (body B of the pair) coupled to the device's pose by
/// a spring-damper and pushed out of body A (fixed at pose_a) by the penalty wrench of the
/// penetration query. Units: mm, N, s, kg.
///
/// pair: the Pair of trees (its trees are used; the loop keeps its own query state).
/// device: "omega" (Force Dimension omega.6 class: 12 N) or "touch" (Geomagic Touch
///     class: 3.3 N); sets the force limits and the coupling.
/// rate: device ticks per second (Hz); the integration step is its inverse.
/// start: the tool's pose at rest at the start (default the identity).
/// pose_a: A's fixed pose (default the identity).
/// budget: most time a tick may take (s; default one period): beyond it the exact query
///     gives way to the time-critical one.
/// collision_thread: run the penetration query in a thread of its own (the multi-rate
///     loop: each tick uses the newest contact model it published; for 4–10 kHz rates, or
///     contacts whose query exceeds a tick). Pace the ticks in real time. The thread stops
///     when the Haptic is deleted.
/// collision_delay: with collision_thread, seconds the collision thread sleeps before each
///     query (a stress knob standing for a slow machine).
///
/// Call tick(device_pose) once per device tick, from one thread. Raises ValueError for a bad
/// option or a tree of B without mass properties.
#[pyclass(module = "innersphere", name = "Haptic")]
pub struct Haptic {
    inner: Loop,
}

/// Either loop.
enum Loop {
    Single(Box<HapticLoop>),
    Multirate(Box<MultirateLoop>),
}

/// The same call on either loop.
macro_rules! either {
    ($l:expr, $h:ident => $e:expr) => {
        match $l {
            Loop::Single($h) => $e,
            Loop::Multirate($h) => $e,
        }
    };
}

#[pymethods]
impl Haptic {
    #[new]
    #[pyo3(signature = (pair, device="omega", rate=1000.0, start=None, *, pose_a=None, budget=None, collision_thread=false, collision_delay=0.0))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        pair: PyRef<'_, Pair>,
        device: &str,
        rate: f64,
        start: Option<&Bound<'_, PyAny>>,
        pose_a: Option<&Bound<'_, PyAny>>,
        budget: Option<f64>,
        collision_thread: bool,
        collision_delay: f64,
    ) -> PyResult<Haptic> {
        let class = DeviceClass::ALL
            .into_iter()
            .find(|c| c.name() == device.to_ascii_lowercase())
            .ok_or_else(|| {
                PyValueError::new_err(format!(
                    "invalid option: unknown device \"{device}\" (expected \"omega\" or \"touch\")"
                ))
            })?;
        let start = pose_or_identity(start, "start")?;
        let pose_a = pose_or_identity(pose_a, "pose_a")?;
        let mut opts = HapticOptions::for_device_at(class, rate);
        opts.budget = budget.unwrap_or(1.0 / rate);
        let inner = if collision_thread {
            let c = CollisionOptions {
                delay: collision_delay,
                ..Default::default()
            };
            Loop::Multirate(Box::new(
                MultirateLoop::spawn(pair.fresh(), pose_a, start, opts, c).map_err(error)?,
            ))
        } else {
            if collision_delay != 0.0 {
                return Err(PyValueError::new_err(
                    "invalid option: collision_delay needs collision_thread=True",
                ));
            }
            Loop::Single(Box::new(
                HapticLoop::new(pair.fresh(), pose_a, start, opts).map_err(error)?,
            ))
        };
        Ok(Haptic { inner })
    }

    /// One device tick: the device's pose in (B's pose in the world as read this tick), a
    /// Tick out (the force and torque to send, the tool's new pose). dt: seconds since the
    /// last tick as measured by the caller; 0 means one period (more than ten periods counts
    /// as one). A NaN pose, or a negative, NaN or infinite dt, raises ValueError and changes
    /// nothing.
    #[pyo3(signature = (device_pose, dt=0.0))]
    fn tick(&mut self, device_pose: &Bound<'_, PyAny>, dt: f64) -> PyResult<Tick> {
        let p = pose(device_pose, "device_pose")?;
        innersphere_haptic::check_step(dt).map_err(error)?;
        Ok(Tick {
            t: either!(&mut self.inner, h => h.tick_step(&p, dt)),
        })
    }

    /// Energy the device has delivered to the hand so far (J); a passive loop keeps it at
    /// most zero.
    #[getter]
    fn energy_to_user(&self) -> f64 {
        either!(&self.inner, h => h.energy_to_user())
    }

    /// The largest value energy_to_user has had (J).
    #[getter]
    fn energy_to_user_max(&self) -> f64 {
        either!(&self.inner, h => h.energy_to_user_max())
    }

    /// The tool's current pose (tx, ty, tz, qw, qx, qy, qz).
    #[getter]
    fn tool<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        pose7(py, &either!(&self.inner, h => h.state().pose))
    }

    /// Device ticks per second (Hz).
    #[getter]
    fn rate(&self) -> f64 {
        either!(&self.inner, h => h.options().rate)
    }

    /// Most time one tick may take (s).
    #[getter]
    fn budget(&self) -> f64 {
        either!(&self.inner, h => h.options().budget)
    }

    /// Contact models the collision thread has published so far (0 without one).
    #[getter]
    fn collision_queries(&self) -> u64 {
        match &self.inner {
            Loop::Single(_) => 0,
            Loop::Multirate(h) => h.collision_queries(),
        }
    }

    /// The tool's mass (kg) from tree B's mass properties and the tooth density.
    #[getter]
    fn mass(&self) -> f64 {
        either!(&self.inner, h => h.body().mass)
    }

    fn __repr__(&self) -> String {
        format!(
            "Haptic(rate={}, budget={}, energy_to_user={})",
            either!(&self.inner, h => h.options().rate),
            either!(&self.inner, h => h.options().budget),
            either!(&self.inner, h => h.energy_to_user())
        )
    }
}
