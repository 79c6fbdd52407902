# SPDX-License-Identifier: BSD-3-Clause
"""Unilateral contacts as users see them (issue #31 item 5, docs/contact.md), from Python: the
bouncing ball of examples/models against its closed forms, the work_impact channel, the gap
columns, the contacts plot's data and the viewer page with its contacts in headless Chromium —
a robot's contacts too, drawn without a visual: section (arm_hits_floor: the marker and the
impact ring where the camera projects the fingertip's contact point; a pendulum resting on the
floor: its force m g L_c / L read out).

Closed forms (h0 = 1, g = 9.81, e = 0.5, m = 0.5): the first impact at t0 = sqrt(2 h0 / g) with
v0 = sqrt(2 g h0); the k-th rebound leaves at e^k v0, so the k-th apex is e^(2k) h0 and the
flight between impacts k and k + 1 lasts 2 e^k v0 / g; the impacts accumulate at
t_inf = t0 (1 + e) / (1 - e), where the ball comes to rest with the floor carrying m g. Each
impact takes (1 - e^2) of the kinetic energy: after k impacts work_impact = -m g h0 (1 - e^(2k)),
and at rest all of m g h0.
"""

import json
import math
import pathlib
import subprocess

import numpy as np
import pytest

import ukdyn
from test_viewer import Page, browser  # noqa: F401 (the browser fixture)
from ukdyn import plotting, viewer

H0, G, E, M = 1.0, 9.81, 0.5, 0.5
T0 = math.sqrt(2 * H0 / G)
V0 = math.sqrt(2 * G * H0)
T_INF = T0 * (1 + E) / (1 - E)


def impact_time(k):
    """The time of the k-th impact (k = 1, 2, …)."""
    return T0 + sum(2 * E ** j * V0 / G for j in range(1, k))


@pytest.fixture(scope="module")
def ball():
    return ukdyn.load("bouncing_ball").simulate()


def _impacts(result):
    return [e for e in result.contact_events if e["kind"] == "impact"]


def test_impact_times_and_speeds_are_the_closed_forms(ball):
    impacts = _impacts(ball)
    # the rest criterion (approach below 1e-6 of the first) ends the sequence near k = 20
    assert 15 <= len(impacts) <= 25
    for k, e in enumerate(impacts, start=1):
        assert e["contact"] == "floor"
        assert e["t"] == pytest.approx(impact_time(k), rel=1e-9, abs=1e-11)
        assert e["speed_before"] == pytest.approx(-E ** (k - 1) * V0, rel=1e-8)
        assert e["speed_after"] == pytest.approx(E ** k * V0, rel=1e-8)


def test_read_hdf5_gives_the_contact_events_of_the_run(ball, tmp_path):
    """A Result read back from its HDF5 file (ukdyn.read_hdf5) has the run's impacts and rest,
    the same as the live one's (before, its contact_events was empty: a silent "no impact")."""
    path = tmp_path / "ball.h5"
    ball.to_hdf5(path)
    back, summary = ukdyn.read_hdf5(path)
    assert len(summary["contact_events"]) == len(ball.contact_events) > 15
    assert len(back.contact_events) == len(ball.contact_events)
    for a, b in zip(back.contact_events, ball.contact_events):
        assert a["contact"] == b["contact"] == "floor"
        assert a["kind"] == b["kind"]
        assert a["t"] == b["t"]
    assert _impacts(back)[0]["t"] == pytest.approx(T0, rel=1e-9)


def test_apex_heights_are_e_to_the_2k_h0(ball):
    """Between impacts k and k + 1 the flight keeps y + y'^2 / (2 g) = e^(2k) h0 (its apex), at
    every sample; the highest sample of the flight is within (g/2) (dt/2)^2 below it."""
    t, y, v = ball["t"], ball["y"], ball["y_dot"]
    times = [e["t"] for e in _impacts(ball)]
    for k in range(1, 5):
        inside = (t > times[k - 1] + 1e-9) & (t < times[k] - 1e-9)
        assert inside.sum() >= 3
        apex = E ** (2 * k) * H0
        np.testing.assert_allclose(y[inside] + v[inside] ** 2 / (2 * G), apex, rtol=1e-8)
        assert apex - 0.5 * G * 0.005 ** 2 - 1e-9 <= y[inside].max() <= apex + 1e-9


