//! The case file: which scans, their unit and role, the build preset, the bite, the contact
//! map and the wafers (JSON, versioned; docs/PLAN.md has the schema). Read with limits and
//! checked whole before any work starts, so that a typo costs a message, not a minute.

use crate::splint::{Opening, SplintOptions, MAX_CLOSING, MAX_OPENING};
use innersphere::build::Preset;
use innersphere::error::{Error, Result};
use innersphere::mesh::Unit;
use innersphere::pose::Pose;
use innersphere_haptic::ContactSource;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The case file version this library reads and writes.
pub const CASE_VERSION: u32 = 1;
/// The largest case file read (bytes): a case is a few hundred bytes of settings.
pub const MAX_CASE_BYTES: u64 = 1 << 20;
/// A case file as the core's bounded reader takes it ([`MAX_CASE_BYTES`]).
pub const CASE_INPUT: innersphere::input::TextInput = innersphere::input::TextInput {
    what: "case file (JSON)",
    max_bytes: MAX_CASE_BYTES,
};

/// The most wafers one case makes.
pub const MAX_SPLINTS: usize = 8;

/// A case: the plan of one patient's bite and wafers (see the module docs). Paths are as
/// written in the file; [`Case::resolve`] makes them relative to the file's folder.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Case {
    /// [`CASE_VERSION`].
    pub version: u32,
    /// The upper arch's mesh (A, fixed): .stl, .obj, .ply or .off, optionally .gz.
    pub upper: PathBuf,
    /// The lower arch's mesh (B, moved).
    pub lower: PathBuf,
    /// The unit of both mesh files (and of the teeth files): `mm`, `cm`, `m` or `in`;
    /// everything the plan gives is in mm.
    #[serde(default)]
    pub unit: Unit,
    /// How the arches' trees are built (default `jaw`: dental scans).
    #[serde(default = "default_preset", with = "preset_name")]
    pub preset: Preset,
    /// Teeth files of the arches (crown centres, as `ist occlusion-map` takes them): the
    /// contact map's table per tooth. Without them the table is per region of the arch.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub teeth_upper: Option<PathBuf>,
    /// The lower arch's teeth file (B's own frame).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub teeth_lower: Option<PathBuf>,
    /// How the bite is found.
    #[serde(default)]
    pub bite: BiteSpec,
    /// Whether to write the contact map (the two coloured PLYs and the table).
    #[serde(default = "yes")]
    pub contact_map: bool,
    /// The wafers to make at the bite, in order.
    #[serde(default)]
    pub splints: Vec<SplintSpec>,
}

fn default_preset() -> Preset {
    Preset::Jaw
}

fn yes() -> bool {
    true
}

/// The preset by its command-line name.
mod preset_name {
    use innersphere::build::Preset;
    use serde::{Deserialize, Deserializer, Serializer};

    pub fn serialize<S: Serializer>(p: &Preset, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(p.name())
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Preset, D::Error> {
        let name = String::deserialize(d)?;
        name.parse().map_err(serde::de::Error::custom)
    }
}

/// How the bite is found: closed with the joints, free from many starts, or given.
///
/// The default is the joints: a whole lower jaw has them, and they keep it from settling
/// in a rest that is not a bite (on generated arches set in bone blocks, the free search's
/// favourite rest was tilted 6° and 4 mm from the scanned bite; the joints' was 0.14 mm).
/// `free` is for a cut segment.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum BiteMethod {
    /// The lower jaw closed on its temporomandibular joints (held where they are in the
    /// scanned pose): `ist occlude`.
    #[default]
    Joints,
    /// A free segment closed from many starts around the start, the best bilateral rest
    /// chosen: `ist occlude --free`.
    Free,
    /// The bite is `pose`, as given (a registration made elsewhere).
    Pose,
}

/// The bite's settings.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BiteSpec {
    /// How it is found.
    #[serde(default)]
    pub method: BiteMethod,
    /// Where B starts, `[tx, ty, tz, qw, qx, qy, qz]` in A's frame (mm). Default: the
    /// scanned pose opened [`DEFAULT_START_OPENING`] mm along the pair's occlusal axis.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub from: Option<[f64; 7]>,
    /// With `pose`: the bite itself.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pose: Option<[f64; 7]>,
    /// Where the contact comes from: `spheres` or `mesh` (docs/OCCLUSION.md).
    #[serde(default, with = "contact_name")]
    pub contact: ContactSource,
    /// Free: closings in all.
    #[serde(default = "default_starts")]
    pub starts: usize,
    /// Free: the seed of the starts' spread.
    #[serde(default = "default_seed")]
    pub seed: u64,
}

