//! Negative tests of the tree checker `tree::check`: copies of a valid tree corrupted in one
//! known way each (a leaf poking out of the mesh, leaf centres outside it, overlapping leaves,
//! nodes that do not enclose their leaves, the tree of another mesh). Every field of each
//! report is compared with the amount of the corruption and with a brute-force reference, and
//! every invariant is exercised just inside and just beyond the tolerance, so that a checker
//! that ignores a condition, its tolerance or its counting fails here.

use innersphere::build::{build_tree, BuildOptions, Resolution};
use innersphere::glam::DVec3;
use innersphere::mesh::closest::point_triangle_distance_sq;
use innersphere::mesh::winding::exact_winding_number;
use innersphere::packing::PackingOptions;
use innersphere::progress::Silent;
use innersphere::tree::check::{check, max_leaf_overlap, CheckReport};
use innersphere::tree::{TreeMeta, NO_PARENT};
use innersphere::{shapes, Mesh, SphereTree};

/// Half extents of the box the test trees are built from: distances to it are analytic.
const HALF: DVec3 = DVec3::new(1.0, 0.6, 0.4);

fn box_mesh() -> Mesh {
    shapes::cuboid(HALF)
}

/// Distance from a point inside the box to its surface.
fn box_depth(p: DVec3) -> f64 {
    (HALF - p.abs()).min_element()
}

/// The tree of the box: 600 leaves, built in milliseconds.
fn box_tree() -> SphereTree {
    let opts = BuildOptions {
        resolution: Resolution::Cells(20),
        ..Default::default()
    };
    build_tree(&box_mesh(), &opts, &Silent).unwrap().0
}

/// The checker's tolerance as documented: 1e-6 of the mesh's bounding-box diagonal.
fn tolerance_of(mesh: &Mesh) -> f64 {
    let (lo, hi) = mesh.bbox();
    1e-6 * (hi - lo).length()
}

fn center(t: &SphereTree, n: usize) -> DVec3 {
    t.sphere(n).0.as_dvec3()
}

fn radius(t: &SphereTree, n: usize) -> f64 {
    t.r[n] as f64
}

fn set_sphere(t: &mut SphereTree, n: usize, c: DVec3, r: f64) {
    t.x[n] = c.x as f32;
    t.y[n] = c.y as f32;
    t.z[n] = c.z as f32;
    t.r[n] = r as f32;
}

fn ancestors(t: &SphereTree, n: usize) -> Vec<usize> {
    let mut out = Vec::new();
    let mut a = t.parent[n];
    while a != NO_PARENT {
        out.push(a as usize);
        a = t.parent[a as usize];
    }
    out
}

/// Grows every ancestor of `leaf` just enough (in f32, rounded up) to enclose it again.
fn enclose(t: &mut SphereTree, leaf: usize) {
    let (cl, rl) = (center(t, leaf), radius(t, leaf));
    for a in ancestors(t, leaf) {
        let need = (cl - center(t, a)).length() + rl;
        while (t.r[a] as f64) < need {
            t.r[a] = f32::from_bits(t.r[a].to_bits() + 1);
        }
    }
}

/// Shrinks every leaf except `keep` by `by` (not below 0). They stay inside the mesh and their
/// ancestors, at least `by` apart from each other and from a kept leaf that grew by less.
fn shrink_leaves_except(t: &mut SphereTree, keep: &[usize], by: f64) {
    for l in t.leaves().collect::<Vec<_>>() {
        if !keep.contains(&l) {
            t.r[l] = (radius(t, l) - by).max(0.0) as f32;
        }
    }
}

/// The leaf with the largest sphere (the first one packed), the smallest index on ties.
fn largest_leaf(t: &SphereTree) -> usize {
    t.leaves()
        .reduce(|a, b| if t.r[b] > t.r[a] { b } else { a })
        .unwrap()
}

/// The child of the root above `n`.
fn top_ancestor(t: &SphereTree, n: usize) -> usize {
    let mut n = n;
    while t.parent[n] != 0 {
        n = t.parent[n] as usize;
    }
    n
}

/// Overlap `r_a + r_b − |c_a − c_b|` of two nodes as stored.
fn overlap(t: &SphereTree, a: usize, b: usize) -> f64 {
    radius(t, a) + radius(t, b) - (center(t, a) - center(t, b)).length()
}

