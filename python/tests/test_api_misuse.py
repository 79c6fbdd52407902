# SPDX-License-Identifier: BSD-3-Clause
"""Misuse of the Python API (issue #14, items 8 and 9; reliability report D13, D15): each mistake
gives an error naming the function and what is wrong, a failed solve leaves no stale results,
and a model run's columns have distinct names, a body's coordinate being found by both of its
spellings (``crank.x`` and ``crank_x``)."""

import math

import numpy as np
import pytest

import ukdyn

G = 9.81


@pytest.fixture()
def solver():
    return ukdyn.load("pendulum").solver()


# --- Solver ----------------------------------------------------------------------------------

def test_failed_solve_without_check_leaves_nan_not_the_previous_results(solver):
    good = solver.solve([1.0, 0.0], [0.0, 0.0], 0.0)
    # released at rest from the horizontal: q'' = (0, -g), no rod force
    np.testing.assert_allclose(good.qdd, [0.0, -G], rtol=0, atol=1e-12)
    bad = solver.solve([math.nan, 0.0], [0.0, 0.0], 0.0, check=False)
    assert bad.status.startswith("non-finite input")
    assert "in q (coordinate 'x')" in bad.message
    assert np.isnan(bad.qdd).all() and np.isnan(bad.Qc).all() and np.isnan(bad.lambda_).all()
    # the live views too
    assert np.isnan(solver.qdd).all()
    # and with check=True the error names the coordinate
    with pytest.raises(ukdyn.SolveError, match=r"in q \(coordinate 'x'\)"):
        solver.solve([math.nan, 0.0], [0.0, 0.0], 0.0)
    # the good result kept its values (it is a copy)
    np.testing.assert_allclose(good.qdd, [0.0, -G], rtol=0, atol=1e-12)


def test_solve_with_none_says_none(solver):
    with pytest.raises(ValueError, match=r"^Solver\.solve: q is None$"):
        solver.solve(None, [0.0, 0.0], 0.0)
    with pytest.raises(ValueError, match=r"^Solver\.solve: q_dot is None$"):
        solver.solve([1.0, 0.0], None, 0.0)


def test_evaluate_errors_name_evaluate(solver):
    with pytest.raises(ValueError, match=r"^Solver\.evaluate: q must have 2 entries \(got 1\)$"):
        solver.evaluate([1.0], [0.0, 0.0], 0.0)
    with pytest.raises(ValueError, match=r"^Solver\.evaluate: q_dot is None"):
        solver.evaluate([1.0, 0.0], None, 0.0)
    with pytest.raises(ValueError, match=r"^Solver\.solve: q must have 2 entries \(got 3\)$"):
        solver.solve([1.0, 0.0, 0.0], [0.0, 0.0], 0.0)


# --- callables ---------------------------------------------------------------------------------

def test_callable_returning_none_says_it_returned_none():
    system = ukdyn.from_callables(["x", "y"], M=np.eye(2), Q=lambda q, qd, t: None)
    with pytest.raises(ValueError, match=r"Q\(q, q_dot, t\) returned None"):
        ukdyn.simulate(system, [1.0, 0.0], [0.0, 0.0], t_end=1.0)


def test_coulomb_on_unknown_constraint_lists_only_the_given_constraints():
    rod = ukdyn.constraint("rod", lambda q, qd, t: np.array([q[0], q[1]]),
                           lambda q, qd, t: 0.0)
    with pytest.raises(ValueError) as info:
        ukdyn.from_callables(["x", "y"], M=np.eye(2), constraints=[rod],
                             nonideal=[ukdyn.coulomb("nope", 0.3)])
    text = str(info.value)
    assert "no constraint named 'nope'" in text
    assert "the constraints are 'rod'" in text
    assert "stick." not in text


# --- multibody columns (D13) ------------------------------------------------------------------

@pytest.fixture(scope="module")
def slider_crank():
    return ukdyn.load("slider_crank").simulate(t_end=0.25)


def test_multibody_result_names_are_distinct(slider_crank):
    r = slider_crank
    assert len(r.names) == len(set(r.names))
    frame = r.to_dataframe()
    assert list(frame.columns) == r.names
    assert list(frame.columns).count("crank.x") == 1


@pytest.mark.parametrize("example", ["slider_crank", "double_four_bar_bodies", "heavy_top",
                                     "pendulum_loop", "rolling_disk_bodies",
                                     "double_four_bar_bodies_redundant"])
