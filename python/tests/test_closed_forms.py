# SPDX-License-Identifier: BSD-3-Clause
"""The closed-form cases of the engine and simulation issues, from Python (tests/modelfile/test_examples.cpp
checks the same in C++). Every reference number comes from analysis, not from ukdyn."""

import math

import numpy as np
import pytest

import ukdyn


def agm(a, b):
    for _ in range(40):  # converges quadratically; 40 rounds are plenty
        a, b = (a + b) / 2, math.sqrt(a * b)
    return a


def pendulum_period(L, g, theta0):
    """4 sqrt(L/g) K(k), k = sin(theta0/2), K by the arithmetic-geometric mean."""
    k = math.sin(theta0 / 2)
    K = math.pi / (2 * agm(1.0, math.sqrt(1 - k * k)))
    return 4 * math.sqrt(L / g) * K


def test_pendulum_returns_after_the_elliptic_period_with_tension_three_mg_cos():
    m = ukdyn.load("pendulum")
    T = pendulum_period(1.0, 9.81, math.pi / 2)
    assert m.options["t_end"] == pytest.approx(T, rel=1e-12)
    r = m.simulate()
    assert r.ok and r.t[-1] == pytest.approx(T, abs=1e-12)
    # back at (L, 0), at rest
    assert r.x[-1] == pytest.approx(1.0, abs=1e-8)
    assert r.y[-1] == pytest.approx(0.0, abs=1e-7)
    assert r.x_dot[-1] == pytest.approx(0.0, abs=1e-7)
    assert r.y_dot[-1] == pytest.approx(0.0, abs=1e-7)
    # rod tension 3 m g cos(theta) = -3 m g y / L, reported as lambda.rod = 3 m g y / L
    np.testing.assert_allclose(r["lambda.rod"], 3 * 9.81 * r.y, rtol=0, atol=1e-8)
    # energy is conserved (no non-ideal force)
    np.testing.assert_allclose(r.energy, r.energy[0], rtol=0, atol=1e-8 * 9.81)  # 1e-8 of m g L
    np.testing.assert_array_equal(r.work_nonideal, 0.0)
    # the output expressions: r = L on the rod, theta from pi/2 down to -pi/2
    np.testing.assert_allclose(r.r, 1.0, rtol=0, atol=1e-10)
    assert r.theta[0] == pytest.approx(math.pi / 2, abs=1e-12)


def test_pendulum_period_scales_with_the_square_root_of_the_overridden_length():
    T = pendulum_period(2.0, 9.81, math.pi / 2)
    r = ukdyn.load("pendulum", L=2.0).simulate(t_end=T, output_every=0.05)
    assert r.x[-1] == pytest.approx(2.0, abs=1e-8)
    assert r.y[-1] == pytest.approx(0.0, abs=1e-7)
    assert r.x_dot[-1] == pytest.approx(0.0, abs=1e-7)


def test_bead_on_rotating_wire_follows_cosh_and_sinh():
    m = ukdyn.load("bead_on_rotating_wire")
    p = m.parameters
    r = m.simulate()
    W, t = p["Omega"], r.t
    s = r.x * np.cos(W * t) + r.y * np.sin(W * t)
    closed = p["r0"] * np.cosh(W * t) + p["rd0"] / W * np.sinh(W * t)
    np.testing.assert_allclose(s, closed, rtol=0, atol=1e-8)
    # the rheonomic wire does work: the energy grows as m/2 (r'^2 + W^2 r^2)
    rd = p["r0"] * W * np.sinh(W * t) + p["rd0"] * np.cosh(W * t)
    np.testing.assert_allclose(r.kinetic_energy, 0.5 * p["m"] * (rd**2 + W**2 * closed**2),
                               rtol=1e-8, atol=0)


def test_block_on_rough_incline_slides_at_g_sin_minus_mu_cos():
    m = ukdyn.load("incline_friction")
    p = m.parameters
    r = m.simulate()
    a, g, mu = p["alpha"], p["g"], p["mu"]
    s = r.x * math.cos(a) - r.y * math.sin(a)
    closed = p["v0"] * r.t + 0.5 * g * (math.sin(a) - mu * math.cos(a)) * r.t**2
    np.testing.assert_allclose(s, closed, rtol=0, atol=1e-8)
    # friction of magnitude mu N, N = m g cos(alpha)
    friction = np.hypot(r["Qc_nonideal.x"], r["Qc_nonideal.y"])
    np.testing.assert_allclose(friction, mu * p["m"] * g * math.cos(a), rtol=1e-8)
    # energy balance: E - E0 = work of the friction
    np.testing.assert_allclose(r.energy - r.energy[0], r.work_nonideal, rtol=0, atol=1e-8)


def test_controlled_duffing_error_decays_as_one_plus_t_times_exp_minus_two_t():
    m = ukdyn.load("control_duffing")
    assert m.controller is not None
    r = m.simulate()
    assert r.control is not None and r.control["not_met"] == 0
    e = r.x - np.sin(r.t)
    np.testing.assert_allclose(e, (1 + r.t) * np.exp(-2 * r.t), rtol=0, atol=1e-8)
    np.testing.assert_allclose(r["error.track"], e, rtol=0, atol=1e-12)
    # Gauss control force (fully actuated, no physical constraint): m x_d'' - Q with e'' = -4e' - 4e
    p = m.parameters
    ed = r.x_dot - np.cos(r.t)
    Q = -p["c"] * r.x_dot + r.x - r.x**3 + p["F"] * np.cos(p["w"] * r.t)
    np.testing.assert_allclose(r["Qc_control.x"], p["m"] * (-np.sin(r.t) - 4 * ed - 4 * e) - Q,
                               rtol=0, atol=1e-9)
