//! Named build settings: [`Preset`], the constants they are made of, and
//! [`BuildOptions::preset`] / [`BuildOptions::recommended_for`], which turn a preset into
//! options for a given mesh.

use super::options::{BuildOptions, Resolution};
use crate::error::{Error, Result};
use crate::field::thick::ThickParts;
use crate::hierarchy::HierarchyOptions;
use crate::mesh::Mesh;
use crate::packing::PackingOptions;

/// Named build settings, each a function of the mesh ([`BuildOptions::preset`]).
///
/// Why a function of the mesh: the build cost and the accuracy of a tree follow the voxel
/// size *relative to the model* (cells along it) while an accuracy requirement is usually an
/// *absolute* length. The unit-free presets (`Fast`, `Default`, `Fine`) therefore scale the
/// voxel with the mesh's bounding box; the jaw presets fix it in millimetres, because that is
/// what their accuracy was calibrated for, and refuse a mesh whose size says it is not a
/// dental scan in millimetres (a jaw in metres would get a one-cell grid, one in micrometres
/// a grid too large to build).
///
/// What each costs and how accurate it is, measured: `BENCHMARKS.md` ("Build", "An arch
/// with its bone") and `docs/RESULTS.md` ("Calibration").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Preset {
    /// A quick look: 64 cells along the longest side of the bounding box, plain greedy
    /// packing (no minimum radius, no refinement); 8× fewer voxels than `Default`.
    Fast,
    /// [`BuildOptions::default`]: 128 cells along the longest side, plain greedy packing (the
    /// paper's).
    Default,
    /// The calibrated packing scaled to the mesh: voxel = longest side / 384 (the main trees
    /// of the paper's evaluation, `ist bench paper`), minimum radius half a voxel and 8
    /// off-grid refinement steps (the ratio and steps chosen in `docs/RESULTS.md`: about a
    /// quarter voxel of distance error with fewer spheres than the plain packing at the same
    /// error); 27× the voxels of `Default`. What [`BuildOptions::recommended_for`] returns.
    Fine,
    /// Jaw scans in **millimetres**, the accuracy-calibrated setting of `docs/RESULTS.md`:
    /// 0.1 mm voxels, 0.05 mm minimum radius, 8 refinement steps, chosen so that the sphere
    /// distance error stays within the 0.03 mm bar on the real arches (refined to the meshes
    /// by [`Pair::refined_distance`](crate::Pair::refined_distance), far below it). Thick
    /// parts (where a 12 mm ball fits: bone, `JAW_THICK_RADIUS_MM`) are packed from a
    /// 0.4 mm lattice with spheres of at least 0.2 mm, so an arch modelled with its bone
    /// builds at about its teeth's cost instead of its volume's.
    Jaw,
    /// Jaw scans in **millimetres**, the query benchmark's trees: 0.15 mm voxels, 0.05 mm
    /// minimum radius, 8 refinement steps. Faster to build than `Jaw` and with fewer
    /// spheres, but its distance error is above the 0.03 mm bar: for iterating and timing,
    /// not for the final trees.
    JawFast,
}

impl Preset {
    /// Every preset, in the order of [`Preset::name`]'s documentation.
    pub const ALL: [Preset; 5] = [
        Preset::Fast,
        Preset::Default,
        Preset::Fine,
        Preset::Jaw,
        Preset::JawFast,
    ];

    /// True for the presets made for dental scans in millimetres (`jaw`, `jaw-fast`): a mesh
    /// built with them is expected to be tooth- to skull-sized in mm
    /// ([`unit_warning`](crate::mesh::unit::unit_warning)).
    pub fn is_dental(self) -> bool {
        matches!(self, Preset::Jaw | Preset::JawFast)
    }

    /// The name used on the command line (`ist build --preset NAME`): `fast`, `default`,
    /// `fine`, `jaw`, `jaw-fast`.
    pub fn name(self) -> &'static str {
        match self {
            Preset::Fast => "fast",
            Preset::Default => "default",
            Preset::Fine => "fine",
            Preset::Jaw => "jaw",
            Preset::JawFast => "jaw-fast",
        }
    }
}

