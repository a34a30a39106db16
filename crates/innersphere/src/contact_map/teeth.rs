//! Regions of an arch by tooth, from a teeth-axes JSON: `{"18": {"c": [x, y, z], "x": [..],
//! "y": [..], "z": [..]}, ...}` (tooth number in the Universal Numbering System → crown
//! centre of mass `c` and the end points of its principal axes, in the arch's own frame;
//! the format of the jaw data's `*teeth_axes*.json`).

use crate::error::{Error, Result};
use glam::DVec3;
use std::path::Path;

/// One tooth: its number and crown centre (the arch's frame).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Tooth {
    /// Universal Numbering System (1–32).
    pub number: u32,
    /// Crown centre of mass.
    pub centre: DVec3,
}

/// The teeth of one arch, by number.
#[derive(Debug, Clone, PartialEq)]
pub struct Teeth {
    /// Sorted by number.
    pub teeth: Vec<Tooth>,
}

/// Vertices farther than this from every crown centre (mm) belong to no tooth: a crown is
/// at most about 12 mm across, so 10 mm from its centre reaches the cusps and the contact
/// points of the widest molar, and not the base of a scanned model.
pub const MAX_TOOTH_REACH: f64 = 10.0;

impl Teeth {
    /// Parses a teeth-axes JSON (see the module doc). Errors name what is wrong.
    pub fn from_json(text: &str, name: &Path) -> Result<Teeth> {
        let bad = |m: String| Error::InvalidOption(format!("{}: {m}", name.display()));
        let v: serde_json::Value =
            serde_json::from_str(text).map_err(|e| bad(format!("not JSON: {e}")))?;
        let obj = v
            .as_object()
            .ok_or_else(|| bad("expected an object of teeth by number".into()))?;
        let mut teeth = Vec::with_capacity(obj.len());
        for (k, t) in obj {
            let number: u32 = k
                .trim()
                .parse()
                .ok()
                .filter(|n| (1..=32).contains(n))
                .ok_or_else(|| bad(format!("\"{k}\" is no tooth number (1–32)")))?;
            let c = t
                .get("c")
                .and_then(|c| c.as_array())
                .filter(|c| c.len() == 3)
                .and_then(|c| {
                    let x: Vec<f64> = c.iter().filter_map(|x| x.as_f64()).collect();
                    (x.len() == 3).then(|| DVec3::new(x[0], x[1], x[2]))
                })
                .filter(|c| c.is_finite())
                .ok_or_else(|| bad(format!("tooth {k}: \"c\" must be 3 finite numbers")))?;
            teeth.push(Tooth { number, centre: c });
        }
        if teeth.is_empty() {
            return Err(bad("no teeth".into()));
        }
        teeth.sort_by_key(|t| t.number);
        Ok(Teeth { teeth })
    }

    /// Reads and parses a teeth-axes JSON file.
    pub fn load(path: &Path) -> Result<Teeth> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        Teeth::from_json(&text, path)
    }

    /// The tooth (index into `teeth`) of every vertex: the nearest crown centre within
    /// [`MAX_TOOTH_REACH`], else `u32::MAX`.
    pub fn regions(&self, vertices: &[DVec3]) -> Vec<u32> {
        vertices
            .iter()
            .map(|v| {
                let (k, d2) = self
                    .teeth
                    .iter()
                    .enumerate()
                    .map(|(k, t)| (k, (t.centre - *v).length_squared()))
                    .fold((u32::MAX, f64::INFINITY), |(bk, bd), (k, d)| {
                        if d < bd {
                            (k as u32, d)
                        } else {
                            (bk, bd)
                        }
                    });
                if d2 <= MAX_TOOTH_REACH * MAX_TOOTH_REACH {
                    k
                } else {
                    u32::MAX
                }
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_and_refuses() {
        let p = Path::new("t.json");
        let t = Teeth::from_json(
            r#"{"19": {"c": [1, 2, 3]}, "18": {"c": [0, 0, 0], "x": [1,0,0]}}"#,
            p,
        )
        .unwrap();
        assert_eq!(
            t.teeth.iter().map(|t| t.number).collect::<Vec<_>>(),
            [18, 19]
        );
        let r = t.regions(&[DVec3::new(0.9, 2.0, 3.0), DVec3::ZERO, DVec3::splat(50.0)]);
        assert_eq!(r, [1, 0, u32::MAX]);
        for bad in [
            "",
            "[]",
            "{}",
            r#"{"x": {"c": [0,0,0]}}"#,
            r#"{"40": {"c": [0,0,0]}}"#,
            r#"{"1": {"c": [0,0]}}"#,
            r#"{"1": {"c": [0,0,"a"]}}"#,
            r#"{"1": {}}"#,
        ] {
            assert!(Teeth::from_json(bad, p).is_err(), "{bad}");
        }
    }
}
