# SPDX-License-Identifier: BSD-3-Clause
"""Settings and arrays of the wrong type are refused with a ValueError naming the setting (never
pybind11's "Unable to cast", never a complex number silently cast to a real one); a failed
control evaluation is a SolveError like a failed solve. Found by fuzz/fuzz_python.py."""

import math

import numpy as np
import pytest

import ukdyn


@pytest.fixture(scope="module")
def pendulum():
    return ukdyn.load("pendulum")


@pytest.mark.parametrize("setting, value, words", [
    ("max_steps", [1, 2], "max_steps must be a whole number (got list)"),
    ("max_steps", 1e30, "max_steps must be a whole number between"),
    ("max_steps", 2.5, "max_steps must be a whole number between"),
    ("projection_iterations", "20", "projection_iterations must be a whole number (got str)"),
    ("stiff_switch", "x", "stiff_switch must be True or False (got 'x')"),
    ("project_initial", 2, "project_initial must be True or False (got 2)"),
    ("compute_residuals", None, None),  # None keeps the model's value
    ("output_at", np.array([0.1 + 2j]), "output_at must be a real number (got complex128)"),
    ("rtol", 1j, "rtol must be a real number (got complex)"),
    ("output_at", "abc", "output_at must be a number or a sequence of numbers (got str)"),
])
def test_wrong_types_are_named(pendulum, setting, value, words):
    if words is None:
        r = pendulum.simulate(t_end=0.05, **{setting: value})
        assert r.t[-1] == pytest.approx(0.05, rel=1e-12, abs=1e-12)
        return
    with pytest.raises(ValueError) as e:
        pendulum.simulate(t_end=0.05, **{setting: value})
    assert words in str(e.value)
    assert "Unable to cast" not in str(e.value)


def test_whole_numbers_and_booleans_still_accepted(pendulum):
    r = pendulum.simulate(t_end=0.05, max_steps=100000.0, stiff_switch=np.bool_(False),
                          project_initial=1, projection_iterations=np.int64(30))
    assert r.stats["status"] == "ok"
    assert r.t[-1] == pytest.approx(0.05, rel=1e-12, abs=1e-12)
    assert 4 <= r.stats["steps"] <= 200


def test_solver_settings_types(pendulum):
    with pytest.raises(ValueError, match="sparse_threshold must be a whole number"):
        pendulum.solver(sparse_threshold=[1])
    with pytest.raises(ValueError, match="compute_residuals must be True or False"):
        pendulum.solver(compute_residuals="yes")


def test_arrays_none_and_complex(pendulum):
    s = pendulum.solver()
    with pytest.raises(ValueError, match="q is None"):
        s.solve(None, [0.0, 0.0])
    with pytest.raises(ValueError, match="q_dot must be real numbers \\(got complex\\)"):
        s.solve([1.0, 0.0], np.array([0.0, 1j]))
    sol = s.solve([1.0, 0.0], [0.0, 0.0])
    # at rest at the side the rod takes no load: free fall, q'' = (0, -g)
    assert sol.qdd[0] == pytest.approx(0.0, abs=1e-12)
    assert sol.qdd[1] == pytest.approx(-9.81, rel=1e-12)


def test_failed_control_evaluation_is_a_solve_error():
    c = ukdyn.load("control_duffing").controller.solver()
    with pytest.raises(ukdyn.SolveError, match="non-finite input .* in q \\(coordinate 'x'\\)") as e:
        c.compute([math.nan], [0.0], 0.0)
    assert e.value.status == "non-finite input (NaN or Inf)"
    assert isinstance(e.value, RuntimeError)  # as before: SolveError is a RuntimeError
