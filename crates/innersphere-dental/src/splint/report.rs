//! What is measured on a finished splint: is it one printable solid, does it keep its
//! clearance, how much of each arch's occlusal surface it carries, how thin it gets.

use glam::DVec3;
use rayon::prelude::*;
use serde::Serialize;

use super::shape::Shape;
use super::SplintOptions;
use innersphere::mesh::bvh::TriangleBvh;
use innersphere::mesh::Mesh;
use innersphere::pose::Pose;

/// An arch's occlusal surface is the part the other arch sees along the insertion axis: over
/// the other arch, up to the coverage cap, and within this of the first surface a line along
/// the axis meets (the imprint), so that the crowns' steep sides and undercuts, which no
/// wafer inserted along the axis can carry, do not count. Defined whatever the gap between
/// the arches, so an open pair has one too.
pub const VISIBLE_TOLERANCE: f64 = 0.5;
/// A point of the occlusal surface is carried by the splint when the splint's surface is
/// within `clearance` plus this of it.
pub const CARRIED_TOLERANCE: f64 = 0.15;

/// The measurements of a splint (lengths in model units, millimetres for dental scans).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SplintReport {
    /// Enclosed volume.
    pub volume: f64,
    /// Number of triangles.
    pub triangles: usize,
    /// Number of vertices.
    pub vertices: usize,
    /// Connected components (1: one body).
    pub bodies: usize,
    /// Every edge is used by exactly two triangles.
    pub watertight: bool,
    /// Watertight, and every vertex's triangles form one fan (no pinched vertex).
    pub manifold: bool,
    /// Every edge is used once in each direction: the triangles are consistently wound.
    pub winding_consistent: bool,
    /// Thinnest plate: the least thickness along the insertion axis, from the vertices that
    /// face down (up) to the surface above (below).
    pub min_thickness: f64,
    /// The same, 1st percentile over the vertices.
    pub thickness_p01: f64,
    /// Least exact distance from a splint vertex to arch A.
    pub min_distance_a: f64,
    /// Least exact distance from a splint vertex to arch B.
    pub min_distance_b: f64,
    /// Vertices of arch A inside the splint (0 for a splint that seats).
    pub a_vertices_inside: usize,
    /// Vertices of arch B inside the splint.
    pub b_vertices_inside: usize,
    /// Share (by area) of A's occlusal surface ([`VISIBLE_TOLERANCE`]) within clearance +
    /// [`CARRIED_TOLERANCE`] of the splint.
    pub coverage_a: f64,
    /// The same for B.
    pub coverage_b: f64,
    /// Area of the perforations (where the arches leave less than the least thickness).
    pub perforated_area: f64,
    /// Parts of the outline that did not touch the main wafer and were left out.
    pub dropped_parts: usize,
    /// Specks of a few cells apart from the wafer, left out of the mesh.
    pub dropped_specks: usize,
    /// Vertices pushed out to the clearance after extraction (and after simplification).
    pub moved_vertices: usize,
    /// Triangles the surface had before it was simplified down to
    /// [`SplintOptions::max_triangles`] (equal to `triangles` when it was not).
    pub extracted_triangles: usize,
    /// The simplification's geometric error bound reached (model units; 0 when not
    /// simplified).
    pub simplify_error: f64,
    /// Pairs of triangles that meet away from a shared corner (exact; counted up to
    /// [`SELF_INTERSECTIONS_COUNTED`](super::SELF_INTERSECTIONS_COUNTED)): 0 for a wafer
    /// a slicer reads unambiguously.
    pub self_intersections: usize,
    /// Vertices moved apart by a few `f32` steps because they would have coincided in the
    /// file ([`written`](super::written)).
    pub separated_vertices: usize,
    /// Every guarantee kept ([`checks`](Self::checks)): the wafer is fit to print.
    pub fit: bool,
    /// The guarantees, each judged on these measurements ([`judge`](super::checks::judge)).
    pub checks: Vec<super::checks::Check>,
    /// How far B was opened about the hinge at the incisors before the splint was made
    /// ([`make_opened`](super::make_opened); 0 for [`make`](super::make)).
    pub opened: f64,
    /// The pose of B it was made at, `[tx, ty, tz, qw, qx, qy, qz]` in A's frame.
    pub pose: [f64; 7],
    /// The insertion axis (occlusal up, from B to A) in A's frame.
    pub insertion_axis: [f64; 3],
    /// The options it was made with.
    pub options: SplintOptions,
    /// Wall-clock seconds to make and measure it.
    pub seconds: f64,
    /// Seconds per stage: preparing the arches, the height field, the surface, seating,
    /// measuring.
    pub stage_seconds: [f64; 5],
}

