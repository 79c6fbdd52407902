# SPDX-License-Identifier: BSD-3-Clause
"""A robot's URDF visual geometry and loop closures in the viewer (issue #30 item 2,
docs/viewer.md, docs/robots.md "In the viewer"), in headless Chromium: the arm of
tests/data/visual_robot/visual_shapes.urdf (a box and an OBJ mesh on its base, a cylinder along
its arm, a sphere and an STL mesh on its hand, and a mesh of hostile name found nowhere), its shoulder turned by
0.5 rad about y, the hand's sphere tied to the floor by a distance loop. Every expected position
is worked out by hand from the URDF's numbers (the shoulder at z = 0.1, the arm 0.6 long, the
hand's frame turned by 90° about z), not read from the page."""

import json
import math
import pathlib

import numpy as np
import pytest

import ukdyn
from test_viewer import Page, _mask, browser  # noqa: F401 (the browser fixture)
from test_viewer_page import _page_data, _python_page, _run

DATA = pathlib.Path(__file__).resolve().parents[2] / "tests" / "data" / "visual_robot"
MODEL = DATA / "visual_shapes.yaml"
HOSTILE = "meshes/</script><script>window.pwned=1</script><!--.stl"
S, C = math.sin(0.5), math.cos(0.5)
ELBOW = np.array([0.6 * S, 0.0, 0.1 + 0.6 * C])   # the hand's frame
# the world position of each visual's origin at t = 0, and its three.js geometries
EXPECTED = [
    ("base", "box", [0, 0, 0.05], ["BoxBufferGeometry"]),
    ("base", "mesh", [0.15, 0, 0.1], ["BufferGeometry"]),                 # the OBJ square
    ("base", "mesh", [-0.15, 0, 0.1], ["BufferGeometry"]),                # the COLLADA triangle
    ("arm", "cylinder", [0.3 * S, 0, 0.1 + 0.3 * C], ["CylinderBufferGeometry"]),
    ("hand", "sphere", ELBOW + [0, 0.1, 0], ["SphereBufferGeometry"]),   # x of the hand is y
    ("hand", "mesh", ELBOW + [0.05 * S, 0, 0.05 * C], ["BufferGeometry"]),  # 0.05 up the hand
    ("hand", "mesh", ELBOW, ["BoxBufferGeometry"]),                     # its placeholder
    ("hand", "mesh", ELBOW - [0.05 * S, 0, 0.05 * C], ["BufferGeometry"]),  # the STL again
]


@pytest.fixture(scope="module")
def page_path(tmp_path_factory):
    path = tmp_path_factory.mktemp("visuals") / "visual_shapes.html"
    ukdyn.load(str(MODEL)).simulate(t_end=0.2).save_animation(path)
    return path


def test_the_shapes_are_drawn_where_the_urdf_puts_them(browser, page_path):  # noqa: F811
    page = Page(browser, page_path)
    page.js("ukdyn.setFrame(0)")
    drawn = page.js("return ukdyn.robotVisuals()")
    assert len(drawn) == len(EXPECTED)
    for d, (link, shape, position, geometries) in zip(drawn, EXPECTED):
        assert (d["link"], d["shape"], d["geometries"]) == (link, shape, geometries)
        assert d["visible"]
        # three.js's matrices are single precision: 1e-6 m on a 1 m scene
        np.testing.assert_allclose(d["position"], position, atol=1e-6, rtol=0)
    # the cylinder's axis is the arm's (URDF's z, three.js's y turned onto it): (sin, 0, cos)
    np.testing.assert_allclose(drawn[3]["axis"], [S, 0, C], atol=1e-6, rtol=0)
    # the OBJ's two triangles, COLLADA's one and the STL's four are drawn; the mesh not found
    # is a placeholder
    assert [d["vertices"] for d in drawn[1:3]] == [6, 3]
    assert drawn[5]["vertices"] == drawn[7]["vertices"] == 12
    assert [d["placeholder"] for d in drawn] == [False] * 6 + [True, False]
    # the OBJ square (0.1 m, in the plane z = 0.1); the COLLADA triangle in the (x, z) plane as
    # its Z_UP file says (not turned to y up), 10 cm long in x, twice that (scale 1 1 2) in z
    np.testing.assert_allclose(drawn[1]["bounds"], [[0.15, 0, 0.1], [0.25, 0.1, 0.1]], atol=1e-6)
    np.testing.assert_allclose(drawn[2]["bounds"], [[-0.15, 0, 0.1], [-0.05, 0, 0.3]], atol=1e-6)
    # the base's box in its URDF colour (red), the loop's markers in purple
    img = page.pixels()
    assert _mask(img, "#ff0000", tolerance=0.08).sum() > 200
    assert _mask(img, "#6a3d9a", tolerance=0.08).sum() > 10
    assert page.errors() == []
    page.save("visual_shapes.png")


