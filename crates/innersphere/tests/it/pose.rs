//! `Pose` constructors: round trips through matrices and text, the two storage orders, and
//! input that is no rigid pose (an error with a message, never a panic).

use innersphere::glam::{DMat3, DQuat, DVec3};
use innersphere::{MatrixOrder, Pose, PoseError};
use proptest::prelude::*;

const ORDERS: [MatrixOrder; 2] = [MatrixOrder::RowMajor, MatrixOrder::ColumnMajor];

/// A pose with any rotation and a translation within ±1000.
fn any_pose() -> impl Strategy<Value = Pose> {
    (
        prop::array::uniform4(-1.0f64..1.0),
        prop::array::uniform3(-1000.0f64..1000.0),
    )
        .prop_filter("quaternion too short", |(q, _)| {
            q.iter().map(|v| v * v).sum::<f64>() > 1e-4
        })
        .prop_map(|(q, t)| Pose::from_array([t[0], t[1], t[2], q[0], q[1], q[2], q[3]]).unwrap())
}

/// Largest distance between the images of `points` under `a` and under `b`.
fn max_gap(a: &Pose, b: &Pose, points: &[[f64; 3]]) -> f64 {
    points
        .iter()
        .map(|p| {
            let p = DVec3::from_array(*p);
            (a.transform_point(p) - b.transform_point(p)).length()
        })
        .fold(0.0, f64::max)
}

fn transpose4(m: &[f64; 16]) -> [f64; 16] {
    std::array::from_fn(|i| m[4 * (i % 4) + i / 4])
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    /// pose → 4×4 (either order) → pose, and pose → 3×3 + t → pose, move points the same.
    #[test]
    fn matrix_round_trips(
        pose in any_pose(),
        points in prop::collection::vec(prop::array::uniform3(-100.0f64..100.0), 1..8),
    ) {
        for order in ORDERS {
            let m = pose.to_matrix4(order);
            let back = Pose::from_matrix4(&m, order).unwrap();
            prop_assert!(max_gap(&pose, &back, &points) < 1e-12, "{order:?}");
            prop_assert_eq!(back.translation, pose.translation);
        }
        let back = Pose::from_rotation_matrix(pose.to_rotation_matrix(), pose.translation).unwrap();
        prop_assert!(max_gap(&pose, &back, &points) < 1e-12);
    }

    /// The row-major and column-major matrices are transposes, and reading one in the other
    /// order's transpose gives the same pose bit for bit.
    #[test]
    fn row_and_column_major_are_transposes(pose in any_pose()) {
        let row = pose.to_matrix4(MatrixOrder::RowMajor);
        let col = pose.to_matrix4(MatrixOrder::ColumnMajor);
        prop_assert_eq!(transpose4(&row), col);
        prop_assert_eq!(&row[12..], &[0.0, 0.0, 0.0, 1.0]);
        prop_assert_eq!([col[12], col[13], col[14]], pose.translation.to_array());
        let a = Pose::from_matrix4(&row, MatrixOrder::RowMajor).unwrap();
        let b = Pose::from_matrix4(&transpose4(&row), MatrixOrder::ColumnMajor).unwrap();
        prop_assert_eq!(a, b);
    }

    /// The numbers of `to_array`, written with `{}` and separated by spaces or commas, parse
    /// back to the same pose; so does `Display`.
    #[test]
    fn text_round_trips(
        pose in any_pose(),
        points in prop::collection::vec(prop::array::uniform3(-100.0f64..100.0), 1..8),
    ) {
        let fields = pose.to_array().map(|v| v.to_string());
        for text in [fields.join(" "), fields.join(", "), format!("  {}\t", fields.join(" \n")), pose.to_string()] {
            let back: Pose = text.parse().unwrap();
            prop_assert_eq!(back.translation, pose.translation, "{}", text);
            prop_assert!((back.rotation - pose.rotation).length() < 1e-15, "{}", text);
            prop_assert!(max_gap(&pose, &back, &points) < 1e-12, "{}", text);
        }
    }

    /// Any text and any 16 numbers (NaN and infinities included) give a pose or an error,
    /// never a panic; a pose obtained is finite and its quaternion unit.
    #[test]
    fn no_input_panics(
        text in ".{0,80}",
        m in prop::array::uniform16(prop_oneof![
            4 => -2.0f64..2.0,
            1 => Just(0.0),
            1 => Just(1.0),
            1 => proptest::num::f64::ANY,
        ]),
    ) {
        let mut results = vec![text.parse::<Pose>()];
        for order in ORDERS {
            results.push(Pose::from_matrix4(&m, order));
        }
        let r3 = DMat3::from_cols_array(&[m[0], m[1], m[2], m[3], m[4], m[5], m[6], m[7], m[8]]);
        results.push(Pose::from_rotation_matrix(r3, DVec3::new(m[9], m[10], m[11])));
        results.push(Pose::new(DVec3::new(m[0], m[1], m[2]), DQuat::from_xyzw(m[3], m[4], m[5], m[6])));
        for r in results {
            match r {
                Ok(p) => {
                    prop_assert!(p.translation.is_finite() && p.rotation.is_finite());
                    prop_assert!((p.rotation.length() - 1.0).abs() < 1e-12);
                }
                Err(e) => prop_assert!(!e.to_string().is_empty()),
            }
        }
    }
}

