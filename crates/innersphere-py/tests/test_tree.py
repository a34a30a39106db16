"""Trees: build from arrays, files and trimesh objects (the same tree as `ist build`), save
and load, the arrays and the meta."""

import pickle
import warnings

import numpy as np
import pytest

import innersphere
from helpers import box_mesh, icosphere, write_obj



def same_tree(a, b):
    """The same spheres, nodes and meta, whatever file each remembers (meta's "source")."""
    ma, mb = dict(a.meta), dict(b.meta)
    ma.pop("source", None)
    mb.pop("source", None)
    return (np.array_equal(a.spheres, b.spheres) and np.array_equal(a.nodes, b.nodes)
            and ma == mb)

def test_build_from_arrays_equals_file_and_cli(meshes, ist, tmp_path):
    v, f = meshes["sphere"]
    obj = tmp_path / "sphere.obj"
    write_obj(obj, v, f)
    opts = dict(resolution=20, min_radius=0.02, refine_steps=2, fanout=6)
    from_arrays = innersphere.Tree.build((v, f), **opts)
    from_file = innersphere.Tree.build(obj, **opts)
    from_str = innersphere.Tree.build(str(obj), **opts)
    cli = tmp_path / "cli.ist"
    ist.run("build", obj, "-o", cli, "-q", "--resolution", 20, "--min-radius", 0.02,
            "--refine-steps", 2, "--fanout", 6)
    want = cli.read_bytes()
    # A tree built from a file remembers the file (path and content hash), as `ist build`'s
    # does: the same bytes. From arrays there is no file: the same tree otherwise.
    assert from_file.to_bytes() == want
    assert from_str.to_bytes() == want
    assert from_file.meta["source"]["path"] == str(obj.resolve())
    assert "source" not in from_arrays.meta
    assert same_tree(from_arrays, innersphere.Tree.from_bytes(want))


def test_build_with_voxel_size_and_preset_equals_cli(ist, tmp_path):
    v, f = icosphere(2, 5.0)  # 10 "mm" across: the jaw presets accept it
    obj = tmp_path / "ball.obj"
    write_obj(obj, v, f)
    cli = tmp_path / "cli.ist"
    ist.run("build", obj, "-o", cli, "-q", "--voxel-size", 0.4)
    assert same_tree(innersphere.Tree.build((v, f), voxel_size=0.4), innersphere.Tree.load(cli))
    ist.run("build", obj, "-o", cli, "-q", "--preset", "jaw-fast", "--voxel-size", 0.5)
    t = innersphere.Tree.build((v, f), preset="jaw-fast", voxel_size=0.5)
    assert same_tree(t, innersphere.Tree.load(cli))
    assert t.meta["min_radius"] == 0.05 and t.meta["built_by"]["refine_steps"] == 8
    # Each build option given beside a preset overrides that field, as in the CLI.
    ist.run("build", obj, "-o", cli, "-q", "--preset", "jaw-fast", "--voxel-size", 0.5,
            "--min-radius", 0.08, "--refine-steps", 2, "--fanout", 8)
    t = innersphere.Tree.build((v, f), preset="jaw-fast", voxel_size=0.5, min_radius=0.08,
                               refine_steps=2, fanout=8)
    assert same_tree(t, innersphere.Tree.load(cli))
    assert t.meta["min_radius"] == 0.08 and t.meta["built_by"]["refine_steps"] == 2
    assert t.meta["fanout"] == 8


def test_arrays_are_welded(meshes):
    """A triangle soup (every corner its own vertex) gives the tree of the indexed mesh."""
    v, f = meshes["box"]
    soup_v = v[f.reshape(-1)]
    soup_f = np.arange(len(soup_v)).reshape(-1, 3)
    a = innersphere.Tree.build((v, f), resolution=16)
    b = innersphere.Tree.build((soup_v, soup_f), resolution=16)
    c = innersphere.Tree.build([soup_v.tolist(), soup_f.tolist()], resolution=16)
    assert a.to_bytes() == b.to_bytes() == c.to_bytes()
    # -0.0 and 0.0 are one coordinate: a soup of the box [0, 1]³ whose origin corner is
    # written with a -0.0 in x, y or z in its triangles still welds into the closed box.
    from helpers import box_mesh
    v, f = box_mesh((0.0, 0.0, 0.0), (1.0, 1.0, 1.0))
    soup_v = v[f.reshape(-1)].copy()
    corner = np.flatnonzero(np.all(soup_v == 0.0, axis=1))
    for j, row in enumerate(corner):
        soup_v[row, j % 3] = -0.0
    assert len(corner) >= 6 and all(np.signbit(soup_v[:, c]).any() for c in range(3))
    soup_f = np.arange(len(soup_v)).reshape(-1, 3)
    a = innersphere.Tree.build((v, f), resolution=16)
    b = innersphere.Tree.build((soup_v, soup_f), resolution=16)
    assert b.meta["mesh_closed"] and a.to_bytes() == b.to_bytes()


