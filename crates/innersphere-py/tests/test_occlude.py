"""The bite of a jaw pair (`innersphere.occlude`): the same answer as `ist occlude` bit for bit,
with the joints and free, the teeth brought together, and clear errors."""

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
    assert got["converged"] and got["volume"] > 0 and got["candidates"] is None
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
    assert sum(c["starts"] for c in got["candidates"]) <= 6


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