#[test]
fn identity_and_simple_poses() {
    assert_eq!(Pose::default(), Pose::IDENTITY);
    for order in ORDERS {
        let m = Pose::IDENTITY.to_matrix4(order);
        assert_eq!(Pose::from_matrix4(&m, order).unwrap(), Pose::IDENTITY);
    }
    assert_eq!("0 0 0 1 0 0 0".parse::<Pose>().unwrap(), Pose::IDENTITY);
    assert_eq!(Pose::IDENTITY.to_string(), "0 0 0 1 0 0 0");
    // A quarter turn about z and a translation, as OpenGL stores it (column-major).
    let gl = [
        0.0, 1.0, 0.0, 0.0, //
        -1.0, 0.0, 0.0, 0.0, //
        0.0, 0.0, 1.0, 0.0, //
        5.0, 6.0, 7.0, 1.0,
    ];
    let p = Pose::from_matrix4(&gl, MatrixOrder::ColumnMajor).unwrap();
    let x = p.transform_point(DVec3::X);
    assert!((x - DVec3::new(5.0, 7.0, 7.0)).length() < 1e-15, "{x}");
    // The same numbers read row-major have (5, 6, 7, 1) as last row: refused.
    assert_eq!(
        Pose::from_matrix4(&gl, MatrixOrder::RowMajor),
        Err(PoseError::NotHomogeneous {
            row: [5.0, 6.0, 7.0, 1.0]
        })
    );
    // A non-unit quaternion is normalised.
    let p: Pose = " 1,2,3, 2,0,0,0 ".parse().unwrap();
    assert_eq!(p.to_array(), [1.0, 2.0, 3.0, 1.0, 0.0, 0.0, 0.0]);
}

/// A rotation rounded to f32 (as from a float OpenGL matrix) is accepted and stays within
/// the rounding of the original.
#[test]
fn rotations_rounded_to_f32_are_accepted() {
    let q = DQuat::from_euler(innersphere::glam::EulerRot::XYZ, 0.3, -1.2, 2.5);
    let pose = Pose::new(DVec3::new(10.0, -20.0, 30.0), q).unwrap();
    for order in ORDERS {
        let m = pose.to_matrix4(order).map(|v| v as f32 as f64);
        let back = Pose::from_matrix4(&m, order).unwrap();
        assert!(max_gap(&pose, &back, &[[1.0, 2.0, 3.0], [-50.0, 0.0, 4.0]]) < 1e-4);
    }
}

#[test]
fn bad_text_is_an_error() {
    let cases: [(&str, PoseError); 8] = [
        ("", PoseError::WrongCount { got: 0 }),
        ("1 2 3", PoseError::WrongCount { got: 3 }),
        ("1 0 0 1 0 0", PoseError::WrongCount { got: 6 }),
        ("1 2 3 1 0 0 0 0", PoseError::WrongCount { got: 8 }),
        (
            "0 0 x 1 0 0 0",
            PoseError::NotANumber {
                token: "x".to_string(),
            },
        ),
        (
            "NaN 0 0 1 0 0 0",
            PoseError::NotFinite {
                what: "translation",
            },
        ),
        (
            "0 0 0 inf 0 0 0",
            PoseError::NotFinite { what: "quaternion" },
        ),
        ("0 0 0 0 0 0 0", PoseError::BadQuaternion { length: 0.0 }),
    ];
    for (text, want) in cases {
        let got = text.parse::<Pose>();
        assert_eq!(got, Err(want), "{text:?}");
        let message = got.unwrap_err().to_string();
        assert!(message.len() > 10, "{text:?}: {message}");
    }
    let e = "0 0 0 1e-13 0 0 0".parse::<Pose>().unwrap_err();
    assert!(
        matches!(e, PoseError::BadQuaternion { length } if length < 1e-12),
        "{e:?}"
    );
    // A quaternion whose length overflows cannot be normalised either.
    let e = "0 0 0 1e200 1e200 0 0".parse::<Pose>().unwrap_err();
    assert!(
        matches!(e, PoseError::BadQuaternion { length } if length.is_infinite()),
        "{e:?}"
    );
    assert!(e.to_string().contains("cannot be normalised"), "{e}");
    // The library's error wraps it.
    let e: innersphere::Error = e.into();
    assert!(e.to_string().starts_with("invalid pose: "), "{e}");
}