def test_faces_of_unsigned_integers_build_the_same_tree(meshes):
    v, f = meshes["box"]
    a = innersphere.Tree.build((v, f), resolution=16)
    for dtype in (np.uint32, np.uint64, np.int32):
        assert innersphere.Tree.build((v, f.astype(dtype)), resolution=16).to_bytes() == a.to_bytes()


def test_an_object_with_vertices_but_no_faces_is_no_mesh(meshes):
    class Half:
        vertices = meshes["box"][0]

    with pytest.raises(ValueError, match="expected a mesh file path"):
        innersphere.Tree.build(Half(), resolution=16)


def test_object_with_vertices_and_faces(meshes):
    class Mesh:
        vertices, faces = meshes["box"]

    a = innersphere.Tree.build(Mesh(), resolution=16)
    assert a.to_bytes() == innersphere.Tree.build(meshes["box"], resolution=16).to_bytes()


def test_trimesh_interop(tmp_path):
    trimesh = pytest.importorskip("trimesh")
    m = trimesh.creation.icosphere(subdivisions=2, radius=0.8)
    t = innersphere.Tree.build(m, resolution=24)
    assert t.to_bytes() == innersphere.Tree.build((m.vertices, m.faces), resolution=24).to_bytes()
    assert t.meta["mesh_volume"] == pytest.approx(m.volume, rel=1e-9)
    assert np.allclose(t.meta["center_of_mass"], m.center_mass, atol=1e-9)
    # A trimesh file round trip builds the same tree.
    path = tmp_path / "ico.stl"
    m.export(path)
    from_file = innersphere.Tree.build(path, resolution=24)
    assert from_file.leaf_count == pytest.approx(t.leaf_count, rel=0.05)
    # trimesh's 4×4 transforms are poses.
    box = trimesh.creation.box(extents=(2, 2, 2))
    pair = innersphere.Pair(innersphere.Tree.build(box, resolution=24), t)
    tf = trimesh.transformations.rotation_matrix(0.3, [0, 0, 1])
    tf[:3, 3] = [3.0, 0, 0]
    assert pair.distance(tf).distance == pytest.approx(1.2, abs=0.1)
    assert not pair.contact(tf)


def test_arrays_and_meta(trees, meshes):
    a, b = trees
    s = a.spheres
    assert s.shape == (a.leaf_count, 4) and s.dtype == np.float64
    assert a.nodes.shape == (a.node_count, 4)
    assert a.node_count > a.leaf_count > 100
    assert a.depth >= 3
    # Inner spheres lie inside the box [-1, 1]³.
    assert np.all(np.abs(s[:, :3]) + s[:, 3:] <= 1.0 + 1e-6)
    # The root encloses every leaf.
    root = a.nodes[0]
    assert np.all(np.linalg.norm(s[:, :3] - root[:3], axis=1) + s[:, 3] <= root[3] * (1 + 1e-6))
    m = a.meta
    assert m["fanout"] == 4 and m["mesh_closed"] is True
    assert m["mesh_volume"] == pytest.approx(8.0)
    assert m["bbox_min"] == [-1.0, -1.0, -1.0] and m["bbox_max"] == [1.0, 1.0, 1.0]
    assert 0.5 < m["coverage"] < 1.0
    assert m["built_by"]["revision"] >= 2 and len(m["inertia"]) == 6
    assert b.meta["min_radius"] == 0.01
    r = a.report
    assert r["spheres"] == a.leaf_count and r["nodes"] == a.node_count and r["warnings"] == []
    assert "Tree(node_count=" in repr(a)


def test_save_load_round_trip(trees, tmp_path):
    a = trees[1]
    path = tmp_path / "b.ist"
    a.save(path)
    b = innersphere.Tree.load(path)
    assert b.to_bytes() == a.to_bytes() == path.read_bytes()
    assert np.array_equal(b.spheres, a.spheres) and np.array_equal(b.nodes, a.nodes)
    assert b.meta == a.meta and (b.node_count, b.leaf_count, b.depth) == (a.node_count, a.leaf_count, a.depth)
    assert b.report is None
    assert innersphere.Tree.load(str(path)).to_bytes() == a.to_bytes()
    a.save(bytes(tmp_path / "c.ist"))
    assert innersphere.Tree.load(bytes(tmp_path / "c.ist")).to_bytes() == a.to_bytes()
    c = innersphere.Tree.from_bytes(a.to_bytes())
    assert c.to_bytes() == a.to_bytes()
    d = pickle.loads(pickle.dumps(a))
    assert d.to_bytes() == a.to_bytes()


