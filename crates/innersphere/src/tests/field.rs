//! The inside test, the winding number and the exact distance field.

use super::data as common;

use innersphere::field::distance::{compute, distance_of_points};
use innersphere::field::inside::{classify, inside_by_rays, inside_by_winding, is_oriented_closed};
use innersphere::field::{InsideMethod, VoxelGrid};
use innersphere::glam::DVec3;
use innersphere::mesh::bvh::TriangleBvh;
use innersphere::mesh::closest::point_triangle_distance_sq;
use innersphere::mesh::winding::{exact_winding_number, FastWinding};
use innersphere::progress::Silent;
use innersphere::Mesh;
use proptest::prelude::*;
use std::collections::HashSet;

// ---------------------------------------------------------------------------------------
// Mesh generators

/// Axis-aligned box `[lo, hi]`, outward facing, each face split into `n × n` quads of two
/// triangles (alternating diagonals).
fn box_mesh(lo: DVec3, hi: DVec3, n: usize) -> Mesh {
    let mut soup = Vec::new();
    // For each axis and side: a face spanned by the two other axes.
    for axis in 0..3 {
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        for side in [false, true] {
            let w = if side { hi[axis] } else { lo[axis] };
            let at = |a: usize, b: usize| {
                let mut p = DVec3::ZERO;
                p[axis] = w;
                p[u] = lo[u] + (hi[u] - lo[u]) * a as f64 / n as f64;
                p[v] = lo[v] + (hi[v] - lo[v]) * b as f64 / n as f64;
                p
            };
            for a in 0..n {
                for b in 0..n {
                    let (p00, p10, p11, p01) =
                        (at(a, b), at(a + 1, b), at(a + 1, b + 1), at(a, b + 1));
                    // (u, v, axis) is right-handed: counter-clockwise in (u, v) faces +axis.
                    let quad = if (a + b) % 2 == 0 {
                        [[p00, p10, p11], [p00, p11, p01]]
                    } else {
                        [[p00, p10, p01], [p10, p11, p01]]
                    };
                    for mut t in quad {
                        if !side {
                            t.swap(1, 2);
                        }
                        soup.push(t);
                    }
                }
            }
        }
    }
    Mesh::from_soup(&soup)
}

/// The octahedron `|x| + |y| + |z| = r`, each face subdivided `n` times (flat).
fn octahedron(r: f64, n: usize) -> Mesh {
    let mut soup = Vec::new();
    for sx in [-1.0, 1.0] {
        for sy in [-1.0, 1.0] {
            for sz in [-1.0, 1.0] {
                let ccw = sx * sy * sz > 0.0;
                // Barycentric (n − i − j, i, j) on (±x, ±y, ±z), computed per coordinate so
                // that shared edges give identical (welded) vertices.
                let pt = |i: usize, j: usize| {
                    let f = |k: usize| r * (k as f64 / n as f64);
                    DVec3::new(sx * f(n - i - j), sy * f(i), sz * f(j))
                };
                for i in 0..n {
                    for j in 0..n - i {
                        let mut tris = vec![[pt(i, j), pt(i + 1, j), pt(i, j + 1)]];
                        if i + j + 1 < n {
                            tris.push([pt(i + 1, j), pt(i + 1, j + 1), pt(i, j + 1)]);
                        }
                        for mut t in tris {
                            if !ccw {
                                t.swap(1, 2);
                            }
                            soup.push(t);
                        }
                    }
                }
            }
        }
    }
    Mesh::from_soup(&soup)
}

/// A polyhedral sphere: the subdivided octahedron pushed onto the sphere of radius `r`.
fn sphere(r: f64, n: usize) -> Mesh {
    let mut m = octahedron(1.0, n);
    for v in &mut m.vertices {
        *v = v.normalize() * r;
    }
    m
}

/// A torus around z with major radius `big`, tube radius `small`.
fn torus(big: f64, small: f64, nu: u32, nv: u32) -> Mesh {
    innersphere::shapes::torus(big, small, nu, nv)
}

fn flipped(m: &Mesh) -> Mesh {
    let mut m = m.clone();
    m.flip();
    m
}

