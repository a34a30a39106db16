"""The occlusal splint: a watertight, consistently wound single body by trimesh's own checks
(an independent tool), the same file and numbers as `ist splint`, and clear errors."""

import json
import os
import pathlib

import manifold3d
import numpy as np
import pytest
import trimesh

import innersphere
from helpers import icosphere, write_obj

DATA = os.environ.get("INNERSPHERE_DATA")


def arches():
    """The library's generated arch pair (8 molar-like teeth with roots per arch, mm), B
    lowered 4 mm from the interlocking bite: an open pair, as an intermediate wafer sees it."""
    a, b = innersphere.arch_pair(teeth=8)
    return a, (b[0] - np.array([0.0, 0.0, 4.0]), b[1])


def manifold(vertices, faces):
    """manifold3d's solid of a mesh (its own manifold check: status NoError)."""
    m = manifold3d.Manifold(manifold3d.Mesh(vert_properties=np.asarray(vertices, np.float32),
                                            tri_verts=np.asarray(faces, np.uint32)))
    assert m.status() == manifold3d.Error.NoError, m.status()
    return m


def check_solid(vertices, faces, report, arches=None):
    """One watertight, consistently wound body by trimesh; a manifold of the same volume by
    manifold3d; with `arches` (each (vertices, faces), closed, at their places), no overlap
    with either by manifold3d's exact intersection."""
    m = trimesh.Trimesh(vertices, faces, process=False)
    assert m.is_watertight and m.is_winding_consistent
    assert m.volume > 0 and abs(m.volume - report["volume"]) < 1e-6 * m.volume
    assert len(m.split(only_watertight=False)) == 1
    assert report["watertight"] and report["manifold"] and report["bodies"] == 1
    assert report["fit"], report["checks"]
    w = manifold(vertices, faces)
    assert abs(w.volume() - m.volume) < 1e-4 * m.volume
    for v, f in arches or []:
        assert (manifold(v, f) ^ w).volume() < 1e-9
    return m


def test_splint_between_generated_arches_is_one_solid_and_matches_ist(tmp_path, ist):
    a, b = arches()
    out = tmp_path / "py.stl"
    vertices, faces, report = innersphere.splint(a, b, voxel=0.15, out=out)
    check_solid(vertices, faces, report, arches=[a, b])
    assert report["min_distance_a"] >= 0.1 - 0.02 and report["min_distance_b"] >= 0.1 - 0.02
    assert report["a_vertices_inside"] == 0 and report["b_vertices_inside"] == 0
    assert report["coverage_a"] >= 0.85 and report["coverage_b"] >= 0.85
    # The STL on disk is the same solid, and trimesh reads it as one.
    check_solid(*(lambda m: (m.vertices, m.faces))(trimesh.load(out, process=True)), report)
    # `ist splint` on the same mesh files writes the same bytes and the same numbers (the
    # loader welds and orders vertices its own way, so the arrays above differ in rounding).
    write_obj(tmp_path / "a.obj", *a)
    write_obj(tmp_path / "b.obj", *b)
    _, _, same = innersphere.splint(tmp_path / "a.obj", tmp_path / "b.obj", voxel=0.15,
                                    out=tmp_path / "files.stl")
    cli = json.loads(ist.run("splint", tmp_path / "a.obj", tmp_path / "b.obj", "--voxel", "0.15",
                             "-o", tmp_path / "cli.stl", "--json"))
    assert (tmp_path / "cli.stl").read_bytes() == (tmp_path / "files.stl").read_bytes()
    for k in ("volume", "triangles", "min_thickness", "min_distance_a", "coverage_b", "opened"):
        assert cli[k] == same[k], k


def test_an_automatic_opening_is_the_clis(tmp_path, ist):
    a, b = arches()
    write_obj(tmp_path / "a.obj", *a)
    write_obj(tmp_path / "b.obj", *b)
    _, _, got = innersphere.splint(tmp_path / "a.obj", tmp_path / "b.obj", voxel=0.15, open="auto")
    cli = json.loads(ist.run("splint", tmp_path / "a.obj", tmp_path / "b.obj", "--voxel", "0.15",
                             "--open", "auto", "-o", tmp_path / "cli.stl", "--json"))
    for k in ("volume", "triangles", "opened", "coverage_b"):
        assert cli[k] == got[k], k


def test_bad_splint_options_are_value_errors():
    a, b = arches()
    with pytest.raises(ValueError, match="voxel size"):
        innersphere.splint(a, b, voxel=0.0)
    with pytest.raises(ValueError, match="auto"):
        innersphere.splint(a, b, open="sideways")
    with pytest.raises(ValueError, match="clearance"):
        innersphere.splint(a, b, clearance=float("nan"))


@pytest.mark.skipif(not DATA or not pathlib.Path(DATA or ".", "jaw").is_dir(),
                    reason="real data: set INNERSPHERE_DATA to ../shared/data")
def test_intermediate_splint_on_the_jaw_is_one_solid(tmp_path):
    jaw = pathlib.Path(DATA, "jaw")
    vertices, faces, report = innersphere.splint(
        jaw / "ofj_p26_maxilla_teeth.stl.gz", jaw / "ofj_p26_mandible_teeth.stl.gz", open=3.0,
        out=tmp_path / "splint.stl")
    check_solid(vertices, faces, report)
    assert report["opened"] == 3.0
    assert report["coverage_a"] >= 0.85 and report["coverage_b"] >= 0.85
    assert report["min_distance_a"] >= 0.08 and report["min_distance_b"] >= 0.08


def test_an_unfit_wafer_raises_unless_kept(tmp_path):
    """At a pose where the arches touch, no plate fits between the cusps: the wafer fails its
    coverage, raises, and is not written; keep_unfit returns it with fit false."""
    a, b = arches()
    touching = [0.0, 0.0, 4.0, 1.0, 0.0, 0.0, 0.0]
    out = tmp_path / "unfit.stl"
    with pytest.raises(ValueError, match="not fit to print"):
        innersphere.splint(a, b, touching, voxel=0.15, out=out)
    assert not out.exists()
    _, _, report = innersphere.splint(a, b, touching, voxel=0.15, out=out, keep_unfit=True)
    assert not report["fit"] and out.exists()
    assert any(not c["ok"] for c in report["checks"])


def test_arches_in_metres_need_their_unit():
    a, b = arches()
    m = lambda x: (x[0] * 1e-3, x[1])
    with pytest.raises(ValueError, match="--unit m"):
        innersphere.splint(m(a), m(b), voxel=0.15)
    _, _, report = innersphere.splint(m(a), m(b), voxel=0.15, unit="m")
    assert report["fit"]


def test_the_wafer_between_arches_with_bone_is_one_manifold_solid_that_covers_them():
    """Generated arches with their bone (each one closed surface of teeth and bone), opened
    3 mm: the wafer is fit, one watertight body by trimesh, a manifold by manifold3d that
    overlaps neither arch (exact intersection), and carries at least 85 % of each arch's
    occlusal surface."""
    a, b = innersphere.arch_pair(bone=True)
    vertices, faces, report = innersphere.splint(a, b, open=3.0, voxel=0.15)
    pose = report["pose"]
    q = np.array(pose[3:])
    R = trimesh.transformations.quaternion_matrix(q)[:3, :3]
    b_at = (np.asarray(b[0]) @ R.T + np.array(pose[:3]), b[1])
    check_solid(vertices, faces, report, arches=[a, b_at])
    assert report["a_vertices_inside"] == 0 and report["b_vertices_inside"] == 0
    assert report["coverage_a"] >= 0.85 and report["coverage_b"] >= 0.85