/// How far the default start opens B from the scanned pose along the pair's occlusal axis
/// (mm): clear of the other arch, close enough to close in a second.
pub const DEFAULT_START_OPENING: f64 = 2.0;

fn default_starts() -> usize {
    crate::bite::BiteOptions::default().starts
}

fn default_seed() -> u64 {
    crate::bite::BiteOptions::default().seed
}

impl Default for BiteSpec {
    fn default() -> Self {
        BiteSpec {
            method: BiteMethod::default(),
            from: None,
            pose: None,
            contact: ContactSource::Spheres,
            starts: default_starts(),
            seed: default_seed(),
        }
    }
}

/// The contact source by its command-line name.
mod contact_name {
    use innersphere_haptic::ContactSource;
    use serde::{Deserialize, Deserializer, Serializer};

    pub fn serialize<S: Serializer>(c: &ContactSource, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(match c {
            ContactSource::Spheres => "spheres",
            ContactSource::Mesh => "mesh",
        })
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<ContactSource, D::Error> {
        let name = String::deserialize(d)?;
        name.parse().map_err(serde::de::Error::custom)
    }
}

/// How far a wafer opens B about the hinge at the incisors: `"auto"` (the final wafer: the
/// least opening that leaves room for it) or millimetres (an intermediate wafer's).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum OpenSpec {
    /// Millimetres at the incisors.
    By(f64),
    /// `"auto"`.
    Word(AutoWord),
}

/// The one word [`OpenSpec`] takes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum AutoWord {
    /// The least opening that leaves room for the wafer.
    Auto,
}

impl OpenSpec {
    /// The splint module's opening.
    pub fn opening(self) -> Opening {
        match self {
            OpenSpec::By(o) => Opening::By(o),
            OpenSpec::Word(AutoWord::Auto) => Opening::Auto,
        }
    }
}

/// One wafer: its name (the file's), opening and shape (the [`SplintOptions`], each
/// defaulting to `ist splint`'s).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SplintSpec {
    /// Its name: the output is `NAME.stl`; letters, digits, `-` and `_`, at most 64.
    pub name: SplintName,
    /// The opening.
    pub open: OpenSpec,
    /// Gap to each arch (mm).
    #[serde(default = "d_clearance")]
    pub clearance: f64,
    /// How far it climbs the crowns beyond the cusp tips (mm).
    #[serde(default = "d_coverage")]
    pub coverage: f64,
    /// Least thickness (mm).
    #[serde(default = "d_thickness")]
    pub min_thickness: f64,
    /// Walls beyond the teeth (mm).
    #[serde(default = "d_rim")]
    pub rim: f64,
    /// Grid spacing (mm).
    #[serde(default = "d_voxel")]
    pub voxel: f64,
    /// The most triangles it is written with (0: as extracted).
    #[serde(default = "d_max_triangles")]
    pub max_triangles: usize,
}

fn d_clearance() -> f64 {
    SplintOptions::default().clearance
}
fn d_coverage() -> f64 {
    SplintOptions::default().coverage
}
fn d_thickness() -> f64 {
    SplintOptions::default().min_thickness
}
fn d_rim() -> f64 {
    SplintOptions::default().rim
}
fn d_voxel() -> f64 {
    SplintOptions::default().voxel
}
fn d_max_triangles() -> usize {
    SplintOptions::default().max_triangles
}

impl SplintSpec {
    /// Its shape's options.
    pub fn options(&self) -> SplintOptions {
        SplintOptions {
            clearance: self.clearance,
            coverage: self.coverage,
            min_thickness: self.min_thickness,
            rim: self.rim,
            voxel: self.voxel,
            max_triangles: self.max_triangles,
        }
    }
}

/// A wafer's name, stored inline (a case is `Copy`-cheap to pass around): letters, digits,
/// `-` and `_`, 1 to 64 of them, so that `NAME.stl` is a file name on every system.
#[derive(Clone, Copy, PartialEq, Eq)]
pub struct SplintName {
    len: u8,
    bytes: [u8; 64],
}