/// The report's fields recomputed by brute force with other code than the checker's: the
/// distance to every triangle, the exact winding number, all leaf pairs, and every inner node
/// against the leaves of its subtree (found through the children, not the parents).
#[derive(Debug)]
struct Reference {
    max_protrusion: f64,
    centers_outside: usize,
    max_overlap: f64,
    enclosure_violations: usize,
}

fn reference(t: &SphereTree, mesh: &Mesh) -> Reference {
    let tol = tolerance_of(mesh);
    let tris: Vec<[DVec3; 3]> = (0..mesh.triangles.len())
        .map(|i| mesh.triangle(i))
        .collect();
    let leaves: Vec<usize> = t.leaves().collect();
    let (mut max_protrusion, mut centers_outside) = (0.0f64, 0);
    for &l in &leaves {
        let c = center(t, l);
        let d = tris
            .iter()
            .map(|&[a, b, e]| point_triangle_distance_sq(c, a, b, e))
            .fold(f64::INFINITY, f64::min)
            .sqrt();
        let inside = exact_winding_number(mesh, c).abs() >= 0.5;
        centers_outside += usize::from(!inside);
        max_protrusion = max_protrusion.max(radius(t, l) - if inside { d } else { -d });
    }
    let mut max_overlap = 0.0f64;
    for (i, &a) in leaves.iter().enumerate() {
        for &b in &leaves[i + 1..] {
            max_overlap = max_overlap.max(overlap(t, a, b));
        }
    }
    let enclosure_violations = (0..t.len())
        .filter(|&n| !t.is_leaf(n))
        .filter(|&n| {
            let (cn, rn) = (center(t, n), radius(t, n));
            let mut stack = vec![n];
            let mut violated = false;
            while let Some(m) = stack.pop() {
                if t.is_leaf(m) {
                    violated |= (center(t, m) - cn).length() + radius(t, m) - rn > tol;
                }
                stack.extend(t.children(m));
            }
            violated
        })
        .count();
    Reference {
        max_protrusion,
        centers_outside,
        max_overlap,
        enclosure_violations,
    }
}

/// What a check must report.
#[derive(Debug, Clone, Copy)]
struct Want {
    ok: bool,
    max_protrusion: f64,
    centers_outside: usize,
    max_overlap: f64,
    enclosure_violations: usize,
}

/// Nothing wrong: every field zero.
const CLEAN: Want = Want {
    ok: true,
    max_protrusion: 0.0,
    centers_outside: 0,
    max_overlap: 0.0,
    enclosure_violations: 0,
};

/// Checks `t` against `mesh` and asserts every field of the report: against `want` (lengths
/// computed from the stored f32 spheres, so within 1e-12) and against the brute-force
/// reference. Returns the report.
fn assert_check(t: &SphereTree, mesh: &Mesh, want: Want, case: &str) -> CheckReport {
    let c = check(t, mesh).unwrap();
    let r = reference(t, mesh);
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-12;
    assert_eq!(c.ok, want.ok, "{case}: verdict; {c:?}");
    assert_eq!(c.spheres, t.leaf_count(), "{case}: spheres");
    assert_eq!(c.nodes, t.len(), "{case}: nodes");
    assert_eq!(
        c.tolerance.to_bits(),
        tolerance_of(mesh).to_bits(),
        "{case}: tolerance {}",
        c.tolerance
    );
    assert!(
        close(c.max_protrusion, want.max_protrusion),
        "{case}: max_protrusion {} want {}",
        c.max_protrusion,
        want.max_protrusion
    );
    assert!(
        close(c.max_protrusion, r.max_protrusion),
        "{case}: max_protrusion {} reference {r:?}",
        c.max_protrusion
    );
    assert_eq!(c.centers_outside, want.centers_outside, "{case}: centres");
    assert_eq!(c.centers_outside, r.centers_outside, "{case}: {r:?}");
    assert!(
        close(c.max_overlap, want.max_overlap),
        "{case}: max_overlap {} want {}",
        c.max_overlap,
        want.max_overlap
    );
    assert_eq!(
        c.enclosure_violations, want.enclosure_violations,
        "{case}: enclosure"
    );
    assert_eq!(
        c.enclosure_violations, r.enclosure_violations,
        "{case}: {r:?}"
    );
    // The overlap search relies on the hierarchy, so it is exact only on a tree whose nodes
    // enclose their leaves.
    if r.enclosure_violations == 0 {
        assert!(
            close(c.max_overlap, r.max_overlap),
            "{case}: max_overlap {} reference {r:?}",
            c.max_overlap
        );
    }
    c
}