def test_rest_time_and_the_floor_carrying_the_ball(ball):
    rest = [e for e in ball.contact_events if e["kind"] == "rest"]
    assert len(rest) == 1
    # early by the flights left out, about 1e-6 t_inf (docs/contact.md)
    assert rest[0]["t"] == pytest.approx(T_INF, rel=1e-5)
    assert rest[0]["t"] < T_INF
    after = ball["t"] > rest[0]["t"] + 0.01
    assert after.sum() > 50
    np.testing.assert_allclose(ball["y"][after], 0.0, atol=1e-9)
    np.testing.assert_allclose(ball["lambda.floor"][after], M * G, rtol=1e-8)
    assert any("came to rest" in n for n in ball.stats["notes"])


def test_work_impact_is_the_energy_the_impacts_took(ball):
    t, w = ball["t"], ball["work_impact"]
    times = [e["t"] for e in _impacts(ball)]
    for k in range(0, 6):  # between impacts k and k + 1 (before the first: none taken)
        lo = times[k - 1] if k else 0.0
        inside = (t > lo + 1e-9) & (t < times[k] - 1e-9)
        np.testing.assert_allclose(w[inside], -M * G * H0 * (1 - E ** (2 * k)), rtol=1e-9,
                                   atol=1e-12)
    assert w[-1] == pytest.approx(-M * G * H0, rel=1e-9)
    # the energy balance closes with it: E(t) - E(0) = W_impact (nothing else does work)
    energy = ball["energy"]
    np.testing.assert_allclose(energy - energy[0], w, atol=1e-8)


def test_gap_column_is_the_constraints_expression(ball):
    """gap.floor is the gap g = y: positive in flight, zero at the impacts and at rest."""
    np.testing.assert_array_equal(ball["gap.floor"], ball["y"])
    assert ball["gap.floor"].min() >= -1e-9
    assert ball["gap.floor"][0] == H0


def test_contacts_plot_draws_the_forces_gaps_and_impacts(ball):
    pytest.importorskip("matplotlib")
    import matplotlib
    matplotlib.use("Agg")
    fig = ball.figures()["contacts"]
    lines = {line.get_gid(): line for ax in fig.axes for line in ax.get_lines()}
    np.testing.assert_array_equal(lines["force.floor"].get_ydata(), ball["lambda.floor"])
    np.testing.assert_array_equal(lines["gap.floor"].get_xdata(), ball["t"])
    np.testing.assert_array_equal(lines["gap.floor"].get_ydata(), ball["y"])
    marked = lines["impacts.floor"].get_xdata()
    kinds = [e["kind"] for e in ball.contact_events]
    assert len(marked) == kinds.count("impact") + kinds.count("rest")
    np.testing.assert_allclose(marked[:5], [impact_time(k) for k in range(1, 6)], rtol=1e-9)
    np.testing.assert_array_equal(lines["impacts.floor"].get_ydata(), 0.0)
    matplotlib.pyplot.close(fig)


def test_a_run_without_contacts_has_no_contacts_plot():
    pytest.importorskip("matplotlib")
    import matplotlib
    matplotlib.use("Agg")
    figures = ukdyn.load("pendulum").simulate(t_end=0.2).figures()
    try:
        assert "contacts" not in figures
    finally:
        for f in figures.values():
            matplotlib.pyplot.close(f)


def test_the_commands_contacts_plot_reads_summary_json(cli, tmp_path):
    """ukdyn run writes contacts.png, and its data (read back as the command's script reads
    it: trajectory.csv with summary.json) marks the impacts of summary.json's contact_events."""
    pytest.importorskip("matplotlib")
    out = tmp_path / "run"
    proc = subprocess.run([cli, "run", "--example", "bouncing_ball", "-o", str(out),
                           "--no-viewer"], capture_output=True, text=True, timeout=180)
    assert proc.returncode == 0, proc.stderr
    assert (out / "contacts.png").stat().st_size > 5000
    summary = json.loads((out / "summary.json").read_text())
    events = summary["contact_events"]
    assert [e["contact"] for e in events] == ["floor"] * len(events)
    assert events[0]["kind"] == "impact"
    assert events[0]["t"] == pytest.approx(T0, rel=1e-9)
    assert events[-1]["kind"] == "rest"
    import matplotlib
    matplotlib.use("Agg")
    table = plotting.read_csv(str(out / "trajectory.csv"))
    fig = plotting.contacts_figure(table, plotting.read_summary(str(out / "summary.json")))
    marked = [line for ax in fig.axes for line in ax.get_lines()
              if line.get_gid() == "impacts.floor"][0].get_xdata()
    np.testing.assert_allclose(marked, [e["t"] for e in events], rtol=1e-15)
    matplotlib.pyplot.close(fig)


