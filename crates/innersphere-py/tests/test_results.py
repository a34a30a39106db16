"""What every result object says: its getters equal its ``to_dict``, its ``repr`` shows its
numbers; a haptic tick's timing fields; the build's progress on standard error."""

import re

import numpy as np
import pytest

import innersphere
from helpers import POSES


def same(got, want):
    """Equal values: arrays bit for bit, lists of dicts key by key, scalars exactly."""
    if isinstance(want, list):
        assert isinstance(got, list) and len(got) == len(want)
        for g, w in zip(got, want):
            same(g, w)
    elif isinstance(want, dict):
        assert got.keys() == want.keys()
        for k in want:
            same(got[k], want[k])
    elif isinstance(want, np.ndarray):
        assert np.array_equal(got, want)
    else:
        assert type(got) is type(want) and got == want, (got, want)


def field(text, name):
    """The number (or list of numbers) after ``name=`` in a repr (Rust's shortest
    round-trip form: the same float back)."""
    m = re.search(rf"\b{name}=(\[[^\]]*\]|[^,)]+)", text)
    assert m, (name, text)
    v = m.group(1)
    if v.startswith("["):
        return [float(x) for x in v[1:-1].split(",")]
    return {"True": True, "False": False}.get(v, None) if v in ("True", "False") else float(v)


def assert_dict_is_the_getters(result, renamed=()):
    d = result.to_dict()
    assert d, result
    for key, value in d.items():
        same(value, getattr(result, dict(renamed).get(key, key)))


@pytest.fixture(scope="module")
def pair(trees):
    return innersphere.Pair(*trees)


def touching(pair):
    """A pose of the generated pair in contact."""
    for p in POSES:
        if pair.penetration(p).contact:
            return p
    raise AssertionError("no pose in contact")


def test_a_distance_result_says_what_it_holds(pair):
    d = pair.distance(POSES[0])
    assert d.distance > 0 and not d.contact and d.visits > 0
    assert_dict_is_the_getters(d)
    r = repr(d)
    assert r.startswith("DistanceResult(") and field(r, "distance") == d.distance
    assert field(r, "contact") is False
    assert field(r, "point_a") == d.point_a.tolist() and field(r, "point_b") == d.point_b.tolist()
    c = pair.distance(touching(pair))
    assert c.contact and field(repr(c), "contact") is True


def test_a_penetration_result_says_what_it_holds(pair):
    p = pair.penetration(touching(pair), stiffness=3.0)
    assert p.contact and p.pairs > 0 and p.volume > 0 and len(p.patches) > 0
    assert_dict_is_the_getters(p)
    assert "torque" not in p.to_dict() and p.patch_count == len(p.patches)
    with pytest.raises(AttributeError, match="no attribute 'torque'"):
        p.torque  # noqa: B018 (the attribute lookup is the test)
    assert {"volume", "patches", "stiffness", "to_dict"} <= set(dir(p))
    # Apart: no contact in the dict either.
    apart = pair.penetration(POSES[0])
    assert not apart.contact and apart.to_dict()["contact"] is False
    # The patches asked for: fewer than the default 8, or none, the volume the same.
    many = next(q for q in POSES if len(pair.penetration(q).patches) > 3)
    few = pair.penetration(many, max_patches=3)
    assert len(few.patches) == 3 and len(pair.penetration(many, max_patches=0).patches) == 0
    assert few.volume == pair.penetration(many).volume
    r = repr(p)
    assert field(r, "volume") == p.volume and field(r, "max_depth") == p.max_depth
    assert field(r, "force") == p.force.tolist() and field(r, "patches") == len(p.patches)


def test_a_haptic_tick_says_its_bound_its_time_and_whether_it_was_late(pair, trees):
    start = POSES[0]
    h = innersphere.Haptic(innersphere.Pair(*trees), "omega", 1000.0, start=start, budget=1.0)
    t = h.tick(start)
    assert_dict_is_the_getters(t)
    assert 0 < t.compute < 1.0 and not t.late and t.volume_bound == t.volume
    assert t.to_dict()["compute"] == t.compute
    r = repr(t)
    assert r.startswith("Tick(") and field(r, "force") == t.force.tolist()
    assert field(r, "budgeted") is False
    assert field(r, "volume") == t.volume and field(r, "max_depth") == t.max_depth
    # In contact with a budget of a nanosecond: every tick is late, and budgeted.
    deep = touching(pair)
    late = innersphere.Haptic(innersphere.Pair(*trees), "omega", 1000.0, start=deep, budget=1e-9)
    ticks = [late.tick(deep) for _ in range(5)]
    assert all(k.late and k.compute > 1e-9 for k in ticks)
    assert any(k.budgeted for k in ticks)
    for k in ticks:
        if k.budgeted:
            # The model in use is older than the tick; the bound covers what was found.
            assert k.model_age > 0 and k.volume_bound > 0 and k.volume_bound >= k.volume
    # Exact ticks in contact (after the first, time-critical one): the model's patches.
    exact = innersphere.Haptic(innersphere.Pair(*trees), "omega", 1000.0, start=deep, budget=1.0)
    assert [exact.tick(deep).patches > 0 for _ in range(3)] == [False, True, True]
    assert field(repr(next(k for k in ticks if k.budgeted)), "budgeted") is True
    r = repr(h)
    assert field(r, "rate") == h.rate and field(r, "budget") == h.budget
    assert field(r, "energy_to_user") == h.energy_to_user


