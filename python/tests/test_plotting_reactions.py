# SPDX-License-Identifier: BSD-3-Clause
"""The joint reactions figure (ukdyn/plotting_reactions.py) and the plots' faster drawing
(ukdyn/plotting.py: plain-text log labels, two processes in the command): the figures' objects
are read back — line data, axis labels, titles — never their pixels."""

import os
import subprocess

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

import ukdyn  # noqa: E402
from ukdyn import plotting  # noqa: E402

# a uniform rod of mass m and length L pinned at one end to the ground (a planar revolute joint
# at the origin), released at th0 below the horizontal turning at w; gravity along -y
M, L, G, TH0, W = 2.0, 1.2, 9.81, -1.1, 1.5
ROD = """
name: rod on a pin
parameters: {m: %r, L: %r, g: %r, th0: %r, w: %r}
bodies:
  - {name: rod, type: planar, mass: m, inertia: m*L^2/12,
     position: [L/2*cos(th0), L/2*sin(th0)], angle: th0,
     velocity: [-L/2*w*sin(th0), L/2*w*cos(th0)], angular_velocity: w}
joints:
  - {name: pin, type: revolute, parent: ground, child: rod, parent_point: [0, 0],
     child_point: [-L/2, 0]}
forces:
  - {type: gravity, g: [0, -g]}
simulate: {t_end: 2}
output: {every: 0.05}
""" % (M, L, G, TH0, W)


def rod_reaction(theta, omega):
    """The pin's force on the rod (x and y rows) at angle θ and rate ω, from Newton's law for
    its centre of mass, l = L/2 from the pin: F = m a − m g_vec with a = l (−ω² e + α e⊥),
    e = (cos θ, sin θ), e⊥ = (−sin θ, cos θ), and α = −m g l cos θ / (m L²/3) from the moment
    of gravity about the pin. Hanging still (θ = −π/2, ω = 0) it is (0, m g); along the rod
    it is the familiar m (l ω² + g cos φ) towards the pin, φ = θ + π/2."""
    l = L / 2
    alpha = -M * G * l * np.cos(theta) / (M * L * L / 3)
    e = np.array([np.cos(theta), np.sin(theta)])
    n = np.array([-np.sin(theta), np.cos(theta)])
    a = l * (-omega ** 2 * e + alpha * n)
    return M * a + np.array([0.0 * theta, M * G + 0.0 * theta])


@pytest.fixture(scope="module")
def rod():
    return ukdyn.parse(ROD, "rod.yaml").simulate()


@pytest.fixture(autouse=True)
def close_figures():
    yield
    plt.close("all")


def line(fig, gid):
    found = [ln for ax in fig.axes for ln in ax.get_lines() if ln.get_gid() == gid]
    assert len(found) == 1, (gid, [ln.get_gid() for ax in fig.axes for ln in ax.get_lines()])
    return found[0]


def test_rod_pin_force_is_newtons_law(rod):
    fig = rod.figures()["joint_reactions"]
    fx, fy = line(fig, "reaction.pin.fx"), line(fig, "reaction.pin.fy")
    t = np.asarray(fx.get_xdata())
    theta, omega = np.asarray(rod["rod.theta"]), np.asarray(rod["rod.theta_dot"])
    assert np.array_equal(t, np.asarray(rod["t"]))
    expected = rod_reaction(theta, omega)
    samples = [0, 7, 15, 23, len(t) - 1]
    assert len(t) == 41
    for k in samples:
        assert fx.get_ydata()[k] == pytest.approx(expected[0][k], abs=1e-6)
        assert fy.get_ydata()[k] == pytest.approx(expected[1][k], abs=1e-6)
    # not a trivial agreement: the force swings over more than m g, the rod over a wide arc
    assert np.ptp(np.asarray(fy.get_ydata())) > 0.5 * M * G
    assert np.ptp(theta) > 0.5
    # a revolute joint passes no torque about its axis: roundoff, so no torque column is drawn
    assert np.max(np.abs(rod["reaction.pin.tz"])) < 1e-9
    assert [ax.get_ylabel() for ax in fig.axes] == ["pin: force [N]"]
    assert fig.axes[-1].get_xlabel() == "t [s]"
    assert fig._suptitle.get_text() == ("rod on a pin: joint reactions on the child (world "
                                        "frame, at the joint); no torque (at roundoff)")
    assert [t.get_text() for t in fig.axes[0].get_legend().get_texts()] == ["fx", "fy"]