/// A grid with cell centres at `origin + h·(i, j, k)`.
fn grid(origin: DVec3, h: f64, dims: [u32; 3]) -> VoxelGrid {
    VoxelGrid { origin, h, dims }
}

fn inside_set(g: &VoxelGrid, pred: impl Fn(DVec3) -> bool) -> Vec<u32> {
    (0..g.len())
        .filter(|&i| pred(g.center_of(i)))
        .map(|i| i as u32)
        .collect()
}

// ---------------------------------------------------------------------------------------
// Exact inside test on closed meshes

/// A box whose corners lie on grid columns and whose face diagonals pass through grid
/// columns: many rays run through edges and vertices. Under the perturbation
/// `(x + ε, y + ε²)` a ray on the plane `x = lo.x` is inside, one on `x = hi.x` is not.
#[test]
fn box_on_grid_columns_is_exact() {
    let lo = DVec3::new(2.0, 2.0, 1.5);
    let hi = DVec3::new(8.0, 10.0, 7.5);
    let g = grid(DVec3::ZERO, 1.0, [12, 13, 10]);
    let expect = inside_set(&g, |p| {
        p.x >= lo.x && p.x < hi.x && p.y >= lo.y && p.y < hi.y && p.z > lo.z && p.z < hi.z
    });
    assert!(!expect.is_empty());
    for n in [1, 2, 3] {
        let m = box_mesh(lo, hi, n);
        assert!(is_oriented_closed(&m));
        let (inside, method) = classify(&m, &g, &Silent).unwrap();
        assert_eq!(method, InsideMethod::ClosedExact);
        assert_eq!(inside, expect, "n = {n}");
        // Inward facing: the same cells (nonzero rule).
        let (inside, _) = classify(&flipped(&m), &g, &Silent).unwrap();
        assert_eq!(inside, expect, "flipped, n = {n}");
    }
}

/// The octahedron `|x|+|y|+|z| < 1` with its apexes and edges on grid columns.
#[test]
fn octahedron_through_vertices_and_edges_is_exact() {
    for (h, sub) in [(0.125, 1), (0.125, 2), (0.0625, 4), (0.25, 4)] {
        let m = octahedron(1.0, sub);
        let n = (2.0 / h) as u32 + 3;
        let o = -h * ((n / 2) as f64);
        let g = grid(DVec3::new(o, o, o + 0.5 * h), h, [n, n, n]);
        let expect = inside_set(&g, |p| p.x.abs() + p.y.abs() + p.z.abs() < 1.0);
        let (inside, method) = classify(&m, &g, &Silent).unwrap();
        assert_eq!(method, InsideMethod::ClosedExact);
        assert_eq!(inside, expect, "h = {h}, subdivisions {sub}");
        assert_eq!(inside_by_rays(&flipped(&m), &g, &Silent), expect);
    }
}

/// Compares with the exact O(n) winding-number sum (rounded), on every cell farther than
/// 1e-9 from the surface; returns how many cells were judged.
fn check_against_exact_winding(m: &Mesh, g: &VoxelGrid, inside: &[u32]) -> usize {
    let set: HashSet<u32> = inside.iter().copied().collect();
    let bvh = TriangleBvh::new(m);
    let mut judged = 0;
    for i in 0..g.len() {
        let p = g.center_of(i);
        if bvh.distance_sq(p) > 1e-18 {
            judged += 1;
            let w = exact_winding_number(m, p);
            assert!((w - w.round()).abs() < 1e-6, "{p}: winding number {w}");
            assert_eq!(
                set.contains(&(i as u32)),
                w.round() != 0.0,
                "cell {i} at {p}: {w}"
            );
        }
    }
    judged
}

