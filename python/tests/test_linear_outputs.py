# SPDX-License-Identifier: BSD-3-Clause
"""Model.linearize with a model file's output expressions as outputs, and Model.linearize_along
(the time-varying linearization along a motion) from Python and the command line (issue #32)."""

import json
import math
import subprocess

import numpy as np
import pytest

import ukdyn

PENDULUM = """
name: pendulum in its angle
parameters: {m: 2, L: 0.7, g: 9.81}
coordinates: [th]
kinetic_energy: 0.5*m*L^2*th_dot^2
potential_energy: -m*g*L*cos(th)
initial: {q: {th: 1.2}, q_dot: {th: 0}}
simulate: {t_end: 1.5, rtol: 1e-11, atol: 1e-13}
output:
  every: 0.25
  expressions:
    height: -L*cos(th)
    speed: L*th_dot
"""
L, g = 0.7, 9.81


def test_output_expressions_are_rows_of_C():
    model = ukdyn.parse(PENDULUM)
    th0, w0 = 0.4, 1.5
    lm = model.linearize(q=[th0], q_dot=[w0], outputs=["height", "speed", "th_dot"])
    assert lm.outputs == ["height", "speed", "th_dot"]
    # d(-L cos th) = L sin th dth;  d(L th') = L dth'
    np.testing.assert_allclose(lm.C, [[L * math.sin(th0), 0], [0, L], [0, 1]], rtol=0,
                               atol=1e-10)
    assert np.all(np.abs(lm.C - [[L * math.sin(th0), 0], [0, L], [0, 1]]) <= lm.C_error + 1e-15)
    np.testing.assert_array_equal(lm.D, np.zeros((3, 0)))
    with pytest.raises(ValueError, match="neither a coordinate, NAME_dot, nor an output "
                                         r"expression \(height, speed\)"):
        model.linearize(q=[th0], q_dot=[w0], outputs=["heigth"])


def test_linearize_along_a_run_is_the_variational_equation():
    model = ukdyn.parse(PENDULUM)
    run = model.simulate()
    models = model.linearize_along(run, outputs=["height"])
    assert len(models) == len(run.t) == 7
    for lm, t, th, w in zip(models, run.t, run.q[:, 0], run.q_dot[:, 0]):
        assert lm.t == t and lm.states == ["th", "th_dot"]
        # A(t) = [[0, 1], [-g/L cos th(t), 0]];  f0 = (th', th'') of the motion
        exact = np.array([[0, 1], [-g / L * math.cos(th), 0]])
        np.testing.assert_allclose(lm.A, exact, rtol=0, atol=1e-9)
        np.testing.assert_allclose(lm.f0, [w, -g / L * math.sin(th)], rtol=0, atol=1e-12)
        np.testing.assert_allclose(lm.C, [[L * math.sin(th), 0]], rtol=0, atol=1e-10)
    # the same from arrays
    again = model.linearize_along(t=run.t, q=run.q, q_dot=run.q_dot)
    np.testing.assert_array_equal(again[3].A, models[3].A)
    with pytest.raises(ValueError, match="give a motion or the arrays"):
        model.linearize_along(run, t=run.t)
    with pytest.raises(ValueError, match="they must agree"):
        model.linearize_along(t=run.t[:3], q=run.q, q_dot=run.q_dot)


def test_the_command_linearizes_along_the_models_run(cli, tmp_path):
    path = tmp_path / "pendulum.yaml"
    path.write_text(PENDULUM)
    out = subprocess.run([cli, "linearize", str(path), "--along", "--outputs", "height"],
                         capture_output=True, text=True, check=True)
    j = json.loads(out.stdout)
    points = j["points"]
    run = ukdyn.load(path).simulate()
    assert [p["t"] for p in points] == pytest.approx(list(run.t), abs=0)
    for p, th in zip(points, run.q[:, 0]):
        np.testing.assert_allclose(p["A"], [[0, 1], [-g / L * math.cos(th), 0]], atol=1e-9)
        np.testing.assert_allclose(p["C"], [[L * math.sin(th), 0]], atol=1e-10)
    bad = subprocess.run([cli, "linearize", str(path), "--along", "--at", "th=0"],
                         capture_output=True, text=True)
    assert bad.returncode == 2 and "takes no --at" in bad.stderr
    bad = subprocess.run([cli, "linearize", str(path), "--outputs", "nosuch"],
                         capture_output=True, text=True)
    assert bad.returncode == 2 and "output nosuch: neither a coordinate" in bad.stderr


