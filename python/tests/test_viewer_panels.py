# SPDX-License-Identifier: BSD-3-Clause
"""The viewer's control torques, magnitudes, triads, joint axes and chart legends (issue #33
item 5, docs/viewer.md), in headless Chromium (test_viewer.py's browser).

The two-link arm of tests/data/arm_circle_bodies.yaml is actuated by torques at its joints, so
its trajectory has Qc_control.link1.theta and Qc_control.link2.theta (the generalized control
forces of the links' angles, in N·m). The page draws each as a torque arc on its body, in the
control colour, and its readout gives each drawn arrow's magnitude: checked here against the
command's trajectory.csv at the frame shown (the page keeps 4 significant digits: the CSV's value
so rounded, to 1e-9 relative). The toggles are checked by what they draw (the triads' red x axes,
the joint axes' world directions: a planar revolute joint turns about z, at its point)."""

import csv
import json
import math
import os
import pathlib
import subprocess

import numpy as np
import pytest

import ukdyn
from test_viewer import Page, _mask, browser  # noqa: F401 (the browser fixture)
from ukdyn import viewer

ROOT = pathlib.Path(__file__).resolve().parents[2]
ARM = ROOT / "tests" / "data" / "arm_circle_bodies.yaml"
OPENING = '<script type="application/json" id="ukdyn-data">'


def _page_data(html: str):
    start = html.index(OPENING) + len(OPENING)
    return json.loads(html[start:html.index("</script>", start)])


@pytest.fixture(scope="module")
def arm_run(tmp_path_factory):
    """`ukdyn run` of the arm (3 s), with its page: the output directory."""
    cli = os.environ.get("UKDYN_CLI")
    if not cli or not os.access(cli, os.X_OK):
        pytest.skip("UKDYN_CLI (the command) is not set")
    out = tmp_path_factory.mktemp("arm") / "run"
    proc = subprocess.run([cli, "run", str(ARM), "-o", str(out), "--no-plots", "--viewer"],
                          capture_output=True, text=True, timeout=180)
    assert proc.returncode == 0, proc.stderr
    return out