/// A polyhedral sphere on an aligned and on a shifted grid (rays through its octahedral
/// vertices and edges in the first case).
#[test]
fn polyhedral_sphere_matches_exact_winding_number() {
    let m = sphere(1.0, 5);
    for (origin, h) in [
        (DVec3::new(-1.0, -1.0, -1.025), 0.05),
        (DVec3::new(-1.03, -0.98, -1.01), 0.04),
    ] {
        let n = (2.1 / h) as u32 + 1;
        let g = grid(origin, h, [n, n, n]);
        let (inside, method) = classify(&m, &g, &Silent).unwrap();
        assert_eq!(method, InsideMethod::ClosedExact);
        let judged = check_against_exact_winding(&m, &g, &inside);
        assert!(judged as f64 > 0.99 * g.len() as f64);
        assert!(inside.windows(2).all(|w| w[0] < w[1]));
        assert_eq!(inside_by_rays(&flipped(&m), &g, &Silent), inside);
    }
}

/// Torus (genus 1): inside iff inside the analytic torus, away from the faceted surface.
#[test]
fn torus_is_inside_the_analytic_torus() {
    let (big, small) = (1.0, 0.4);
    let m = torus(big, small, 96, 48);
    let g = VoxelGrid::with_resolution(DVec3::new(-1.4, -1.4, -0.4), DVec3::new(1.4, 1.4, 0.4), 70)
        .unwrap();
    let (inside, method) = classify(&m, &g, &Silent).unwrap();
    assert_eq!(method, InsideMethod::ClosedExact);
    let set: HashSet<u32> = inside.iter().copied().collect();
    for i in 0..g.len() {
        let p = g.center_of(i);
        let q = ((p.x * p.x + p.y * p.y).sqrt() - big).hypot(p.z) - small;
        // The facets lie within ~1e-3 of the analytic surface.
        if q.abs() > 3e-3 {
            assert_eq!(set.contains(&(i as u32)), q < 0.0, "{p}");
        }
    }
}

/// Overlapping shells and shells sharing an edge (closed but not manifold): the union.
#[test]
fn overlapping_and_touching_shells_give_the_union() {
    let a = box_mesh(DVec3::new(0.0, 0.0, 0.0), DVec3::new(4.0, 4.0, 4.0), 2);
    let b = box_mesh(DVec3::new(2.0, 2.0, 2.0), DVec3::new(6.0, 6.0, 6.0), 2);
    let c = box_mesh(DVec3::new(4.0, 4.0, 0.0), DVec3::new(6.0, 6.0, 2.0), 1); // shares an edge with a
    let mut m = a.clone();
    for other in [&b, &c] {
        let off = m.vertices.len() as u32;
        m.vertices.extend_from_slice(&other.vertices);
        m.triangles
            .extend(other.triangles.iter().map(|t| t.map(|i| i + off)));
    }
    assert!(is_oriented_closed(&m));
    let g = grid(DVec3::new(-0.5, -0.5, -0.25), 0.5, [14, 14, 14]);
    let inside_of = |p: DVec3, lo: DVec3, hi: DVec3| {
        // Perturbation: x and y boundaries are half-open, z never on a face.
        p.x >= lo.x && p.x < hi.x && p.y >= lo.y && p.y < hi.y && p.z > lo.z && p.z < hi.z
    };
    let expect = inside_set(&g, |p| {
        inside_of(p, DVec3::ZERO, DVec3::splat(4.0))
            || inside_of(p, DVec3::splat(2.0), DVec3::splat(6.0))
            || inside_of(p, DVec3::new(4.0, 4.0, 0.0), DVec3::new(6.0, 6.0, 2.0))
    });
    let (inside, method) = classify(&m, &g, &Silent).unwrap();
    assert_eq!(method, InsideMethod::ClosedExact);
    assert_eq!(inside, expect);
    assert_eq!(classify(&flipped(&m), &g, &Silent).unwrap().0, expect);
}

