# SPDX-License-Identifier: BSD-3-Clause
"""Model.linearize and Model.equilibrium (python/ukdyn/linear.py, issue #32): the textbook cart
pendulum, a parameter input, the pendulum's hanging equilibrium and its frequency, errors."""

import math

import numpy as np
import pytest

import ukdyn

CART = """
name: cart pendulum
parameters: {M: 2, m: 0.5, l: 0.8, g: 9.81, F0: 0}
coordinates: [x, th]
kinetic_energy: 0.5*(M + m)*x_dot^2 + m*l*cos(th)*x_dot*th_dot + 0.5*m*l^2*th_dot^2
potential_energy: m*g*l*cos(th)
forces: [F0, 0]
"""
M, m, l, g = 2.0, 0.5, 0.8, 9.81
A_TEXTBOOK = np.array([[0, 0, 1, 0], [0, 0, 0, 1], [0, -m * g / M, 0, 0],
                       [0, (M + m) * g / (M * l), 0, 0]])
B_TEXTBOOK = np.array([[0], [0], [1 / M], [-1 / (M * l)]])


def test_cart_pendulum_matches_the_textbook_matrices():
    model = ukdyn.parse(CART)
    lm = model.linearize(q=[0, 0], q_dot=[0, 0], inputs=["x"], outputs=["th", "x_dot"])
    assert isinstance(lm, ukdyn.LinearModel)
    assert lm.states == ["x", "th", "x_dot", "th_dot"]
    assert lm.inputs == ["x"] and lm.outputs == ["th", "x_dot"]
    np.testing.assert_allclose(lm.A, A_TEXTBOOK, rtol=0, atol=1e-8)
    np.testing.assert_allclose(lm.B, B_TEXTBOOK, rtol=0, atol=1e-14)
    np.testing.assert_allclose(lm.C, [[0, 1, 0, 0], [0, 0, 1, 0]], rtol=0, atol=1e-8)
    assert np.all(np.abs(lm.A - A_TEXTBOOK) <= lm.A_error + 1e-14 * (1 + np.abs(A_TEXTBOOK)))
    unstable = math.sqrt((M + m) * g / (M * l))
    np.testing.assert_allclose(max(lm.eigenvalues.real), unstable, rtol=1e-8)
    # the unstable mode leans the pendulum more than it moves the cart (per unit)
    k = int(np.argmax(lm.eigenvalues.real))
    shape = lm.mode(k)
    assert set(shape) == set(lm.states)


def test_parameter_input_from_a_file(tmp_path):
    path = tmp_path / "cart.yaml"
    path.write_text(CART)
    lm = ukdyn.load(path).linearize(q=[0, 0], q_dot=[0, 0], inputs=["F0"])
    np.testing.assert_allclose(lm.B, B_TEXTBOOK, rtol=0, atol=1e-8)
    assert np.all(np.abs(lm.B - B_TEXTBOOK) <= lm.B_error + 1e-14 * (1 + np.abs(B_TEXTBOOK)))


def test_pendulum_hangs_and_swings_at_sqrt_g_over_L(examples_dir):
    model = ukdyn.load(examples_dir / "pendulum.yaml")
    L = model.parameters["L"]
    q, q_dot = model.equilibrium(q=[L * math.cos(0.3), -L * math.sin(0.3)], q_dot=[0, 0])
    np.testing.assert_allclose(q, [0, -L], rtol=0, atol=1e-10)
    lm = model.linearize(q=q, q_dot=q_dot)
    np.testing.assert_allclose(sorted(lm.eigenvalues.imag), [-math.sqrt(9.81 / L),
                                                              math.sqrt(9.81 / L)], rtol=1e-8)
    np.testing.assert_allclose(lm.eigenvalues.real, [0, 0], rtol=0, atol=1e-8)


def test_a_state_off_the_constraints_is_refused_or_projected(examples_dir):
    model = ukdyn.load(examples_dir / "pendulum.yaml")
    with pytest.raises(ValueError, match="not on the constraint manifold"):
        model.linearize(q=[0.1, -1.2], q_dot=[0, 0])
    lm = model.linearize(q=[0.1, -1.2], q_dot=[0, 0], project=True)
    np.testing.assert_allclose(np.hypot(*lm.q), model.parameters["L"], rtol=1e-12)


