"""On the real models of ../shared/data (skipped unless INNERSPHERE_DATA points there): the
molar pair built as `ist build --preset jaw` builds it, and the jaw chewing motion replayed
with the batch queries, against `ist replay`. With INNERSPHERE_TREES pointing to a folder
holding maxilla.ist and mandible.ist (the arches built with --preset jaw), the same replay
on the arch pair."""

import os
import pathlib

import numpy as np
import pytest

import innersphere

DATA = os.environ.get("INNERSPHERE_DATA")
pytestmark = pytest.mark.skipif(
    not DATA or not pathlib.Path(DATA, "jaw").is_dir(),
    reason="real data: set INNERSPHERE_DATA to ../shared/data",
)
MOTION = pathlib.Path(DATA or ".", "motion", "jaw_chew_demo.csv")


@pytest.fixture(scope="module")
def molars(ist, tmp_path_factory):
    """The opposing first molars (teeth 3 and 30) built by the module and by `ist build`."""
    d = tmp_path_factory.mktemp("molars")
    out = []
    for name in ("ofj_p26_tooth03_upper_first_molar.stl", "ofj_p26_tooth30_lower_first_molar.stl"):
        mesh = pathlib.Path(DATA, "jaw", name)
        path = d / (name + ".ist")
        ist.run("build", mesh, "-o", path, "-q", "--preset", "jaw")
        out.append((innersphere.Tree.build(mesh, preset="jaw"), path))
    return out


def test_molars_build_as_the_cli(molars):
    for tree, path in molars:
        assert tree.to_bytes() == path.read_bytes()
        assert tree.meta["voxel_size"] == 0.1 and tree.meta["min_radius"] == 0.05
        assert tree.leaf_count > 5000


def test_load_motion_real():
    t, poses = innersphere.load_motion(MOTION)
    raw = np.loadtxt(MOTION, delimiter=",", skiprows=1)
    assert t.shape == (3000,) and poses.shape == (3000, 7)
    assert np.array_equal(t, raw[:, 0]) and np.array_equal(poses, raw[:, 1:])


def replay_equal(ist, a, b, pair, tmp_path):
    """distance_many and penetration_many on new pairs equal `ist replay` on every frame."""
    _, poses = innersphere.load_motion(MOTION)
    csv = ist.replay_csv(a, b, MOTION, "distance", tmp_path / "d.csv")
    d = pair().distance_many(poses)
    assert np.array_equal(d, np.array([float(x) for x in csv["distance"]]))
    csv = ist.replay_csv(a, b, MOTION, "penetration", tmp_path / "p.csv")
    p = pair().penetration_many(poses)
    assert np.array_equal(p["volume"], np.array([float(x) for x in csv["penetration_volume"]]))
    assert np.array_equal(p["pairs"], np.array([int(x) for x in csv["penetration_pairs"]]))
    return d, p


def test_molar_replay_equals_cli(molars, ist, tmp_path):
    (ta, pa), (tb, pb) = molars
    d, p = replay_equal(ist, pa, pb, lambda: innersphere.Pair(ta, tb), tmp_path)
    assert (d == 0).any() and (d > 0).any()
    assert p["volume"].max() > 0


def test_arch_replay_equals_cli(ist, tmp_path):
    trees = os.environ.get("INNERSPHERE_TREES")
    if not trees or not pathlib.Path(trees, "maxilla.ist").is_file():
        pytest.skip("set INNERSPHERE_TREES to a folder with maxilla.ist and mandible.ist")
    a, b = pathlib.Path(trees, "maxilla.ist"), pathlib.Path(trees, "mandible.ist")
    ta, tb = innersphere.Tree.load(a), innersphere.Tree.load(b)
    replay_equal(ist, a, b, lambda: innersphere.Pair(ta, tb), tmp_path)