impl std::fmt::Display for Preset {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Preset {
    type Err = Error;
    fn from_str(s: &str) -> Result<Preset> {
        Preset::ALL
            .into_iter()
            .find(|p| p.name() == s)
            .ok_or_else(|| {
                let names: Vec<_> = Preset::ALL.iter().map(|p| p.name()).collect();
                Error::InvalidOption(format!(
                    "unknown preset \"{s}\" (expected one of {})",
                    names.join(", ")
                ))
            })
    }
}

/// Cells along the longest side of the bounding box for [`Preset::Fast`].
pub(crate) const FAST_CELLS: u32 = 64;
/// Voxel size of [`Preset::Fine`] = longest side of the bounding box / this.
pub(crate) const FINE_CELLS: u32 = 384;
/// Minimum radius of the calibrated packing as a fraction of the voxel size (0.05 mm at
/// 0.1 mm voxels in `docs/RESULTS.md`).
pub(crate) const CALIBRATED_MIN_RADIUS_PER_VOXEL: f64 = 0.5;
/// Off-grid refinement steps of the calibrated packing (`docs/RESULTS.md`: 16 steps gain
/// little over 8 for twice the packing time).
pub(crate) const CALIBRATED_REFINE_STEPS: u32 = 8;
/// The jaw presets' thick parts (millimetres): where a body holds a ball of this radius it is
/// bone, not tooth (the widest human molar crown is about 11.5 mm across, so no tooth holds a
/// 12 mm ball), and never within reach of the other arch's teeth: packed from a coarse lattice
/// ([`JAW_THICK_LATTICE_MM`], [`JAW_THICK_MIN_RADIUS_MM`]) so that an arch modelled with its
/// bone builds at the cost of its teeth and its surface, not of its volume.
pub(crate) const JAW_THICK_RADIUS_MM: f64 = 6.0;
/// How far (mm) the jaw presets' thick parts reach beyond their balls: into the bone's edges
/// and the creases too narrow for a 6 mm ball, and up to 2 mm onto the teeth standing in it.
/// What stays fine is every part thinner than 12 mm that stands more than 2 mm out of the
/// bone: the crowns, whose occlusal surfaces (the only ones within reach of the other arch)
/// stand 5–9 mm above the bone in a human jaw.
pub(crate) const JAW_THICK_MARGIN_MM: f64 = 2.0;
/// The spacing (mm) of the coarse lattice of voxels in thick parts, rounded to a whole number
/// of voxels: 4 voxels at the jaw preset's 0.1 mm (a 64th of the voxels).
pub(crate) const JAW_THICK_LATTICE_MM: f64 = 0.4;
/// The smallest sphere (mm) in thick parts: half the lattice spacing, the calibrated ratio of
/// minimum radius to voxel ([`CALIBRATED_MIN_RADIUS_PER_VOXEL`]).
pub(crate) const JAW_THICK_MIN_RADIUS_MM: f64 = 0.2;
/// Longest bounding-box sides (mm) the jaw presets accept: a single tooth crown to a skull.
/// Outside it the mesh is almost certainly not in millimetres.
pub(crate) const JAW_PRESET_SIZE_MM: std::ops::RangeInclusive<f64> = 1.0..=500.0;

/// Longest side of the mesh's bounding box, or an error for a mesh without extent.
fn longest_side(mesh: &Mesh) -> Result<f64> {
    let (lo, hi) = mesh.bbox();
    let longest = (hi - lo).max_element();
    if longest.is_finite() && longest > 0.0 {
        Ok(longest)
    } else {
        Err(Error::InvalidMesh(
            "the mesh has no extent (empty, a point, or non-finite coordinates)".into(),
        ))
    }
}

impl BuildOptions {
    /// The options of a named [`Preset`] for this mesh. Lengths are model units; the jaw
    /// presets require the mesh to be in millimetres and fail with
    /// [`Error::InvalidOption`] when its longest side lies outside
    /// `JAW_PRESET_SIZE_MM`. Fails with [`Error::InvalidMesh`] for a mesh without extent
    /// (the relative presets need its size). Change any field afterwards to override it
    /// (`ist build --preset` does that with the explicitly given flags).
    pub fn preset(preset: Preset, mesh: &Mesh) -> Result<BuildOptions> {
        let longest = longest_side(mesh)?;
        let calibrated = |voxel: f64, min_radius: f64| BuildOptions {
            resolution: Resolution::VoxelSize(voxel),
            packing: PackingOptions {
                min_radius,
                refine_steps: CALIBRATED_REFINE_STEPS,
                ..PackingOptions::default()
            },
            hierarchy: HierarchyOptions::default(),
            thick: None,
        };
        let jaw = |voxel_mm: f64, min_radius_mm: f64| {
            if JAW_PRESET_SIZE_MM.contains(&longest) {
                Ok(BuildOptions {
                    thick: Some(ThickParts {
                        radius: JAW_THICK_RADIUS_MM,
                        margin: JAW_THICK_MARGIN_MM,
                        stride: ((JAW_THICK_LATTICE_MM / voxel_mm).round() as u32).max(2),
                        min_radius: JAW_THICK_MIN_RADIUS_MM,
                    }),
                    ..calibrated(voxel_mm, min_radius_mm)
                })
            } else {
                Err(Error::InvalidOption(format!(
                    "preset {preset} is in millimetres, for dental scans {}–{} mm across; this mesh is {longest:.4} model units across (is the file in another unit? give it: --unit m, cm or in converts to mm; or use the unit-free presets fast, default or fine)",
                    JAW_PRESET_SIZE_MM.start(),
                    JAW_PRESET_SIZE_MM.end()
                )))
            }
        };
        match preset {
            Preset::Fast => Ok(BuildOptions {
                resolution: Resolution::Cells(FAST_CELLS),
                ..BuildOptions::default()
            }),
            Preset::Default => Ok(BuildOptions::default()),
            Preset::Fine => {
                let voxel = longest / FINE_CELLS as f64;
                Ok(calibrated(voxel, voxel * CALIBRATED_MIN_RADIUS_PER_VOXEL))
            }
            Preset::Jaw => jaw(0.1, 0.05),
            Preset::JawFast => jaw(0.15, 0.05),
        }
    }