#[test]
fn bad_matrices_are_errors() {
    let t = DVec3::new(1.0, 2.0, 3.0);
    let scaled = DMat3::from_diagonal(DVec3::splat(1.001));
    assert!(matches!(
        Pose::from_rotation_matrix(scaled, t),
        Err(PoseError::NotOrthonormal { deviation }) if (deviation - 0.002001).abs() < 1e-9
    ));
    let shear = DMat3::from_cols(DVec3::X, DVec3::new(0.01, 1.0, 0.0), DVec3::Z);
    assert!(matches!(
        Pose::from_rotation_matrix(shear, t),
        Err(PoseError::NotOrthonormal { .. })
    ));
    let mirror = DMat3::from_diagonal(DVec3::new(1.0, 1.0, -1.0));
    assert_eq!(
        Pose::from_rotation_matrix(mirror, t),
        Err(PoseError::NotRightHanded { determinant: -1.0 })
    );
    let e = Pose::from_rotation_matrix(-DMat3::IDENTITY, t).unwrap_err();
    assert!(e.to_string().contains("reflection"), "{e}");
    assert_eq!(
        Pose::from_rotation_matrix(DMat3::ZERO, t),
        Err(PoseError::NotOrthonormal { deviation: 1.0 })
    );
    // Entries whose products overflow (inf − inf = NaN in RᵀR) are infinitely far.
    let huge = DMat3::from_cols(
        DVec3::new(1e200, 1e200, 0.0),
        DVec3::new(1e200, -1e200, 0.0),
        DVec3::Z,
    );
    assert_eq!(
        Pose::from_rotation_matrix(huge, t),
        Err(PoseError::NotOrthonormal {
            deviation: f64::INFINITY
        })
    );
    let mut nan = DMat3::IDENTITY;
    nan.y_axis.z = f64::NAN;
    assert_eq!(
        Pose::from_rotation_matrix(nan, t),
        Err(PoseError::NotFinite {
            what: "rotation matrix"
        })
    );
    assert_eq!(
        Pose::from_rotation_matrix(DMat3::IDENTITY, DVec3::new(0.0, f64::INFINITY, 0.0)),
        Err(PoseError::NotFinite {
            what: "translation"
        })
    );
    // Just inside and just outside the documented tolerance.
    let inside = DMat3::from_diagonal(DVec3::new(1.0, 1.0, (1.0f64 + 0.9e-5).sqrt()));
    assert!(Pose::from_rotation_matrix(inside, t).is_ok());
    let outside = DMat3::from_diagonal(DVec3::new(1.0, 1.0, (1.0f64 + 1.1e-5).sqrt()));
    assert!(Pose::from_rotation_matrix(outside, t).is_err());

    for order in ORDERS {
        let good = Pose::from_translation(t).to_matrix4(order);
        let last_row = |i: usize| match order {
            MatrixOrder::RowMajor => 12 + i,
            MatrixOrder::ColumnMajor => 4 * i + 3,
        };
        for (i, v) in [(0, 0.5), (1, -1e-12), (2, 1.0), (3, 2.0), (3, 0.0)] {
            let mut m = good;
            m[last_row(i)] = v;
            let e = Pose::from_matrix4(&m, order).unwrap_err();
            assert!(
                matches!(e, PoseError::NotHomogeneous { .. }),
                "{order:?} {i}"
            );
            assert!(e.to_string().contains("last row"), "{e}");
        }
        for v in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            for i in [0, 5, 11, 14, 15] {
                let mut m = good;
                m[i] = v;
                assert_eq!(
                    Pose::from_matrix4(&m, order),
                    Err(PoseError::NotFinite {
                        what: "4×4 matrix"
                    })
                );
            }
        }
        let mut scaled = good;
        scaled[0] = 2.0;
        assert!(matches!(
            Pose::from_matrix4(&scaled, order),
            Err(PoseError::NotOrthonormal { .. })
        ));
        let mut mirrored = good;
        mirrored[10] = -1.0;
        assert!(matches!(
            Pose::from_matrix4(&mirrored, order),
            Err(PoseError::NotRightHanded { .. })
        ));
    }
}