def test_rod_figure_file_and_command(rod, cli, tmp_path):
    written = rod.save_plots(str(tmp_path / "module"))
    assert str(tmp_path / "module" / "joint_reactions.png") in written
    model = tmp_path / "rod.yaml"
    model.write_text(ROD)
    out = tmp_path / "command"
    done = subprocess.run([cli, "run", str(model), "-o", str(out)], capture_output=True,
                          text=True)
    assert done.returncode == 0, done.stderr
    assert (out / "joint_reactions.png").stat().st_size > 10000
    # the command writes the figures that the module makes (its two processes share them)
    pngs = sorted(f[:-4] for f in os.listdir(out) if f.endswith(".png"))
    assert pngs == sorted(rod.figures())
    # and no figure of a model without joints
    assert "joint_reactions" not in ukdyn.load("pendulum").simulate(t_end=0.2).figures()


def test_drive_row():
    crank = ukdyn.load("slider_crank").simulate(t_end=0.25)
    fig = crank.figures()["joint_reactions"]
    labels = [ax.get_ylabel() for ax in fig.axes]
    assert labels == ["|reaction force| [N]", "drive effort\n[N·m; N prismatic]"]
    drive = line(fig, "drive.pin")
    assert np.array_equal(drive.get_ydata(), crank["drive.pin"])
    assert np.max(np.abs(crank["drive.pin"])) > 1.0
    assert fig.axes[-1].get_xlabel() == "t [s]" and fig.axes[0].get_xlabel() == ""


def test_many_joints_drawn_as_magnitudes():
    loop = ukdyn.load("pendulum_loop").simulate(t_end=0.2)
    fig = loop.figures()["joint_reactions"]
    from ukdyn.plotting_reactions import MAX_JOINT_ROWS, joints
    found = joints(loop)
    assert len(found) > MAX_JOINT_ROWS
    assert [ax.get_ylabel() for ax in fig.axes] == ["|reaction force| [N]"]
    for name, columns in found:
        magnitude = line(fig, "|reaction.%s.f|" % name).get_ydata()
        np.testing.assert_allclose(
            magnitude, np.hypot(loop[columns["fx"]], loop[columns["fy"]]), rtol=1e-14)
    assert len(fig.axes[0].get_lines()) == len(found)


def test_spatial_joint_has_three_components(pendulum_top):
    fig = pendulum_top.figures()["joint_reactions"]
    assert [t.get_text() for t in fig.axes[0].get_legend().get_texts()] == ["fx", "fy", "fz"]
    # the top's weight is carried at the tip: fz averages about m g over a precession
    assert np.all(np.abs(line(fig, "reaction.tip.fz").get_ydata()) > 0)


@pytest.fixture(scope="module")
def pendulum_top():
    return ukdyn.load("heavy_top").simulate(t_end=0.1)


def test_log_axis_labels_are_plain_text():
    assert plotting.power_label(1e-6) == "10⁻⁶"
    assert plotting.power_label(1e3) == "10³"
    assert plotting.power_label(2e-12) == "2×10⁻¹²"
    assert plotting.power_label(5.0) == "5×10⁰"
    assert plotting.power_label(0.0) == ""
    fig = ukdyn.load("pendulum").simulate(t_end=0.5).figures()["violation"]
    ax = fig.axes[0]
    fig.canvas.draw()
    labels = [t.get_text() for t in ax.get_yticklabels() if t.get_text()]
    assert labels and all("$" not in s and "10" in s for s in labels)
    assert len(ax.yaxis.get_minor_locator().tick_values(1e-9, 1e-3)) == 0


def test_read_csv_thins_long_files(tmp_path, monkeypatch):
    path = tmp_path / "t.csv"
    rows = np.column_stack([np.arange(10.0), np.arange(10.0) ** 2])
    path.write_text("t,x\n" + "\n".join("%r,%r" % tuple(r) for r in rows) + "\n")
    table = plotting.read_csv(str(path))
    assert table.names == ["t", "x"] and np.array_equal(table["x"], rows[:, 1])
    from ukdyn import plotting_data  # (read_csv is its)
    monkeypatch.setattr(plotting_data, "MAX_ROWS", 4)
    thinned = plotting.read_csv(str(path))
    assert np.array_equal(thinned["t"], [0.0, 3.0, 6.0, 9.0])
    (tmp_path / "e.csv").write_text("t,x\n")
    assert len(plotting.read_csv(str(tmp_path / "e.csv"))["t"]) == 0