    /// What this library recommends for a mesh of unknown unit: [`Preset::Fine`] (the
    /// calibrated packing at longest side / 384). For jaw scans in millimetres prefer
    /// [`Preset::Jaw`], whose absolute voxel size is what the 0.03 mm accuracy bar was met
    /// with; for a quick look [`Preset::Fast`]. Fails only for a mesh without extent.
    pub fn recommended_for(mesh: &Mesh) -> Result<BuildOptions> {
        BuildOptions::preset(Preset::Fine, mesh)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::build::validate_options;
    use crate::shapes;
    use glam::DVec3;

    /// `mesh` scaled by `s` about the origin.
    fn scaled(mesh: &Mesh, s: f64) -> Mesh {
        let mut m = mesh.clone();
        for v in &mut m.vertices {
            *v *= s;
        }
        m
    }

    fn voxel(o: &BuildOptions) -> f64 {
        match o.resolution {
            Resolution::VoxelSize(h) => h,
            Resolution::Cells(n) => panic!("expected a voxel size, got {n} cells"),
        }
    }

    #[test]
    fn presets_have_names_that_parse_back() {
        for p in Preset::ALL {
            assert_eq!(p.name().parse::<Preset>().unwrap(), p);
            assert_eq!(p.to_string(), p.name());
        }
        let err = "coarse".parse::<Preset>().unwrap_err().to_string();
        assert!(err.contains("unknown preset \"coarse\""), "{err}");
        assert!(err.contains("fast, default, fine, jaw, jaw-fast"), "{err}");
    }

    #[test]
    fn every_preset_gives_valid_options() {
        // A 17 mm molar: in range for the jaw presets too.
        let molar = shapes::molar(3, 0.0);
        for p in Preset::ALL {
            let o = BuildOptions::preset(p, &molar).unwrap();
            validate_options(&o).unwrap_or_else(|e| panic!("{p}: {e}"));
            assert_eq!(o.hierarchy.fanout, 4, "{p}");
            assert_eq!(o.packing.max_spheres, usize::MAX, "{p}");
        }
    }

    #[test]
    fn unit_free_presets_scale_with_the_mesh() {
        let ball = shapes::icosphere(2); // longest side 2
        let fast = BuildOptions::preset(Preset::Fast, &ball).unwrap();
        assert_eq!(fast.resolution, Resolution::Cells(FAST_CELLS));
        assert_eq!(fast.packing, PackingOptions::default());
        let default = BuildOptions::preset(Preset::Default, &ball).unwrap();
        assert_eq!(default.resolution, BuildOptions::default().resolution);
        assert_eq!(default.packing, BuildOptions::default().packing);

        let fine = BuildOptions::preset(Preset::Fine, &ball).unwrap();
        let (lo, hi) = ball.bbox();
        let h = (hi - lo).max_element() / 384.0;
        assert_eq!(voxel(&fine), h);
        assert_eq!(fine.packing.min_radius, h / 2.0);
        assert_eq!(fine.packing.refine_steps, 8);
        // The same shape in other units: every length scales, nothing else changes.
        for s in [1e-3, 1e3] {
            let big = BuildOptions::preset(Preset::Fine, &scaled(&ball, s)).unwrap();
            assert!((voxel(&big) / (h * s) - 1.0).abs() < 1e-12);
            assert!((big.packing.min_radius / (h * s / 2.0) - 1.0).abs() < 1e-12);
            assert_eq!(big.packing.refine_steps, 8);
        }
        let rec = BuildOptions::recommended_for(&ball).unwrap();
        assert_eq!(rec.resolution, fine.resolution);
        assert_eq!(rec.packing, fine.packing);
    }

    #[test]
    fn jaw_presets_are_absolute_millimetres_and_refuse_other_units() {
        let molar = shapes::molar(3, 0.0); // about 10 x 10 x 17 mm
        let jaw = BuildOptions::preset(Preset::Jaw, &molar).unwrap();
        assert_eq!(jaw.resolution, Resolution::VoxelSize(0.1));
        assert_eq!(jaw.packing.min_radius, 0.05);
        assert_eq!(jaw.packing.refine_steps, 8);
        let fast = BuildOptions::preset(Preset::JawFast, &molar).unwrap();
        assert_eq!(fast.resolution, Resolution::VoxelSize(0.15));
        assert_eq!(fast.packing.min_radius, 0.05);
        assert_eq!(fast.packing.refine_steps, 8);
        // The same numbers for a whole arch (a larger mesh): absolute, not relative.
        let arch = BuildOptions::preset(Preset::Jaw, &scaled(&molar, 4.0)).unwrap();
        assert_eq!(arch.resolution, Resolution::VoxelSize(0.1));
        // In metres or micrometres: refused, with the reason.
        for s in [1e-3, 1e3] {
            for p in [Preset::Jaw, Preset::JawFast] {
                let err = BuildOptions::preset(p, &scaled(&molar, s))
                    .unwrap_err()
                    .to_string();
                assert!(err.contains("millimetres"), "{err}");
                assert!(err.contains(&format!("preset {p}")), "{err}");
            }
        }
    }

    #[test]
    fn presets_need_a_mesh_with_extent() {
        let point = Mesh {
            vertices: vec![DVec3::ONE],
            triangles: vec![[0, 0, 0]],
        };
        for p in Preset::ALL {
            assert!(matches!(
                BuildOptions::preset(p, &point),
                Err(Error::InvalidMesh(_))
            ));
        }
        assert!(BuildOptions::recommended_for(&Mesh::default()).is_err());
    }
}