def test_viewer_data_of_the_contacts(ball):
    """The page's data: the contact's point and normal, its force lambda.floor (rounded to 4
    digits), and every impact of the run with its time."""
    data = viewer.scene_data(ball.scene, ball.names, ball._columns,
                             contact_events=ball.contact_events)
    (contact,) = data["contacts"]
    assert contact["name"] == "floor"
    shown = np.array(data["t"])
    y = np.interp(shown, ball["t"], ball["y"])
    np.testing.assert_allclose(contact["q"][1], y, atol=1e-4)
    assert set(contact["n"][0]) == {0} and set(contact["n"][1]) == {1}
    at_rest = shown > T_INF + 0.01
    np.testing.assert_allclose(np.array(contact["force"])[at_rest], M * G, rtol=1e-3)
    kinds = [e["kind"] for e in ball.contact_events]
    assert len(data["impacts"]) == kinds.count("impact") + kinds.count("rest")
    assert data["impacts"][0] == {"t": round(T0, 7 - 1 - math.floor(math.log10(T0))),
                                  "contact": "floor"}
    assert data["force_scale"]["contact"] == pytest.approx(M * G, rel=1e-3)


def test_visual_contact_errors_name_the_contact():
    base = ("name: b\ncoordinates: [y]\nkinetic_energy: 0.5*y_dot^2\npotential_energy: y\n"
            "constraints:\n  - {name: floor, holonomic: y, unilateral: true}\n"
            "  - {name: rod, holonomic: y - 2}\ninitial: {q: {y: 1}}\nvisual:\n  contacts:\n")
    cases = [("    wall: {at: [0, y], normal: [0, 1]}\n", "no unilateral constraint of that name"),
             ("    rod: {at: [0, y], normal: [0, 1]}\n", "no unilateral constraint of that name"),
             ("    floor: {at: [0, y], normal: [1]}\n", "normal must have as many components"),
             ("    floor: {at: [0], normal: [0, 1]}\n", "at must be [x, y] or [x, y, z]"),
             ("    floor: {at: [0, y], normal: [0, 1], size: 2}\n", "unknown key 'size'")]
    for text, message in cases:
        with pytest.raises(ukdyn.ModelError) as info:
            ukdyn.parse(base + text)
        assert message in str(info.value)
        assert "visual contact" in str(info.value)


def test_the_viewer_draws_the_contact_and_flashes_the_impacts(browser, ball, tmp_path):  # noqa: F811
    path = tmp_path / "bouncing_ball.html"
    ball.save_animation(path)
    page = Page(browser, path)
    assert page.errors() == []
    t = page.js("return ukdyn.data.t")
    # the frame just after the first impact: a ring flashes; long before it, none
    after = next(i for i, v in enumerate(t) if v >= T0)
    page.js("ukdyn.setFrame(arguments[0])", after)
    assert page.js("return ukdyn.impactsShown()") == 1
    from test_viewer import _mask
    ring = _mask(page.pixels(), "#ffb000", tolerance=0.08).sum()
    assert ring > 20
    page.js("ukdyn.setFrame(arguments[0])", 2)
    assert page.js("return ukdyn.impactsShown()") == 0
    assert _mask(page.pixels(), "#ffb000", tolerance=0.08).sum() == 0
    # at rest the floor's force m g is drawn: the contact colour shows, and goes when turned off
    page.js("ukdyn.setFrame(arguments[0])", len(t) - 1)
    assert _mask(page.pixels(), "#0050ff").sum() > 30
    page.js("ukdyn.show('contact', false)")
    assert _mask(page.pixels(), "#0050ff").sum() == 0
    page.js("ukdyn.show('contact', true)")
    assert page.errors() == []
    page.save("bouncing_ball.png")


