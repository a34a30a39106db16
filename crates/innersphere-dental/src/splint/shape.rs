//! The splint as a height field over the occlusal plane: per column of a [`ColumnGrid`] in
//! the pair's anatomical frame, the wafer spans `lower ≤ z ≤ upper`, inside a horseshoe
//! outline.
//!
//! - `upper` is the lower of A's imprint (the lowest point within `clearance` of A on the
//!   column: [`lowest_offset`], which also blocks A's undercuts along the insertion axis)
//!   and A's coverage cap (A's local cusp level plus `coverage`: how far the wafer climbs
//!   the crowns). `lower` likewise from B, mirrored.
//! - The outline is the set of columns where either arch reaches into the covered band,
//!   grown by `rim` and smoothed: the buccal and lingual walls follow the arch curve at
//!   `rim` from the teeth, with no user-picked curve.
//! - A column is kept where the outline holds and the wafer is at least `min_thickness`
//!   thick across its mid-surface; elsewhere the wafer is perforated (the arches come too
//!   close there to leave printable material between the imprints).

use glam::{DVec2, DVec3};

use super::inputs;
use super::raster::{self, Dims};
use super::SplintOptions;
use crate::anatomy::AnatomicalFrame;
use crate::columns::{lowest_offset, ColumnGrid};
use innersphere::error::{Error, Result};
use innersphere::mesh::Mesh;
use innersphere::pose::Pose;

/// Bytes per column of the height field: about twenty `f64` maps (imprints, cusp tips, caps,
/// outline, margins, heights) alive at once.
const COLUMN_BYTES: u64 = 20 * 8;

/// Radius (model units) of the neighbourhood within which a cusp tip is the lowest point of
/// the imprint: about half a molar's cusp spacing.
const CUSP_RADIUS: f64 = 1.5;
/// Radius (mm) of the neighbourhood of a cusp tip's fellow tips: about two molars and a
/// premolar, so that the bone behind the last molar (the retromolar pad, the tuberosity, up
/// to 2 cm along the arch) has the molars' cusps within it.
const CUSP_REACH: f64 = 25.0;
/// How far (mm) a cusp tip stands back from the foremost tip within [`CUSP_REACH`] at most:
/// the cusps of neighbouring crowns differ by a millimetre or two (canine against premolar,
/// the curve of Spee, an arch opened a few degrees about the hinge); bone or gum beside and
/// behind the crowns stands back further (4–10 mm).
const CUSP_BAND: f64 = 3.0;
/// Standard deviation (model units) of the smoothing of the occlusal surfaces through the
/// cusp tips (under the coverage caps).
const CAP_SIGMA: f64 = 1.5;
/// Standard deviation (model units) of the smoothing of the outline.
const OUTLINE_SIGMA: f64 = 0.5;

/// The imprints are laid this much beyond the clearance: surface nets puts a vertex at the
/// mean of its cell's edge crossings, a little inside a curved imprint, and with this margin
/// all but about one vertex in a thousand keep the clearance as extracted (the rest are
/// pushed out after).
pub const FIELD_MARGIN: f64 = 0.02;

/// The occlusal frame: x anterior, y left, z up (right-handed), in A's frame.
#[derive(Debug, Clone, Copy)]
pub struct OcclusalFrame {
    /// The unit axes x, y, z.
    pub axes: [DVec3; 3],
}

impl OcclusalFrame {
    /// From the pair's anatomical frame.
    pub fn of(f: &AnatomicalFrame) -> Self {
        OcclusalFrame {
            axes: [f.anterior, f.left, f.up],
        }
    }

    /// Coordinates of a point of A's frame.
    #[inline]
    pub fn coords(&self, p: DVec3) -> DVec3 {
        DVec3::new(
            p.dot(self.axes[0]),
            p.dot(self.axes[1]),
            p.dot(self.axes[2]),
        )
    }