/// Measures `mesh`, the splint between `a` and `b` (B at `pose`).
#[allow(clippy::too_many_arguments)]
pub fn report(
    mesh: &Mesh,
    a: &Mesh,
    bvh_a: &TriangleBvh,
    b: &Mesh,
    bvh_b: &TriangleBvh,
    pose: &Pose,
    opts: &SplintOptions,
    shape: &Shape,
) -> SplintReport {
    let r = mesh.report();
    let pinched = pinched_vertices(mesh);
    let inv = pose.inverse();
    // Only the nearest vertices matter: search within a bound, far beyond the clearance.
    let reach = (opts.clearance + 1.0).powi(2);
    let near = |t: &TriangleBvh, p: DVec3| {
        t.closest_point(p, reach)
            .map_or(f64::INFINITY, |c| c.dist_sq.sqrt())
    };
    let (min_a, min_b) = mesh
        .vertices
        .par_iter()
        .map(|v| (near(bvh_a, *v), near(bvh_b, inv.transform_point(*v))))
        .reduce(
            || (f64::INFINITY, f64::INFINITY),
            |x, y| (x.0.min(y.0), x.1.min(y.1)),
        );
    let splint_bvh = TriangleBvh::new(mesh);
    let b_world: Vec<DVec3> = b
        .vertices
        .iter()
        .map(|v| pose.transform_point(*v))
        .collect();
    let (lo, hi) = (DVec3::from_array(r.bbox_min), DVec3::from_array(r.bbox_max));
    // Inside by the parity of crossings along a direction off every axis.
    let ray = DVec3::new(0.3127, 0.2181, 0.9244).normalize();
    let inside = |pts: &[DVec3]| -> usize {
        pts.par_iter()
            .filter(|p| {
                p.cmpge(lo).all() && p.cmple(hi).all() && splint_bvh.crossings(**p, ray) % 2 == 1
            })
            .count()
    };
    let carried = opts.clearance + CARRIED_TOLERANCE;
    let coverage = |m: &Mesh, pts: &[DVec3], facing: &(dyn Fn(DVec3) -> bool + Sync)| -> f64 {
        let area = vertex_areas(m);
        // The distances in parallel, the sums in vertex order: a parallel reduction would
        // group the terms as the scheduling fell, and the last bits with them.
        let terms: Vec<(f64, f64)> = pts
            .par_iter()
            .zip(&area)
            .filter(|(p, _)| facing(**p))
            .map(|(p, w)| {
                let d = splint_bvh.distance_sq(*p).sqrt();
                (if d <= carried { *w } else { 0.0 }, *w)
            })
            .collect();
        let (num, den) = terms.iter().fold((0.0, 0.0), |x, y| (x.0 + y.0, x.1 + y.1));
        if den > 0.0 {
            num / den
        } else {
            0.0
        }
    };
    // The imprints are laid at the clearance plus the field's margin.
    let off = opts.clearance + super::shape::FIELD_MARGIN;
    let column = |p: DVec3| -> Option<(f64, usize)> {
        let c = shape.frame.coords(p);
        let g = &shape.grid;
        let i = ((c.x - g.origin.x) / g.h).round();
        let j = ((c.y - g.origin.y) / g.h).round();
        let inside = i >= 0.0 && j >= 0.0 && (i as usize) < g.dims[0] && (j as usize) < g.dims[1];
        inside.then(|| (c.z, g.index(i as usize, j as usize)))
    };
    let both = |k: usize| shape.a_low[k].is_finite() && shape.b_high[k].is_finite();
    let coverage_a = coverage(a, &a.vertices, &|p| {
        column(p).is_some_and(|(z, k)| {
            both(k) && z <= shape.a_low[k] + off + VISIBLE_TOLERANCE && z <= shape.cap_a[k]
        })
    });
    let coverage_b = coverage(b, &b_world, &|p| {
        column(p).is_some_and(|(z, k)| {
            both(k) && z >= shape.b_high[k] - off - VISIBLE_TOLERANCE && z >= shape.cap_b[k]
        })
    });
    let (min_thickness, thickness_p01) = thickness(mesh, &splint_bvh, shape.frame.axes[2]);
    let ia = inside(&a.vertices);
    let ib = inside(&b_world);
    SplintReport {
        volume: r.volume,
        triangles: r.triangles,
        vertices: r.vertices,
        bodies: r.components,
        watertight: r.watertight,
        manifold: r.watertight && pinched == 0,
        winding_consistent: r.winding_consistent,
        min_thickness,
        thickness_p01,
        min_distance_a: min_a,
        min_distance_b: min_b,
        a_vertices_inside: ia,
        b_vertices_inside: ib,
        coverage_a,
        coverage_b,
        perforated_area: shape.perforated_area,
        dropped_parts: shape.dropped_parts,
        opened: 0.0,
        pose: [0.0; 7],
        dropped_specks: 0,
        moved_vertices: 0,
        extracted_triangles: mesh.triangles.len(),
        simplify_error: 0.0,
        self_intersections: 0,
        separated_vertices: 0,
        fit: false,
        checks: Vec::new(),
        insertion_axis: shape.frame.axes[2].to_array(),
        options: *opts,
        seconds: 0.0,
        stage_seconds: [0.0; 5],
    }
}

