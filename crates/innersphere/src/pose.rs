//! Rigid poses (rotation + translation) in f64, made from what a caller holds: a translation
//! and a unit quaternion, a 3×3 rotation matrix, a 4×4 homogeneous matrix in row- or
//! column-major order (OpenGL and OpenHaptics send column-major), or the text
//! `"tx ty tz qw qx qy qz"`. Input that is no rigid pose is a [`PoseError`], never a panic.

use glam::{DMat3, DMat4, DQuat, DVec3, DVec4};
use std::fmt;
use std::str::FromStr;

/// How far a 3×3 matrix may be from a rotation and still be accepted: every entry of
/// `RᵀR − I`, and `det R − 1`, within this. Loose enough for a rotation rounded to f32
/// (about 1e-7 per entry) and composed a few times, tight enough to refuse any scale or shear
/// that would matter (a uniform scale of 1.00001 already gives 2e-5).
pub const ROTATION_TOLERANCE: f64 = 1e-5;

/// The shortest quaternion [`Pose::new`] normalises; a shorter one has no reliable direction.
pub const MIN_QUATERNION_LENGTH: f64 = 1e-12;

/// The message of [`PoseError::BadQuaternion`]: too small or too large, said as such.
fn bad_quaternion_text(length: f64) -> String {
    if length.is_finite() {
        format!(
            "the quaternion (qw qx qy qz) has length {length:e}, too small to normalise to a \
             rotation (its length must be above {MIN_QUATERNION_LENGTH:e})"
        )
    } else {
        format!(
            "the quaternion (qw qx qy qz) has length {length:e}: it cannot be normalised to a \
             rotation (its length overflows; scale its components down)"
        )
    }
}

/// A rigid transform `p' = R(q)·p + t`, in f64 so that composing poses along a long motion
/// loses nothing; queries convert the relative pose of a pair to f32 once per query.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose {
    /// Unit quaternion of the rotation.
    pub rotation: DQuat,
    /// Translation, applied after the rotation.
    pub translation: DVec3,
}

/// The storage order of a 4×4 matrix given as 16 numbers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MatrixOrder {
    /// Row after row: `m[4·row + col]`; the translation is `m[3], m[7], m[11]`.
    RowMajor,
    /// Column after column, as OpenGL, OpenHaptics and glam store it: `m[4·col + row]`; the
    /// translation is `m[12], m[13], m[14]`.
    ColumnMajor,
}