    /// The point of A's frame with these coordinates.
    #[inline]
    pub fn point(&self, c: DVec3) -> DVec3 {
        self.axes[0] * c.x + self.axes[1] * c.y + self.axes[2] * c.z
    }
}

/// The wafer as a height field; see the [module docs](self).
#[derive(Debug, Clone)]
pub struct Shape {
    /// The occlusal frame the columns stand in.
    pub frame: OcclusalFrame,
    /// The columns.
    pub grid: ColumnGrid,
    /// Top of the wafer per column (A's imprint or cap).
    pub upper: Vec<f64>,
    /// Bottom of the wafer per column (B's imprint or cap).
    pub lower: Vec<f64>,
    /// A smooth surface between the caps (their mean): the extraction grid is sheared
    /// along z to follow it, which keeps the grid as thin as the wafer.
    pub mid: Vec<f64>,
    /// Signed horizontal margin per column: positive inside the outline and where the wafer
    /// is thick enough, negative outside or in a perforation (in model units, roughly the
    /// distance to that boundary).
    pub side: Vec<f64>,
    /// The kept columns: one 4-connected part.
    pub keep: Vec<bool>,
    /// A's imprint per column: the lowest point within the clearance (and
    /// [`FIELD_MARGIN`]) of A, infinite where the column misses A.
    pub a_low: Vec<f64>,
    /// B's imprint per column: the highest point within the clearance of B, minus infinity
    /// where the column misses B.
    pub b_high: Vec<f64>,
    /// How high the wafer climbs A per column (A's cusp level plus the coverage).
    pub cap_a: Vec<f64>,
    /// How low the wafer climbs B per column.
    pub cap_b: Vec<f64>,
    /// Area of the perforations: columns inside the outline that are too thin.
    pub perforated_area: f64,
    /// Area inside the outline.
    pub outline_area: f64,
    /// Parts of the outline dropped because they do not touch the main part.
    pub dropped_parts: usize,
}

/// The columns over both arches' triangles (in the occlusal frame), padded by the rim and the
/// outline's smoothing; refused at once when the least extraction grid any wafer needs on
/// them (as tall as both coverages and the plate) would pass the memory bound.
fn column_grid(
    tris_a: &[[DVec3; 3]],
    tris_b: &[[DVec3; 3]],
    o: &SplintOptions,
) -> Result<ColumnGrid> {
    let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
    for t in tris_a.iter().chain(tris_b) {
        for v in t {
            lo = lo.min(v.truncate());
            hi = hi.max(v.truncate());
        }
    }
    let h = o.voxel;
    let pad = o.rim + 3.0 * OUTLINE_SIGMA + 2.0 * h;
    let (lo, hi) = (lo - pad, hi + pad);
    let nx = ((hi.x - lo.x) / h).ceil() + 1.0;
    let ny = ((hi.y - lo.y) / h).ceil() + 1.0;
    // Before the columns' work: their maps, and the least extraction grid any wafer needs (as
    // tall as both coverages and the plate), so that a voxel far too fine is refused at once.
    let least_cells_per_column = (2.0 * o.coverage + o.min_thickness) / h + 6.0;
    let bytes = nx * ny * (COLUMN_BYTES as f64 + 8.0 * least_cells_per_column);
    if bytes.is_nan() || bytes > super::extract::MAX_SPLINT_BYTES as f64 {
        return Err(super::extract::too_fine(
            h,
            bytes.min(u64::MAX as f64) as u64,
            true,
        ));
    }
    Ok(ColumnGrid {
        origin: lo,
        h,
        dims: [nx as usize, ny as usize],
    })
}