#[test]
fn the_clean_tree_passes_with_every_field_zero() {
    let (mesh, t) = (box_mesh(), box_tree());
    assert!(
        t.leaf_count() > 300 && t.max_depth() >= 4,
        "{}",
        t.leaf_count()
    );
    let c = assert_check(&t, &mesh, CLEAN, "clean");
    assert_eq!(c.spheres, 600);
    // Sanity of the reference on an unchanged tree: leaves touch but never overlap.
    assert!(reference(&t, &mesh).max_overlap <= 0.0);
}

#[test]
fn a_leaf_poking_out_is_caught_by_its_protrusion() {
    let mesh = box_mesh();
    let tol = tolerance_of(&mesh);
    // Beyond the tolerance (clearly, and just) not ok; within it ok: only the protrusion
    // changes, the other leaves shrink away from the grown one and its ancestors grow.
    for (poke, ok) in [(0.01, false), (2.0 * tol, false), (0.5 * tol, true)] {
        let mut t = box_tree();
        let l = largest_leaf(&t);
        let c = center(&t, l);
        let grow = box_depth(c) + poke - radius(&t, l);
        assert!(grow > 0.0);
        set_sphere(&mut t, l, c, box_depth(c) + poke);
        shrink_leaves_except(&mut t, &[l], grow + 1e-3);
        enclose(&mut t, l);
        let got = radius(&t, l) - box_depth(center(&t, l));
        assert!((got - poke).abs() < 1e-7 && got > 0.0, "{got}");
        assert_check(
            &t,
            &mesh,
            Want {
                ok,
                max_protrusion: got,
                ..CLEAN
            },
            &format!("poke {poke:e}"),
        );
    }
}

#[test]
fn leaf_centres_outside_the_mesh_are_counted() {
    let mesh = box_mesh();
    let tol = tolerance_of(&mesh);

    // A point leaf just outside the +x face: its protrusion is within the tolerance, so only
    // the count of centres outside makes the verdict.
    let mut t = box_tree();
    shrink_leaves_except(&mut t, &[], 1e-3);
    let l = largest_leaf(&t);
    set_sphere(&mut t, l, DVec3::new(HALF.x + 0.25 * tol, 0.1, 0.05), 0.0);
    enclose(&mut t, l);
    let out = center(&t, l).x - HALF.x;
    assert!(out > 0.0 && out < tol, "{out}");
    assert_check(
        &t,
        &mesh,
        Want {
            ok: false,
            max_protrusion: out,
            centers_outside: 1,
            ..CLEAN
        },
        "one point leaf just outside",
    );

    // Two leaves wholly outside, 0.07 and 0.11 beyond the surface at their far side (either
    // way round): both counted, the larger protrusion reported.
    let t0 = box_tree();
    let leaves: Vec<usize> = t0.leaves().collect();
    let (first, last) = (leaves[3], leaves[leaves.len() - 3]);
    for (a, b) in [(first, last), (last, first)] {
        let mut t = t0.clone();
        shrink_leaves_except(&mut t, &[], 1e-3);
        set_sphere(&mut t, a, DVec3::new(HALF.x + 0.05, 0.0, 0.0), 0.02);
        set_sphere(&mut t, b, DVec3::new(-HALF.x - 0.1, 0.2, 0.0), 0.01);
        enclose(&mut t, a);
        enclose(&mut t, b);
        let want = radius(&t, b) - center(&t, b).x - HALF.x;
        assert!((want - 0.11).abs() < 1e-7);
        assert_check(
            &t,
            &mesh,
            Want {
                ok: false,
                max_protrusion: want,
                centers_outside: 2,
                ..CLEAN
            },
            &format!("leaves {a} and {b} outside"),
        );
    }
}