def test_cam_follower_jumps_at_the_closed_form():
    """examples/models/cam_follower_jump.yaml: the cam h(t) = a (1 - cos w t) pushes with
    N = m (a w^2 cos w t + g) until that is zero, at cos w t* = -g / (a w^2); the follower leaves
    at the cam's speed a w sin w t*, flies freely, lands where its parabola meets h(t) (found
    here by bisection) with a plastic impact, and leaves again one cam period after t*."""
    m, g, a, w = 0.2, 9.81, 0.02, 30.0
    result = ukdyn.load("cam_follower_jump").simulate()
    events = result.contact_events
    assert events[0]["kind"] == "release" and events[0]["contact"] == "cam"
    t_star = math.acos(-g / (a * w * w)) / w
    assert events[0]["t"] == pytest.approx(t_star, abs=1e-9)
    y_star, v_star = a * (1 - math.cos(w * t_star)), a * w * math.sin(w * t_star)
    assert v_star == pytest.approx(0.5031, abs=1e-4)

    def lift(t):
        return a * (1 - math.cos(w * t))

    def flight(t):
        return y_star + v_star * (t - t_star) - 0.5 * g * (t - t_star) ** 2

    lo, hi = t_star + 1e-3, t_star + 0.19  # the parabola is above the cam, then below
    assert flight(lo) > lift(lo) and flight(hi) < lift(hi)
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if flight(mid) > lift(mid) else (lo, mid)
    landing = [ev for ev in events if ev["kind"] == "impact"][0]
    assert landing["t"] == pytest.approx(lo, abs=1e-8)
    approach = (v_star - g * (lo - t_star)) - a * w * math.sin(w * lo)
    assert landing["speed_before"] == pytest.approx(approach, rel=1e-6)
    assert landing["speed_after"] == pytest.approx(0.0, abs=1e-9)
    again = [ev for ev in events if ev["kind"] == "release"][1]
    assert again["t"] == pytest.approx(t_star + 2 * math.pi / w, abs=1e-9)
    t, y, lam = result["t"], result["y"], result["lambda.cam"]
    before = t < t_star - 1e-9
    np.testing.assert_allclose(lam[before], m * (a * w * w * np.cos(w * t[before]) + g),
                               rtol=1e-7, atol=1e-9)
    flying = (t > t_star + 1e-9) & (t < landing["t"] - 1e-9)
    assert flying.sum() > 10
    np.testing.assert_allclose(y[flying], [flight(s) for s in t[flying]], atol=1e-9)
    np.testing.assert_allclose(lam[flying], 0.0, atol=1e-12)
    assert result["gap.cam"][flying].min() > 0


# the rod of tests/contact/test_impact_restitution.cpp: a rod (m = 1, length 2l = 2, at 45°) in
# the coordinates of its lower end A, translating at (u, -1) onto a floor with friction mu
ROD = """coordinates: [xa, ya, phi]
kinetic_energy: >-
  0.5*((xa_dot - sin(phi)*phi_dot)^2 + (ya_dot + cos(phi)*phi_dot)^2) + 0.5/3*phi_dot^2
constraints:
  - {{name: floor, holonomic: ya, unilateral: true, restitution: 0.5, restitution_law: {law}}}
{friction}initial:
  q: {{xa: 0, ya: 0.1, phi: 0.7853981633974483}}
  q_dot: {{xa: 0.5, ya: -1, phi: 0}}
simulate: {{t_end: 0.15, integrator: dopri5, rtol: 1e-11, atol: 1e-13}}
output: {{every: 0}}
"""


def _rod_impact(law, mu):
    friction = (f"nonideal:\n  - {{friction: coulomb, constraint: floor, mu: {mu}, "
                f"coordinates: [xa]}}\n" if mu else "")
    result = ukdyn.parse(ROD.format(law=law, friction=friction)).simulate()
    return [e for e in result.contact_events if e["kind"] == "impact"][0]


def test_poisson_restitution_from_a_model_file():
    """docs/contact.md, "Poisson's restitution" (in C++: tests/contact/test_impact_restitution.cpp).
    At A, W = [[2.5, -1.5], [-1.5, 2.5]] (n, t). Smooth floor: both laws give g'+ = e v = 0.5
    with the impulse (1 + e) v / W_nn = 0.6. Rough floor (mu = 2, A ends stuck): Newton's
    g'+ = 0.5, Poisson's e (det W / W_tt) P_c = 0.35 with P_c = [-W^-1 v-]_n = 0.4375 and the
    whole impulse (1 + e) P_c; T+ - T- = -0.16484375."""
    for law in ("newton", "poisson"):
        smooth = _rod_impact(law, 0)
        assert smooth["speed_after"] == pytest.approx(0.5, abs=1e-12)
        assert smooth["impulse"] == pytest.approx(0.6, abs=1e-12)
    newton, poisson = _rod_impact("newton", 2), _rod_impact("poisson", 2)
    assert newton["speed_after"] == pytest.approx(0.5, abs=1e-12)
    assert poisson["speed_after"] == pytest.approx(0.35, abs=1e-12)
    assert poisson["impulse"] == pytest.approx(1.5 * 0.4375, abs=1e-12)
    assert poisson["energy_change"] == pytest.approx(-0.16484375, abs=1e-12)
    with pytest.raises(ukdyn.ModelError) as info:
        ukdyn.parse(ROD.format(law="posson", friction=""))
    assert "<string>:5:87: error: the restitution_law" in str(info.value)
    assert "must be newton or poisson, got 'posson'" in str(info.value)


