//! What a haptic device can render, and the virtual coupling tuned to it.
//!
//! Units throughout the haptic module: millimetres, newtons, seconds, kilograms, radians.

use innersphere::error::{Error, Result};

/// The limits of a haptic device: what it can push and how stiff a spring it renders stably.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct DeviceLimits {
    /// Largest force (N); the force sent is clamped to it.
    pub max_force: f64,
    /// Largest torque (N·mm); 0 for a device whose rotations are sensed but not actuated
    /// (the tool still turns with the handle through the coupling; no torque is sent).
    pub max_torque: f64,
    /// Stiffest spring it renders stably (N/mm): the coupling may not be stiffer.
    pub max_stiffness: f64,
    /// Most damping it renders (N·s/mm).
    pub max_damping: f64,
}

/// The 6-DOF virtual coupling: a spring-damper between the device's pose and the tool's,
/// acting at the tool's centre of mass (translation) and about it (rotation).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Coupling {
    /// Translational stiffness (N/mm).
    pub stiffness: f64,
    /// Translational damping on the velocity difference (N·s/mm).
    pub damping: f64,
    /// Rotational stiffness (N·mm/rad).
    pub angular_stiffness: f64,
    /// Rotational damping on the angular-velocity difference (N·mm·s/rad).
    pub angular_damping: f64,
}

/// The lever (mm) that turns translational coupling figures into rotational ones
/// (`angular = linear × LEVER²`): a rotation moves the tool's far teeth as much as a
/// translation of `angle × LEVER` would, so both feel alike.
pub const LEVER: f64 = 20.0;

/// Classes of haptic device with their limits and default coupling.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum DeviceClass {
    /// A desktop 3-DOF-output pen device (Geomagic Touch, Phantom Omni): 3.3 N peak, about
    /// 1 N/mm stiffness (its weakest axis), rotations sensed only.
    Touch,
    /// A parallel-kinematics device (Force Dimension omega.6): 12 N, 5 N/mm, 30 N·s/m,
    /// rotations sensed only (CHAI3D's figures for it).
    Omega,
}

impl DeviceClass {
    /// Every class.
    pub const ALL: [DeviceClass; 2] = [DeviceClass::Touch, DeviceClass::Omega];

    /// `touch` or `omega`.
    pub fn name(self) -> &'static str {
        match self {
            DeviceClass::Touch => "touch",
            DeviceClass::Omega => "omega",
        }
    }

    /// The device's limits.
    pub fn limits(self) -> DeviceLimits {
        match self {
            DeviceClass::Touch => DeviceLimits {
                max_force: 3.3,
                max_torque: 0.0,
                max_stiffness: 1.0,
                max_damping: 0.004,
            },
            DeviceClass::Omega => DeviceLimits {
                max_force: 12.0,
                max_torque: 0.0,
                max_stiffness: 5.0,
                max_damping: 0.03,
            },
        }
    }

    /// The default coupling at 1 kHz and above: 60 % of the device's stiffness (room for the
    /// sampled spring's extra energy, see `docs/HAPTICS.md`) and a damping that keeps the
    /// coupling passive at rates down to 1 kHz (`b ≥ k·T/2`, Colgate & Schenkel) with a
    /// factor of 4 to spare, within the device's damping limit.
    pub fn coupling(self) -> Coupling {
        self.coupling_at(1000.0)
    }

    /// The default coupling for a loop at `rate` Hz: as [`coupling`](Self::coupling) at
    /// 1 kHz and above; below, the damping grows with the period to stay 4 × `k·T/2`, and
    /// where that would pass the device's damping limit the stiffness drops instead (a
    /// slower loop renders a softer coupling).
    pub fn coupling_at(self, rate: f64) -> Coupling {
        let l = self.limits();
        let period = 1.0 / rate.min(1000.0);
        let mut k = 0.6 * l.max_stiffness;
        let mut b = 4.0 * k * period / 2.0;
        if b > l.max_damping {
            b = l.max_damping;
            k = 2.0 * b / (4.0 * period);
        }
        Coupling {
            stiffness: k,
            damping: b,
            angular_stiffness: k * LEVER * LEVER,
            angular_damping: b * LEVER * LEVER,
        }
    }
}

impl std::fmt::Display for DeviceClass {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for DeviceClass {
    type Err = Error;
    fn from_str(s: &str) -> Result<DeviceClass> {
        match s.trim().to_ascii_lowercase().as_str() {
            "touch" => Ok(DeviceClass::Touch),
            "omega" => Ok(DeviceClass::Omega),
            _ => Err(Error::InvalidOption(format!(
                "unknown device class \"{s}\" (expected touch or omega)"
            ))),
        }
    }
}