/// A third of the area of the triangles around each vertex.
fn vertex_areas(m: &Mesh) -> Vec<f64> {
    let mut area = vec![0.0; m.vertices.len()];
    for t in 0..m.triangles.len() {
        let [p, q, r] = m.triangle(t);
        let a = (q - p).cross(r - p).length() / 6.0;
        for i in m.triangles[t] {
            area[i as usize] += a;
        }
    }
    area
}

/// The triangles around each vertex: those of vertex `v` are
/// `tris[start[v]..start[v + 1]]`, in mesh order.
fn triangles_around(m: &Mesh) -> (Vec<u32>, Vec<u32>) {
    let n = m.vertices.len();
    let mut start = vec![0u32; n + 1];
    for t in &m.triangles {
        for &v in t {
            start[v as usize + 1] += 1;
        }
    }
    for i in 0..n {
        start[i + 1] += start[i];
    }
    let mut fill = start.clone();
    let mut tris = vec![0u32; start[n] as usize];
    for (t, tri) in m.triangles.iter().enumerate() {
        for &v in tri {
            tris[fill[v as usize] as usize] = t as u32;
            fill[v as usize] += 1;
        }
    }
    (start, tris)
}

/// Vertices whose triangles do not form one fan: following the edges opposite a vertex
/// (`b → c` for each triangle `v, b, c`) does not visit them all in one cycle.
pub fn pinched_vertices(m: &Mesh) -> usize {
    let n = m.vertices.len();
    let (start, around) = triangles_around(m);
    // The edge opposite `v` in triangle `t`, in the triangle's direction.
    let opposite = |v: u32, t: u32| -> (u32, u32) {
        let tri = m.triangles[t as usize];
        let k = tri.iter().position(|&x| x == v).unwrap_or(0);
        (tri[(k + 1) % 3], tri[(k + 2) % 3])
    };
    (0..n)
        .into_par_iter()
        .filter(|&v| {
            let fan: Vec<(u32, u32)> = around[start[v] as usize..start[v + 1] as usize]
                .iter()
                .map(|&t| opposite(v as u32, t))
                .collect();
            if fan.is_empty() {
                return false;
            }
            // Walk b → c → ... from the first edge; a single cycle visits every edge.
            let mut at = fan[0].1;
            let mut steps = 1;
            while at != fan[0].0 && steps <= fan.len() {
                match fan.iter().find(|e| e.0 == at) {
                    Some(e) => at = e.1,
                    None => return true,
                }
                steps += 1;
            }
            steps != fan.len()
        })
        .count()
}

/// Thickness of the wafer along the insertion axis `up` ([`vertex_thickness`]): the least
/// and the 1st percentile.
fn thickness(m: &Mesh, bvh: &TriangleBvh, up: DVec3) -> (f64, f64) {
    let mut t: Vec<f64> = vertex_thickness(m, bvh, up)
        .into_iter()
        .map(|x| x.1)
        .collect();
    if t.is_empty() {
        return (0.0, 0.0);
    }
    t.sort_by(f64::total_cmp);
    (t[0], t[t.len() / 100])
}

/// Thickness of the wafer along the insertion axis `up`, per vertex that faces down (or up,
/// within 45°): the distance along `up` (or `-up`) to the surface across, past the
/// triangles around the vertex. This is the plate's thickness between the imprints that
/// `min_thickness` asks for; steep walls, whose thickness is across rather than along the
/// axis, are not measured. `bvh` is `m`'s.
pub(super) fn vertex_thickness(m: &Mesh, bvh: &TriangleBvh, up: DVec3) -> Vec<(u32, f64)> {
    // Measured from the vertices whose normal is within 45° of the axis.
    const FLAT: f64 = std::f64::consts::FRAC_1_SQRT_2;
    let n = m.vertices.len();
    let mut normal = vec![DVec3::ZERO; n];
    for t in 0..m.triangles.len() {
        let [p, q, r] = m.triangle(t);
        let nt = (q - p).cross(r - p);
        for i in m.triangles[t] {
            normal[i as usize] += nt;
        }
    }
    let (start, around) = triangles_around(m);
    (0..n)
        .into_par_iter()
        .filter_map(|v| {
            let facing = normal[v].normalize_or_zero().dot(up);
            let dir = if facing < -FLAT {
                up
            } else if facing > FLAT {
                -up
            } else {
                return None;
            };
            let own = &around[start[v] as usize..start[v + 1] as usize];
            bvh.first_hit(m.vertices[v], dir, 0.0, f64::INFINITY, |tri| {
                own.contains(&tri)
            })
            .map(|h| (v as u32, h.t))
        })
        .collect()
}
