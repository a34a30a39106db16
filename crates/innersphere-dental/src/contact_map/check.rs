//! Whether a teeth file fits the arch it labels ([`Teeth::check_against`], [`check_pair`]).
//!
//! A teeth file for another arch, another patient, another unit or another frame parses
//! fine and then labels nothing, or the wrong teeth: the per-tooth list of a contact map
//! would name contacts on teeth that are not there. The checks, each cheap (the crown
//! centres against the arch's bounding box and vertices, a winding number at each centre):
//!
//! 1. **One arch per file**: upper teeth (1–16) and lower teeth (17–32) are never mixed
//!    ([`Teeth::jaw`]); when the caller knows the arch (or the other file of a pair says it),
//!    the file must hold that arch's teeth.
//! 2. **Inside the arch**: every crown centre lies within the arch's bounding box grown by
//!    [`TEETH_BOX_MARGIN`]. A crown centre of mass lies inside its crown, so a centre outside
//!    the box belongs to another file: the message says which cause the numbers point to —
//!    another unit (the centres' spread 1000 times smaller than the arch's: metres against
//!    millimetres; 25.4: inches; 10: centimetres), the other arch (the centres lie within the
//!    opposing arch), or another patient or frame.
//! 3. **Not the other arch's**: with the opposing arch at hand, in its place, a file most of
//!    whose centres lie inside the opposing arch (winding number ≥ ½) and not inside the arch
//!    it is given for is the other arch's file. In a bite the arches interleave, so the box
//!    alone cannot tell; a crown centre is inside its own crown, never inside the opposing
//!    one. Only a clear majority refuses: on open scans the winding number is soft.
//! 4. **Labels the arch**: a tooth whose crown centre labels no vertex (none within
//!    [`MAX_TOOTH_REACH`] is nearer to it than to another centre) is a warning, not an error:
//!    a tooth extracted or cut off the scan is real, and the map is right without it (its
//!    line says 0 vertices). A file most of whose teeth label nothing is refused, with the
//!    causes of 2.: with the arch's origin inside its box, a file in metres collapses onto
//!    the origin, inside the box and far from every crown.

use super::teeth::{Jaw, Teeth, MAX_TOOTH_REACH};
use glam::DVec3;
use innersphere::error::{num, Error, Result};
use innersphere::mesh::union_find::UnionFind;
use innersphere::mesh::winding::solid_angle;
use innersphere::mesh::Mesh;
use innersphere::pose::Pose;
use rayon::prelude::*;

/// How far (mm) beyond an arch's bounding box a crown centre may lie. A crown centre lies
/// inside its crown, so inside the box; the margin leaves room for a file made on a slightly
/// different segmentation of the same scan, and is half [`MAX_TOOTH_REACH`], so a centre
/// just outside still reaches the crown it labels.
pub const TEETH_BOX_MARGIN: f64 = 5.0;

/// What a teeth file is checked against ([`Teeth::check_against`]).
#[derive(Debug, Clone, Copy)]
pub struct ArchContext<'a> {
    /// The arch the file labels, in its own frame (the file's frame). A mesh without
    /// triangles (a point cloud, such as a tree's leaf centres) gets the box and reach checks
    /// only.
    pub arch: &'a Mesh,
    /// The opposing arch and its pose in `arch`'s frame, when known (for the jaw scans at
    /// the bite, the identity).
    pub opposing: Option<(&'a Mesh, Pose)>,
    /// Upper or lower, when the caller knows which arch `arch` is.
    pub jaw: Option<Jaw>,
}

/// A teeth file that fits its arch: its arch, every vertex's tooth and the warnings.
#[derive(Debug, Clone, PartialEq)]
pub struct TeethFit {
    /// The arch the file labels.
    pub jaw: Jaw,
    /// Per vertex of the arch, its tooth (index into [`Teeth::teeth`]) or `u32::MAX`
    /// ([`Teeth::regions`]).
    pub regions: Vec<u32>,
    /// Per tooth, the vertices it labels.
    pub vertices: Vec<usize>,
    /// What a user should know and the map still shows rightly (a tooth that labels no
    /// vertex), one sentence each, naming the file.
    pub warnings: Vec<String>,
}

