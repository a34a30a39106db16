//! The wafer's guarantees, judged on the measurements of the mesh as written
//! ([`SplintReport`]): what the report states as facts is only what was checked here. A
//! wafer that fails one is not fit to print; the doors say which and exit non-zero.

use serde::Serialize;

use super::report::SplintReport;
use super::SplintOptions;

/// How far below the clearance a vertex may measure: the `f32` rounding of the written
/// coordinates (a few millionths of a millimetre) and the seating's own margin.
pub const CLEARANCE_TOLERANCE: f64 = 1e-3;
/// How far below the least thickness the plate may measure, in grid cells: the surface
/// rounds the rims of the perforations and of the outline within about a cell.
pub const THICKNESS_TOLERANCE_CELLS: f64 = 1.5;
/// The least share of each arch's occlusal surface the wafer must carry: below it, the
/// wafer does not hold the bite where the plan puts it (it rocks on what it carries).
pub const MIN_COVERAGE: f64 = 0.85;

/// One guarantee and whether the written wafer keeps it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Check {
    /// `solid`, `no_self_intersection`, `clearance_a`, `clearance_b`, `no_arch_inside`,
    /// `thickness`, `coverage` or `triangles`.
    pub name: &'static str,
    /// Kept.
    pub ok: bool,
    /// What was asked and what was measured, in words.
    pub detail: String,
}

/// Every guarantee of a wafer with `r`'s measurements made with `opts`.
pub fn judge(r: &SplintReport, opts: &SplintOptions) -> Vec<Check> {
    let clear = opts.clearance - CLEARANCE_TOLERANCE;
    let thick = opts.min_thickness - THICKNESS_TOLERANCE_CELLS * opts.voxel;
    vec![
        Check {
            name: "solid",
            ok: r.watertight && r.manifold && r.winding_consistent && r.bodies == 1 && r.volume > 0.0,
            detail: format!(
                "one closed, manifold, consistently wound body as read back from the file: {} bod{}, watertight {}, manifold {}, consistently wound {}",
                r.bodies,
                if r.bodies == 1 { "y" } else { "ies" },
                r.watertight,
                r.manifold,
                r.winding_consistent
            ),
        },
        Check {
            name: "no_self_intersection",
            ok: r.self_intersections == 0,
            detail: format!(
                "no two triangles meet away from a shared corner (exact): {} pair{} found",
                r.self_intersections,
                if r.self_intersections == 1 { "" } else { "s" }
            ),
        },
        Check {
            name: "clearance_a",
            ok: r.min_distance_a >= clear,
            detail: format!(
                "every vertex at least the clearance {} mm from arch A: the nearest is {:.4} mm",
                opts.clearance, r.min_distance_a
            ),
        },
        Check {
            name: "clearance_b",
            ok: r.min_distance_b >= clear,
            detail: format!(
                "every vertex at least the clearance {} mm from arch B: the nearest is {:.4} mm",
                opts.clearance, r.min_distance_b
            ),
        },
        Check {
            name: "no_arch_inside",
            ok: r.a_vertices_inside == 0 && r.b_vertices_inside == 0,
            detail: format!(
                "no arch vertex inside the wafer: {} of A, {} of B",
                r.a_vertices_inside, r.b_vertices_inside
            ),
        },
        Check {
            name: "thickness",
            ok: r.min_thickness >= thick,
            detail: format!(
                "the plate at least {} mm thick (less {THICKNESS_TOLERANCE_CELLS} grid cells at rounded rims): the thinnest is {:.3} mm",
                opts.min_thickness, r.min_thickness
            ),
        },
        Check {
            name: "coverage",
            ok: r.coverage_a >= MIN_COVERAGE && r.coverage_b >= MIN_COVERAGE,
            detail: format!(
                "at least {:.0} % of each arch's occlusal surface carried: A {:.1} %, B {:.1} %",
                100.0 * MIN_COVERAGE,
                100.0 * r.coverage_a,
                100.0 * r.coverage_b
            ),
        },
        Check {
            name: "triangles",
            ok: opts.max_triangles == 0 || r.triangles <= opts.max_triangles,
            detail: if opts.max_triangles == 0 {
                format!("{} triangles, as extracted (no cap asked)", r.triangles)
            } else {
                format!(
                    "at most {} triangles for the lab: {} (simplified from {} within {:.4} mm)",
                    opts.max_triangles, r.triangles, r.extracted_triangles, r.simplify_error
                )
            },
        },
    ]
}