def test_every_multibody_example_has_distinct_names(example):
    r = ukdyn.load(example).simulate(t_end=0.01)
    assert len(r.names) == len(set(r.names)), [n for n in r.names if r.names.count(n) > 1]


def test_body_coordinates_are_found_by_both_spellings(slider_crank):
    r = slider_crank
    for dotted in ["crank.x", "crank.theta", "slider.x", "crank.x_dot", "slider.x_ddot",
                   "Qc_ideal.crank.x", "Qc_nonideal.rod.theta"]:
        underscored = dotted.replace("crank.", "crank_").replace("slider.", "slider_") \
                            .replace("rod.", "rod_")
        assert dotted in r and underscored in r
        assert r[underscored] is r[dotted]
    assert r.crank_x is r["crank.x"]
    # the piston: x = r cos(th) + sqrt(l^2 - r^2 sin(th)^2), th = 0.3 + 2 pi t (the file's
    # closed form; r = 0.3, l = 1)
    th = 0.3 + 2 * math.pi * r.t
    piston = 0.3 * np.cos(th) + np.sqrt(1 - 0.09 * np.sin(th) ** 2)
    np.testing.assert_allclose(r["slider_x"], piston, rtol=0, atol=1e-8)
    # the pose columns that are not coordinates stay, once
    assert r.names.count("crank.qw") == 1 and r.names.count("crank.z") == 1
    with pytest.raises(KeyError, match="no column 'crank_w'"):
        r["crank_w"]


# --- typed errors ----------------------------------------------------------------------------

def test_a_penetrated_contact_is_its_own_cause():
    # (u15 10) a ball 0.05 into its floor: "penetrated", not "not_projected" (which says that
    # project_initial=True may help: it cannot, projection does not act on a gap)
    text = ("bodies:\n  - {name: ball, type: rigid, mass: 1, inertia: [1, 1, 1], "
            "position: [0, 0, 0.05]}\ncontacts:\n  - {name: floor, body: ball, shape: sphere, "
            "radius: 0.1}\nsimulate: {t_end: 0.01}\n")
    for project in (False, True):
        with pytest.raises(ukdyn.InconsistentInitialState) as info:
            ukdyn.parse(text, "sunk.yaml").simulate(project_initial=project)
        assert info.value.cause == "penetrated"
        assert "the unilateral constraint 'floor' is penetrated" in str(info.value)
    # the model's System simulated directly: the C++ cause itself (Cause::kPenetrated), which
    # this path reported as "not_projected" before
    model = ukdyn.parse(text, "sunk.yaml")
    with pytest.raises(ukdyn.InconsistentInitialState) as info:
        ukdyn.simulate(model.system, model.q0, model.qd0, t_end=0.01)
    assert info.value.cause == "penetrated"


def test_inconsistent_initial_state_is_a_value_error_typed_by_its_cause():
    text = ("coordinates: [x, y]\nmass_matrix: [[1, 0], [0, 1]]\nforces: [0, -9.81]\n"
            "constraints:\n  - {name: rod, holonomic: x^2 + y^2 - 1}\n"
            "initial: {q: {x: 1.1, y: 0}}\nsimulate: {t_end: 0.01}\n")
    model = ukdyn.parse(text, "off_rod.yaml")
    with pytest.raises(ukdyn.InconsistentInitialState) as info:
        model.simulate()
    assert isinstance(info.value, ValueError)
    assert info.value.cause == "not_projected"
    assert "inconsistent initial conditions at t = 0" in str(info.value)
    contradictory = text.replace("initial: {q: {x: 1.1, y: 0}}\n", "").replace(
        "  - {name: rod", "  - {name: a, holonomic: x}\n  - {name: b, holonomic: x - 1}\n"
        "  - {name: rod")
    with pytest.raises(ukdyn.InconsistentInitialState) as info:
        ukdyn.parse(contradictory, "c.yaml").simulate(project_initial=True)
    assert info.value.cause == "contradictory"
    # projected onto the rod in the M-norm (M = I): starts at (1, 0)
    result = model.simulate(project_initial=True)
    assert result.q[0, 0] == pytest.approx(1.0, abs=1e-12)
    assert result.q[0, 1] == pytest.approx(0.0, abs=1e-12)