impl SplintName {
    /// Checks `name`.
    pub fn new(name: &str) -> Result<SplintName> {
        let ok = !name.is_empty()
            && name.len() <= 64
            && name
                .bytes()
                .all(|c| c.is_ascii_alphanumeric() || c == b'-' || c == b'_');
        if !ok {
            return Err(Error::InvalidOption(format!(
                "a wafer's name must be 1 to 64 letters, digits, '-' or '_' (it names its file), got \"{name}\""
            )));
        }
        let mut bytes = [0u8; 64];
        bytes[..name.len()].copy_from_slice(name.as_bytes());
        Ok(SplintName {
            len: name.len() as u8,
            bytes,
        })
    }

    /// The name.
    pub fn as_str(&self) -> &str {
        std::str::from_utf8(&self.bytes[..self.len as usize]).unwrap_or("")
    }
}

impl std::fmt::Debug for SplintName {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{:?}", self.as_str())
    }
}

impl Serialize for SplintName {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        s.serialize_str(self.as_str())
    }
}

impl<'de> Deserialize<'de> for SplintName {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        let s = String::deserialize(d)?;
        SplintName::new(&s).map_err(serde::de::Error::custom)
    }
}

/// A pose from seven numbers, checked: finite, a non-zero rotation (normalised).
fn pose_of(what: &str, p: &[f64; 7]) -> Result<Pose> {
    Pose::from_array(*p).map_err(|e| {
        Error::InvalidOption(format!(
            "the bite's {what} must be seven finite numbers [tx, ty, tz, qw, qx, qy, qz] with a non-zero rotation, got {p:?}: {e}"
        ))
    })
}

impl Case {
    /// Parses and checks a case (see [`check`](Self::check)). Unknown keys are refused, so
    /// that a misspelt setting is not silently a default.
    pub fn from_json(text: &str) -> Result<Case> {
        let case: Case = serde_json::from_str(text)
            .map_err(|e| Error::InvalidOption(format!("the case file: {e}")))?;
        case.check()?;
        Ok(case)
    }

    /// Reads `path` (at most [`MAX_CASE_BYTES`]) and [`resolve`](Self::resolve)s its paths
    /// against its folder.
    pub fn load(path: &Path) -> Result<Case> {
        // The core's bounded text reader: a device, a FIFO or a binary file is refused at
        // its first chunk, a long file unread.
        let text = innersphere::input::read_text(path, CASE_INPUT)?;
        let case = Case::from_json(&text)
            .map_err(|e| Error::InvalidOption(format!("{}: {e}", path.display())))?;
        Ok(case.resolve(path.parent().unwrap_or(Path::new(""))))
    }

    /// The paths made relative to `dir` (the case file's folder) where they are relative.
    pub fn resolve(mut self, dir: &Path) -> Case {
        let fix = |p: &mut PathBuf| {
            if p.is_relative() {
                *p = dir.join(&*p);
            }
        };
        fix(&mut self.upper);
        fix(&mut self.lower);
        if let Some(p) = &mut self.teeth_upper {
            fix(p);
        }
        if let Some(p) = &mut self.teeth_lower {
            fix(p);
        }
        self
    }

    /// Refuses what cannot be planned, naming the setting: another version, a bite without
    /// its pose (or a pose where none is used), bad poses, wafers with the same name, too
    /// many, or settings outside `ist splint`'s limits.
    pub fn check(&self) -> Result<()> {
        if self.version != CASE_VERSION {
            return Err(Error::InvalidOption(format!(
                "case version {} is not read by this library (it reads version {CASE_VERSION})",
                self.version
            )));
        }
        let b = &self.bite;
        match (b.method, b.pose) {
            (BiteMethod::Pose, None) => {
                return Err(Error::InvalidOption(
                    "the bite's method is \"pose\" but it gives no \"pose\"".into(),
                ))
            }
            (BiteMethod::Joints | BiteMethod::Free, Some(_)) => {
                return Err(Error::InvalidOption(
                    "the bite gives a \"pose\" but its method finds one: use \"method\": \"pose\", or drop the pose".into(),
                ))
            }
            _ => {}
        }
        if let Some(p) = &b.from {
            pose_of("start (from)", p)?;
        }
        if let Some(p) = &b.pose {
            pose_of("pose", p)?;
        }
        let opts = crate::bite::BiteOptions {
            free: b.method == BiteMethod::Free,
            starts: b.starts,
            seed: b.seed,
            contact: b.contact,
            ..crate::bite::BiteOptions::default()
        };
        opts.validate()?;
        if self.splints.len() > MAX_SPLINTS {
            return Err(Error::InvalidOption(format!(
                "a case makes at most {MAX_SPLINTS} wafers, this one asks for {}",
                self.splints.len()
            )));
        }
        for (i, s) in self.splints.iter().enumerate() {
            let name = s.name.as_str();
            if self.splints[..i].iter().any(|t| t.name == s.name) {
                return Err(Error::InvalidOption(format!(
                    "two wafers are named \"{name}\" (each names its file)"
                )));
            }
            s.options()
                .validate()
                .map_err(|e| Error::InvalidOption(format!("wafer \"{name}\": {e}")))?;
            if let OpenSpec::By(o) = s.open {
                if !(o.is_finite() && (-MAX_CLOSING..=MAX_OPENING).contains(&o)) {
                    return Err(Error::InvalidOption(format!(
                        "wafer \"{name}\": \"open\" must be \"auto\" or millimetres within -{MAX_CLOSING} ..= {MAX_OPENING}, got {o}"
                    )));
                }
            }
        }
        Ok(())
    }