# a block on a rough incline pulled off it along the normal (tests/simulation/
# test_contact_friction.cpp, docs/contact.md "Friction at contacts"), with its contact drawn
INCLINE = """parameters: {m: 2, g: 9.81, alpha: 0.3, mu: 0.25, k: 10, v0: 0.2}
coordinates: [x, y]
mass_matrix: [[m, 0], [0, m]]
forces: [k*t*sin(alpha), k*t*cos(alpha) - m*g]
constraints:
  - {name: plane, holonomic: x*sin(alpha) + y*cos(alpha), unilateral: true}
nonideal:
  - {friction: coulomb, constraint: plane, mu: mu}
initial:
  q: {x: 0, y: 0}
  q_dot: {x: v0*cos(alpha), y: -v0*sin(alpha)}
simulate: {t_end: 2.4, integrator: dopri5, rtol: 1e-10, atol: 1e-12}
output: {every: 0.01}
visual:
  points:
    block: {at: [x, y], radius: 0.05}
  contacts:
    plane: {at: [x, y], normal: [sin(alpha), cos(alpha)]}
"""
ALPHA, MU, K, MASS = 0.3, 0.25, 10.0, 2.0
T_OFF = MASS * G * math.cos(ALPHA) / K  # where N = m g cos(alpha) - k t reaches 0


@pytest.fixture(scope="module")
def incline():
    return ukdyn.parse(INCLINE).simulate()


def test_viewer_data_of_the_friction_at_a_contact(incline):
    """While the block slides down the slope s = (cos a, -sin a) the plane's friction is
    mu N up the slope, -mu (m g cos a - k t) s; off the plane (t > t*) there is none. The scene
    maps the sliding coordinates (x, y) to the page's axes by the identity."""
    (c,) = incline.scene["contacts"]
    assert c["friction"]["map"] == [[1, 0], [0, 1]]
    assert c["friction"]["mu"] == MU
    data = viewer.scene_data(incline.scene, incline.names, incline._columns,
                             contact_events=incline.contact_events)
    (contact,) = data["contacts"]
    t = np.array(data["t"])
    fx, fy = (np.array(v, dtype=float) for v in contact["friction_force"])
    on = (t > 0.05) & (t < T_OFF - 0.05)
    assert on.sum() > 20
    N = MASS * G * math.cos(ALPHA) - K * t[on]
    np.testing.assert_allclose(fx[on], -MU * N * math.cos(ALPHA), rtol=1e-3, atol=1e-6)
    np.testing.assert_allclose(fy[on], MU * N * math.sin(ALPHA), rtol=1e-3, atol=1e-6)
    off = t > T_OFF + 0.05
    assert off.sum() > 10
    np.testing.assert_allclose(fx[off], 0.0, atol=1e-9)
    np.testing.assert_allclose(fy[off], 0.0, atol=1e-9)


def test_the_viewer_draws_the_friction_at_a_contact(browser, incline, tmp_path):  # noqa: F811
    """The friction arrow in its colour (purple) while the block slides, none once it is off;
    the contacts box hides it with the normal force."""
    from test_viewer import _mask
    path = tmp_path / "incline.html"
    incline.save_animation(path)
    page = Page(browser, path)
    assert page.errors() == []
    t = page.js("return ukdyn.data.t")
    sliding = next(i for i, v in enumerate(t) if v >= 0.3 * T_OFF)
    page.js("ukdyn.setFrame(arguments[0])", sliding)
    assert _mask(page.pixels(), "#9b30ff").sum() > 30
    assert _mask(page.pixels(), "#0050ff").sum() > 30
    page.save("incline_friction.png")
    page.js("ukdyn.show('contact', false)")
    assert _mask(page.pixels(), "#9b30ff").sum() == 0
    page.js("ukdyn.show('contact', true)")
    flying = next(i for i, v in enumerate(t) if v >= T_OFF + 0.3)
    page.js("ukdyn.setFrame(arguments[0])", flying)
    assert _mask(page.pixels(), "#9b30ff").sum() == 0
    assert page.errors() == []


@pytest.fixture(scope="module")
def rolling_ball():
    return ukdyn.load("ball_rolls_after_sliding").simulate()


ROLL_T = 2 * 4.0 / (7 * 0.2 * G)  # the ball (v0 = 4, mu = 0.2, m = 6) rolls from t* = 2 v0/(7 mu g)