def test_loaded_trees_answer_alike(trees, tree_files):
    x = innersphere.Pair(*trees)
    y = innersphere.Pair(innersphere.Tree.load(tree_files[0]), innersphere.Tree.load(tree_files[1]))
    for p in ([1.7, 0, 0, 1, 0, 0, 0], [1.2, 0.3, 0.1, 1, 0, 0, 0]):
        assert x.distance(p).distance == y.distance(p).distance
        assert x.penetration(p).volume == y.penetration(p).volume


def test_open_mesh_warns():
    v, f = box_mesh()
    with pytest.warns(UserWarning, match="not closed"):
        t = innersphere.Tree.build((v, f[:-1]), resolution=16)
    assert t.report["warnings"]
    assert t.meta["mesh_closed"] is False


def test_inward_mesh_warns_and_builds_the_same():
    v, f = box_mesh()
    with pytest.warns(UserWarning, match="inward"):
        t = innersphere.Tree.build((v, f[:, [0, 2, 1]]), resolution=16)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        u = innersphere.Tree.build((v, f), resolution=16)
    assert np.array_equal(t.spheres, u.spheres)


def test_progress_goes_to_stderr(meshes, capfd):
    innersphere.Tree.build(meshes["box"], resolution=16, progress=True)
    err = capfd.readouterr().err
    assert "done" in err
    innersphere.Tree.build(meshes["box"], resolution=16)
    assert capfd.readouterr().err == ""


def test_build_with_a_cache_reads_the_same_tree_back(meshes, tmp_path):
    """cache=folder: built once, then read back bit for bit; a corrupt entry is rebuilt."""
    want = innersphere.Tree.build(meshes["box"], preset="fast").to_bytes()
    first = innersphere.Tree.build(meshes["box"], preset="fast", cache=tmp_path)
    again = innersphere.Tree.build(meshes["box"], preset="fast", cache=str(tmp_path))
    assert first.report["cache"]["outcome"] == "built"
    assert again.report["cache"]["outcome"] == "hit"
    assert first.to_bytes() == again.to_bytes() == want
    (entry,) = list(tmp_path.glob("innersphere-trees-v1/*.ist"))
    entry.write_bytes(entry.read_bytes()[:100])
    with pytest.warns(UserWarning, match="failed the tree file's checks"):
        fixed = innersphere.Tree.build(meshes["box"], preset="fast", cache=tmp_path)
    assert fixed.report["cache"]["outcome"] == "rebuilt" and fixed.to_bytes() == want
    # Other options: another entry.
    innersphere.Tree.build(meshes["box"], preset="default", cache=tmp_path)
    assert len(list(tmp_path.glob("innersphere-trees-v1/*.ist"))) == 2
    assert innersphere.Tree.build(meshes["box"], preset="fast", cache=False).report.get("cache") is None


def test_the_cache_keeps_to_its_own_subfolder_and_checks_what_it_reads(meshes, tmp_path):
    """cache= a folder of the user's own: their files stay byte for byte, the trees go to
    the cache's own subfolder; a valid tree planted under another mesh's key is rebuilt
    with a warning; a cache path that is a file is an OSError in a sentence."""
    mine = {
        "my_maxilla.ist": innersphere.Tree.build(meshes["ellipsoid"], preset="fast").to_bytes(),
        "notes.txt": b"bite on the left",
    }
    for name, data in mine.items():
        (tmp_path / name).write_bytes(data)
    box = innersphere.Tree.build(meshes["box"], preset="fast", cache=tmp_path)
    ball = innersphere.Tree.build(meshes["ellipsoid"], preset="fast", cache=tmp_path)
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([*mine, "innersphere-trees-v1"])
    for name, data in mine.items():
        assert (tmp_path / name).read_bytes() == data
    # The box's entry replaced by the ball's (valid) tree.
    entries = {p.read_bytes(): p for p in tmp_path.glob("innersphere-trees-v1/*.ist")}
    entries[box.to_bytes()].write_bytes(ball.to_bytes())
    with pytest.warns(UserWarning, match="not the tree of this mesh"):
        again = innersphere.Tree.build(meshes["box"], preset="fast", cache=tmp_path)
    assert again.report["cache"]["outcome"] == "rebuilt" and again.to_bytes() == box.to_bytes()
    with pytest.raises(OSError, match="notes.txt: is a file, not a folder.*give cache= a folder"):
        innersphere.Tree.build(meshes["box"], preset="fast", cache=tmp_path / "notes.txt")