/// An arch's cusp tips on the columns, from its imprint `low` (NaN elsewhere): the columns
/// where the imprint is lowest within CUSP_RADIUS, and within CUSP_BAND of the lowest within
/// CUSP_REACH (the flat bone or gum beside the crowns is a local lowest too, but it stands
/// back from the crowns).
fn cusp_tips(low: &[f64], dims: Dims, h: f64) -> Vec<f64> {
    let r = (CUSP_RADIUS / h).round() as usize;
    let reach = (CUSP_REACH / h).round() as usize;
    let wide = raster::min_filter(low, dims, reach);
    raster::min_filter(low, dims, r)
        .iter()
        .zip(low)
        .zip(&wide)
        .map(|((m, z), w)| {
            if z.is_finite() && z <= m && *z <= w + CUSP_BAND {
                *z
            } else {
                f64::NAN
            }
        })
        .collect()
}

/// The height field of the splint between `a` and `b` (B placed by `pose` in A's frame).
pub fn shape(a: &Mesh, b: &Mesh, pose: &Pose, o: &SplintOptions) -> Result<Shape> {
    let b_world: Vec<DVec3> = b
        .vertices
        .iter()
        .map(|v| pose.transform_point(*v))
        .collect();
    let anat = AnatomicalFrame::from_points(&a.vertices, &b_world)?;
    let frame = OcclusalFrame::of(&anat);
    inputs::check_arch("A", a.vertices.iter().map(|v| frame.coords(*v)))?;
    inputs::check_arch("B", b_world.iter().map(|v| frame.coords(*v)))?;
    inputs::check_directions(&a.vertices, &b_world, &anat)?;
    let tris_a: Vec<[DVec3; 3]> = a
        .triangles
        .iter()
        .map(|t| t.map(|i| frame.coords(a.vertices[i as usize])))
        .collect();
    // B mirrored along z: its highest offset point is minus the lowest of the mirror.
    let tris_b: Vec<[DVec3; 3]> = b
        .triangles
        .iter()
        .map(|t| {
            t.map(|i| {
                let c = frame.coords(b_world[i as usize]);
                DVec3::new(c.x, c.y, -c.z)
            })
        })
        .collect();
    let grid = column_grid(&tris_a, &tris_b, o)?;
    let h = grid.h;
    let dims: Dims = grid.dims;
    let c = o.clearance + FIELD_MARGIN;
    let a_low = lowest_offset(&tris_a, &grid, c);
    let b_high: Vec<f64> = lowest_offset(&tris_b, &grid, c)
        .into_iter()
        .map(|z| -z)
        .collect();
    inputs::check_facing(&a_low, &b_high, &grid, c)?;

    // Each arch's occlusal surface: a smooth surface through its cusp tips ([`cusp_tips`]),
    // carried over the columns without teeth.
    let cusps = |low: &[f64]| cusp_tips(low, dims, h);
    let tip_a: Vec<f64> = cusps(&a_low).into_iter().map(|z| z + c).collect();
    let neg_b: Vec<f64> = b_high.iter().map(|z| -z).collect();
    let tip_b: Vec<f64> = cusps(&neg_b).into_iter().map(|z| -(z + c)).collect();
    let tip_a = fill(&tip_a, dims, h)?;
    let tip_b = fill(&tip_b, dims, h)?;
    let cap_a: Vec<f64> = tip_a.iter().map(|z| z + o.coverage).collect();
    let cap_b: Vec<f64> = tip_b.iter().map(|z| z - o.coverage).collect();
    let upper: Vec<f64> = a_low.iter().zip(&cap_a).map(|(a, c)| a.min(*c)).collect();
    let lower: Vec<f64> = b_high.iter().zip(&cap_b).map(|(b, c)| b.max(*c)).collect();

    // The outline: the columns where an arch reaches into the covered band, grown by the rim.
    let core: Vec<bool> = (0..grid.len())
        .map(|k| a_low[k] + c < cap_a[k] || b_high[k] - c > cap_b[k])
        .collect();
    let dist = raster::distance_to(&core, dims);
    let margin: Vec<f64> = dist.iter().map(|d| o.rim - d * h).collect();
    let outline = raster::smooth_fill(&margin, dims, OUTLINE_SIGMA / h);

    // Thick enough across the mid-surface: vertical thickness ≥ t·√(1 + |∇m|²).
    let mid: Vec<f64> = cap_a
        .iter()
        .zip(&cap_b)
        .map(|(a, b)| 0.5 * (a + b))
        .collect();
    let [nx, ny] = dims;
    let mut side = vec![0.0; grid.len()];
    let mut perforated = 0usize;
    let mut within = 0usize;
    for j in 0..ny {
        for i in 0..nx {
            let k = i + nx * j;
            let gx = (mid[(i + 1).min(nx - 1) + nx * j] - mid[i.saturating_sub(1) + nx * j])
                / (h * ((i + 1).min(nx - 1) - i.saturating_sub(1)).max(1) as f64);
            let gy = (mid[i + nx * (j + 1).min(ny - 1)] - mid[i + nx * j.saturating_sub(1)])
                / (h * ((j + 1).min(ny - 1) - j.saturating_sub(1)).max(1) as f64);
            let need = o.min_thickness * (1.0 + gx * gx + gy * gy).sqrt();
            let thick = upper[k] - lower[k] - need;
            if outline[k] > 0.0 {
                within += 1;
                if thick <= 0.0 {
                    perforated += 1;
                }
            }
            side[k] = outline[k].min(thick);
        }
    }
    let mut inside: Vec<bool> = side.iter().map(|s| *s > 0.0).collect();
    remove_diagonals(&mut inside, dims);
    let (keep, parts) = raster::largest_part(&inside, dims);
    if parts == 0 {
        return Err(Error::InvalidMesh(
            "the arches leave no room for a splint at this pose (no column is both inside the arch outline and thick enough)".into(),
        ));
    }
    Ok(Shape {
        frame,
        grid,
        upper,
        lower,
        mid,
        side,
        keep,
        a_low,
        b_high,
        cap_a,
        cap_b,
        perforated_area: perforated as f64 * h * h,
        outline_area: within as f64 * h * h,
        dropped_parts: parts - 1,
    })
}