def test_viewer_data_of_the_friction_at_a_contact_point(rolling_ball):
    """Friction at a body's contact point (docs/viewer.md): the run's own columns
    visual.contact.floor.fx, fy, fz, read with the identity map — -mu m g along x while the ball
    slides, none once it rolls."""
    (c,) = rolling_ball.scene["contacts"]
    assert c["friction"]["columns"] == [["visual.contact.floor.f" + a] for a in "xyz"]
    assert c["friction"]["map"] == [[1, 0, 0], [0, 1, 0], [0, 0, 1]]
    data = viewer.scene_data(rolling_ball.scene, rolling_ball.names, rolling_ball._columns,
                             contact_events=rolling_ball.contact_events)
    (contact,) = data["contacts"]
    t = np.array(data["t"])
    fx, fy, fz = (np.array(v, dtype=float) for v in contact["friction_force"])
    sliding, rolling = t < ROLL_T - 0.01, t > ROLL_T + 0.01
    assert sliding.sum() > 10 and rolling.sum() > 10
    np.testing.assert_allclose(fx[sliding], -0.2 * 6 * G, rtol=1e-3)
    np.testing.assert_allclose(fx[rolling], 0.0, atol=1e-3)
    np.testing.assert_allclose(fy, 0.0, atol=1e-9)
    np.testing.assert_allclose(fz, 0.0, atol=1e-9)
    # one force per contact: the contact is not also drawn as a joint
    assert data["joints"] == []


def test_contacts_plot_has_units_and_a_friction_panel(rolling_ball):
    """contacts.png's axes carry units (repro u13/08): a body's contact's gap is a distance, in
    the length unit, its normal force in the force unit; with Coulomb friction at the contact a
    third panel draws the friction force (the run's visual.contact.floor.f* columns: -mu m g
    along x while it slides). In mm, g, ms the labels are those units'; a generalized model's
    gap has the unit its coordinates share (bouncing_ball: y in m, so m and N; u24), and one
    whose coordinates have none has none (never a guessed label)."""
    pytest.importorskip("matplotlib")
    import matplotlib
    matplotlib.use("Agg")
    assert rolling_ball.units["gap.floor"] == "m"
    fig = rolling_ball.figures()["contacts"]
    labels = [ax.get_ylabel() for ax in fig.axes]
    assert labels == ["normal force λ [N]", "gap g [m]", "friction force [N]"]
    lines = {line.get_gid(): line for ax in fig.axes for line in ax.get_lines()}
    fx = lines["friction.floor.fx"].get_ydata()
    np.testing.assert_array_equal(fx, rolling_ball["visual.contact.floor.fx"])
    sliding = rolling_ball["t"] < ROLL_T - 0.01
    np.testing.assert_allclose(fx[sliding], -0.2 * 6 * G, rtol=1e-9)
    matplotlib.pyplot.close(fig)
    text = ukdyn.example_text("ball_rolls_after_sliding")
    mm = ukdyn.parse(text + "units: {length: mm, mass: g, time: ms}\n", "mm.yaml")
    assert mm.units["gap.floor"] == "mm"
    fig = mm.simulate(t_end=0.1).figures()["contacts"]
    assert [ax.get_ylabel() for ax in fig.axes] == [
        "normal force λ [g·mm/ms²]", "gap g [mm]", "friction force [g·mm/ms²]"]
    matplotlib.pyplot.close(fig)
    ball = ukdyn.load("bouncing_ball")
    assert ball.units["gap.floor"] == "m" and ball.units["lambda_total.floor"] == "N"
    fig = ball.simulate(t_end=0.1).figures()["contacts"]
    assert [ax.get_ylabel() for ax in fig.axes] == ["normal force λ [N]", "gap g [m]"]
    matplotlib.pyplot.close(fig)


def test_the_viewer_draws_the_friction_at_a_contact_point(browser, rolling_ball,  # noqa: F811
                                                           tmp_path):
    """The purple friction arrow at the ball's contact point while it slides, none once it
    rolls."""
    from test_viewer import _mask
    path = tmp_path / "rolling.html"
    rolling_ball.save_animation(path)
    page = Page(browser, path)
    assert page.errors() == []
    t = page.js("return ukdyn.data.t")
    page.js("ukdyn.setFrame(arguments[0])", next(i for i, v in enumerate(t) if v >= 0.2))
    page.save("rolling_ball_friction.png")
    # (a short arrow, mu = 0.2 of the normal force's, partly behind the ball)
    assert _mask(page.pixels(), "#9b30ff").sum() > 5
    assert "friction force at floor: 11.77 N" in page.js("return document.body.innerText")
    page.js("ukdyn.setFrame(arguments[0])", next(i for i, v in enumerate(t) if v >= ROLL_T + 0.3))
    assert _mask(page.pixels(), "#9b30ff").sum() == 0
    assert page.errors() == []