    /// The bite's start (`None`: the default, opened from the scanned pose) and given pose,
    /// checked.
    pub fn poses(&self) -> Result<(Option<Pose>, Option<Pose>)> {
        let from = self
            .bite
            .from
            .as_ref()
            .map(|p| pose_of("start (from)", p))
            .transpose()?;
        let pose = self
            .bite
            .pose
            .as_ref()
            .map(|p| pose_of("pose", p))
            .transpose()?;
        Ok((from, pose))
    }

    /// The case as JSON text (what a saved case holds; [`from_json`](Self::from_json) reads
    /// it back to the same case).
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).unwrap_or_default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_minimal_form_reads_with_its_defaults() {
        let c = Case::from_json(
            r#"{"version": 1, "upper": "maxilla.stl", "lower": "mandible.stl", "unit": "mm", "bite": {"method": "free"}, "splints": [{"name": "final", "open": "auto"}, {"name": "intermediate", "open": 3}]}"#,
        )
        .unwrap();
        assert_eq!(c.preset, Preset::Jaw);
        assert_eq!(c.bite.method, BiteMethod::Free);
        assert_eq!(c.splints.len(), 2);
        assert_eq!(c.splints[0].open.opening(), Opening::Auto);
        assert_eq!(c.splints[1].open.opening(), Opening::By(3.0));
        assert_eq!(c.splints[1].name.as_str(), "intermediate");
        assert!(c.contact_map);
        // Written and read back: the same case.
        assert_eq!(Case::from_json(&c.to_json()).unwrap(), c);
        let r = c.resolve(Path::new("/cases/p1"));
        assert_eq!(r.upper, Path::new("/cases/p1/maxilla.stl"));
    }

    #[test]
    fn mistakes_are_refused_with_the_setting_named() {
        let base =
            |extra: &str| format!(r#"{{"version": 1, "upper": "u.stl", "lower": "l.stl"{extra}}}"#);
        for (extra, says) in [
            (r#", "unit": "furlong""#, "expected one of `mm`"),
            (r#", "preset": "huge""#, "preset"),
            (r#", "splint": []"#, "unknown field"),
            (r#", "bite": {"method": "pose"}"#, "gives no \"pose\""),
            (
                r#", "bite": {"method": "free", "pose": [0,0,0,1,0,0,0]}"#,
                "drop the pose",
            ),
            (
                r#", "bite": {"from": [0,0,0,0,0,0,0]}"#,
                "non-zero rotation",
            ),
            (r#", "bite": {"method": "free", "starts": 0}"#, "starts"),
            (r#", "splints": [{"name": "a/b", "open": 1}]"#, "name"),
            (
                r#", "splints": [{"name": "w", "open": "wide"}]"#,
                "did not match",
            ),
            (r#", "splints": [{"name": "w", "open": 30}]"#, "open"),
            (
                r#", "splints": [{"name": "w", "open": 1}, {"name": "w", "open": 2}]"#,
                "two wafers",
            ),
            (
                r#", "splints": [{"name": "w", "open": 1, "clearance": -1}]"#,
                "clearance",
            ),
        ] {
            let e = Case::from_json(&base(extra)).unwrap_err().to_string();
            assert!(e.contains(says), "{extra}: {e}");
        }
        let e = Case::from_json(r#"{"version": 2, "upper": "u", "lower": "l"}"#)
            .unwrap_err()
            .to_string();
        assert!(e.contains("version 2"), "{e}");
    }
}
