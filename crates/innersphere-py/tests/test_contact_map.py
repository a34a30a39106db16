"""The contact map: every vertex's signed gap to the other mesh, as `ist occlusion-map`
computes it (the same f64 numbers), with the sign of inside."""

import json

import numpy as np
import pytest

import innersphere
from helpers import box_mesh, icosphere, pose_text, write_obj


def read_gap_ply(path):
    """(positions (n, 3), gap (n,)) of a contact-map PLY."""
    data = open(path, "rb").read()
    h = data.index(b"end_header\n") + len(b"end_header\n")
    n = int([l for l in data[:h].decode().splitlines() if l.startswith("element vertex")][0].split()[2])
    rec = np.frombuffer(data, dtype=np.dtype([("p", "<f4", 3), ("gap", "<f4"), ("rgb", "u1", 3)]), count=n, offset=h)
    return rec["p"].astype(float), rec["gap"].astype(float)


def test_gaps_have_the_sign_of_inside_and_match_ist(tmp_path, ist):
    ball = icosphere(3)
    box = box_mesh()
    pose = [1.5, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0]
    ga, gb = innersphere.contact_map(box, ball, pose)
    assert ga.shape == (len(box[0]),) and gb.shape == (len(ball[0]),)
    # Ball vertices (centre 1.5 along x, radius 1) inside the box [-1, 1]³: those with x < 1.
    at = ball[0] + np.array(pose[:3])
    inside = at[:, 0] < 1.0 - 1e-6
    outside = at[:, 0] > 1.0 + 1e-6
    assert inside.any() and outside.any()
    assert np.all(gb[inside] < 0) and np.all(gb[outside] > 0)
    # On the face (within rounding) the sign is either, the gap 0 to rounding.
    assert np.all(np.abs(gb[~inside & ~outside]) < 1e-6)
    # Where the ball's vertex is inside, its gap is its depth below the face x = 1 (or the
    # other faces, farther here).
    assert np.allclose(-gb[inside], np.minimum(1.0 - at[inside, 0], 1.0 - np.abs(at[inside, 1:]).max(axis=1)), atol=1e-12)
    # The box corners at x = 1 lie inside the ball.
    corners_in = np.linalg.norm(box[0] - np.array(pose[:3]), axis=1) < 1.0
    assert np.all((ga < 0) == corners_in)
    # The same numbers as the CLI's (files; the PLY stores f32).
    write_obj(tmp_path / "box.obj", *box)
    write_obj(tmp_path / "ball.obj", *ball)
    fa, fb = innersphere.contact_map(tmp_path / "box.obj", tmp_path / "ball.obj", pose)
    out = ist.run("occlusion-map", tmp_path / "box.obj", tmp_path / "ball.obj", "--pose", pose_text(pose),
                  "--out-a", tmp_path / "a.ply", "--out-b", tmp_path / "b.ply", "--json")
    r = json.loads(out)
    assert r["a"]["min_gap"] == fa.min() and r["b"]["min_gap"] == fb.min()
    assert r["b"]["vertices_inside"] == int((fb < 0).sum())
    _, gap_b = read_gap_ply(tmp_path / "b.ply")
    assert np.array_equal(gap_b, fb.astype(np.float32).astype(float))
    # The loader welds nothing here: the same gaps as from the arrays, in some order.
    assert np.array_equal(np.sort(fb), np.sort(gb))


def test_bad_input_raises():
    ball = icosphere(1)
    with pytest.raises(ValueError):
        innersphere.contact_map(ball, ball, [float("nan"), 0, 0, 1, 0, 0, 0])
    with pytest.raises(ValueError):
        innersphere.contact_map(ball, 42)
    with pytest.raises(OSError):
        innersphere.contact_map("/nonexistent/mesh.stl", ball)
    with pytest.raises(ValueError):
        innersphere.contact_map((np.zeros((3, 3)), np.array([[0, 1, 5]])), ball)


def test_a_unit_converts_the_meshes_to_millimetres():
    """`unit="m"` reads metre arrays as the same meshes in mm: the gaps are the mm gaps."""
    ball = icosphere(3)
    box = box_mesh()
    pose = [1.5, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0]
    ga, gb = innersphere.contact_map(box, ball, pose)
    m = lambda mesh: (np.asarray(mesh[0]) * 1e-3, mesh[1])
    ga_m, gb_m = innersphere.contact_map(m(box), m(ball), pose, unit="m")
    assert np.allclose(ga_m, ga, atol=1e-9) and np.allclose(gb_m, gb, atol=1e-9)
    with pytest.raises(ValueError, match="mm, cm, m or in"):
        innersphere.contact_map(box, ball, pose, unit="furlong")
