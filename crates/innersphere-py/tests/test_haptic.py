"""The haptic loop: the same ticks as `ist haptic --trace`, forces that push the hand out,
passivity, NaN device poses refused."""

import numpy as np
import pytest

import innersphere
from helpers import read_csv, write_motion


def press(n=300):
    """The device moves the sphere from x = 3 into the box's face (x = 1) down to x = 1.3."""
    t = np.arange(n) * 0.001
    x = np.linspace(3.0, 1.3, n)
    poses = np.column_stack([x, np.full(n, 0.1), np.full(n, -0.05), np.ones(n), np.zeros((n, 3))])
    return t, poses


def test_haptic_equals_cli(trees, tree_files, ist, tmp_path):
    t, poses = press()
    dev = tmp_path / "press.csv"
    write_motion(dev, t, poses)
    trace = tmp_path / "trace.csv"
    # A budget of a second: every tick runs the exact query, so the ticks are reproducible.
    ist.run("haptic", *tree_files, "--device", dev, "--budget-us", 1e6, "--trace", trace)
    want = read_csv(trace)
    _, loaded = innersphere.load_motion(dev)
    h = innersphere.Haptic(innersphere.Pair(*trees), "omega", 1000.0, start=loaded[0], budget=1.0)
    ticks = [h.tick(p) for p in loaded]
    col = lambda *names: np.array([[float(x) for x in want[n]] for n in names]).T
    assert len(ticks) == len(want["t"])
    assert np.allclose([k.force for k in ticks], col("fx", "fy", "fz"), atol=1e-9)
    assert np.allclose([k.torque for k in ticks], col("tx", "ty", "tz"), atol=1e-9)
    tool = col("tool_tx", "tool_ty", "tool_tz", "tool_qw", "tool_qx", "tool_qy", "tool_qz")
    assert np.allclose([k.tool for k in ticks], tool, atol=1e-9)
    assert np.allclose([k.volume for k in ticks], col("volume")[:, 0], atol=1e-12)
    assert np.allclose([k.max_depth for k in ticks], col("depth")[:, 0], atol=1e-12)
    # The first ticks take the time-critical query until an exact time is known.
    assert [k.budgeted for k in ticks] == [x == "1" for x in want["budgeted"]]


def test_haptic_pushes_back_and_stays_passive(trees):
    pair = innersphere.Pair(*trees)
    _, poses = press()
    h = innersphere.Haptic(pair, device="touch", start=poses[0])
    assert h.rate == 1000.0 and h.budget == pytest.approx(1e-3) and h.mass > 0
    ticks = [h.tick(p, dt=0.001) for p in poses]
    last = ticks[-1]
    # The tool (semi-axis 0.6 along x) is held at the face x = 1 while the hand goes on to
    # x = 1.3: the device is pulled back out along +x, within the Touch's 3.3 N.
    assert last.tool[0] > poses[-1][0] + 0.1 and last.volume > 0 and last.max_depth > 0
    assert last.force[0] > 0.02 and np.linalg.norm(last.force) <= 3.3 + 1e-9
    assert last.contact_force[0] > 0
    assert ticks[0].volume == 0 and not ticks[-1].budgeted
    assert h.energy_to_user <= 1e-9 and h.energy_to_user_max <= 1e-9
    assert np.array_equal(h.tool, last.tool)
    assert last.tool_matrix.shape == (4, 4)
    d = last.to_dict()
    assert set(d) >= {"force", "torque", "tool", "volume", "max_depth", "budgeted"}
    assert "Tick(" in repr(last) and "Haptic(" in repr(h)


def test_haptic_refuses_nan_and_keeps_going(trees):
    h = innersphere.Haptic(innersphere.Pair(*trees), start=[3, 0, 0, 1, 0, 0, 0])
    h.tick([3, 0, 0, 1, 0, 0, 0])
    before = h.tool.copy()
    with pytest.raises(ValueError, match="device_pose: invalid pose"):
        h.tick([float("nan"), 0, 0, 1, 0, 0, 0])
    assert np.array_equal(h.tool, before)
    assert np.all(np.isfinite(h.tick(np.eye(4) + np.diag([0, 0, 0, 0])).force))


def test_haptic_leaves_the_pair_alone(trees):
    """The loop queries its own pair of the same trees; the caller's pair keeps its state."""
    pair = innersphere.Pair(*trees)
    innersphere.Haptic(pair).tick([1.3, 0, 0, 1, 0, 0, 0])
    assert pair.distance([5, 0, 0, 1, 0, 0, 0]).distance == pytest.approx(3.4, abs=0.05)


def test_haptic_with_a_collision_thread_pushes_back_passively(trees):
    """The multi-rate loop, paced in real time at 2 kHz: the models arrive, the tool is held
    at the face as in one thread, the hand gets no energy; bad options are refused."""
    import time

    pair = innersphere.Pair(*trees)
    _, poses = press(600)
    h = innersphere.Haptic(pair, "touch", 2000.0, start=poses[0], collision_thread=True)
    start = time.perf_counter()
    ticks = []
    for i, p in enumerate(poses):
        while time.perf_counter() < start + i / 2000.0:
            pass
        ticks.append(h.tick(p))
    last = ticks[-1]
    assert h.collision_queries > 100
    assert last.tool[0] > poses[-1][0] + 0.1 and last.force[0] > 0.02
    assert all(0.0 <= k.model_age < 0.05 for k in ticks)
    assert h.energy_to_user_max <= 1e-9
    assert "model_age" in last.to_dict()
    with pytest.raises(ValueError, match="collision delay"):
        innersphere.Haptic(pair, collision_thread=True, collision_delay=-1.0)
    with pytest.raises(ValueError, match="collision_delay needs collision_thread"):
        innersphere.Haptic(pair, collision_delay=0.001)
    single = innersphere.Haptic(pair)
    assert single.collision_queries == 0 and single.tick(poses[0]).model_age == 0.0


def test_haptic_on_the_meshes_contact_pushes_back_passively(trees, mesh_files):
    """contact="mesh": the meshes' own volume in the collision thread (implied), the tool held
    at the box's face, the hand given no energy; refused without the meshes or for an unknown
    contact."""
    import time

    with pytest.raises(ValueError, match="meshes"):
        innersphere.Haptic(innersphere.Pair(*trees), contact="mesh")
    with pytest.raises(ValueError, match="spheres"):
        innersphere.Haptic(innersphere.Pair(*trees), contact="voxels")
    pair = innersphere.Pair(trees[0].with_mesh(str(mesh_files[0])), trees[1].with_mesh(mesh_files[1]))
    _, poses = press(600)
    h = innersphere.Haptic(pair, "touch", 2000.0, start=poses[0], contact="mesh")
    start = time.perf_counter()
    ticks = []
    for i, p in enumerate(poses):
        while time.perf_counter() < start + i / 2000.0:
            pass
        ticks.append(h.tick(p))
    last = ticks[-1]
    assert h.collision_queries > 100
    assert last.tool[0] > poses[-1][0] + 0.1 and last.force[0] > 0.02
    assert last.volume > 0
    assert h.energy_to_user_max <= 1e-9