def _csv_rows(path: pathlib.Path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    return rows[0], np.array(rows[1:], float)


def test_the_commands_arm_page_is_pythons_and_has_the_control_torques(arm_run):
    page = (arm_run / "animation.html").read_text(encoding="utf-8")
    scene = json.loads(ukdyn.load(ARM)._scene_json)
    names, columns = viewer.read_csv(arm_run / "trajectory.csv")
    assert page == viewer.build_page(scene, names, columns)
    data = _page_data(page)
    link1, link2 = data["bodies"]
    # a planar body's control torque is about z only; no control force (the arm has none)
    for body in (link1, link2):
        assert body["control_torque"][:2] == [None, None]
        assert len(body["control_torque"][2]) == len(data["t"])
        assert "control" not in body
    assert data["units"]["link1.theta"] == "rad" and data["units"]["link1.x"] == "m"
    # the peak of 10.44 N·m of the report
    peak = max(abs(v) for v in link1["control_torque"][2])
    assert peak == pytest.approx(10.44, abs=0.005)
    assert data["force_scale"]["control_torque"] > 0
    # the joints carry their axes (revolute: the child frame's z, here the plane's normal)
    for joint in data["joints"]:
        assert (joint["axis"], joint["axis_on"]) == ([0.0, 0.0, 1.0], "child")


def test_the_control_torque_is_drawn_with_the_csvs_magnitude(browser, arm_run):  # noqa: F811
    header, rows = _csv_rows(arm_run / "trajectory.csv")
    t, torque = rows[:, header.index("t")], rows[:, header.index("Qc_control.link1.theta")]
    page = Page(browser, arm_run / "animation.html")
    assert page.errors() == []
    times = page.js("return ukdyn.data.t")
    # the frame shown nearest the peak, and one later
    for frame in (int(np.argmin(np.abs(np.array(times) - t[np.argmax(np.abs(torque))]))), 60):
        page.js("ukdyn.setFrame(arguments[0])", frame)
        row = int(np.argmin(np.abs(t - times[frame])))
        assert t[row] == pytest.approx(times[frame], abs=1e-6)
        csv_value = abs(torque[row])
        readout = {m["name"]: m for m in page.js("return ukdyn.magnitudes()")}
        m = readout["control torque on link1"]
        assert (m["kind"], m["torque"], m["unit"], m["drawn"]) == ("control", True, "N·m", True)
        rounded = abs(float("%.4g" % csv_value))
        assert m["value"] == pytest.approx(rounded, rel=1e-9)
        assert m["value"] == pytest.approx(csv_value, rel=5e-4)  # 4 significant digits
        # the side panel says it, with its unit
        text = page.js("return document.getElementById('magnitudes').textContent")
        assert "control torque on link1: %s N·m" % ("%#.4g" % m["value"]) in text
        assert "constraint force at shoulder" in readout
        assert readout["constraint force at shoulder"]["unit"] == "N"
    # turning the control off removes its arrows and their lines
    page.js("ukdyn.show('control', false)")
    assert not any(m["kind"] == "control" for m in page.js("return ukdyn.magnitudes()"))
    page.js("ukdyn.show('control', true)")


def test_the_triads_and_joint_axes_are_drawn_on_request(browser, arm_run):  # noqa: F811
    page = Page(browser, arm_run / "animation.html")
    # off by default, and their boxes unchecked
    assert page.js("return ukdyn.triadsShown()") == 0
    axes = page.js("return ukdyn.jointAxes()")
    assert len(axes) == 2 and not any(a["visible"] for a in axes)
    assert page.js("return [document.getElementById('show-triads').checked, "
                   "document.getElementById('show-axes').checked]") == [False, False]
    page.js("ukdyn.show('ideal', false); ukdyn.show('control', false); ukdyn.show('trails', false)")
    page.js("ukdyn.setFrame(40)")
    red_before = int(_mask(page.pixels(), "#cc0000").sum())
    page.js("ukdyn.show('triads', true)")
    assert page.js("return ukdyn.triadsShown()") == 2
    red_after = int(_mask(page.pixels(), "#cc0000").sum())
    assert red_before == 0 and red_after > 50
    page.js("ukdyn.show('axes', true)")
    shoulder, elbow = page.js("return ukdyn.jointAxes()")
    assert shoulder["visible"] and elbow["visible"]
    for a in (shoulder, elbow):  # a planar revolute joint's axis is the plane's normal
        np.testing.assert_allclose(a["direction"], [0, 0, 1], atol=1e-12)
    # at the joints' points: the shoulder at the origin, the elbow at link1's far end
    data = page.js("return ukdyn.data")
    x, y, th = (data["bodies"][0]["q"][k][40] for k in range(3))
    np.testing.assert_allclose(shoulder["position"], [0, 0, 0], atol=2e-3)
    np.testing.assert_allclose(elbow["position"], [x + 0.3 * math.cos(th), y + 0.3 * math.sin(th), 0],
                               atol=2e-3)
    page.js("ukdyn.show('triads', false); ukdyn.show('axes', false)")
    assert page.js("return ukdyn.triadsShown()") == 0
    assert not any(a["visible"] for a in page.js("return ukdyn.jointAxes()"))
    assert page.errors() == []


def test_the_charts_have_legends_and_units(browser, arm_run):  # noqa: F811
    page = Page(browser, arm_run / "animation.html")
    legend = page.js("return [...document.querySelectorAll('#chart-legend div')]"
                     ".map((d) => d.textContent)")
    assert legend[:2] == ["tip.0", "tip.1"]
    assert "t [s]" in legend[2] and "error" in legend[2]
    paths = page.js("return document.getElementById('paths-legend').textContent")
    assert "tip.0" in paths and "t [s]" in paths and "dashed: desired" in paths
    # each series' key in its line's colour (the palette's first two)
    colours = page.js("return [...document.querySelectorAll('#chart-legend .key')]"
                      ".map((k) => getComputedStyle(k).backgroundColor)")
    assert colours == ["rgb(31, 119, 180)", "rgb(255, 127, 14)"]
    # a model without requirements has no chart and no legend
    other = Page(browser, _pendulum_page(arm_run.parent))
    assert other.js("return getComputedStyle(document.getElementById('chart-legend')).display") \
        == "none"


def _pendulum_page(directory: pathlib.Path) -> pathlib.Path:
    path = directory / "pendulum.html"
    ukdyn.load("pendulum").simulate(t_end=0.5).save_animation(path)
    return path


def test_a_points_forces_are_in_its_coordinates_units(tmp_path):
    """The page's units are the model's: a point that is exactly coordinates in m carries forces
    in N; a planar body's torque is in N·m (its angle in rad)."""
    data = viewer.scene_data(
        {"model": "m", "coordinates": ["x", "y", "b.theta"], "coordinate_units": ["m", "m", ""],
         "points": [{"name": "p", "dimensions": 2, "coordinates": ["x", "y"]}]},
        ["t", "x", "y", "visual.p.x", "visual.p.y", "Qc_ideal.x", "Qc_ideal.y"],
        [[0.0, 1.0], [0.0, 0.1], [1.0, 1.0], [0.0, 0.1], [1.0, 1.0], [3.0, 3.0], [4.0, 4.0]])
    assert data["units"] == {"x": "m", "y": "m"}
    assert data["points"][0]["ideal"] == [[3, 3], [4, 4]]


def test_the_page_carries_the_models_units_when_not_si():
    """units: {length: mm, mass: g, time: ms}: the page's time, energy and forces are labelled
    in them (data["unit_system"], which the page's script reads; docs/model-format.md, "Units");
    an SI model's page carries none and keeps its SI labels."""
    scene = {"model": "m", "coordinates": ["x"], "coordinate_units": ["mm"]}
    names, columns = ["t", "x"], [[0.0, 1.0], [0.0, 0.1]]
    mm = {"length": "mm", "mass": "g", "time": "ms", "velocity": "mm/ms", "force": "g·mm/ms²",
          "energy": "g·mm²/ms²", "power": "g·mm²/ms³"}
    data = viewer.scene_data(scene, names, columns, unit_system=mm)
    assert data["unit_system"] == {"length": "mm", "time": "ms", "force": "g·mm/ms²",
                                   "energy": "g·mm²/ms²"}
    si = dict(mm, length="m", mass="kg", time="s", force="N", energy="J")
    assert "unit_system" not in viewer.scene_data(scene, names, columns, unit_system=si)
    assert "unit_system" not in viewer.scene_data(scene, names, columns)


def _rotate(q, v):
    """v turned by the unit quaternion q = (w, x, y, z) (normalized here): R(q) v."""
    w, x, y, z = np.array(q, float) / np.linalg.norm(q)
    R = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                  [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                  [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])
    return R @ np.array(v, float)


def test_a_spatial_joints_axis_is_its_bodies_axis(browser, tmp_path):  # noqa: F811
    """The Bricard linkage's six revolute joints (examples/models/bricard.yaml: each joint's
    parent_axis and child_axis): the page's axis of a joint, drawn from its child's pose, is the
    parent's axis turned by the parent's pose too (the joint keeps them aligned), to the
    rounding of the quaternions (1e-4)."""
    result = ukdyn.load("bricard").simulate(t_end=0.5)
    path = tmp_path / "bricard.html"
    result.save_animation(path)
    page = Page(browser, path)
    page.js("ukdyn.show('axes', true)")
    page.js("ukdyn.setFrame(10)")
    data = page.js("return ukdyn.data")
    bodies = {b["name"]: b for b in data["bodies"]}
    parent_axes = {"j1": [0, 1, 0], "j2": [0, 0, 1]}  # the model file's parent_axis
    drawn = page.js("return ukdyn.jointAxes()")
    for k, joint in enumerate(data["joints"][:2]):
        assert drawn[k]["visible"]
        want = np.array(parent_axes[joint["name"]], float)
        if joint["parent"] != "ground":
            want = _rotate([c[10] for c in bodies[joint["parent"]]["q"][3:]], want)
        np.testing.assert_allclose(drawn[k]["direction"], want, atol=1e-3)
    assert page.errors() == []


def test_a_rigid_bodys_control_torque_does_the_quaternion_forces_work():
    """A rigid body's control torque tau (world axes) from its quaternion forces Q: its power
    tau . omega is Q . u' for omega along each axis (u' = 1/2 (0, omega) u, the quaternion
    product), to the page's 4 significant digits (app/tests/test_viewer_page.cpp, the same)."""
    u = np.array([0.3, -0.5, 0.7, 0.4]) / np.linalg.norm([0.3, -0.5, 0.7, 0.4])
    Q = [1.3, -0.4, 2.2, 0.9]
    names = ["t", "top.x", "top.y", "top.z", "top.u0", "top.u1", "top.u2", "top.u3",
             "Qc_control.top.u0", "Qc_control.top.u1", "Qc_control.top.u2", "Qc_control.top.u3"]
    values = [0.0, 0.0, 0.0, 0.0, *u, *Q]
    data = viewer.scene_data({"model": "m", "planar": False,
                              "bodies": [{"name": "top", "kind": "rigid", "mass": 1.0}]},
                             names, [[0.0, 1.0]] + [[v, v] for v in values[1:]])
    tau = data["bodies"][0]["control_torque"]
    w, v = u[0], u[1:]
    for axis in range(3):
        omega = np.eye(3)[axis]
        ud = 0.5 * np.concatenate([[-omega @ v], w * omega + np.cross(omega, v)])
        power = float(np.dot(Q, ud))
        assert tau[axis][0] == pytest.approx(power, rel=5e-4)