/// Degenerate triangles (zero area, repeated indices, duplicate faces in both directions) do
/// not disturb the exact test.
#[test]
fn degenerate_triangles_are_harmless() {
    let mut m = box_mesh(DVec3::splat(1.0), DVec3::splat(5.0), 2);
    let n = m.vertices.len() as u32;
    m.vertices.push(DVec3::new(3.0, 3.0, 3.0));
    m.vertices.push(DVec3::new(3.0, 3.0, 3.0)); // duplicate vertex
    m.triangles.push([n, n, n]);
    m.triangles.push([n, n + 1, 0]);
    m.triangles.push([n, 0, n + 1]);
    m.triangles.push([0, 1, 0]);
    m.triangles.push([0, 1, 2]);
    m.triangles.push([0, 2, 1]);
    assert!(is_oriented_closed(&m));
    let g = grid(DVec3::new(0.0, 0.0, 0.5), 1.0, [7, 7, 7]);
    let expect = inside_set(&g, |p| {
        p.x >= 1.0 && p.x < 5.0 && p.y >= 1.0 && p.y < 5.0 && p.z > 1.0 && p.z < 5.0
    });
    assert_eq!(classify(&m, &g, &Silent).unwrap().0, expect);
}

// ---------------------------------------------------------------------------------------
// Open meshes and soups: the winding number

/// The box without its top face: not closed, the winding number still finds the interior.
#[test]
fn open_box_uses_the_winding_number() {
    let m = box_mesh(DVec3::ZERO, DVec3::splat(4.0), 4);
    let keep: Vec<[u32; 3]> = (0..m.triangles.len())
        .filter(|&t| m.triangle(t).iter().any(|v| v.z < 4.0))
        .map(|t| m.triangles[t])
        .collect();
    let open = Mesh {
        vertices: m.vertices.clone(),
        triangles: keep,
    };
    assert!(open.triangles.len() < m.triangles.len());
    assert!(!is_oriented_closed(&open));
    let g = grid(DVec3::splat(-0.75), 0.5, [11, 11, 11]);
    let (inside, method) = classify(&open, &g, &Silent).unwrap();
    assert_eq!(method, InsideMethod::WindingNumber);
    let set: HashSet<u32> = inside.iter().copied().collect();
    for i in 0..g.len() {
        let p = g.center_of(i);
        let inner = p.cmpgt(DVec3::ZERO).all() && p.cmplt(DVec3::splat(4.0)).all();
        if inner && p.z < 3.0 {
            assert!(set.contains(&(i as u32)), "{p} should be inside");
        }
        if !inner {
            assert!(!set.contains(&(i as u32)), "{p} should be outside");
        }
    }
    // Inward facing: the same cells.
    assert_eq!(classify(&flipped(&open), &g, &Silent).unwrap().0, inside);
}

/// A soup of scattered triangles encloses nothing.
#[test]
fn triangle_soup_has_no_inside() {
    let mut s = 7u64;
    let mut rnd = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut soup = Vec::new();
    for _ in 0..200 {
        let c = DVec3::new(rnd(), rnd(), rnd()) * 10.0;
        let t = [
            c,
            c + DVec3::new(rnd(), rnd(), rnd()) * 0.5,
            c + DVec3::new(rnd(), rnd(), rnd()) * 0.5,
        ];
        soup.push(t);
    }
    let m = Mesh::from_soup(&soup);
    let (lo, hi) = m.bbox();
    let g = VoxelGrid::with_resolution(lo, hi, 40).unwrap();
    let (inside, method) = classify(&m, &g, &Silent).unwrap();
    assert_eq!(method, InsideMethod::WindingNumber);
    assert!(inside.is_empty(), "{} cells", inside.len());
}

/// On closed meshes both methods agree except next to the surface.
#[test]
fn winding_number_agrees_with_rays_on_closed_meshes() {
    for m in [sphere(1.0, 8), torus(1.0, 0.4, 64, 32)] {
        let (lo, hi) = m.bbox();
        let g = VoxelGrid::with_resolution(lo, hi, 48).unwrap();
        let a = inside_by_rays(&m, &g, &Silent);
        let b = inside_by_winding(&m, &g, &Silent);
        let bvh = TriangleBvh::new(&m);
        let a_set: HashSet<u32> = a.iter().copied().collect();
        let b_set: HashSet<u32> = b.iter().copied().collect();
        for &c in a_set.symmetric_difference(&b_set) {
            let d = bvh.distance_sq(g.center_of(c as usize)).sqrt();
            assert!(d < 1e-3 * g.h, "cell {c} differs at distance {d}");
        }
    }
}