/// Moves leaf `b` inside leaf `a` so that they overlap by `ov`: `b` gets radius 0.45·ov and
/// lies 0.1·ov inside `a`'s sphere, so it touches no other leaf and stays inside the mesh;
/// its ancestors grow to enclose it. Returns the overlap as stored.
fn nest(t: &mut SphereTree, a: usize, b: usize, ov: f64) -> f64 {
    let (ca, ra) = (center(t, a), radius(t, a));
    let (rho, mu) = (0.45 * ov, 0.1 * ov);
    let u = DVec3::new(1.0, 2.0, 3.0).normalize();
    set_sphere(t, b, ca + u * (ra - rho - mu), rho);
    enclose(t, b);
    let got = overlap(t, a, b);
    assert!((got - ov).abs() < 1e-6 * ov.max(1.0), "{got} vs {ov}");
    assert!(
        (center(t, b) - ca).length() + radius(t, b) < ra,
        "not nested"
    );
    got
}

#[test]
fn overlapping_leaves_are_caught_by_their_overlap() {
    let mesh = box_mesh();
    let tol = tolerance_of(&mesh);
    let t0 = box_tree();
    let a = largest_leaf(&t0);
    // A sibling of `a` (found below their common parent) and a leaf below another child of
    // the root (found only by descending two different subtrees).
    let sibling = t0
        .children(t0.parent[a] as usize)
        .find(|&n| n != a && t0.is_leaf(n))
        .expect("the largest leaf has a leaf sibling");
    let far = t0
        .leaves()
        .filter(|&n| top_ancestor(&t0, n) != top_ancestor(&t0, a))
        .last()
        .unwrap();
    assert!(ancestors(&t0, far).len() >= 3);
    for (b, ov, ok) in [
        (sibling, 0.05, false),
        (far, 0.03, false),
        (far, 2.0 * tol, false),
        (sibling, 2.0 * tol, false),
        (far, 0.5 * tol, true),
    ] {
        let mut t = t0.clone();
        let got = nest(&mut t, a, b, ov);
        let c = assert_check(
            &t,
            &mesh,
            Want {
                ok,
                max_overlap: got,
                ..CLEAN
            },
            &format!("leaf {b} into {a} by {ov:e}"),
        );
        assert_eq!(max_leaf_overlap(&t), c.max_overlap);
    }
}

#[test]
fn nodes_that_do_not_enclose_their_leaves_are_counted() {
    let mesh = box_mesh();
    let tol = tolerance_of(&mesh);
    let t0 = box_tree();
    // Smallest radius the root needs to hold every leaf.
    let need = t0
        .leaves()
        .map(|l| (center(&t0, l) - center(&t0, 0)).length() + radius(&t0, l))
        .fold(0.0, f64::max);
    for (short, violations) in [(0.5 * tol, 0), (2.0 * tol, 1)] {
        let mut t = t0.clone();
        t.r[0] = (need - short) as f32;
        let miss = need - radius(&t, 0);
        assert!(miss > 0.0 && (miss - short).abs() < 1e-7, "{miss}");
        assert_check(
            &t,
            &mesh,
            Want {
                ok: violations == 0,
                enclosure_violations: violations,
                ..CLEAN
            },
            &format!("root short by {short:e}"),
        );
    }

    // Three nodes at three depths, each counted once however many leaves it misses: the
    // root, a node below it that is no parent of a leaf, and the parent of a deepest leaf.
    let deepest = t0.leaves().max_by_key(|&l| t0.depth[l]).unwrap();
    let parent = t0.parent[deepest] as usize;
    let middle = (1..t0.len())
        .find(|&n| t0.children(n).all(|c| !t0.is_leaf(c)) && t0.child_count[n] > 0)
        .unwrap();
    assert!(middle != parent && t0.depth[middle] > 0 && t0.depth[parent] > t0.depth[middle]);
    let mut t = t0.clone();
    for (n, violations) in [(0, 1), (middle, 2), (parent, 3)] {
        t.r[n] *= 0.5;
        assert_check(
            &t,
            &mesh,
            Want {
                ok: false,
                enclosure_violations: violations,
                ..CLEAN
            },
            &format!("{violations} nodes halved"),
        );
    }
}