/// Why some input is not a rigid pose.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PoseError {
    /// A NaN or an infinity in the named input.
    #[error("the {what} has a NaN or infinite component")]
    NotFinite {
        /// Which input: "translation", "quaternion", "rotation matrix" or "4×4 matrix".
        what: &'static str,
    },
    /// A quaternion too short (at most [`MIN_QUATERNION_LENGTH`]) or too long (its length
    /// overflows) to normalise.
    #[error("{}", bad_quaternion_text(*length))]
    BadQuaternion {
        /// Its length as computed.
        length: f64,
    },
    /// A 3×3 matrix whose columns are not orthonormal (it scales or shears).
    #[error(
        "the 3×3 matrix is not a rotation: RᵀR differs from the identity by {deviation:e} \
         (tolerance {ROTATION_TOLERANCE:e}); it scales or shears"
    )]
    NotOrthonormal {
        /// The largest entry of `|RᵀR − I|`.
        deviation: f64,
    },
    /// An orthonormal 3×3 matrix that mirrors (determinant −1) instead of rotating.
    #[error(
        "the 3×3 matrix is not a rotation: its determinant is {determinant}, not +1 \
         (a reflection)"
    )]
    NotRightHanded {
        /// Its determinant.
        determinant: f64,
    },
    /// A 4×4 matrix whose last row is not exactly `0 0 0 1` (a projection, not a rigid pose).
    #[error(
        "the 4×4 matrix is not a rigid transform: its last row is {row:?}, not [0, 0, 0, 1] \
         (is the storage order right?)"
    )]
    NotHomogeneous {
        /// The last row as read in the given order.
        row: [f64; 4],
    },
    /// Text with another count of numbers than seven.
    #[error("expected 7 numbers \"tx ty tz qw qx qy qz\", got {got}")]
    WrongCount {
        /// How many fields the text had.
        got: usize,
    },
    /// Text with a field that is not a number.
    #[error("\"{token}\" is not a number")]
    NotANumber {
        /// The field.
        token: String,
    },
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

    /// A pose from a translation and a (not necessarily unit) quaternion, which is
    /// normalised. Fails on a NaN or infinity, and on a quaternion that cannot be normalised.
    pub fn new(translation: DVec3, rotation: DQuat) -> Result<Pose, PoseError> {
        if !translation.is_finite() {
            return Err(PoseError::NotFinite {
                what: "translation",
            });
        }
        if !rotation.is_finite() {
            return Err(PoseError::NotFinite { what: "quaternion" });
        }
        let length = rotation.length();
        if !(length.is_finite() && length > MIN_QUATERNION_LENGTH) {
            // Too short: its true length for the message (the square underflows below
            // about 1e-154). Too long: its length overflowed, said as such.
            let scale = DVec4::from(rotation).abs().max_element();
            let length = if length.is_finite() && scale > 0.0 {
                (rotation / scale).length() * scale
            } else {
                length
            };
            return Err(PoseError::BadQuaternion { length });
        }
        Ok(Pose {
            rotation: rotation / length,
            translation,
        })
    }

    /// A pure translation (not checked: a non-finite `t` gives a non-finite pose).
    pub fn from_translation(t: DVec3) -> Pose {
        Pose {
            rotation: DQuat::IDENTITY,
            translation: t,
        }
    }

    /// A pose from `[tx, ty, tz, qw, qx, qy, qz]` (the order of motion files and `--pose-b`),
    /// checked as [`Pose::new`].
    pub fn from_array(a: [f64; 7]) -> Result<Pose, PoseError> {
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

    /// A pose from a 3×3 rotation matrix and a translation. The matrix must be orthonormal
    /// with determinant +1 within [`ROTATION_TOLERANCE`]; scale, shear and reflection fail.
    pub fn from_rotation_matrix(rotation: DMat3, translation: DVec3) -> Result<Pose, PoseError> {
        if !translation.is_finite() {
            return Err(PoseError::NotFinite {
                what: "translation",
            });
        }
        if !rotation.is_finite() {
            return Err(PoseError::NotFinite {
                what: "rotation matrix",
            });
        }
        let gram = rotation.transpose() * rotation - DMat3::IDENTITY;
        // Huge finite entries can overflow to inf − inf = NaN: count that as infinitely far.
        let deviation = gram
            .to_cols_array()
            .iter()
            .map(|v| if v.is_nan() { f64::INFINITY } else { v.abs() })
            .fold(0.0f64, f64::max);
        if deviation > ROTATION_TOLERANCE {
            return Err(PoseError::NotOrthonormal { deviation });
        }
        let determinant = rotation.determinant();
        // Finite here: the columns are unit vectors within the tolerance.
        if (determinant - 1.0).abs() > ROTATION_TOLERANCE {
            return Err(PoseError::NotRightHanded { determinant });
        }
        Pose::new(translation, DQuat::from_mat3(&rotation))
    }

    /// The rotation as a 3×3 matrix.
    pub fn to_rotation_matrix(&self) -> DMat3 {
        DMat3::from_quat(self.rotation)
    }

    /// A pose from a 4×4 homogeneous matrix `[R t; 0 0 0 1]` stored in `order`. The last row
    /// must be exactly `0 0 0 1` (every product of rigid matrices keeps it exact) and `R` a
    /// rotation as in [`Pose::from_rotation_matrix`].
    pub fn from_matrix4(m: &[f64; 16], order: MatrixOrder) -> Result<Pose, PoseError> {
        if m.iter().any(|v| !v.is_finite()) {
            return Err(PoseError::NotFinite {
                what: "4×4 matrix"
            });
        }
        let at = |row: usize, col: usize| match order {
            MatrixOrder::RowMajor => m[4 * row + col],
            MatrixOrder::ColumnMajor => m[4 * col + row],
        };
        let row = [at(3, 0), at(3, 1), at(3, 2), at(3, 3)];
        if row != [0.0, 0.0, 0.0, 1.0] {
            return Err(PoseError::NotHomogeneous { row });
        }
        let col = |c: usize| DVec3::new(at(0, c), at(1, c), at(2, c));
        Pose::from_rotation_matrix(DMat3::from_cols(col(0), col(1), col(2)), col(3))
    }

    /// The pose as a 4×4 homogeneous matrix `[R t; 0 0 0 1]` stored in `order`.
    pub fn to_matrix4(&self, order: MatrixOrder) -> [f64; 16] {
        let r = self.to_rotation_matrix();
        let m = DMat4::from_cols(
            r.x_axis.extend(0.0),
            r.y_axis.extend(0.0),
            r.z_axis.extend(0.0),
            self.translation.extend(1.0),
        );
        match order {
            MatrixOrder::ColumnMajor => m.to_cols_array(),
            MatrixOrder::RowMajor => m.transpose().to_cols_array(),
        }
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

/// Parses `"tx ty tz qw qx qy qz"`, the numbers separated by whitespace and/or commas (the
/// command line's `--pose-b`); the quaternion is normalised, checked as [`Pose::new`].
/// Serialized as its 7 numbers `[tx, ty, tz, qw, qx, qy, qz]` ([`Pose::to_array`]): the
/// form `ist query --pose-b` and Python take.
impl serde::Serialize for Pose {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        serde::Serialize::serialize(&self.to_array(), s)
    }
}

impl FromStr for Pose {
    type Err = PoseError;

    fn from_str(s: &str) -> Result<Pose, PoseError> {
        let fields = || {
            s.split(|c: char| c.is_whitespace() || c == ',')
                .filter(|p| !p.is_empty())
        };
        let got = fields().count();
        if got != 7 {
            return Err(PoseError::WrongCount { got });
        }
        let mut v = [0.0f64; 7];
        for (slot, field) in v.iter_mut().zip(fields()) {
            *slot = field.parse().map_err(|_| PoseError::NotANumber {
                token: field.to_string(),
            })?;
        }
        Pose::from_array(v)
    }
}

/// Writes `tx ty tz qw qx qy qz` separated by single spaces, each number with the given
/// format options (plain `{}` is the shortest text that [`FromStr`] reads back exactly).
impl fmt::Display for Pose {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, v) in self.to_array().iter().enumerate() {
            if i > 0 {
                f.write_str(" ")?;
            }
            fmt::Display::fmt(v, f)?;
        }
        Ok(())
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
        assert!(Pose::from_array([0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]).is_err());
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