/// The generalized winding number of points over a mesh, summed over only the connected
/// components whose bounding box (grown by 1 mm) holds the point: a closed component adds
/// exactly 0 outside itself, an open one little, so a crown centre costs the triangles of
/// its own tooth (about 30k on the jaw scans, against 440k for the arch) when the teeth are
/// separate shells, and the whole arch when it is one.
struct Winding<'a> {
    mesh: &'a Mesh,
    /// Per component: its bounding box and its triangles.
    parts: Vec<(DVec3, DVec3, Vec<u32>)>,
}

impl<'a> Winding<'a> {
    fn new(mesh: &'a Mesh) -> Winding<'a> {
        let mut sets = UnionFind::new(mesh.vertices.len());
        for t in &mesh.triangles {
            sets.union(t[0], t[1]);
            sets.union(t[0], t[2]);
        }
        let mut part_of = vec![u32::MAX; mesh.vertices.len()];
        let mut parts: Vec<(DVec3, DVec3, Vec<u32>)> = Vec::new();
        for (i, t) in mesh.triangles.iter().enumerate() {
            let root = sets.find(t[0]) as usize;
            if part_of[root] == u32::MAX {
                part_of[root] = parts.len() as u32;
                parts.push((
                    DVec3::splat(f64::INFINITY),
                    DVec3::splat(f64::NEG_INFINITY),
                    Vec::new(),
                ));
            }
            let part = &mut parts[part_of[root] as usize];
            for &v in t {
                let p = mesh.vertices[v as usize];
                part.0 = part.0.min(p);
                part.1 = part.1.max(p);
            }
            part.2.push(i as u32);
        }
        Winding { mesh, parts }
    }

    /// ≈ 1 inside, ≈ 0 outside (absolute value: an inward-facing mesh counts as inside too).
    fn at(&self, p: DVec3) -> f64 {
        let sum: f64 = self
            .parts
            .iter()
            .filter(|(lo, hi, _)| within(p, (*lo, *hi), 1.0))
            .flat_map(|(_, _, tris)| tris.par_chunks(4096).collect::<Vec<_>>())
            .collect::<Vec<_>>()
            .into_par_iter()
            .map(|ts| {
                ts.iter()
                    .map(|&t| {
                        let [a, b, c] = self.mesh.triangles[t as usize]
                            .map(|i| self.mesh.vertices[i as usize] - p);
                        solid_angle(a, b, c)
                    })
                    .sum::<f64>()
            })
            .sum();
        (sum / (4.0 * std::f64::consts::PI)).abs()
    }
}

fn bbox(points: impl Iterator<Item = DVec3>) -> (DVec3, DVec3) {
    points.fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(p), hi.max(p)),
    )
}

fn within(p: DVec3, (lo, hi): (DVec3, DVec3), margin: f64) -> bool {
    p.cmpge(lo - margin).all() && p.cmple(hi + margin).all()
}

/// `x` to 4 significant digits, as a message writes it.
fn sig(x: f64) -> innersphere::error::Num {
    if x == 0.0 || !x.is_finite() {
        return num(x);
    }
    let scale = 10f64.powi(3 - x.abs().log10().floor() as i32);
    num((x * scale).round() / scale)
}

/// A point to 4 significant digits per coordinate.
fn point(p: DVec3) -> String {
    format!("({}, {}, {})", sig(p.x), sig(p.y), sig(p.z))
}

fn numbers<'a>(teeth: impl Iterator<Item = &'a super::Tooth>) -> String {
    teeth
        .map(|t| t.number.to_string())
        .collect::<Vec<_>>()
        .join(", ")
}