def test_the_command_names_its_own_remedy_for_a_point_off_the_constraints(cli, examples_dir):
    # u16 04: the hint named the C++ functions (ukdyn::project_positions); the command's own
    # --project then linearizes the hanging pendulum, eigenvalues +-i sqrt(g/L)
    path = examples_dir / "pendulum.yaml"
    L = ukdyn.load(path).parameters["L"]
    at = f"x=0,y={-1.1 * L}"
    bad = subprocess.run([cli, "linearize", str(path), "--at", at], capture_output=True, text=True)
    assert bad.returncode == 2, bad.stderr
    assert "not on the constraint manifold" in bad.stderr
    assert "add --project to project the point onto the constraints first" in bad.stderr
    assert "ukdyn::project_positions" not in bad.stderr
    ok = subprocess.run([cli, "linearize", str(path), "--at", at, "--project"],
                        capture_output=True, text=True, check=True)
    im = sorted(m["eigenvalue"][1] for m in json.loads(ok.stdout)["modes"])
    np.testing.assert_allclose(im, [-math.sqrt(9.81 / L), math.sqrt(9.81 / L)], rtol=1e-7)


CART_FREE = """
name: a free cart beside a pendulum
parameters: {m: 2, L: 0.7, g: 9.81}
coordinates: [x, th]
kinetic_energy: 0.5*m*x_dot^2 + 0.5*m*L^2*th_dot^2
potential_energy: -m*g*L*cos(th)
initial: {q: {x: 0, th: 0.3}, q_dot: {x: 1, th: 0}}
output:
  expressions:
    height: -L*cos(th)
    position: x + L*sin(th)
"""


def test_kept_states_refuse_an_output_of_a_dropped_state():
    """states= keeps th, th_dot (x is cyclic: a subsystem of its own); an output that reads the
    dropped x would be silently wrong without it, so it is refused, naming both."""
    model = ukdyn.parse(CART_FREE)
    lm = model.linearize(q=[0.0, 0.3], q_dot=[1.0, 0.0], outputs=["height"],
                         states=["th", "th_dot"])
    assert lm.states == ["th", "th_dot"]
    np.testing.assert_allclose(lm.C, [[L * math.sin(0.3), 0]], rtol=0, atol=1e-10)
    with pytest.raises(ValueError, match="the output 'position' depends on the dropped state 'x'"):
        model.linearize(q=[0.0, 0.3], q_dot=[1.0, 0.0], outputs=["position"],
                        states=["th", "th_dot"])


def test_the_command_says_that_control_is_left_out(cli, tmp_path):
    # u19 05: a free mass held at x = 0 by a requirement (closed loop: poles -2, -2) was
    # linearized to the open loop A = [[0, 1], [0, 0]] without a word; the plant's open-loop model
    # is what the command gives, and it says so
    path = tmp_path / "held.yaml"
    path.write_text("coordinates: [x]\nkinetic_energy: 0.5*x_dot^2\ninitial: {q: {x: 0.1}}\n"
                    "control:\n  requirements:\n"
                    "    - {name: hold, holonomic: x, dynamics: {omega: 2, zeta: 1}}\n")
    out = subprocess.run([cli, "linearize", str(path)], capture_output=True, text=True,
                         check=True)
    np.testing.assert_allclose(json.loads(out.stdout)["A"], [[0, 1], [0, 0]], atol=1e-12)
    assert "the model's control: section is left out" in out.stderr
    assert "open-loop linear model" in out.stderr
    plain = tmp_path / "plain.yaml"
    plain.write_text("coordinates: [x]\nkinetic_energy: 0.5*x_dot^2\n")
    out = subprocess.run([cli, "linearize", str(plain)], capture_output=True, text=True,
                         check=True)
    assert "control" not in out.stderr


def test_python_says_that_control_is_left_out(tmp_path):
    # the same in Python: a UserWarning, and the open-loop A (eigenvalues 0, 0)
    held = ukdyn.parse("coordinates: [x]\nkinetic_energy: 0.5*x_dot^2\ninitial: {q: {x: 0.1}}\n"
                       "control:\n  requirements:\n"
                       "    - {name: hold, holonomic: x, dynamics: {omega: 2, zeta: 1}}\n")
    with pytest.warns(UserWarning, match="control: section is left out"):
        lm = held.linearize()
    np.testing.assert_allclose(lm.A, [[0, 1], [0, 0]], atol=1e-12)