def test_the_commands_friction_at_a_contact_is_pythons(cli, tmp_path):
    """The command's page (app/viewer_data.cpp) carries the same friction arrows as viewer.py's
    from the same trajectory, byte for byte."""
    from test_viewer_page import _page_data, _python_page, _run
    model = tmp_path / "incline.yaml"
    model.write_text(INCLINE, encoding="utf-8")
    out = tmp_path / "run"
    proc = _run(cli, [str(model)], out)
    assert proc.returncode == 0, proc.stderr
    page = (out / "animation.html").read_text(encoding="utf-8")
    expected = _python_page(model, out / "trajectory.csv")
    assert _page_data(page)["contacts"][0]["friction_force"] == \
        _page_data(expected)["contacts"][0]["friction_force"]
    assert page == expected


@pytest.fixture(scope="module")
def arm():
    """examples/models/arm_hits_floor.yaml: no visual: section; its fingertip contact is drawn
    from the robot's forward kinematics (src/modelfile/visual_contacts.cpp)."""
    return ukdyn.load("arm_hits_floor").simulate()


def test_viewer_data_of_a_robots_contact(arm):
    """The scene carries the robot's contact; the page's data puts it at the fingertip ball's
    lowest point, whose height is the gap (to the page's rounding), with the floor's normal."""
    assert [c["name"] for c in arm.scene["contacts"]] == ["fingertip"]
    data = viewer.scene_data(arm.scene, arm.names, arm._columns, contact_events=arm.contact_events)
    (contact,) = data["contacts"]
    shown = np.array(data["t"])
    gap = np.interp(shown, arm["t"], arm["gap.fingertip"])
    np.testing.assert_allclose(contact["q"][2], gap, atol=1e-4)
    assert set(contact["n"][0]) == {0} and set(contact["n"][2]) == {1}
    impacts = [e for e in arm.contact_events if e["kind"] == "impact"]
    assert len(impacts) >= 2
    assert len(data["impacts"]) >= len(impacts)
    assert data["impacts"][0]["contact"] == "fingertip"


def test_the_viewer_draws_a_robots_contact_and_its_impacts(browser, arm, tmp_path):  # noqa: F811
    """The contact's marker is drawn where the camera projects the fingertip's contact point,
    and the first impact's ring flashes there at that time; the contacts box hides them."""
    from test_viewer import _mask, _project
    path = tmp_path / "arm_hits_floor.html"
    arm.save_animation(path)
    page = Page(browser, path)
    assert page.errors() == []
    page.js("ukdyn.show('trails', false)")
    camera = page.js("return ukdyn.camera()")
    t = page.js("return ukdyn.data.t")

    def contact_at(time):
        return [float(np.interp(time, arm["t"], arm["visual.contact.fingertip." + a]))
                for a in ("x", "y", "z")]

    # the marker (the arm falls freely until the first impact: no force, no arrow)
    for frame in (0, 10):
        page.js("ukdyn.setFrame(arguments[0])", frame)
        assert page.js("return ukdyn.impactsShown()") == 0
        assert _mask(page.pixels(), "#ffb000", tolerance=0.08).sum() == 0
        marker = _mask(page.pixels(), "#0050ff")
        assert marker.sum() > 30
        expected = _project(camera, contact_at(t[frame]))
        ys, xs = np.nonzero(marker)
        assert abs(xs.mean() - expected[0]) < 3 and abs(ys.mean() - expected[1]) < 3, \
            (frame, (xs.mean(), ys.mean()), expected)
    # the first impact's ring, centred on the contact point at the impact
    first = next(e for e in arm.contact_events if e["kind"] == "impact")["t"]
    after = next(i for i, v in enumerate(t) if v >= first)
    page.js("ukdyn.setFrame(arguments[0])", after)
    assert page.js("return ukdyn.impactsShown()") == 1
    ring = _mask(page.pixels(), "#ffb000", tolerance=0.08)
    assert ring.sum() > 20
    expected = _project(camera, contact_at(first))
    ys, xs = np.nonzero(ring)
    assert abs(xs.mean() - expected[0]) < 6 and abs(ys.mean() - expected[1]) < 6, \
        ((xs.mean(), ys.mean()), expected)
    page.save("arm_hits_floor.png")
    page.js("ukdyn.show('contact', false)")
    assert _mask(page.pixels(), "#0050ff").sum() == 0
    assert _mask(page.pixels(), "#ffb000", tolerance=0.08).sum() == 0
    page.js("ukdyn.show('contact', true)")
    assert page.errors() == []