/// The likely unit mismatch when the crown centres span `ratio` times less than the arch
/// (same unit: about 1.2 to 1.5), or `None` when the ratio points to none.
fn unit_mismatch(ratio: f64) -> Option<String> {
    const UNITS: [(f64, &str); 3] = [(1000.0, "metres"), (25.4, "inches"), (10.0, "centimetres")];
    const SAME_UNIT: f64 = 1.3;
    let r = ratio / SAME_UNIT;
    if !(r.is_finite() && r > 0.0) || (0.2..5.0).contains(&r) {
        return None;
    }
    let (f, name) = UNITS
        .iter()
        .map(|&(f, name)| if r > 1.0 { (f, name) } else { (1.0 / f, name) })
        .min_by(|a, b| {
            let d = |f: f64| (r / f).ln().abs();
            d(a.0).total_cmp(&d(b.0))
        })?;
    if (r / f).ln().abs() > 1.5f64.ln() {
        return None;
    }
    Some(if r > 1.0 {
        format!("the teeth file is likely in {name} and the mesh in millimetres")
    } else {
        format!("the mesh is likely in {name} and the teeth file in millimetres")
    })
}

impl Teeth {
    /// Why the centres do not fit an arch with bounding box `own`, as the end of a sentence:
    /// the unit their spread points to, else another patient, arch or frame.
    fn likely_causes(&self, own: (DVec3, DVec3)) -> String {
        let spread = |(lo, hi): (DVec3, DVec3)| (hi - lo).length();
        let teeth_spread = spread(bbox(self.teeth.iter().map(|t| t.centre)));
        let ratio = spread(own) / teeth_spread;
        match (self.teeth.len() >= 2).then(|| unit_mismatch(ratio)).flatten() {
            Some(unit) => format!(
                ": the centres span {} and the arch {}, {} times more: {unit} (a teeth file is in its mesh's unit); otherwise it is another patient's or the other arch's teeth file",
                sig(teeth_spread),
                sig(spread(own)),
                sig(ratio)
            ),
            None => ": in the arch's unit by their spread, so likely another patient's or the other arch's teeth file, or one in another frame (a teeth file is in its mesh's unit and frame)".into(),
        }
    }

    fn refusal(&self, message: String) -> Error {
        Error::Input {
            path: self.source.clone(),
            message,
        }
    }