#[test]
fn the_tree_of_another_mesh_fails() {
    let t = box_tree();
    // The box moved by 0.15 along x: the leaves touching its -x face poke out by 0.15, and
    // the centres of those nearest to it (0.1 inside) lie outside.
    let mut moved = box_mesh();
    for v in &mut moved.vertices {
        v.x += 0.15;
    }
    let r = reference(&t, &moved);
    assert!((r.max_protrusion - 0.15).abs() < 1e-6, "{r:?}");
    assert!(r.centers_outside > 0);
    assert_check(
        &t,
        &moved,
        Want {
            ok: false,
            max_protrusion: r.max_protrusion,
            centers_outside: r.centers_outside,
            ..CLEAN
        },
        "moved box",
    );
    // A unit sphere: the corners of the box (1.23 from its centre) are well outside it.
    let ball = shapes::icosphere(3);
    let r = reference(&t, &ball);
    assert!(r.max_protrusion > 0.1 && r.centers_outside > 10, "{r:?}");
    assert_check(
        &t,
        &ball,
        Want {
            ok: false,
            max_protrusion: r.max_protrusion,
            centers_outside: r.centers_outside,
            ..CLEAN
        },
        "unit sphere",
    );
}

#[test]
fn max_leaf_overlap_is_zero_on_disjoint_leaves_and_finds_an_overlap() {
    let t = box_tree();
    assert_eq!(max_leaf_overlap(&t), 0.0);
    let a = largest_leaf(&t);
    for b in [t.leaves().next().unwrap(), t.leaves().last().unwrap()] {
        let mut bad = t.clone();
        let ov = nest(&mut bad, a, b, 0.02);
        assert_eq!(max_leaf_overlap(&bad), ov, "leaf {b}");
        assert_eq!(reference(&bad, &box_mesh()).max_overlap, ov);
    }
    // Two overlapping pairs in different subtrees, either way round: the larger overlap.
    let a2 = t
        .leaves()
        .filter(|&n| top_ancestor(&t, n) != top_ancestor(&t, a))
        .reduce(|x, y| if t.r[y] > t.r[x] { y } else { x })
        .unwrap();
    let leaves: Vec<usize> = t.leaves().filter(|&n| n != a && n != a2).collect();
    let (b, b2) = (leaves[0], leaves[leaves.len() - 1]);
    for (ov, ov2) in [(0.02, 0.01), (0.01, 0.02)] {
        let mut bad = t.clone();
        let got = nest(&mut bad, a, b, ov);
        let got2 = nest(&mut bad, a2, b2, ov2);
        let want = got.max(got2);
        assert_eq!(max_leaf_overlap(&bad), want);
        assert_check(
            &bad,
            &box_mesh(),
            Want {
                ok: false,
                max_overlap: want,
                ..CLEAN
            },
            &format!("two overlaps {ov} and {ov2}"),
        );
    }
    // A tree of one leaf has no pair.
    let opts = BuildOptions {
        resolution: Resolution::Cells(20),
        packing: PackingOptions {
            max_spheres: 1,
            ..Default::default()
        },
        ..Default::default()
    };
    let (one, _) = build_tree(&box_mesh(), &opts, &Silent).unwrap();
    assert_eq!(one.len(), 1);
    assert_eq!(max_leaf_overlap(&one), 0.0);
    assert_check(&one, &box_mesh(), CLEAN, "one leaf");
}

fn meta() -> TreeMeta {
    TreeMeta::unmeasured(4, 0.1, [0.0; 3], [0.0; 3])
}

