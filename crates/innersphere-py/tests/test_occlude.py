"""The bite of a jaw pair (`innersphere.occlude`): the same answer as `ist occlude` bit for bit,
with the joints and free, the teeth brought together, a status that says how each closing
ended ("converged" only at rest in contact), and clear errors for what cannot bite."""

import json

import numpy as np
import pytest

import innersphere
from helpers import icosphere


def arch(dz, n=8):
    """A generated 'arch': n balls (radius 3.5 mm) along a parabolic horseshoe at height dz."""
    v, f = icosphere(2, 3.5)
    xs = np.linspace(-18.0, 18.0, n)
    centres = np.stack([xs, 30.0 - xs**2 / 15.0, np.full_like(xs, dz)], axis=1)
    verts = np.concatenate([v + c for c in centres])
    faces = np.concatenate([f + i * len(v) for i in range(len(centres))])
    return verts, faces


@pytest.fixture(scope="module")
def jaws(tmp_path_factory):
    """Upper arch A 8 mm above the lower B (1 mm between the crowns), as trees and files."""
    a = innersphere.Tree.build(arch(8.0), resolution=96)
    b = innersphere.Tree.build(arch(0.0), resolution=96)
    d = tmp_path_factory.mktemp("jaws")
    a.save(d / "a.ist")
    b.save(d / "b.ist")
    return a, b, d / "a.ist", d / "b.ist"


START = [0.0, 0.0, -0.5, 1.0, 0.0, 0.0, 0.0]


def cli(ist, pa, pb, *extra):
    out = json.loads(ist.run("occlude", pa, pb, "--from", " ".join(map(str, START)), "--json", *extra))
    for k in ("wall_seconds", "landmark_error_max", "landmark_errors"):
        out.pop(k)
    for c in out["candidates"] or []:
        c.pop("landmark_error_max")
    return out


def test_the_bite_equals_ist_occlude_with_the_joints(jaws, ist):
    a, b, pa, pb = jaws
    got = innersphere.occlude(a, b, START)
    assert got == cli(ist, pa, pb)
    # Closed: from 1.5 mm apart, B turned about its joints until the crowns touch, at rest.
    assert got["status"] == "converged" and got["converged"]
    assert got["volume"] > 0 and got["candidates"] is None and got["closings"] is None
    pair = innersphere.Pair(a, b)
    assert pair.distance(START).distance > 1.4
    assert pair.penetration(got["pose"]).volume > 0
    assert np.dot(got["frame"]["up"], [0, 0, 1]) > 0.99
    assert got["joints"]["stiffness"] == 20.0 and got["contact_stiffness"] == 10.0
    # JSON integers stay ints (`==` above takes 3 == 3.0).
    assert type(got["steps"]) is int and type(got["converged"]) is bool


def test_the_free_bite_equals_ist_occlude_free(jaws, ist):
    a, b, pa, pb = jaws
    got = innersphere.occlude(a, b, START, free=True, starts=6, spread=1.0, seed=3)
    assert got == cli(ist, pa, pb, "--free", "--starts", 6, "--spread", 1.0, "--seed", 3)
    assert got["joints"] is None and got["contact_stiffness"] == 1000.0
    assert 1 <= len(got["candidates"]) <= 6 and got["candidates"][0]["pose"] == got["pose"]
    # Every start accounted for, by status; the candidates are the converged ones.
    assert got["status"] == "converged"
    assert set(got["closings"]) == {"converged", "no_contact", "time_limit", "passed_through", "escaped"}
    assert sum(got["closings"].values()) == 6
    assert sum(c["starts"] for c in got["candidates"]) == got["closings"]["converged"]


def test_a_closing_out_of_time_says_so(jaws):
    a, b, _, _ = jaws
    got = innersphere.occlude(a, b, START, max_seconds=0.05)
    assert got["status"] == "time_limit" and not got["converged"] and got["steps"] == 50
    # Still open: the exact gap between the spheres is more than the 0.25 mm it closed.
    assert innersphere.Pair(a, b).distance(got["pose"]).distance > 1.0


def test_what_cannot_bite_is_refused_with_the_limit_named(jaws):
    a, b, _, _ = jaws
    for kw, want in [
        (dict(force=0.001), "0.5 to 1000 N"),
        (dict(force=2000.0), "0.5 to 1000 N"),
        (dict(force=100.0), "2 mm³"),
        (dict(contact_stiffness=1e300), "at most 100000 N/mm³"),
        (dict(free=True, spread=1000.0), "at most 10 mm"),
        (dict(free=True, starts=5000), "1 to 1000"),
    ]:
        with pytest.raises(ValueError, match=want):
            innersphere.occlude(a, b, START, **kw)
    # An arch against its own copy: they do not face each other.
    for free in (False, True):
        with pytest.raises(ValueError, match="do not face each other"):
            innersphere.occlude(a, a, START, free=free, starts=2)
    # A start far open, beside A, beyond it.
    for start, want in [
        ([0, 0, -1e15, 1, 0, 0, 0], "at most 30 mm open"),
        ([60, 0, -1, 1, 0, 0, 0], "side by side"),
        ([0, 0, 20, 1, 0, 0, 0], "beyond A's"),
    ]:
        with pytest.raises(ValueError, match=want):
            innersphere.occlude(a, b, start)


def test_bad_options_are_value_errors(jaws):
    a, b, _, _ = jaws
    for kw in [
        dict(force=-1.0),
        dict(axis=[0.0, 0.0, 0.0]),
        dict(max_seconds=1e300),
        dict(joint_stiffness=float("nan")),
        dict(free=True, starts=0),
        dict(free=True, spread=float("inf")),
        dict(reference=[0, 0, float("nan"), 1, 0, 0, 0]),
    ]:
        with pytest.raises(ValueError):
            innersphere.occlude(a, b, START, **kw)
    with pytest.raises(ValueError, match="from_pose"):
        innersphere.occlude(a, b, [0, 0, 0, 0, 0, 0, 0])


def test_the_bite_on_the_meshes_equals_ist_occlude_contact_mesh(jaws, ist, tmp_path):
    """contact="mesh": the same answer as `ist occlude --contact mesh`, resting on the meshes'
    own overlap (carrying part of the 5 N closing force, the joints the rest: at most
    5 N / 10 N/mm³); refused without the meshes."""
    from helpers import write_obj

    a, b, pa, pb = jaws
    ma, mb = tmp_path / "a.obj", tmp_path / "b.obj"
    write_obj(ma, *arch(8.0))
    write_obj(mb, *arch(0.0))
    with pytest.raises(ValueError, match="meshes"):
        innersphere.occlude(a, b, START, contact="mesh")
    with pytest.raises(ValueError, match="spheres"):
        innersphere.occlude(a, b, START, contact="voxels")
    got = innersphere.occlude(a.with_mesh(str(ma)), b.with_mesh(str(mb)), START, contact="mesh")
    assert got == cli(ist, pa, pb, "--contact", "mesh", "--meshes", ma, mb)
    assert got["status"] == "converged" and got["contact"] == "mesh"
    assert 0.05 < got["volume"] <= 0.5 * 1.05