    /// Checks that the file fits the arch it labels (see the docs of this module, `contact_map::check`): refuses a
    /// file that mixes arches, holds the other arch's teeth where `ctx.jaw` says which arch
    /// this is, has crown centres outside the arch (saying whether another unit, the other
    /// arch or another patient or frame is the likely cause), or whose centres lie inside the
    /// opposing arch rather than this one; warns of teeth that label no vertex. Returns the
    /// regions ([`Teeth::regions`]) it computed on the way. About 25 ms on a 220k-vertex arch
    /// with 16 teeth (two cores), plus a winding number per centre when the opposing arch is
    /// given.
    // Over 120 lines: the checks run in the order their refusals are worded (arch, box,
    // winding, regions), most of the length is the refusals' text.
    pub fn check_against(&self, ctx: &ArchContext) -> Result<TeethFit> {
        let jaw = self.jaw()?;
        if let Some(want) = ctx.jaw.filter(|&w| w != jaw) {
            return Err(self.refusal(format!(
                "holds {}, but the arch it is given for is the {} one: this looks like the other arch's teeth file",
                jaw.describe(),
                want.name()
            )));
        }
        let arch = ctx.arch;
        if arch.vertices.is_empty() {
            return Err(self.refusal("the arch it is given for has no vertices".into()));
        }
        let n = self.teeth.len();
        let own = bbox(arch.vertices.iter().copied());
        let outside: Vec<&super::Tooth> = self
            .teeth
            .iter()
            .filter(|t| !within(t.centre, own, TEETH_BOX_MARGIN))
            .collect();
        if let Some(first) = outside.first() {
            let arch_box = format!(
                "the arch it is given for (its bounding box {} to {}, grown by {} mm)",
                point(own.0),
                point(own.1),
                num(TEETH_BOX_MARGIN)
            );
            let mut m = if outside.len() == 1 {
                format!(
                    "the crown centre of tooth {}, {}, lies outside {arch_box}",
                    first.number,
                    point(first.centre)
                )
            } else {
                format!(
                    "{} of its {n} crown centres (teeth {}) lie outside {arch_box}, e.g. tooth {} at {}",
                    outside.len(),
                    numbers(outside.iter().copied()),
                    first.number,
                    point(first.centre)
                )
            };
            let to_other = ctx.opposing.map(|(opp, pose)| {
                let inv = pose.inverse();
                let other = bbox(opp.vertices.iter().copied());
                !opp.vertices.is_empty()
                    && outside
                        .iter()
                        .all(|t| within(inv.transform_point(t.centre), other, TEETH_BOX_MARGIN))
            });
            if to_other == Some(true) {
                m += ", and within the other arch: this looks like the other arch's teeth file";
            } else {
                m += &self.likely_causes(own);
            }
            return Err(self.refusal(m));
        }
        if let Some((opp, pose)) = ctx.opposing {
            if !arch.triangles.is_empty() && !opp.triangles.is_empty() {
                let inv = pose.inverse();
                let own = Winding::new(arch);
                let not_own: Vec<&super::Tooth> = self
                    .teeth
                    .iter()
                    .filter(|t| own.at(t.centre) < 0.5)
                    .collect();
                if 2 * not_own.len() > n {
                    let other = Winding::new(opp);
                    let in_other: Vec<&super::Tooth> = not_own
                        .into_iter()
                        .filter(|t| other.at(inv.transform_point(t.centre)) >= 0.5)
                        .collect();
                    if 2 * in_other.len() > n {
                        return Err(self.refusal(format!(
                            "{} of its {n} crown centres (teeth {}) lie inside the opposing arch and not inside the arch it is given for: this looks like the other arch's teeth file",
                            in_other.len(),
                            numbers(in_other.iter().copied())
                        )));
                    }
                }
            }
        }
        let regions = self.regions(&arch.vertices);
        let mut vertices = vec![0usize; n];
        for &r in &regions {
            if let Some(c) = vertices.get_mut(r as usize) {
                *c += 1;
            }
        }
        let unlabelled: Vec<&super::Tooth> = self
            .teeth
            .iter()
            .zip(&vertices)
            .filter(|(_, &c)| c == 0)
            .map(|(t, _)| t)
            .collect();
        if 2 * unlabelled.len() > n {
            return Err(self.refusal(format!(
                "{} of its {n} crown centres (teeth {}) label no vertex of the arch it is given for (none within {} mm){}",
                unlabelled.len(),
                numbers(unlabelled.iter().copied()),
                num(MAX_TOOTH_REACH),
                self.likely_causes(own)
            )));
        }
        let mut warnings = Vec::new();
        if !unlabelled.is_empty() {
            warnings.push(format!(
                "{}: {} {} no vertex of the arch (no vertex within {} mm is nearer to {} crown centre than to another's): missing from the scan?",
                self.source.display(),
                if unlabelled.len() == 1 {
                    format!("tooth {}", unlabelled[0].number)
                } else {
                    format!("teeth {}", numbers(unlabelled.iter().copied()))
                },
                if unlabelled.len() == 1 { "labels" } else { "label" },
                num(MAX_TOOTH_REACH),
                if unlabelled.len() == 1 { "its" } else { "their" },
            ));
        }
        Ok(TeethFit {
            jaw,
            regions,
            vertices,
            warnings,
        })
    }
}

