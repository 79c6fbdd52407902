# SPDX-License-Identifier: BSD-3-Clause
"""The LQR example (python/examples/lqr_cart_pendulum.py, issue #32): designed on
Model.linearize of a constrained system, stable in the linear model (checked against the
Hamiltonian matrix's eigenvalues), converging in the nonlinear model; the exact tracking
controller on the same task follows its closed-form error; the comparison plot."""

import importlib.util
import math
import pathlib

import numpy as np
import pytest

pytest.importorskip("scipy")

ROOT = pathlib.Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def example():
    spec = importlib.util.spec_from_file_location(
        "lqr_cart_pendulum", ROOT / "python" / "examples" / "lqr_cart_pendulum.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def design(example):
    return example.design()


def test_the_riccati_solution_and_the_closed_loop_are_right(design):
    A, B, Q, R, P, K = design.lm.A, design.lm.B, design.Q, design.R, design.P, design.K
    assert design.lm.states == ["x", "px", "x_dot", "px_dot"]
    assert design.lm.inputs == ["x", "px"]
    residual = A.T @ P + P @ A - P @ B @ np.linalg.solve(R, B.T) @ P + Q
    np.testing.assert_allclose(residual, 0, atol=1e-9 * np.abs(Q).max())
    np.testing.assert_allclose(P, P.T, atol=1e-12 * np.abs(P).max())
    assert np.linalg.eigvalsh(P).min() > 0
    # the closed-loop poles are the stable half of the Hamiltonian matrix's spectrum
    H = np.block([[A, -B @ np.linalg.solve(R, B.T)], [-Q, -A.T]])
    stable = np.sort_complex([z for z in np.linalg.eigvals(H) if z.real < 0])
    poles = np.sort_complex(design.closed_loop_eigenvalues())
    np.testing.assert_allclose(poles, stable, rtol=1e-8)
    assert poles.real.max() < -0.5
    # the open loop is unstable (the inverted pendulum)
    assert np.linalg.eigvals(A).real.max() > 1.0


def test_the_nonlinear_closed_loop_converges(example, design):
    res, u = example.run_lqr(design)
    assert res.ok
    l = example.PARAMETERS["l"]
    end = {s: res[s][-1] for s in ("x", "px", "x_dot", "px_dot")}
    for s, v in end.items():
        assert abs(v) < 1e-3, (s, v)
    assert abs(res["py"][-1] - l) < 1e-6
    # the rod is kept by the fundamental equation, not by the controller
    rod = np.hypot(res["px"] - res["x"], res["py"])
    np.testing.assert_allclose(rod, l, rtol=0, atol=1e-8)
    assert u.shape == (len(res.t), 2)


def test_the_tracking_controller_follows_its_error_dynamics(example):
    res, qc = example.run_tracking()
    assert res.ok
    w = example.OMEGA_UPRIGHT
    e0 = example.PARAMETERS["l"] * math.sin(example.PARAMETERS["th0"])
    t = np.asarray(res.t)
    np.testing.assert_allclose(res["px"] - res["x"], e0 * (1 + w * t) * np.exp(-w * t),
                               rtol=0, atol=1e-7)
    np.testing.assert_allclose(res["x"], 0, atol=1e-9)
    assert qc.shape == (len(t), 2)


def test_the_comparison_plot(example, design, tmp_path):
    c = example.compare(design)
    for name in ("lqr", "tracking"):
        assert c[name]["upright_error_after_3s"] < 1e-2
        assert c[name]["effort"] > 0
    path = tmp_path / "lqr_vs_tracking.png"
    fig = example.plot(design, str(path))
    assert path.exists() and path.stat().st_size > 10000
    assert len(fig.axes) == 3
    for ax in fig.axes:
        assert len([ln for ln in ax.get_lines() if not ln.get_label().startswith("_")]) == 2