def test_the_loop_is_drawn_between_its_frames(browser, page_path):  # noqa: F811
    page = Page(browser, page_path)
    page.js("ukdyn.setFrame(0)")
    (loop,) = page.js("return ukdyn.loops()")
    # the hand's frame, the sphere's centre, the floor point below it (the world's end: no line
    # on to the world's origin)
    floor = [0.6 * S, 0.1, 0]
    np.testing.assert_allclose(loop, [ELBOW, ELBOW + [0, 0.1, 0], floor, floor], atol=1e-6, rtol=0)
    # held at the next frames too (at rest in zero gravity, its loop closed)
    page.js("ukdyn.setFrame(ukdyn.frames - 1)")
    (last,) = page.js("return ukdyn.loops()")
    assert np.linalg.norm(np.subtract(last[1], last[2])) == pytest.approx(0.1 + 0.6 * C, abs=1e-4)


def test_a_hostile_mesh_name_is_only_text(browser, page_path):  # noqa: F811
    page = Page(browser, page_path)
    assert page.js("return window.pwned === undefined")
    # the page's own three scripts only, and the name said in the notes as it is
    assert page.js("return document.scripts.length") == 3
    notes = page.js("return ukdyn.notes()")
    assert notes == ['mesh %s of link "hand" is not drawn: no such file beside the URDF; a grey '
                     'wire box marks its origin' % json.dumps(HOSTILE)]
    assert page.js("return document.getElementById('notes').textContent") == notes[0]
    assert page.errors() == []


def test_the_page_holds_the_meshes_and_their_loaders(page_path):
    html = page_path.read_text(encoding="utf-8")
    loader = "Generated from 'examples/jsm/loaders/%s.js'"  # the first line of each loader
    for name in ("STLLoader", "OBJLoader", "ColladaLoader"):
        assert html.count(loader % name) == 1
    data = _page_data(html)
    visuals = data["robot"]["visuals"]
    assert [v.get("format") for v in visuals] == [None, "obj", "dae", None, None, "stl", None, "stl"]
    # each file once: the STL shown twice is embedded once
    assert [v.get("file") for v in visuals] == [None, 0, 1, None, None, 2, None, 2]
    assert len(data["robot"]["meshes"]) == 3
    assert data["robot"]["meshes"][2].startswith("c29saWQgdGV0cmE")  # "solid tetra"
    assert visuals[6]["mesh"] == HOSTILE
    assert str(DATA) not in html  # no path of this machine in the page


def test_the_commands_page_is_pythons(cli, tmp_path):
    out = tmp_path / "run"
    proc = _run(cli, [str(MODEL)], out)
    assert proc.returncode == 0, proc.stderr
    page = (out / "animation.html").read_text(encoding="utf-8")
    expected = _python_page(MODEL, out / "trajectory.csv")
    if page != expected:  # the first difference, readably
        assert _page_data(page) == _page_data(expected)
        assert page == expected


def test_a_page_without_meshes_has_no_loader(tmp_path):
    """The leg's URDF has boxes and cylinders only: no loader in its page."""
    path = tmp_path / "leg.html"
    ukdyn.load("leg_four_bar_knee").simulate(t_end=0.1).save_animation(path)
    html = path.read_text(encoding="utf-8")
    assert "examples/jsm/controls/OrbitControls.js" in html
    assert "examples/jsm/loaders/" not in html
    assert len(_page_data(html)["robot"]["visuals"]) == 6