/// The teeth files of an arch pair checked together and each against its arch: A's against
/// `a` with `b` opposing at `pose_b` (B's pose in A's frame), B's against `b` with `a`
/// opposing at the inverse pose; and two files must be one upper and one lower (in a pair
/// neither arch is declared upper or lower, so the files say it, and must agree). Either
/// file may be absent.
pub fn check_pair(
    a: &Mesh,
    teeth_a: Option<&Teeth>,
    b: &Mesh,
    teeth_b: Option<&Teeth>,
    pose_b: &Pose,
) -> Result<(Option<TeethFit>, Option<TeethFit>)> {
    let (jaw_a, jaw_b) = (
        teeth_a.map(Teeth::jaw).transpose()?,
        teeth_b.map(Teeth::jaw).transpose()?,
    );
    if let (Some(ta), Some(tb), Some(ja), Some(jb)) = (teeth_a, teeth_b, jaw_a, jaw_b) {
        if ja == jb {
            return Err(tb.refusal(format!(
                "holds {}, as does {}: the two arches of a pair need one upper and one lower teeth file (one of the two is the other arch's, or both are the same file)",
                jb.describe(),
                ta.source.display()
            )));
        }
    }
    let fit_a = teeth_a
        .map(|t| {
            t.check_against(&ArchContext {
                arch: a,
                opposing: Some((b, *pose_b)),
                jaw: None,
            })
        })
        .transpose()?;
    let fit_b = teeth_b
        .map(|t| {
            t.check_against(&ArchContext {
                arch: b,
                opposing: Some((a, pose_b.inverse())),
                jaw: None,
            })
        })
        .transpose()?;
    Ok((fit_a, fit_b))
}

#[cfg(test)]
mod tests {
    use super::*;
    use innersphere::shapes;

    fn message(r: Result<impl std::fmt::Debug>) -> String {
        match r {
            Err(Error::Input { message, .. }) => message,
            other => panic!("expected a refusal, got {other:?}"),
        }
    }

    #[test]
    fn the_generated_arches_own_teeth_fit() {
        let (upper, lower) = shapes::arch_pair(1, 10);
        let (tu, tl) = Teeth::of_arch_pair(10);
        let (fu, fl) = check_pair(&upper, Some(&tu), &lower, Some(&tl), &Pose::IDENTITY).unwrap();
        let (fu, fl) = (fu.unwrap(), fl.unwrap());
        assert_eq!((fu.jaw, fl.jaw), (Jaw::Upper, Jaw::Lower));
        for f in [&fu, &fl] {
            assert!(f.warnings.is_empty(), "{:?}", f.warnings);
            assert!(f.vertices.iter().all(|&c| c > 0), "{:?}", f.vertices);
        }
        assert_eq!(fu.regions, tu.regions(&upper.vertices));
    }

    #[test]
    fn the_other_arch_s_file_is_refused() {
        let (upper, lower) = shapes::arch_pair(1, 10);
        let (tu, tl) = Teeth::of_arch_pair(10);
        // Given for the other arch, in a bite: the centres are inside the opposing arch.
        let m = message(check_pair(&upper, None, &lower, Some(&tu), &Pose::IDENTITY));
        assert!(
            m.contains("this looks like the other arch's teeth file"),
            "{m}"
        );
        assert!(m.contains("lie inside the opposing arch"), "{m}");
        // Both files of one arch.
        let m = message(check_pair(
            &upper,
            Some(&tl),
            &lower,
            Some(&tl),
            &Pose::IDENTITY,
        ));
        assert!(m.contains("need one upper and one lower"), "{m}");
        // A known arch.
        let m = message(tl.check_against(&ArchContext {
            arch: &upper,
            opposing: None,
            jaw: Some(Jaw::Upper),
        }));
        assert!(
            m.contains("holds lower teeth (17–32), but the arch it is given for is the upper one"),
            "{m}"
        );
        // The arches apart (B 40 mm down): the centres are outside B's box, within A's.
        let apart = Pose::from_translation(DVec3::new(0.0, 0.0, -40.0));
        let far = Teeth {
            teeth: tu.teeth.clone(),
            source: "upper.json".into(),
        };
        let lower_apart = Mesh {
            vertices: lower
                .vertices
                .iter()
                .map(|v| apart.transform_point(*v))
                .collect(),
            triangles: lower.triangles.clone(),
        };
        let m = message(check_pair(
            &upper,
            None,
            &lower_apart,
            Some(&far),
            &Pose::IDENTITY,
        ));
        assert!(m.contains("and within the other arch"), "{m}");
    }