def test_an_open_contact_is_left_out_and_projection_keeps_its_gap(examples_dir):
    # the bouncing ball 1 m above its floor: the free ball, x = (y, y'), f0 = (0, -g)
    model = ukdyn.load(examples_dir / "bouncing_ball.yaml")
    lm = model.linearize()
    assert lm.open_contacts == ["floor"]
    np.testing.assert_allclose(lm.A, [[0, 1], [0, 0]], rtol=0, atol=1e-8)
    np.testing.assert_allclose(lm.f0, [0, -9.81], rtol=0, atol=1e-12)
    # project=True keeps an open gap (the same model), moves a penetrating ball onto the floor
    assert model.linearize(q=[0.3], q_dot=[-1.0], project=True).states == ["y", "y_dot"]
    held = model.linearize(q=[-0.01], q_dot=[0.0], project=True)
    assert held.states == [] and held.open_contacts == []
    assert abs(held.q[0]) <= 1e-12


def test_errors_name_what_is_wrong():
    model = ukdyn.parse(CART)
    with pytest.raises(ValueError, match="neither a coordinate"):
        model.linearize(q=[0, 0], q_dot=[0, 0], inputs=["nosuch"])
    with pytest.raises(ValueError, match="cannot be read"):
        model.linearize(q=[0, 0], q_dot=[0, 0], inputs=["F0"])  # parsed from a string
    pushed = ukdyn.parse(CART, F0=1.0)
    with pytest.raises(RuntimeError, match="no equilibrium found"):
        pushed.equilibrium(q=[0, 0.1], q_dot=[0, 0], unknowns=["x"])


FOUR_BAR_URDF = """<?xml version="1.0"?>
<robot name="fourbar">
  <link name="base"/>
  <link name="crank1"><inertial><origin xyz="0 0 -0.25"/><mass value="1.2"/><inertia ixx="0.025" ixy="0" ixz="0" iyy="0.025" iyz="0" izz="1e-06"/></inertial></link>
  <link name="coupler"><inertial><origin xyz="0.4 0 0"/><mass value="0.7"/><inertia ixx="1e-06" ixy="0" ixz="0" iyy="0.037333333333333333" iyz="0" izz="0.037333333333333333"/></inertial></link>
  <link name="crank2"><inertial><origin xyz="0 0 0.25"/><mass value="1.2"/><inertia ixx="0.025" ixy="0" ixz="0" iyy="0.025" iyz="0" izz="1e-06"/></inertial></link>
  <joint name="a" type="continuous"><parent link="base"/><child link="crank1"/><origin xyz="0 0 2"/><axis xyz="0 1 0"/></joint>
  <joint name="b" type="continuous"><parent link="crank1"/><child link="coupler"/><origin xyz="0 0 -0.5"/><axis xyz="0 1 0"/></joint>
  <joint name="c" type="continuous"><parent link="coupler"/><child link="crank2"/><origin xyz="0.8 0 0"/><axis xyz="0 1 0"/></joint>
</robot>
"""


def test_a_urdf_four_bar_at_its_equilibrium_swings_at_the_closed_form(tmp_path):
    # u20 05: a URDF tree closed by a point loop, linearized where the equilibrium search leaves
    # it (q at the roundoff of 0): omega^2 = g (mc + mk) / (L (2 mc/3 + mk)) = 24.852 /s^2 (it
    # came out 4.43 or 4.61 rad/s for 4.985, unstable with an independent crank)
    (tmp_path / "fb.urdf").write_text(FOUR_BAR_URDF)
    (tmp_path / "fb.yaml").write_text(
        "name: four-bar\nrobot:\n  urdf: fb.urdf\n  loops:\n"
        "    - {name: close, type: point, link_a: crank2, point_a: [0, 0, 0.5], link_b: world,"
        " point_b: [0.8, 0, 2]}\n")
    model = ukdyn.load(str(tmp_path / "fb.yaml"))
    w = math.sqrt(9.81 * 1.9 / (0.5 * (0.8 + 0.7)))
    q, q_dot = model.equilibrium(q=[0.3, -0.3, 0.3], q_dot=[0, 0, 0])
    assert np.max(np.abs(q)) == pytest.approx(0.0, abs=1e-10)
    for independent in ([], ["a"]):
        for step in (0.1, 0.01):
            lm = model.linearize(q=q, q_dot=q_dot, independent=independent, initial_step=step)
            assert np.abs(lm.eigenvalues.real).max() == pytest.approx(0.0, abs=1e-9 * w)
            assert np.abs(lm.eigenvalues.imag).max() == pytest.approx(w, rel=1e-9)
    with pytest.raises(ValueError, match="initial_step"):
        model.linearize(q=q, q_dot=q_dot, initial_step=0.0)
