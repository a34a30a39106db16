//! The meshes' penetration against a reference that shares nothing with it: per frame the
//! intersection volume (and, where computed, its gradient) of an independent mesh boolean,
//! read from a CSV (`tools/mesh-volume-check/check.py --reference`, manifold3d), and the
//! figures of the bars: the volume within 2 % (or 1e-4 units³), the median ratio,
//! missed and invented contacts, the gradient's direction.

use crate::replay::FrameRow;
use innersphere::glam::DVec3;
use innersphere::{Error, Result};

/// One reference frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReferenceFrame {
    /// Frame index in the motion.
    pub frame: usize,
    /// The meshes' intersection volume.
    pub volume: f64,
    /// Its gradient with respect to B's translation, where computed.
    pub gradient: Option<DVec3>,
}

/// The reference of a motion's frames.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MeshReference {
    /// The frames, in any order.
    pub frames: Vec<ReferenceFrame>,
}

/// A mesh reference CSV: at most 256 MiB (a row is under 100 bytes; a motion of a million
/// frames fits).
pub const REFERENCE_FILE: innersphere::input::TextInput = innersphere::input::TextInput {
    what: "mesh reference CSV",
    max_bytes: 1 << 28,
};

/// Volumes below this (units³) count as no overlap for the contact bars, and the volume bar
/// is this absolute error below 5e-3 units³ (2 % of it).
pub const TINY: f64 = 1e-4;

/// The meshes' penetration against the reference ([`MeshReference::compare`]).
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct MeshAccuracy {
    /// Reference frames the replay ran.
    pub frames: usize,
    /// Of those, frames the reference says overlap.
    pub contact_frames: usize,
    /// Contact frames whose volume is within 2 % of the reference's, or within
    /// [`TINY`] units³ when that is larger.
    pub within_bar: usize,
    /// `within_bar / contact_frames`.
    pub within_bar_fraction: f64,
    /// Median of ours / reference over the contact frames.
    pub median_ratio: f64,
    /// Frames overlapping by at least [`TINY`] in the reference where ours says no contact.
    pub missed_contacts: usize,
    /// Frames apart in the reference where ours says contact.
    pub invented_contacts: usize,
    /// Frames with a reference gradient.
    pub direction_frames: usize,
    /// Angle between our gradient and the reference's (degrees): 95th percentile, maximum.
    pub direction_err_p95_deg: f64,
    /// See `direction_err_p95_deg`.
    pub direction_err_max_deg: f64,
}

impl MeshReference {
    /// Reads a CSV with a header naming `frame` and `volume`, and optionally `gx,gy,gz` (an
    /// empty cell: no gradient on that frame). At most [`REFERENCE_FILE`]'s bytes.
    pub fn load(path: &std::path::Path) -> Result<MeshReference> {
        let text = innersphere::input::read_text(path, REFERENCE_FILE)?;
        Self::parse(&text).map_err(|e| {
            Error::InvalidOption(format!("the mesh reference {}: {e}", path.display()))
        })
    }

    /// [`load`](Self::load) from the CSV's text.
    pub fn parse(text: &str) -> std::result::Result<MeshReference, String> {
        let mut lines = text.lines().filter(|l| !l.trim().is_empty());
        let head: Vec<&str> = lines
            .next()
            .ok_or("no header")?
            .split(',')
            .map(str::trim)
            .collect();
        let col = |name: &str| head.iter().position(|h| *h == name);
        let (Some(f), Some(v)) = (col("frame"), col("volume")) else {
            return Err("the header names no `frame` or no `volume` column".into());
        };
        let g = [col("gx"), col("gy"), col("gz")];
        let mut frames = Vec::new();
        for (i, line) in lines.enumerate() {
            let cells: Vec<&str> = line.split(',').map(str::trim).collect();
            let cell = |k: usize| cells.get(k).copied().unwrap_or("");
            let row = i + 2;
            let frame = cell(f)
                .parse::<usize>()
                .map_err(|_| format!("row {row}: frame `{}` is no index", cell(f)))?;
            let volume = cell(v)
                .parse::<f64>()
                .ok()
                .filter(|x| x.is_finite() && *x >= 0.0)
                .ok_or_else(|| format!("row {row}: volume `{}` is no volume", cell(v)))?;
            let gradient = match g {
                [Some(x), Some(y), Some(z)] if !cell(x).is_empty() => {
                    let n = |k: usize| {
                        cell(k)
                            .parse::<f64>()
                            .ok()
                            .filter(|x| x.is_finite())
                            .ok_or_else(|| format!("row {row}: `{}` is no number", cell(k)))
                    };
                    Some(DVec3::new(n(x)?, n(y)?, n(z)?))
                }
                _ => None,
            };
            frames.push(ReferenceFrame {
                frame,
                volume,
                gradient,
            });
        }
        Ok(MeshReference { frames })
    }