    #[test]
    fn a_file_in_metres_for_a_mesh_in_mm_is_refused_naming_the_unit() {
        let (upper, lower) = shapes::arch_pair(1, 10);
        let (tu, _) = Teeth::of_arch_pair(10);
        for (factor, unit) in [
            (0.001, "in metres"),
            (0.1, "in centimetres"),
            (1.0 / 25.4, "in inches"),
        ] {
            let m = message(check_pair(
                &upper,
                Some(&tu.scaled(factor).unwrap()),
                &lower,
                None,
                &Pose::IDENTITY,
            ));
            assert!(m.contains(unit), "{factor}: {m}");
            assert!(m.contains("another patient"), "{m}");
        }
        // The mesh in metres, the teeth in mm.
        let metres = Mesh {
            vertices: upper.vertices.iter().map(|v| *v * 0.001).collect(),
            triangles: upper.triangles.clone(),
        };
        let m = message(tu.check_against(&ArchContext {
            arch: &metres,
            opposing: None,
            jaw: None,
        }));
        assert!(m.contains("the mesh is likely in metres"), "{m}");
        // Scaled with its mesh, it fits again.
        assert!(tu
            .scaled(0.001)
            .unwrap()
            .check_against(&ArchContext {
                arch: &metres,
                opposing: None,
                jaw: None,
            })
            .is_ok());
        // Another patient: same unit, shifted 30 mm.
        let moved = Teeth {
            teeth: tu
                .teeth
                .iter()
                .map(|t| super::super::Tooth {
                    number: t.number,
                    centre: t.centre + DVec3::new(0.0, 60.0, 0.0),
                })
                .collect(),
            source: "other.json".into(),
        };
        let m = message(moved.check_against(&ArchContext {
            arch: &upper,
            opposing: None,
            jaw: None,
        }));
        assert!(m.contains("in the arch's unit by their spread"), "{m}");
    }

    #[test]
    fn a_tooth_that_labels_nothing_is_a_warning_and_a_file_that_labels_nothing_an_error() {
        let (upper, _) = shapes::arch_pair(1, 10);
        let (tu, _) = Teeth::of_arch_pair(10);
        // One tooth in the hollow of the horseshoe: inside the box, 12 mm from every tooth.
        let mut extra = tu.clone();
        extra.teeth[0].centre = DVec3::new(0.0, 18.0, 2.0);
        let fit = extra
            .check_against(&ArchContext {
                arch: &upper,
                opposing: None,
                jaw: None,
            })
            .unwrap();
        assert_eq!(fit.vertices[0], 0);
        assert_eq!(fit.warnings.len(), 1, "{:?}", fit.warnings);
        assert!(
            fit.warnings[0].contains(&format!("tooth {} labels no vertex", tu.teeth[0].number)),
            "{:?}",
            fit.warnings
        );
        let mut none = tu.clone();
        none.teeth.truncate(2);
        none.teeth[0].centre = DVec3::new(-5.0, 17.0, 2.0);
        none.teeth[1].centre = DVec3::new(5.0, 17.0, 2.0);
        let m = message(none.check_against(&ArchContext {
            arch: &upper,
            opposing: None,
            jaw: None,
        }));
        assert!(m.contains("2 of its 2 crown centres"), "{m}");
        assert!(m.contains("label no vertex"), "{m}");
    }
}