def test_a_tool_pushed_out_of_a_contact_gives_the_rising_hand_energy(trees):
    """B starts 0.3 mm into the box's face x = 1 and the hand rises with it: the contact
    pushes the tool out, the coupling pulls the hand along, the energy to the user rises above
    0; the largest is kept."""
    start = [1.3, 0.1, -0.05, 1.0, 0.0, 0.0, 0.0]
    h = innersphere.Haptic(innersphere.Pair(*trees), "omega", 1000.0, start=start, budget=1.0)
    top = 0.0
    for x in np.linspace(1.3, 2.0, 400):
        h.tick([x] + start[1:])
        top = max(top, h.energy_to_user)
    assert top > 0 and h.energy_to_user_max == top and h.energy_to_user != 0


def test_the_tools_mass_is_its_trees(trees, meshes):
    """The mass follows the tree's volume at one density: two tools' masses are in the ratio
    of their meshes' volumes."""
    a, b = trees
    c = innersphere.Tree.build(meshes["sphere"], resolution=24)
    m = [innersphere.Haptic(innersphere.Pair(a, t), "omega", 1000.0).mass for t in (b, c)]
    v = [t.meta["mesh_volume"] for t in (b, c)]
    assert m[0] > 0 and m[0] / m[1] == pytest.approx(v[0] / v[1], rel=1e-9)


def test_multipoint_takes_its_k_and_split_depth(pair):
    p = next(q for q in POSES if len(pair.multipoint(q)) > 1)
    # One contact asked for: one; at split depth 0 there is one pair of nodes (the roots),
    # so one contact below it.
    assert len(pair.multipoint(p, k=1)) == 1
    assert len(pair.multipoint(p, k=16, split_depth=0)) == 1


def test_an_explicit_none_pose_a_is_the_identity(pair):
    p = touching(pair)
    assert pair.distance(p, pose_a=None).distance == pair.distance(p).distance
    assert pair.penetration(p, pose_a=None).volume == pair.penetration(p).volume


def test_trees_and_pairs_say_their_size(trees):
    a, b = trees
    r = repr(a)
    assert field(r, "node_count") == a.node_count and field(r, "leaf_count") == a.leaf_count
    assert field(r, "depth") == a.depth and field(r, "voxel_size") == a.meta["voxel_size"]
    p = repr(innersphere.Pair(a, b))
    assert f"tree_a=Tree(node_count={a.node_count})" in p
    assert f"tree_b=Tree(node_count={b.node_count})" in p


def test_the_build_reports_its_progress_on_standard_error(meshes, capfd):
    innersphere.Tree.build(meshes["box"], resolution=12, progress=True)
    err = capfd.readouterr().err
    lines = [line for line in err.split("\n") if line]
    assert len(lines) >= 4, err
    middle = 0
    for line in lines:
        # A stage: "name: 0%", rising percentages, each printed once, then "name: done".
        parts = line.split("\r")
        stage = parts[0].rsplit(":", 1)[0]
        assert parts[0] == f"{stage}: 0%" and parts[-1] == f"{stage}: done", line
        pcts = [int(p[len(stage) + 2:-1]) for p in parts[:-1]]
        assert all(p.startswith(f"{stage}: ") for p in parts), line
        assert pcts == sorted(set(pcts)) and pcts[-1] <= 100, line
        middle += sum(0 < p < 100 for p in pcts)
    assert middle > 0, err
    # The percentage is of the stage's total: some stage gets to 100.
    assert any(line.split("\r")[-2].endswith(": 100%") for line in lines), err
    innersphere.Tree.build(meshes["box"], resolution=12)
    assert capfd.readouterr().err == ""


def test_the_stubs_declare_exactly_the_answers_keys(pair, trees):
    """The result objects' attributes come from their answer's serialized form; the type stubs
    declare them by hand, so they must name exactly its keys (plus the methods and derived
    properties the classes define)."""
    import ast
    import pathlib

    stub = pathlib.Path(innersphere.__file__).parent / "_innersphere.pyi"
    classes = {c.name: c for c in ast.parse(stub.read_text()).body if isinstance(c, ast.ClassDef)}

    def properties(name):
        return {f.name for f in classes[name].body if isinstance(f, ast.FunctionDef)
                and any(getattr(d, "id", None) == "property" for d in f.decorator_list)}

    p = touching(pair)
    h = innersphere.Haptic(innersphere.Pair(*trees), "omega", 1000.0, start=p, budget=1.0)
    for name, result, extra in [("DistanceResult", pair.distance(p), set()),
                                ("PenetrationResult", pair.penetration(p), set()),
                                ("Tick", h.tick(p), {"tool_matrix"})]:
        assert properties(name) == set(result.to_dict()) | extra, name
        for key in result.to_dict():
            getattr(result, key)
