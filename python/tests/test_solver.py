# SPDX-License-Identifier: BSD-3-Clause
"""The solver one evaluation at a time: closed forms, redundancy, failures, the fast path."""

import math

import numpy as np
import pytest

import ukdyn

THETA, THETA_DOT, G = 0.6, 1.5, 9.81


def pendulum_state(L=1.0):
    s, c = math.sin(THETA), math.cos(THETA)
    return np.array([L * s, -L * c]), L * THETA_DOT * np.array([c, s])


def test_pendulum_acceleration_tension_and_residuals_are_the_closed_form():
    q, qd = pendulum_state()
    sol = ukdyn.load("pendulum").solver().solve(q, qd, 0.0)
    s, c = math.sin(THETA), math.cos(THETA)
    theta_ddot = -G * s
    expected = theta_ddot * np.array([c, s]) + THETA_DOT**2 * np.array([-s, c])
    np.testing.assert_allclose(sol.qdd, expected, rtol=0, atol=1e-13)
    # the rod pulls towards the pivot with m (g cos(theta) + L theta'^2) = 10.346542382264 N
    tension = G * c + THETA_DOT**2
    assert tension == pytest.approx(10.346542382264, abs=1e-12)
    np.testing.assert_allclose(sol.Qc_ideal, -tension * q, rtol=0, atol=1e-12)
    np.testing.assert_allclose(sol.lambda_, [-tension], rtol=0, atol=1e-12)
    np.testing.assert_array_equal(sol.Qc_nonideal, [0.0, 0.0])
    np.testing.assert_allclose(sol.Qc, sol.Qc_ideal, rtol=0, atol=0)
    assert sol.rank == 1 and sol.active_rows == 1 and sol.ok and sol.status == "ok"
    assert sol.message == ""
    for value in sol.residuals.values():
        assert abs(value) <= 1e-13
    # A = grad phi = (x, y) / L, b = -(x'^2 + y'^2) / L
    np.testing.assert_allclose(sol.A, [q], rtol=0, atol=1e-15)
    np.testing.assert_allclose(sol.b, [-(qd @ qd)], rtol=0, atol=1e-14)


def test_redundant_rod_leaves_the_motion_unchanged_and_splits_the_multiplier(testdata_dir):
    q, qd = pendulum_state()
    single = ukdyn.load("pendulum").solver().solve(q, qd)
    double = ukdyn.load(testdata_dir / "redundant_pendulum.yaml").solver().solve(q, qd)
    assert double.rank == 1 and double.active_rows == 2
    np.testing.assert_allclose(double.qdd, single.qdd, rtol=0, atol=1e-13)
    np.testing.assert_allclose(double.Qc_ideal, single.Qc_ideal, rtol=0, atol=1e-12)
    # rows q and 2q (rod_copy is not divided by 2L): the minimum-norm multipliers with
    # lambda_1 + 2 lambda_2 = lambda are (1, 2) lambda / 5
    np.testing.assert_allclose(double.lambda_, [single.lambda_[0] / 5, 2 * single.lambda_[0] / 5],
                               rtol=0, atol=1e-12)


INCONSISTENT = """
coordinates: [x]
kinetic_energy: 0.5*x_dot^2
constraints:
  - {name: still, nonholonomic: x_dot}
  - {name: moving, nonholonomic: x_dot - t}
"""


def test_inconsistent_constraints_raise_solve_error_or_report_the_status():
    solver = ukdyn.parse(INCONSISTENT).solver()
    with pytest.raises(ukdyn.SolveError) as err:
        solver.solve([0.0], [0.0], 1.0)
    assert err.value.status == "inconsistent constraints"
    assert isinstance(err.value, RuntimeError)
    sol = solver.solve([0.0], [0.0], 1.0, check=False)
    assert not sol.ok and sol.status == "inconsistent constraints"
    assert sol.message in str(err.value)  # throw_if_failed adds the prefix "ukdyn: "
    assert solver.counters["failures"] == 2


def test_wrong_sizes_are_value_errors():
    solver = ukdyn.load("pendulum").solver()
    with pytest.raises(ValueError, match=r"Solver.solve: q must have 2 entries \(got 3\)"):
        solver.solve([1.0, 0.0, 0.0], [0.0, 0.0])
    with pytest.raises(ValueError, match="q_dot must have 2 entries"):
        solver.solve([1.0, 0.0], np.zeros((2, 2)))
    with pytest.raises(ValueError, match="unknown setting"):
        ukdyn.load("pendulum").solver(rank_treshold=1e-8)
    with pytest.raises(ValueError):
        ukdyn.load("pendulum").solver(rank_threshold=2.0)


def test_fast_path_reads_live_views_and_solutions_are_snapshots():
    q, qd = pendulum_state()
    solver = ukdyn.load("pendulum").solver()
    first = solver.solve(q, qd)
    assert solver.evaluate(q, qd, 0.0) == "ok"
    view = solver.qdd
    assert not view.flags.writeable and view.base is not None
    np.testing.assert_array_equal(view, first.qdd)
    solver.evaluate(np.array([1.0, 0.0]), np.zeros(2), 0.0)  # released horizontally: q'' = (0, -g)
    np.testing.assert_allclose(view, [0.0, -G], rtol=0, atol=1e-14)  # the view follows
    np.testing.assert_allclose(first.qdd, solver.solve(q, qd).qdd, rtol=0, atol=0)  # snapshot kept
    assert solver.M.shape == (2, 2) and solver.A.shape == (1, 2)
    assert solver.counters["evaluations"] == 4


def test_model_solve_convenience_matches_the_solver():
    q, qd = pendulum_state()
    m = ukdyn.load("pendulum")
    np.testing.assert_array_equal(m.solve(q, qd).qdd, m.solver().solve(q, qd).qdd)
    system = m.system
    assert system.coordinate_count == 2 and system.coordinates == ["x", "y"]
    assert system.constraint_info()[0]["kind"] == "holonomic"
    np.testing.assert_allclose(system.mass_matrix(q), np.eye(2), rtol=0, atol=0)
    np.testing.assert_allclose(system.forces(q, qd), [0.0, -G], rtol=0, atol=1e-15)
    assert system.potential_energy(q) == pytest.approx(G * q[1], rel=1e-15)
