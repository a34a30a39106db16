//! Rigid poses (rotation + translation) in f64.

use glam::{DQuat, DVec3};

/// A rigid transform `p' = R(q)·p + t`, in f64 so that composing poses along a long motion
/// loses nothing; queries convert the relative pose of a pair to f32 once per query.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose {
    /// Unit quaternion of the rotation.
    pub rotation: DQuat,
    /// Translation, applied after the rotation.
    pub translation: DVec3,
}

impl Default for Pose {
    fn default() -> Self {
        Pose::IDENTITY
    }
}

impl Pose {
    /// The identity.
    pub const IDENTITY: Pose = Pose {
        rotation: DQuat::IDENTITY,
        translation: DVec3::ZERO,
    };

    /// A pose from a translation and a (not necessarily unit) quaternion, which is normalized.
    /// Returns `None` when the quaternion is zero or not finite.
    pub fn new(translation: DVec3, rotation: DQuat) -> Option<Pose> {
        let len = rotation.length();
        if !(len.is_finite() && len > 1e-12 && translation.is_finite()) {
            return None;
        }
        Some(Pose {
            rotation: rotation / len,
            translation,
        })
    }

    /// A pure translation.
    pub fn from_translation(t: DVec3) -> Pose {
        Pose {
            rotation: DQuat::IDENTITY,
            translation: t,
        }
    }

    /// A pose from `[tx, ty, tz, qw, qx, qy, qz]` (the order of motion files and `--pose-b`).
    pub fn from_array(a: [f64; 7]) -> Option<Pose> {
        Pose::new(
            DVec3::new(a[0], a[1], a[2]),
            DQuat::from_xyzw(a[4], a[5], a[6], a[3]),
        )
    }

    /// `[tx, ty, tz, qw, qx, qy, qz]`.
    pub fn to_array(&self) -> [f64; 7] {
        let q = self.rotation;
        let t = self.translation;
        [t.x, t.y, t.z, q.w, q.x, q.y, q.z]
    }

    /// Applies the pose to a point.
    #[inline]
    pub fn transform_point(&self, p: DVec3) -> DVec3 {
        self.rotation * p + self.translation
    }

    /// Applies only the rotation (for directions and normals).
    #[inline]
    pub fn transform_vector(&self, v: DVec3) -> DVec3 {
        self.rotation * v
    }

    /// The inverse transform.
    pub fn inverse(&self) -> Pose {
        let inv = self.rotation.conjugate();
        Pose {
            rotation: inv,
            translation: -(inv * self.translation),
        }
    }

    /// `self ∘ other`: first `other`, then `self`.
    pub fn then(&self, other: &Pose) -> Pose {
        Pose {
            rotation: (self.rotation * other.rotation).normalize(),
            translation: self.rotation * other.translation + self.translation,
        }
    }

    /// The pose of body B in body A's frame, given both in the world: `A⁻¹ ∘ B`.
    pub fn relative(a: &Pose, b: &Pose) -> Pose {
        a.inverse().then(b)
    }

    /// Rotation angle in radians (0..=π).
    pub fn angle(&self) -> f64 {
        2.0 * self.rotation.w.abs().clamp(0.0, 1.0).acos()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inverse_and_relative() {
        let a = Pose::new(DVec3::new(1.0, 2.0, 3.0), DQuat::from_rotation_z(0.3)).unwrap();
        let b = Pose::new(DVec3::new(-1.0, 0.5, 2.0), DQuat::from_rotation_x(1.1)).unwrap();
        let p = DVec3::new(0.3, -0.7, 1.9);
        let back = a.inverse().transform_point(a.transform_point(p));
        assert!((back - p).length() < 1e-12);
        let rel = Pose::relative(&a, &b);
        let via = a.inverse().transform_point(b.transform_point(p));
        assert!((rel.transform_point(p) - via).length() < 1e-12);
        assert!(Pose::from_array([0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]).is_none());
        assert!(
            (Pose::from_array([0.0; 7].map(|_| 1.0))
                .unwrap()
                .rotation
                .length()
                - 1.0)
                .abs()
                < 1e-12
        );
    }
}
