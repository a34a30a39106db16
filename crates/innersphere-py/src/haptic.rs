//! `innersphere.Haptic`: the 6-DOF haptic loop (virtual coupling, penalty contact).

use crate::convert::{error, pose, pose44, pose7, pose_or_identity};
use crate::pair::Pair;
use innersphere_haptic::{
    CollisionOptions, ContactSource, DeviceClass, HapticLoop, HapticOptions, MultirateLoop,
};
use numpy::PyArray1;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// What one haptic tick did (units: mm, N, s for the jaw scans in mm). Attributes: force
/// (3,) and torque (3,) to the device, tool (the pose, 7 numbers), tool_matrix (4×4),
/// contact_force (3,), volume, volume_bound, max_depth, patches (a count), budgeted, compute
/// (s), late, model_age (s).
#[pyclass(module = "innersphere", name = "Tick", frozen)]
pub struct Tick {
    t: innersphere_haptic::Tick,
}

#[pymethods]
impl Tick {
    /// The tool's pose after the tick as a 4×4 homogeneous matrix.
    #[getter]
    fn tool_matrix<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        pose44(py, &self.t.tool)
    }
    /// The tick as a dict: its serde form (vectors as lists, the tool's pose as 7 numbers).
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        crate::convert::answer_dict(py, &self.t, &[])
    }
    fn __getattr__<'py>(&self, py: Python<'py>, name: &str) -> PyResult<Bound<'py, PyAny>> {
        crate::results::attribute(&self.to_dict(py)?, "Tick", name)
    }
    fn __dir__(&self, py: Python<'_>) -> PyResult<Vec<String>> {
        let mut names = crate::results::attribute_names(&self.to_dict(py)?)?;
        names.push("tool_matrix".into());
        names.sort();
        Ok(names)
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
/// contact: "spheres" (the packings' penetration volume) or "mesh" (the meshes' own exact
///     intersection volume: both trees need their meshes, Tree.with_mesh; runs in the
///     collision thread, which it implies).
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
    #[pyo3(signature = (pair, device="omega", rate=1000.0, start=None, *, pose_a=None, budget=None, collision_thread=false, collision_delay=0.0, contact="spheres"))]
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
        contact: &str,
    ) -> PyResult<Haptic> {
        let contact: ContactSource = contact.parse().map_err(error)?;
        let collision_thread = collision_thread || contact == ContactSource::Mesh;
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
                contact,
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