#[test]
fn fast_winding_matches_the_exact_sum() {
    let meshes = [
        sphere(1.0, 6),
        torus(1.0, 0.4, 48, 24),
        box_mesh(DVec3::ZERO, DVec3::ONE, 3),
    ];
    let mut s = 99u64;
    let mut rnd = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 11) as f64 / (1u64 << 53) as f64 * 3.0 - 1.5
    };
    for m in &meshes {
        let fw = FastWinding::new(m);
        for _ in 0..300 {
            let p = DVec3::new(rnd(), rnd(), rnd());
            let (e, f) = (exact_winding_number(m, p), fw.winding_number(p));
            assert!((e - f).abs() < 1e-2, "{p}: exact {e}, fast {f}");
        }
    }
}

// ---------------------------------------------------------------------------------------
// Distances

fn brute_distance(tris: &[[DVec3; 3]], p: DVec3) -> f64 {
    tris.iter()
        .map(|t| point_triangle_distance_sq(p, t[0], t[1], t[2]))
        .fold(f64::INFINITY, f64::min)
        .sqrt()
}

#[test]
fn box_distance_field_is_exact() {
    let (lo, hi) = (DVec3::new(0.0, 0.0, 0.0), DVec3::new(3.0, 2.0, 1.5));
    let m = box_mesh(lo, hi, 3);
    let g = VoxelGrid::covering(lo, hi, 0.1).unwrap();
    let f = compute(&m, g, &Silent).unwrap();
    assert_eq!(f.method, InsideMethod::ClosedExact);
    assert_eq!(f.inside.len(), f.dist.len());
    assert!(!f.inside.is_empty());
    for (&c, &d) in f.inside.iter().zip(&f.dist) {
        let p = g.center_of(c as usize);
        let analytic = (p - lo).min(hi - p).min_element();
        assert!((d - analytic).abs() < 1e-12, "{p}: {d} vs {analytic}");
    }
    // Deterministic.
    let again = compute(&m, g, &Silent).unwrap();
    assert_eq!(again.inside, f.inside);
    assert!(again
        .dist
        .iter()
        .zip(&f.dist)
        .all(|(a, b)| a.to_bits() == b.to_bits()));
}

#[test]
fn sphere_distance_field_matches_brute_force() {
    let m = sphere(1.0, 5);
    let tris: Vec<[DVec3; 3]> = (0..m.triangles.len()).map(|t| m.triangle(t)).collect();
    let (lo, hi) = m.bbox();
    let g = VoxelGrid::with_resolution(lo, hi, 30).unwrap();
    let f = compute(&m, g, &Silent).unwrap();
    for (&c, &d) in f.inside.iter().zip(&f.dist) {
        let p = g.center_of(c as usize);
        assert_eq!(d, brute_distance(&tris, p));
        assert!(d <= 1.0 - p.length() + 1e-12);
    }
}