/// Smooths a map of heights known at some columns (the cusp tips) into a surface over all
/// columns: a normalized convolution whose kernel is a Gaussian of [`CAP_SIGMA`] plus a
/// fainter one (a fifth) four times wider, so that it reaches columns far from any tip and stays
/// continuous where the narrow one fades out; the median where neither reaches.
fn fill(v: &[f64], dims: Dims, h: f64) -> Result<Vec<f64>> {
    let mut known: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    if known.is_empty() {
        return Err(Error::InvalidMesh(
            "an arch has no surface over the other one: no splint can be made between them".into(),
        ));
    }
    known.sort_by(f64::total_cmp);
    let median = known[known.len() / 2];
    let (n1, d1) = raster::weighted(v, dims, CAP_SIGMA / h);
    let (n2, d2) = raster::weighted(v, dims, 4.0 * CAP_SIGMA / h);
    const FAINT: f64 = 0.2;
    Ok((0..v.len())
        .map(|k| {
            let den = d1[k] + FAINT * d2[k];
            if den > 1e-12 {
                (n1[k] + FAINT * n2[k]) / den
            } else {
                median
            }
        })
        .collect())
}

/// Clears the cells of 2×2 blocks whose set cells touch only diagonally, so that the kept
/// columns meet along edges (a diagonal touch would give the surface a non-manifold edge).
fn remove_diagonals(m: &mut [bool], dims: Dims) {
    let [nx, ny] = dims;
    loop {
        let mut changed = false;
        for j in 0..ny.saturating_sub(1) {
            for i in 0..nx.saturating_sub(1) {
                let k = [
                    i + nx * j,
                    i + 1 + nx * j,
                    i + nx * (j + 1),
                    i + 1 + nx * (j + 1),
                ];
                let v = k.map(|x| m[x]);
                if (v[0] && v[3] && !v[1] && !v[2]) || (v[1] && v[2] && !v[0] && !v[3]) {
                    for x in k {
                        m[x] = false;
                    }
                    changed = true;
                }
            }
        }
        if !changed {
            break;
        }
    }
}
