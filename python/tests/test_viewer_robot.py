# SPDX-License-Identifier: BSD-3-Clause
"""The viewer draws robots (issue #30 item 6, docs/robots.md): a robot's links, joint axes and
the desired path of a task-space requirement. The page computes the links' frames itself
(forward kinematics in JavaScript from the joints' origins, axes and coordinates); checked here
against the library's own forward kinematics: the foot of leg_four_bar_knee is where its pose
requirement's actual value (desired + error, computed by the tree in C++) says, at every frame
shown, to the rounding of the angles (1e-4 rad)."""

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