fn v3(r: f64) -> impl Strategy<Value = DVec3> {
    (-r..r, -r..r, -r..r).prop_map(|(x, y, z)| DVec3::new(x, y, z))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// Random small meshes (soups with shared corners) and random points: bit-identical to
    /// brute force, whatever the order of the points (the seeding never changes a result).
    #[test]
    fn distances_equal_brute_force(
        verts in prop::collection::vec(v3(1.0), 3..30),
        idx in prop::collection::vec((0usize..1000, 0usize..1000, 0usize..1000), 1..60),
        pts in prop::collection::vec(v3(1.5), 1..300),
    ) {
        let n = verts.len();
        let m = Mesh {
            vertices: verts.clone(),
            triangles: idx.iter().map(|&(a, b, c)| [(a % n) as u32, (b % n) as u32, (c % n) as u32]).collect(),
        };
        let tris: Vec<[DVec3; 3]> = (0..m.triangles.len()).map(|t| m.triangle(t)).collect();
        let bvh = TriangleBvh::new(&m);
        let d = distance_of_points(&bvh, &pts);
        for (p, d) in pts.iter().zip(&d) {
            prop_assert_eq!(*d, brute_distance(&tris, *p));
        }
        let rev: Vec<DVec3> = pts.iter().rev().copied().collect();
        let dr = distance_of_points(&bvh, &rev);
        prop_assert!(dr.iter().rev().zip(&d).all(|(a, b)| a.to_bits() == b.to_bits()));
    }

    /// Arbitrary small meshes (degenerate, duplicate, non-manifold, open or closed): no panic,
    /// sorted unique cells, finite non-negative distances, same answer twice.
    #[test]
    fn any_mesh_is_handled(
        verts in prop::collection::vec((0i32..5, 0i32..5, 0i32..5), 1..12),
        idx in prop::collection::vec((0usize..100, 0usize..100, 0usize..100), 1..40),
        mirror in any::<bool>(),
        res in 2u32..12,
    ) {
        let vertices: Vec<DVec3> = verts.iter().map(|&(x, y, z)| DVec3::new(x as f64, y as f64, z as f64) * 0.5).collect();
        let n = vertices.len();
        let mut triangles: Vec<[u32; 3]> = idx.iter().map(|&(a, b, c)| [(a % n) as u32, (b % n) as u32, (c % n) as u32]).collect();
        if mirror {
            // Every triangle in both orientations: closed in the directed-edge sense.
            let back: Vec<[u32; 3]> = triangles.iter().map(|t| [t[0], t[2], t[1]]).collect();
            triangles.extend(back);
        }
        let m = Mesh { vertices, triangles };
        let (lo, hi) = m.bbox();
        let Ok(g) = VoxelGrid::with_resolution(lo - 0.3, hi + 0.3, res) else {
            return Ok(());
        };
        let f = compute(&m, g, &Silent).unwrap();
        prop_assert!(f.inside.windows(2).all(|w| w[0] < w[1]));
        prop_assert!(f.inside.iter().all(|&c| (c as usize) < g.len()));
        prop_assert!(f.dist.iter().all(|d| d.is_finite() && *d >= 0.0));
        if mirror {
            prop_assert_eq!(f.method, InsideMethod::ClosedExact);
            prop_assert!(f.inside.is_empty(), "two-sided surfaces enclose nothing");
        }
        let again = compute(&m, g, &Silent).unwrap();
        prop_assert_eq!(again.inside, f.inside);
    }

    /// Random boxes on random grids: the exact test matches the half-open analytic box.
    #[test]
    fn random_boxes_on_random_grids(
        lo in (0i32..6, 0i32..6, 0i32..6),
        ext in (1i32..6, 1i32..6, 1i32..6),
        sub in 1usize..4,
        shift in (0i32..2, 0i32..2),
    ) {
        let h = 0.5;
        let lo = DVec3::new(lo.0 as f64, lo.1 as f64, lo.2 as f64 + 0.25) * h * 2.0;
        let hi = lo + DVec3::new(ext.0 as f64, ext.1 as f64, ext.2 as f64) * h * 2.0;
        let g = grid(DVec3::new(shift.0 as f64 * h * 0.5, shift.1 as f64 * h * 0.5, 0.0), h, [30, 30, 30]);
        let m = box_mesh(lo, hi, sub);
        let expect = inside_set(&g, |p| {
            p.x >= lo.x && p.x < hi.x && p.y >= lo.y && p.y < hi.y && p.z > lo.z && p.z < hi.z
        });
        prop_assert_eq!(classify(&m, &g, &Silent).unwrap().0, expect);
    }
}

// ---------------------------------------------------------------------------------------
// Real data (run with --ignored)

/// Reads a binary STL, optionally gzip-compressed (independent of the library's loader).
fn read_stl(path: &std::path::Path) -> Mesh {
    use std::io::Read;
    let raw = std::fs::read(path).unwrap();
    let bytes = if path.extension().is_some_and(|e| e == "gz") {
        let mut out = Vec::new();
        flate2::read::GzDecoder::new(&raw[..])
            .read_to_end(&mut out)
            .unwrap();
        out
    } else {
        raw
    };
    let n = u32::from_le_bytes(bytes[80..84].try_into().unwrap()) as usize;
    assert_eq!(
        bytes.len(),
        84 + 50 * n,
        "{}: not a binary STL",
        path.display()
    );
    let f = |o: usize| f32::from_le_bytes(bytes[o..o + 4].try_into().unwrap()) as f64;
    let soup: Vec<[DVec3; 3]> = (0..n)
        .map(|t| {
            let o = 84 + 50 * t + 12;
            [0, 1, 2].map(|v| DVec3::new(f(o + 12 * v), f(o + 12 * v + 4), f(o + 12 * v + 8)))
        })
        .collect();
    Mesh::from_soup(&soup)
}

