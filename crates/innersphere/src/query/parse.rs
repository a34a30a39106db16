//! Parsing of poses given as text (command line, config files).

use super::Pose;
use crate::{Error, Result};

/// Parses `"tx ty tz qw qx qy qz"` (whitespace and/or comma separated) into a pose. The
/// quaternion is normalized; a wrong count, a non-number, a non-finite value or a zero
/// quaternion is an [`Error::InvalidOption`].
pub fn parse_pose(s: &str) -> Result<Pose> {
    let bad = |m: String| Error::InvalidOption(format!("pose \"{s}\": {m}"));
    let parts: Vec<&str> = s
        .split(|c: char| c.is_whitespace() || c == ',')
        .filter(|p| !p.is_empty())
        .collect();
    if parts.len() != 7 {
        return Err(bad(format!(
            "expected 7 numbers \"tx ty tz qw qx qy qz\", got {}",
            parts.len()
        )));
    }
    let mut v = [0.0f64; 7];
    for (slot, p) in v.iter_mut().zip(&parts) {
        *slot = p
            .parse::<f64>()
            .map_err(|_| bad(format!("\"{p}\" is not a number")))?;
        if !slot.is_finite() {
            return Err(bad(format!("\"{p}\" is not finite")));
        }
    }
    let q = (v[3] * v[3] + v[4] * v[4] + v[5] * v[5] + v[6] * v[6]).sqrt();
    if q < 1e-12 {
        return Err(bad("the quaternion (qw qx qy qz) is zero".into()));
    }
    Pose::from_array(v).ok_or_else(|| bad("not a valid rigid pose".into()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn poses_parse_and_bad_ones_fail() {
        let p = parse_pose("1 2 3 1 0 0 0").unwrap();
        assert_eq!(p.translation.to_array(), [1.0, 2.0, 3.0]);
        let p = parse_pose(" 0,0,0, 2,0,0,0 ").unwrap();
        assert!((p.rotation.w - 1.0).abs() < 1e-15);
        for bad in [
            "",
            "1 2 3",
            "1 2 3 1 0 0 0 0",
            "0 0 0 0 0 0 0",
            "NaN 0 0 1 0 0 0",
            "0 0 0 inf 0 0 0",
            "0 0 x 1 0 0 0",
        ] {
            assert!(parse_pose(bad).is_err(), "{bad:?}");
        }
    }
}