/// Nodes may miss their leaves by up to the tolerance, so two leaves can overlap by up to
/// twice the tolerance while their parents are disjoint: such an overlap beyond the tolerance
/// must still be found. Root 0 with children 1 and 2; leaf 3 below 1 and leaf 4 below 2, each
/// reaching 0.9·tol out of its parent towards the other leaf; the leaves overlap by 1.5·tol.
#[test]
fn an_overlap_hidden_by_enclosure_slack_is_found() {
    let mesh = box_mesh();
    let tol = tolerance_of(&mesh);
    let (rho, off) = (0.1, 0.05);
    let a = rho - 0.75 * tol;
    let mut t = SphereTree {
        x: vec![0.0; 5],
        y: vec![0.0; 5],
        z: vec![0.0; 5],
        r: vec![0.0; 5],
        first_child: vec![1, 3, 4, 0, 0],
        child_count: vec![2, 1, 1, 0, 0],
        parent: vec![NO_PARENT, 0, 0, 1, 2],
        depth: vec![0, 1, 1, 2, 2],
        meta: meta(),
    };
    set_sphere(&mut t, 0, DVec3::ZERO, 0.5);
    for (side, node, leaf) in [(-1.0, 1, 3), (1.0, 2, 4)] {
        set_sphere(&mut t, leaf, DVec3::X * side * a, rho);
        set_sphere(
            &mut t,
            node,
            DVec3::X * side * (a + off),
            rho + off - 0.9 * tol,
        );
        let miss =
            (center(&t, leaf) - center(&t, node)).length() + radius(&t, leaf) - radius(&t, node);
        assert!(miss > 0.8 * tol && miss < tol, "{miss}");
    }
    assert!(overlap(&t, 1, 2) < 0.0, "the parents are disjoint");
    let ov = overlap(&t, 3, 4);
    assert!(ov > 1.4 * tol && ov < 1.6 * tol, "{ov}");
    assert_check(
        &t,
        &mesh,
        Want {
            ok: false,
            max_overlap: ov,
            ..CLEAN
        },
        "overlap behind disjoint parents",
    );
}

#[test]
fn malformed_trees_and_meshes_are_errors() {
    let (mesh, t) = (box_mesh(), box_tree());
    // A child whose depth disagrees with its parent's, and a negative radius.
    let mut broken = t.clone();
    broken.depth[1] += 1;
    assert!(check(&broken, &mesh).is_err());
    let mut broken = t.clone();
    broken.r[t.len() - 1] = -1.0;
    assert!(check(&broken, &mesh).is_err());
    let mut bad_mesh = mesh.clone();
    bad_mesh.triangles[0][0] = 99;
    assert!(check(&t, &bad_mesh).is_err());
}

/// The overlap search descends the inner node of a pair even when the other side is a larger
/// leaf: a small inner node whose leaf pokes into a big leaf of another subtree.
#[test]
fn an_overlap_below_a_node_smaller_than_the_leaf_it_meets_is_found() {
    // Root (0) with children N (1, inner, small) and L (2, a big leaf); N holds leaves 3, 4.
    let spheres: [([f32; 3], f32); 5] = [
        ([0.2, 0.0, 0.0], 1.2),
        ([1.15, 0.0, 0.0], 0.2),
        ([0.0, 0.0, 0.0], 1.0),
        ([1.05, 0.0, 0.0], 0.1),
        ([1.25, 0.0, 0.0], 0.1),
    ];
    let t = SphereTree {
        x: spheres.iter().map(|s| s.0[0]).collect(),
        y: spheres.iter().map(|s| s.0[1]).collect(),
        z: spheres.iter().map(|s| s.0[2]).collect(),
        r: spheres.iter().map(|s| s.1).collect(),
        first_child: vec![1, 3, 0, 0, 0],
        child_count: vec![2, 2, 0, 0, 0],
        parent: vec![NO_PARENT, 0, 0, 1, 1],
        depth: vec![0, 1, 1, 2, 2],
        meta: meta(),
    };
    t.validate_structure().unwrap();
    // Leaf 3 reaches 1.05 − 0.1 = 0.95 < 1.0: it pokes 0.05 into L.
    let o = max_leaf_overlap(&t);
    assert!((o - 0.05).abs() < 1e-6, "{o}");
    // The same with the root's children in the other order (L first, then N): the pair
    // (leaf, inner node) must descend the inner node too.
    let order = [0, 2, 1, 3, 4];
    let swapped = SphereTree {
        x: order.iter().map(|&i| t.x[i]).collect(),
        y: order.iter().map(|&i| t.y[i]).collect(),
        z: order.iter().map(|&i| t.z[i]).collect(),
        r: order.iter().map(|&i| t.r[i]).collect(),
        first_child: vec![1, 0, 3, 0, 0],
        child_count: vec![2, 0, 2, 0, 0],
        parent: vec![NO_PARENT, 0, 0, 2, 2],
        depth: vec![0, 1, 1, 2, 2],
        meta: meta(),
    };
    swapped.validate_structure().unwrap();
    let o = max_leaf_overlap(&swapped);
    assert!((o - 0.05).abs() < 1e-6, "{o}");
}