fn secs(t: std::time::Instant) -> f64 {
    t.elapsed().as_secs_f64()
}

/// Cells of `a` xor `b` that are not on the surface (farther than `tol` from it).
fn off_surface_differences(
    m: &Mesh,
    g: &VoxelGrid,
    a: &[u32],
    b: &[u32],
    tol: f64,
) -> (usize, usize) {
    let a: HashSet<u32> = a.iter().copied().collect();
    let b: HashSet<u32> = b.iter().copied().collect();
    let bvh = TriangleBvh::new(m);
    let diff: Vec<u32> = a.symmetric_difference(&b).copied().collect();
    let off = diff
        .iter()
        .filter(|&&c| bvh.distance_sq(g.center_of(c as usize)) > tol * tol)
        .count();
    (diff.len(), off)
}

/// The winding number at every cell centre, one evaluation per cell (the reference for the
/// run-based evaluation).
fn winding_every_cell(m: &Mesh, g: &VoxelGrid) -> Vec<u32> {
    use rayon::prelude::*;
    let fw = FastWinding::new(m);
    (0..g.len() as u32)
        .into_par_iter()
        .filter(|&c| fw.winding_number(g.center_of(c as usize)).abs() >= 0.5)
        .collect()
}

#[test]
#[ignore = "real data: run with --ignored"]
fn closed_small_meshes_rays_agree_with_winding_number() {
    let names = [
        "small/cube_cgal.stl",
        "small/torus_trimesh.stl",
        "small/knot1_cgal.stl",
        "small/eight_genus2_cgal.stl",
        "small/elephant_cgal.stl",
        "small/femur_cgal.stl",
        "small/teapot_closed_rainbow.stl",
        "small/dragon_small_rainbow.stl",
        "classic/bunny_closed_cgal.stl",
        "jaw/ofj_p26_tooth30_lower_first_molar.stl",
    ];
    for name in names {
        let m = read_stl(&common::data(name));
        let (lo, hi) = m.bbox();
        let g = VoxelGrid::with_resolution(lo, hi, 96).unwrap();
        let t = std::time::Instant::now();
        let (rays, method) = classify(&m, &g, &Silent).unwrap();
        let t_rays = secs(t);
        let t = std::time::Instant::now();
        let wind = inside_by_winding(&m, &g, &Silent);
        let t_wind = secs(t);
        let (diff, off) = off_surface_differences(&m, &g, &rays, &wind, 1e-9 * (hi - lo).length());
        println!(
            "{name}: {method:?}, {} tris, grid {:?}, inside {} (rays {t_rays:.3} s) vs {} (winding {t_wind:.3} s): {diff} differ, {off} of them off the surface",
            m.triangles.len(),
            g.dims,
            rays.len(),
            wind.len()
        );
        assert_eq!(method, InsideMethod::ClosedExact, "{name}");
        assert!(!rays.is_empty());
        assert!(
            off * 10_000 <= rays.len(),
            "{name}: {off} cells off the surface differ"
        );
    }
}