    /// The replay's answers (`rows`, the meshes' penetration in answer slot `slot`) against
    /// this reference, on the frames both have.
    pub fn compare(&self, rows: &[FrameRow], slot: usize) -> MeshAccuracy {
        let mut acc = MeshAccuracy::default();
        let (mut ratios, mut angles) = (Vec::new(), Vec::new());
        for r in &self.frames {
            let Some(row) = rows.get(r.frame) else {
                continue;
            };
            let Some(ours) = row.answers.get(slot).copied().flatten() else {
                continue;
            };
            acc.frames += 1;
            let v = ours.value;
            if r.volume >= TINY && !ours.in_contact {
                acc.missed_contacts += 1;
            }
            if r.volume == 0.0 && ours.in_contact {
                acc.invented_contacts += 1;
            }
            if r.volume > 0.0 {
                acc.contact_frames += 1;
                acc.within_bar += usize::from((v - r.volume).abs() <= (0.02 * r.volume).max(TINY));
                ratios.push(v / r.volume);
            }
            let g = DVec3::from_array(row.mesh_gradient);
            if let Some(want) = r.gradient.filter(|w| w.length() > 0.0 && g.length() > 0.0) {
                let c = (g.dot(want) / (g.length() * want.length())).clamp(-1.0, 1.0);
                angles.push(c.acos().to_degrees());
            }
        }
        acc.within_bar_fraction = acc.within_bar as f64 / acc.contact_frames.max(1) as f64;
        ratios.sort_by(f64::total_cmp);
        angles.sort_by(f64::total_cmp);
        let q = |v: &[f64], p: f64| {
            if v.is_empty() {
                f64::NAN
            } else {
                v[(((v.len() - 1) as f64) * p).round() as usize]
            }
        };
        acc.median_ratio = q(&ratios, 0.5);
        acc.direction_frames = angles.len();
        acc.direction_err_p95_deg = q(&angles, 0.95);
        acc.direction_err_max_deg = angles.last().copied().unwrap_or(f64::NAN);
        acc
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::replay::KindAnswer;

    fn row(frame: usize, volume: f64, g: [f64; 3]) -> FrameRow {
        let mut r = FrameRow {
            frame,
            mesh_gradient: g,
            ..Default::default()
        };
        r.answers[0] = Some(KindAnswer {
            in_contact: volume > 0.0,
            value: volume,
            count: 0,
        });
        r
    }

    #[test]
    fn the_bars_count_what_they_say() {
        let refr = MeshReference::parse(
            "frame,volume,gx,gy,gz\n0,0,,,\n1,1.0,0,0,1\n2,2e-4,,,\n3,0.5,1,0,0\n4,1e-3,,,\n",
        )
        .unwrap();
        let rows = vec![
            row(0, 1e-6, [0.0; 3]),         // invented
            row(1, 1.019, [0.0, 0.0, 2.0]), // within 2 %, 0°
            row(2, 0.0, [0.0; 3]),          // missed (≥ 1e-4)
            row(3, 0.4, [1.0, 1.0, 0.0]),   // 20 % off, 45°
            row(4, 1.09e-3, [0.0; 3]),      // within 1e-4 absolute
        ];
        let a = refr.compare(&rows, 0);
        assert_eq!((a.frames, a.contact_frames, a.within_bar), (5, 4, 2));
        assert_eq!((a.missed_contacts, a.invented_contacts), (1, 1));
        assert_eq!(a.direction_frames, 2);
        assert!((a.direction_err_max_deg - 45.0).abs() < 1e-9);
        // Ratios 0, 0.8, 1.019, 1.09: the median is the upper middle.
        assert!((a.median_ratio - 1.019).abs() < 1e-12, "{a:?}");
    }

    #[test]
    fn a_bad_reference_is_refused_saying_where() {
        for (text, why) in [
            ("", "no header"),
            ("frame,vol\n1,2\n", "`volume`"),
            ("frame,volume\nx,1\n", "row 2"),
            ("frame,volume\n1,-1\n", "no volume"),
            ("frame,volume,gx,gy,gz\n1,1,0,nan,0\n", "no number"),
        ] {
            let e = MeshReference::parse(text).unwrap_err();
            assert!(e.contains(why), "{text:?}: {e}");
        }
    }
}
