# SPDX-License-Identifier: BSD-3-Clause
"""Coulomb friction from Python (docs/friction.md; tests/simulation/test_friction.cpp checks the same in
C++): static and kinetic coefficients and a surface velocity, from a model file, from SymPy and
from callables. Reference numbers from the stick-slip oscillator's closed form."""

import math

import numpy as np
import pytest
import sympy as sp

import ukdyn

M_, K, G, MU_K, MU_S, V = 1.0, 10.0, 9.81, 0.3, 0.5, 0.2


def belt_x(t):
    """The block's position on the belt: stick until k x = mu_s m g, then slip/stick periods."""
    w = math.sqrt(K / M_)
    x_s, x_eq = MU_S * M_ * G / K, MU_K * M_ * G / K
    A, B = x_s - x_eq, V / w
    phi = math.atan2(A, B)
    t_slip, t_stick = (2 * math.pi - 2 * phi) / w, 2 * (x_s - x_eq) / V
    if t <= x_s / V:
        return V * t
    tau = math.fmod(t - x_s / V, t_slip + t_stick)
    if tau <= t_slip:
        return x_eq + A * math.cos(w * tau) + B * math.sin(w * tau)
    return 2 * x_eq - x_s + V * (tau - t_slip)


def check_belt(r):
    assert r.ok, r.stats["message"]
    exact = np.array([belt_x(t) for t in r.t])
    np.testing.assert_allclose(r.x, exact, rtol=0, atol=2e-7)
    assert r.stats["events"] == 6  # slip, stick, slip, stick, slip, stick in 10 s
    assert r.stats["stick_refusals"] == 0
    # (a floor from callables is in acceleration form: its violation is unknown, and noted)
    assert [n for n in r.stats["notes"] if "given in acceleration form only" not in n] == []


def test_conveyor_belt_from_the_gallery_file():
    check_belt(ukdyn.load("conveyor_stick_slip").simulate())


def test_conveyor_belt_lists_each_stick_and_slip_at_its_closed_form_time():
    """Result.contact_events lists the six events of check_belt: each slip where k x = mu_s m g
    (at t_1 = x_s / V, then every period t_slip + t_stick), its holding force mu_s m g = mu_s N,
    each stick t_slip later, when the block moves with the belt again (early by v_stop / a)."""
    r = ukdyn.load("conveyor_stick_slip").simulate()
    events = r.contact_events
    assert [e["kind"] for e in events] == ["slip", "stick"] * 3
    w = math.sqrt(K / M_)
    x_s, x_eq = MU_S * M_ * G / K, MU_K * M_ * G / K
    phi = math.atan2(x_s - x_eq, V / w)
    t_slip, t_stick = (2 * math.pi - 2 * phi) / w, 2 * (x_s - x_eq) / V
    for k in range(3):
        slip, stick = events[2 * k], events[2 * k + 1]
        t1 = x_s / V + k * (t_slip + t_stick)
        assert slip["t"] == pytest.approx(t1, abs=1e-6)
        assert stick["t"] == pytest.approx(t1 + t_slip, abs=1e-4)
        for e in (slip, stick):
            assert e["contact"] == "floor"
            assert e["friction"] == events[0]["friction"] != ""
        assert slip["holding_force"] == pytest.approx(MU_S * M_ * G, rel=1e-6)
        assert slip["friction_limit"] == pytest.approx(MU_S * M_ * G, rel=1e-6)
        assert slip["speed_before"] == pytest.approx(0.0, abs=1e-9)
        assert stick["speed_after"] == pytest.approx(0.0, abs=1e-9)
        assert stick["holding_force"] is None
    # summary.json's list is the same (ukdyn run writes it from the same statistics)
    assert r.stats["events"] == 6


def test_conveyor_belt_from_sympy_with_mu_static_and_surface_velocity():
    x, y = sp.symbols("x y")
    xd, yd = sp.symbols("x_dot y_dot")
    model = ukdyn.from_sympy(
        [x, y], T=M_ * (xd**2 + yd**2) / 2, V=K * x**2 / 2 + M_ * G * y,
        constraints={"floor": y},
        nonideal=[{"friction": "coulomb", "constraint": "floor", "mu": MU_K, "mu_static": MU_S,
                   "coordinates": [x], "surface_velocity": [V]}],
        initial={"q": {x: 0, y: 0}, "q_dot": {x: V}},
        simulate={"t_end": 10}, output={"every": 0.01})
    check_belt(model.simulate())


def test_conveyor_belt_from_callables_with_a_surface_velocity_callable():
    system = ukdyn.from_callables(
        ["x", "y"], M=M_ * np.eye(2), Q=lambda q, qd, t: [-K * q[0], -M_ * G],
        V=lambda q, t: K * q[0] ** 2 / 2 + M_ * G * q[1],
        constraints=[ukdyn.constraint("floor", lambda q, qd, t: [0.0, 1.0],
                                      lambda q, qd, t: [0.0])],
        nonideal=[ukdyn.coulomb("floor", MU_K, coordinates=["x"], mu_static=MU_S,
                                surface_velocity=lambda q, qd, t: ([V], [0.0]))])
    r = ukdyn.simulate(system, [0.0, 0.0], [V, 0.0], t_end=10, output_every=0.01)
    check_belt(r)


def test_mu_static_below_mu_is_a_value_error():
    with pytest.raises(ValueError, match="mu_static must be >= mu"):
        ukdyn.from_callables(
            ["x", "y"], M=np.eye(2),
            constraints=[ukdyn.constraint("floor", lambda q, qd, t: [0.0, 1.0],
                                          lambda q, qd, t: [0.0])],
            nonideal=[ukdyn.coulomb("floor", 0.5, mu_static=0.2)])