def test_the_viewer_draws_a_resting_robots_contact_force(browser, tmp_path):  # noqa: F811
    """A robot pendulum (tests/data/contact_pendulum.urdf: m = 2 kg at L_c = 0.6 m, its tip
    sphere at L = 0.8 m) resting on the floor: the page draws its contact, with no visual:
    section, and reads out the floor's force m g L_c / L = 14.715 N."""
    from test_viewer import _mask
    data = pathlib.Path(__file__).resolve().parents[2] / "tests" / "data"
    (tmp_path / "contact_pendulum.urdf").write_text(
        (data / "contact_pendulum.urdf").read_text(encoding="utf-8"), encoding="utf-8")
    model = tmp_path / "resting.yaml"
    model.write_text("robot: {urdf: contact_pendulum.urdf}\ncontacts:\n"
                     "  - {name: tip, link: rod, point: [0.8, 0, 0], shape: sphere,"
                     " radius: 0.05}\n"
                     "initial: {q: {hinge: asin(0.5625)}}\nsimulate: {t_end: 0.5}\n",
                     encoding="utf-8")
    result = ukdyn.load(str(model)).simulate()
    np.testing.assert_allclose(result["lambda.tip"], 2 * 9.81 * 0.6 / 0.8, rtol=1e-9)
    path = tmp_path / "resting.html"
    result.save_animation(path)
    page = Page(browser, path)
    assert page.errors() == []
    page.js("ukdyn.setFrame(arguments[0])", 5)
    readout = {m["name"]: m for m in page.js("return ukdyn.magnitudes()")}
    force = readout["normal force at tip"]
    assert (force["kind"], force["unit"]) == ("contact", "N")
    assert force["value"] == pytest.approx(14.715, rel=5e-4)  # (4 significant digits)
    page.save("resting_robot_contact.png")
    assert _mask(page.pixels(), "#0050ff").sum() > 30
    page.js("ukdyn.show('contact', false)")
    assert _mask(page.pixels(), "#0050ff").sum() == 0
    assert page.errors() == []


def test_painleves_rod_past_its_critical_mu_is_refused_at_the_friction_entry(cli, tmp_path):
    """Painlevé's rod (tests/data/painleve_rod.yaml: a planar rod, m = 1, length 2, I = m l²/3,
    on its end at tan θ = 2, sliding away on a rough floor): its critical mu is
    (1 + 3c²)/(3 s c) = 4/3. Past it (mu = 1.4) the run's start refuses the contact with the
    text `ukdyn run` prints, located at the friction's entry (line 13, column 5) — a
    ContactStartError, which is a ModelError and a ValueError; just below (mu = 1.33) it runs
    and the floor's normal force at the start is N = m g / (1 + 3c² − 3 mu s c)."""
    path = str(pathlib.Path(__file__).resolve().parents[2] / "tests" / "data" / "painleve_rod.yaml")
    th = math.atan(2.0)
    c, s = math.cos(th), math.sin(th)
    assert (1 + 3 * c * c) / (3 * s * c) == pytest.approx(4 / 3, rel=1e-14)
    with pytest.raises(ukdyn.ContactStartError) as info:
        ukdyn.load(path).simulate()
    err = info.value
    assert isinstance(err, ukdyn.ModelError) and isinstance(err, ValueError)
    assert (err.file, err.line, err.column) == (path, 13, 5)
    assert str(err).startswith(path + ":13:5: error: the initial state's contacts: contacts at "
                               "t = 0: Painlevé's paradox at the contact 'floor' (mu = 1.4)")
    assert "the critical mu is 1.333" in err.message
    # (the command's text, the same)
    run = subprocess.run([cli, "run", path, "-o", str(tmp_path / "run"), "--no-viewer"],
                         capture_output=True, text=True, timeout=180, check=False)
    assert run.returncode == 3, run.stderr  # (a model error, exit code 3)
    assert run.stderr.strip() == str(err)
    mu = 1.33
    good = ukdyn.load(path, mu=mu).simulate()
    n = 9.81 / (1 + 3 * c * c - 3 * mu * s * c)
    floor = good["Qc_ideal.rod.y"][0] + good["Qc_nonideal.rod.y"][0]
    assert floor == pytest.approx(n, rel=1e-8)
