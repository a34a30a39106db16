"""Shared fixtures: generated meshes and trees (no data files needed), the `ist` CLI."""

import faulthandler
import os
import sys

import pytest

import innersphere
from helpers import Ist, box_mesh, find_ist, icosphere


# --- a time limit per test ------------------------------------------------------------------

#: Seconds a test (setup, call and teardown) may take unless marked ``time_limit(seconds)``.
DEFAULT_TIME_LIMIT = 600


_STDERR = None


def pytest_configure(config):
    # The terminal's stderr, kept before a test's output capture takes over fd 2 (the
    # stacks must reach the log, not the captured output that an exit discards).
    global _STDERR
    _STDERR = os.dup(2)
    config.addinivalue_line(
        "markers", "time_limit(seconds): the test fails (the run stops, every thread's stack "
        "printed) when it takes longer"
    )


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_protocol(item, nextitem):
    """A hung test ends the run with every thread's stack instead of hanging the CI."""
    mark = item.get_closest_marker("time_limit")
    seconds = mark.args[0] if mark else DEFAULT_TIME_LIMIT
    faulthandler.dump_traceback_later(seconds, exit=True, file=_STDERR if _STDERR is not None else sys.stderr)
    try:
        yield
    finally:
        faulthandler.cancel_dump_traceback_later()


# --- fixtures ------------------------------------------------------------------------------


@pytest.fixture(scope="session")
def meshes():
    v, f = icosphere(2, 1.0)
    # B: an ellipsoid (semi-axes 0.6, 0.45, 0.35), so that the refined packing has many
    # spheres (a ball's is one).
    return {"box": box_mesh(), "sphere": icosphere(2, 0.6), "ellipsoid": (v * [0.6, 0.45, 0.35], f)}


@pytest.fixture(scope="session")
def trees(meshes):
    """A (the box [-1, 1]³, plain packing) and B (the ellipsoid, refined packing), built from
    arrays."""
    a = innersphere.Tree.build(meshes["box"], resolution=24)
    b = innersphere.Tree.build(meshes["ellipsoid"], resolution=24, refine_steps=4, min_radius=0.01)
    return a, b


@pytest.fixture(scope="session")
def tree_files(trees, tmp_path_factory):
    d = tmp_path_factory.mktemp("trees")
    a, b = d / "box.ist", d / "ellipsoid.ist"
    trees[0].save(a)
    trees[1].save(b)
    return a, b


@pytest.fixture(scope="session")
def ist():
    exe = find_ist()
    if exe is None:
        msg = "the ist CLI was not found (build it: cargo build --release -p ist, or set IST_BIN)"
        if os.environ.get("INNERSPHERE_REQUIRE_IST"):
            pytest.fail(msg)
        pytest.skip(msg)
    return Ist(exe)


@pytest.fixture(scope="session")
def mesh_files(meshes, tmp_path_factory):
    """The two trees' meshes as OBJ files (the exact floats): what `ist query --meshes`
    and Tree.with_mesh both read."""
    from helpers import write_obj

    d = tmp_path_factory.mktemp("meshes")
    a, b = d / "box.obj", d / "ellipsoid.obj"
    write_obj(a, *meshes["box"])
    write_obj(b, *meshes["ellipsoid"])
    return a, b