#[test]
#[ignore = "real data: run with --ignored"]
fn bad_meshes_are_classified() {
    for (name, method, some_inside) in [
        (
            "bad/elephant_with_holes_cgal.stl",
            InsideMethod::WindingNumber,
            true,
        ),
        (
            "bad/chinese_dragon_10kv_small_hole_cgal.stl",
            InsideMethod::WindingNumber,
            true,
        ),
        (
            "bad/cube_open_two_faces_missing_cgal.stl",
            InsideMethod::WindingNumber,
            true,
        ),
        (
            "bad/tetrahedron_inward_cgal.stl",
            InsideMethod::ClosedExact,
            true,
        ),
        (
            "bad/triangle_soup_trimesh.stl",
            InsideMethod::WindingNumber,
            false,
        ),
    ] {
        let m = read_stl(&common::data(name));
        let (lo, hi) = m.bbox();
        let g = VoxelGrid::with_resolution(lo, hi, 128).unwrap();
        let t = std::time::Instant::now();
        let (inside, got) = classify(&m, &g, &Silent).unwrap();
        let t_classify = secs(t);
        print!(
            "{name}: {got:?}, {} tris, grid {:?} ({} cells), {} inside, {t_classify:.3} s",
            m.triangles.len(),
            g.dims,
            g.len(),
            inside.len(),
        );
        if got == InsideMethod::WindingNumber && some_inside {
            // The run-based evaluation agrees with evaluating every cell.
            let t = std::time::Instant::now();
            let every = winding_every_cell(&m, &g);
            let t_every = secs(t);
            let (d, off) =
                off_surface_differences(&m, &g, &inside, &every, 1e-9 * (hi - lo).length());
            println!(
                "; every cell: {} inside, {t_every:.3} s, {d} differ, {off} off the surface",
                every.len()
            );
            assert!(
                off * 10_000 <= every.len(),
                "{name}: {off} cells off the surface differ"
            );
        } else {
            println!();
        }
        assert_eq!(got, method, "{name}");
        assert_eq!(!inside.is_empty(), some_inside, "{name}");
    }
}

/// The lower jaw arch (440k triangles, 16 shells) at 0.15 mm, the size of a real build: the
/// inside set against the winding number and the distances against brute force, at cells
/// sampled over the whole grid, and the inside volume against the mesh's. (The speed of this
/// stage is measured by `ist bench build`, not here.)
#[test]
#[ignore = "real data: run with --ignored"]
fn jaw_arch_field_matches_independent_references() {
    let m = read_stl(&common::data("jaw/ofj_p26_mandible_teeth.stl.gz"));
    assert_eq!(m.triangles.len(), 440_232, "the data README's count");
    let (lo, hi) = m.bbox();
    let g = VoxelGrid::covering(lo, hi, 0.15).unwrap();
    assert!(is_oriented_closed(&m));
    let (inside, method) = classify(&m, &g, &Silent).unwrap();
    assert_eq!(method, InsideMethod::ClosedExact);
    let bvh = TriangleBvh::new(&m);
    let dist = innersphere::field::distance::distances_of_cells(&bvh, &g, &inside, &Silent);
    assert_eq!(dist.len(), inside.len());
    let vol = inside.len() as f64 * g.h.powi(3);
    assert!(
        (vol - m.signed_volume()).abs() < 0.05 * m.signed_volume(),
        "{vol} vs {}",
        m.signed_volume()
    );
    // Signs: a regular sample of all cells, inside exactly where the winding number says so
    // (cells on the surface, where both answers are right, excepted).
    let fw = FastWinding::new(&m);
    let (mut n_in, mut n_out) = (0, 0);
    for c in (0..g.len() as u32).step_by(997) {
        let p = g.center_of(c as usize);
        if bvh.distance_sq(p) < 1e-12 {
            continue;
        }
        let by_field = inside.binary_search(&c).is_ok();
        assert_eq!(
            by_field,
            fw.winding_number(p).abs() >= 0.5,
            "cell {c} at {p}: inside {by_field}"
        );
        if by_field {
            n_in += 1;
        } else {
            n_out += 1;
        }
    }
    assert!(n_in > 500 && n_out > 5000, "{n_in} inside, {n_out} outside");
    // Values: every distance positive, and at a regular sample of inside cells equal, bit for
    // bit, to the minimum over all triangles.
    assert!(dist.iter().all(|&d| d > 0.0 && d.is_finite()));
    let tris: Vec<[DVec3; 3]> = (0..m.triangles.len()).map(|t| m.triangle(t)).collect();
    for n in (0..inside.len()).step_by(inside.len() / 200 + 1) {
        assert_eq!(
            dist[n],
            brute_distance(&tris, g.center_of(inside[n] as usize))
        );
    }
}
