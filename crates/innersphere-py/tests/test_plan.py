"""A case planned from Python and from `ist plan`: the same files, the wafers one solid with
no self-intersection by CGAL's exact test (an independent tool), at most 300k triangles."""

import json

import trimesh

import innersphere


def cgal_self_intersects(path):
    """CGAL's does_self_intersect (exact predicates) on the mesh in `path`."""
    from CGAL.CGAL_Kernel import Point_3
    from CGAL.CGAL_Polygon_mesh_processing import does_self_intersect
    from CGAL.CGAL_Polyhedron_3 import Polyhedron_3, Polyhedron_modifier

    m = trimesh.load(path, process=True)
    p = Polyhedron_3()
    mod = Polyhedron_modifier()
    mod.begin_surface(len(m.vertices), len(m.faces))
    for v in m.vertices:
        mod.add_vertex(Point_3(float(v[0]), float(v[1]), float(v[2])))
    for f in m.faces:
        mod.begin_facet()
        for i in f:
            mod.add_vertex_to_facet(int(i))
        mod.end_facet()
    mod.end_surface()
    p.delegate(mod)
    return does_self_intersect(p)


def write_case(tmp_path):
    a, b = innersphere.arch_pair(teeth=10)
    for (v, f), name in [(a, "upper.stl"), (b, "lower.stl")]:
        trimesh.Trimesh(v, f, process=False).export(tmp_path / name)
    case = {
        "version": 1,
        "upper": "upper.stl",
        "lower": "lower.stl",
        "unit": "mm",
        "bite": {"method": "joints"},
        "splints": [{"name": "final", "open": "auto"}],
    }
    (tmp_path / "case.json").write_text(json.dumps(case))
    return tmp_path / "case.json"


def test_plan_matches_ist_and_its_wafer_is_clean(tmp_path, ist):
    case = write_case(tmp_path)
    cache = tmp_path / "cache"
    got = innersphere.plan(case, tmp_path / "py", cache=cache)
    want = json.loads(ist.run("plan", case, "-o", tmp_path / "cli", "--json", "--cache", cache))
    assert got["bite"] == want["bite"]
    assert [s["report"] for s in got["splints"]] == [s["report"] for s in want["splints"]]
    for name in ["final.stl", "upper_map.ply", "lower_map.ply"]:
        assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes()
    w = got["splints"][0]
    assert w["file"] == "final.stl" and w["report"]["fit"]
    assert w["report"]["triangles"] <= 300_000 < w["report"]["extracted_triangles"]
    stl = tmp_path / "py" / "final.stl"
    m = trimesh.load(stl, process=True)
    assert m.is_watertight and m.is_winding_consistent and len(m.faces) <= 300_000
    assert not cgal_self_intersects(stl)
    # The 3MF holds the same surface: its XML read here, not by the library.
    import xml.etree.ElementTree as ET
    import zipfile

    with zipfile.ZipFile(tmp_path / "py" / "final.3mf") as z:
        root = ET.fromstring(z.read("3D/3dmodel.model"))
    ns = {"m": "http://schemas.microsoft.com/3dmanufacturing/core/2015/02"}
    assert root.get("unit") == "millimeter"
    verts = [[float(v.get(k)) for k in "xyz"] for v in root.iterfind(".//m:vertex", ns)]
    tris = [[int(t.get(k)) for k in ("v1", "v2", "v3")] for t in root.iterfind(".//m:triangle", ns)]
    three = trimesh.Trimesh(verts, tris, process=False)
    assert len(tris) == len(m.faces) and three.is_watertight
    assert abs(three.volume - m.volume) < 1e-6 * m.volume
    report = (tmp_path / "py" / "report.html").read_text()
    assert "data:image/png;base64," in report and "<script" not in report


def test_plan_refuses_a_folder_of_other_files(tmp_path):
    case = write_case(tmp_path)
    theirs = tmp_path / "theirs"
    theirs.mkdir()
    (theirs / "final.stl").write_text("precious")
    try:
        innersphere.plan(case, theirs, cache=False)
        raise AssertionError("a folder of someone else's files was written into")
    except ValueError as e:
        assert "no plan wrote" in str(e)
    assert (theirs / "final.stl").read_text() == "precious"
