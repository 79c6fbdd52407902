# SPDX-License-Identifier: BSD-3-Clause
"""The viewer draws robots (issue #30 item 6, docs/robots.md): a robot's links, joint axes and
the desired path of a task-space requirement. The page computes the links' frames itself
(forward kinematics in JavaScript from the joints' origins, axes and coordinates); checked here
against the library's own forward kinematics: the foot of leg_four_bar_knee is where its pose
requirement's actual value (desired + error, computed by the tree in C++) says, at every frame
shown, to the rounding of the angles (1e-4 rad)."""

import pathlib

import numpy as np
import pytest

import ukdyn
from test_viewer import Page, browser  # noqa: F401 (the browser fixture)
from ukdyn import viewer


@pytest.fixture(scope="module")
def leg():
    return ukdyn.load("leg_four_bar_knee").simulate(t_end=1.0)


def test_the_scene_has_the_tree_and_the_desired_path(leg):
    data = viewer.scene_data(leg.scene, leg.names, leg._columns)
    links = data["robot"]["links"]
    names = [l["name"] for l in links]
    assert "foot" in names and "shin" in names
    for l in links:  # parents first, each joint's coordinates sampled
        assert l["parent"] < names.index(l["name"])
        assert len(l["q"]) == len(l["coordinates"])
        assert all(len(c) == len(data["t"]) for c in l["q"])
    rows = {r["name"]: r for r in data["requirements"]}
    # the desired path: the ellipse of the model file, x = -0.29 + r (1 - cos w t), z = 0.313 + h sin² w t
    t = np.array(data["t"])
    np.testing.assert_allclose(rows["foot.0"]["desired"], -0.29 + 0.04 * (1 - np.cos(np.pi * t)),
                               atol=1e-4)
    np.testing.assert_allclose(rows["foot.2"]["desired"], 0.313 + 0.03 * np.sin(np.pi * t) ** 2,
                               atol=1e-4)


def test_the_pages_forward_kinematics_is_the_trees(browser, leg, tmp_path):  # noqa: F811
    path = tmp_path / "leg.html"
    leg.save_animation(path)
    page = Page(browser, path)
    assert page.errors() == []
    data = page.js("return ukdyn.data")
    rows = {r["name"]: r for r in data["requirements"]}
    n = len(data["t"])
    assert n > 20
    worst = 0.0
    for i in range(0, n, 3):
        foot = page.js("return ukdyn.robotFrame(arguments[0], 'foot')", i)
        actual = [rows["foot.%d" % k]["actual"][i] for k in range(3)]
        worst = max(worst, float(np.max(np.abs(np.array(foot[:3]) - actual))))
    assert worst < 5e-4  # angles rounded to 1e-4 rad on links of ~0.4 m
    # links (grey rods) and the desired path (green, dashed) are drawn; no error on the way
    page.js("ukdyn.setFrame(arguments[0])", n // 2)
    from test_viewer import _mask
    img = page.pixels()
    assert _mask(img, "#00a651", tolerance=0.08).sum() > 20
    assert _mask(img, "#ff7f0e", tolerance=0.08).sum() > 20  # joint axes, the foot's path
    assert page.errors() == []
    page.save("leg_four_bar_knee.png")


ARM_ON_TABLE = """
parameters: {L1: 0.45, L2: 0.35}
robot: {urdf: %s}
contacts:
  - {name: tip, link: l2, point: [L2, 0, 0], shape: sphere, radius: 0.025,
     plane: {body: ground, point: [0, 0, 0.3], normal: [0, 0, 1]}}
initial:
  q: {j1: 0.6, j2: asin((0.6 - 0.325 - L1*sin(0.6))/L2) - 0.6}
simulate: {t_end: 0.2}
output: {every: 0.05}
"""


def test_a_robots_last_link_and_its_contacts_plane_are_drawn(browser, tmp_path):  # noqa: F811
    # tests/data/arm2_table.urdf: its last link l2 has no child joint and no <visual>; its tip
    # (0.35 m along l2) rests on a table at z = 0.3 (u15 09: the arm ended at the elbow and the
    # table was not drawn). The rod runs from l2's frame to the tip, the patch lies in the plane.
    data_dir = pathlib.Path(__file__).resolve().parents[2] / "tests" / "data"
    model = tmp_path / "arm.yaml"
    model.write_text(ARM_ON_TABLE % (data_dir / "arm2_table.urdf"))
    run = ukdyn.load(str(model)).simulate()
    scene = viewer.scene_data(run.scene, run.names, run._columns)
    (c,) = scene["robot"]["contacts"]
    assert c["name"] == "tip" and c["point"] == [0.35, 0, 0] and c["plane_link"] == -1
    assert c["plane_point"] == [0, 0, 0.3] and c["plane_normal"] == [0, 0, 1]
    path = tmp_path / "arm.html"
    run.save_animation(path)
    page = Page(browser, path)
    assert page.errors() == []
    n = page.js("return ukdyn.frames")
    for i in (0, n - 1):
        page.js("ukdyn.setFrame(arguments[0])", i)
        (drawn,) = page.js("return ukdyn.robotContacts()")
        l2 = page.js("return ukdyn.robotFrame(arguments[0], 'l2')", i)
        # the rod: from l2's origin 0.35 m along its x axis (rotated by its quaternion)
        w, x, y, z = l2[3:]
        axis = np.array([1 - 2 * (y * y + z * z), 2 * (x * y + w * z), 2 * (x * z - w * y)])
        np.testing.assert_allclose(drawn["rod"][0], l2[:3], atol=1e-5)
        np.testing.assert_allclose(drawn["rod"][1], np.array(l2[:3]) + 0.35 * axis, atol=1e-5)
        # the tip (sphere centre) starts r above the table (to the page's angles, rounded to
        # 1e-4 rad on links of 0.8 m); the patch is at z = 0.3 under it
        if i == 0:
            assert abs(drawn["rod"][1][2] - 0.325) < 1e-4
        np.testing.assert_allclose(drawn["plane"]["normal"], [0, 0, 1], atol=1e-12)
        assert abs(drawn["plane"]["centre"][2] - 0.3) < 1e-12
