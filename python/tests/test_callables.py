# SPDX-License-Identifier: BSD-3-Clause
"""Systems and controllers from Python callables (the slow path), exceptions from callables, and
the GIL released during runs."""

import math
import threading
import time

import numpy as np
import pytest

import ukdyn

G = 9.81


def callable_pendulum(c=0.0):
    def A(q, qd, t):
        return [q]  # grad of (x^2 + y^2 - 1)/2

    def b(q, qd, t):
        return [-(qd @ qd)]

    forces = [ukdyn.viscous(c)] if c else []
    return ukdyn.from_callables(["x", "y"], M=np.eye(2), Q=lambda q, qd, t: [0.0, -G],
                                V=lambda q, t: G * q[1],
                                constraints=[ukdyn.constraint("rod", A, b)], nonideal=forces)


def state(theta=0.6, theta_dot=1.5):
    s, c = math.sin(theta), math.cos(theta)
    return np.array([s, -c]), theta_dot * np.array([c, s])


def test_callable_pendulum_solves_like_the_model_file():
    q, qd = state()
    a = callable_pendulum().solver().solve(q, qd)
    b = ukdyn.load("pendulum").solver().solve(q, qd)
    for name in ["qdd", "Qc_ideal", "lambda_"]:
        np.testing.assert_allclose(getattr(a, name), getattr(b, name), rtol=0, atol=1e-13)


def test_viscous_pivot_friction_gives_the_readme_demo_numbers():
    """pendulum_demo: theta'' = -g sin(theta) - c theta' (m = L = 1), Qc_nonideal = -c q'."""
    q, qd = state()
    for system in (callable_pendulum(c=0.2),
                   ukdyn.from_callables(["x", "y"], M=lambda q, t: np.eye(2),
                                        Q=lambda q, qd, t: np.array([0.0, -G]),
                                        constraints=[ukdyn.constraint(
                                            "rod", lambda q, qd, t: q, lambda q, qd, t: -(qd @ qd))],
                                        nonideal=[ukdyn.nonideal("pivot", lambda q, qd, t: -0.2 * qd)])):
        sol = system.solver().solve(q, qd)
        theta_ddot = sol.qdd @ np.array([math.cos(0.6), math.sin(0.6)])
        assert theta_ddot == pytest.approx(-G * math.sin(0.6) - 0.2 * 1.5, abs=1e-12)
        assert theta_ddot == pytest.approx(-5.839142664005, abs=1e-12)
        np.testing.assert_allclose(sol.Qc_nonideal, [-0.247600684473, -0.169392742019], atol=1e-12)
        np.testing.assert_allclose(sol.qdd, [-6.089697966281, -1.440022822764], atol=1e-12)


def test_readme_incline_with_coulomb_friction():
    m, alpha, mu = 2.0, 0.5, 0.3
    system = ukdyn.from_callables(
        ["x", "y"], M=m * np.eye(2), Q=lambda q, qd, t: [0.0, -m * G],
        constraints=[ukdyn.constraint("plane", lambda q, qd, t: [math.tan(alpha), 1.0],
                                      lambda q, qd, t: [0.0])],
        nonideal=[ukdyn.coulomb("plane", mu)])
    down = np.array([math.cos(alpha), -math.sin(alpha)])
    sol = system.solver().solve([0.0, 0.0], down)
    assert sol.qdd @ down == pytest.approx(G * (math.sin(alpha) - mu * math.cos(alpha)), abs=1e-12)
    assert sol.qdd @ down == pytest.approx(2.120439, abs=1e-6)


def test_callables_receive_their_own_numpy_arrays():
    """The C++ side hands the callables views of its memory (Eigen::Ref); the module copies each
    into a fresh float64 array, so a callable may keep what it receives."""
    seen = []

    def Q(q, qd, t):
        seen.append((q, qd))
        return [0.0, -G]

    def A(q, qd, t):
        seen.append((q, qd))
        return [q]

    def b(q, qd, t):
        return [-(qd @ qd)]

    solver = ukdyn.from_callables(["x", "y"], M=np.eye(2), Q=Q,
                                  constraints=[ukdyn.constraint("rod", A, b)]).solver()
    q1, qd1 = state(0.6, 1.5)
    solver.solve(q1, qd1)
    first = len(seen)
    q2, qd2 = state(-0.3, 0.5)
    solver.solve(q2, qd2)
    assert 0 < first < len(seen)
    for q, qd in seen:
        for a in (q, qd):
            assert isinstance(a, np.ndarray) and a.dtype == np.float64 and a.shape == (2,)
            assert a.flags.owndata and a.flags.writeable
    # the arrays of the first solve still hold its state: nothing was a view of a reused buffer
    for q, qd in seen[:first]:
        np.testing.assert_array_equal(q, q1)
        np.testing.assert_array_equal(qd, qd1)
    for q, qd in seen[first:]:
        np.testing.assert_array_equal(q, q2)
        np.testing.assert_array_equal(qd, qd2)


def test_callable_pendulum_period_by_simulation():
    """Released horizontally, back at (1, 0) after 4 sqrt(L/g) K(1/2) = 2.367841947576 s."""
    T = 2.367841947576
    r = ukdyn.simulate(callable_pendulum(), [1.0, 0.0], [0.0, 0.0], t_end=T, rtol=1e-11,
                       atol=1e-13, drift="none", output_every=0.1)
    assert r.ok and r.t[-1] == pytest.approx(T, abs=1e-12)
    assert r.x[-1] == pytest.approx(1.0, abs=1e-6)
    assert r.y[-1] == pytest.approx(0.0, abs=1e-6)
    np.testing.assert_allclose(r.energy, 0.0, rtol=0, atol=1e-7)
    assert r.names[:3] == ["t", "x", "y"]


def test_exception_in_a_callable_is_raised_again_unchanged():
    def Q(q, qd, t):
        if t > 0.05:
            raise ZeroDivisionError("Q failed on purpose")
        return [0.0, -G]

    system = ukdyn.from_callables(["x", "y"], M=np.eye(2), Q=Q)
    with pytest.raises(ZeroDivisionError, match="on purpose"):
        system.solver().solve([0.0, 0.0], [0.0, 0.0], t=0.1)
    with pytest.raises(ZeroDivisionError, match="on purpose"):
        ukdyn.simulate(system, [0.0, 0.0], [0.0, 0.0], t_end=0.2)
    # the system is usable again afterwards
    assert system.solver().solve([0.0, 0.0], [0.0, 0.0], t=0.0).ok


def test_wrong_shape_from_a_callable_is_a_value_error():
    system = ukdyn.from_callables(["x", "y"], M=lambda q, t: np.eye(3))
    with pytest.raises(ValueError, match=r"M\(q, t\) must have shape \(2, 2\) \(got shape \(3, 3\)\)"):
        system.solver().solve([0.0, 0.0], [0.0, 0.0])
    with pytest.raises(ValueError, match="M must be 2 × 2"):
        ukdyn.from_callables(["x", "y"], M=np.eye(3))
    with pytest.raises(ValueError, match="named twice"):
        ukdyn.from_callables(["x", "x"], M=np.eye(2))


@pytest.mark.parametrize("kind, fn, message", [
    ("P", lambda q, qd, t: np.zeros(3), r"P\(q, q_dot, t\) must return one number \(got 3 entries\)"),
    ("P", lambda q, qd, t: None, r"P\(q, q_dot, t\) returned None"),
    ("P", lambda q, qd, t: np.eye(2), r"P\(q, q_dot, t\) must return one number \(got shape \(2, 2\)\)"),
    ("P", lambda q, qd, t: math.nan if t > 0.1 else 0.0,
     r"P\(q, q_dot, t\) returned nan at t = 0\.1\d* \(it must return a finite number\)"),
    ("V", lambda q, t: "abc", r"V\(q, t\) returned 'abc' \(it must return a number\)"),
    ("V", lambda q, t: 1j, r"V\(q, t\) must be real numbers \(got complex\)"),
    ("V", lambda q, t: math.inf, r"V\(q, t\) returned inf at t = 0 "),
])
def test_a_scalar_callable_that_returns_no_number_is_named(kind, fn, message):
    """P and V are named in the error as Q, M, A, b and C are (issue #29; reproducer
    py_callable_casts.py): never pybind11's "Unable to cast", never a NaN left to the energy
    balance; a NaN is reported with the time it was returned at (after t = 0.1 here)."""
    system = ukdyn.from_callables(["x", "y"], M=np.eye(2), Q=lambda q, qd, t: np.array([0.0, -G]),
                                  **{kind: fn})
    with pytest.raises(ValueError, match="ukdyn callable: " + message):
        ukdyn.simulate(system, [1.0, 0.0], [0.0, 0.0], t_end=0.5)


def test_a_surface_velocity_that_returns_no_pair_is_named():
    def A(q, qd, t):
        return [[0.0, 1.0]]

    def b(q, qd, t):
        return [0.0]

    for got, message in ((lambda q, qd, t: 1.0, r"must return \(u, u_dot\) \(got float\)"),
                         (lambda q, qd, t: [0.0], r"must return \(u, u_dot\) \(got 1 items\)")):
        system = ukdyn.from_callables(
            ["x", "y"], M=np.eye(2), Q=lambda q, qd, t: np.array([1.0, -G]),
            constraints=[ukdyn.constraint("floor", A, b)],
            nonideal=[ukdyn.coulomb("floor", 0.3, ["x"], surface_velocity=got)])
        with pytest.raises(ValueError, match=r"ukdyn callable: coulomb friction on 'floor': "
                                             r"surface_velocity\(q, q_dot, t\) " + message):
            ukdyn.simulate(system, [0.0, 0.0], [1.0, 0.0], t_end=0.2)


def test_the_gil_is_released_during_a_run():
    """Counted in GIL handoffs, not in time. The run calls stop() with the GIL every 20 ms of
    its work (Model._run's stop hook, which Model.simulate gives its Ctrl-C guard). Meanwhile a
    second thread loops on time.sleep(0), each pass giving the GIL away and taking it back. Were
    the GIL held while the run computes, that thread could only take it when the run gives it up
    at a checkpoint, and would get back to the run thread at its next sleep(0): about one pass
    per checkpoint. With the GIL released it passes freely all the while."""
    model = ukdyn.load("pendulum")
    passes = 0
    done = threading.Event()
    seen: list[int] = []  # the passes made before each checkpoint

    def spin():
        nonlocal passes
        while not done.is_set():
            passes += 1
            time.sleep(0)

    def stop():
        seen.append(passes)
        return len(seen) > 10  # ten intervals of the run's work, then stop

    worker = threading.Thread(target=spin)
    worker.start()
    try:
        # a run far longer than ten intervals: stop() ends it
        _, _, stats, _, raised, _ = model._run(
            {"t_end": 50.0, "integrator": "rk4", "step": 1e-5, "output_every": 1.0}, None, None,
            stop)
    finally:
        done.set()
        worker.join()
    assert raised is None
    assert stats["status"] == "interrupted" and 0 < stats["t_reached"] < 50.0
    assert len(seen) == 11
    # held (tried by removing the release): exactly one pass per checkpoint, 10 in all;
    # released: about 300 per interval here
    assert seen[-1] - seen[0] > 100, f"passes before each checkpoint: {seen}"


def test_callable_controller_tracks_sin_t_with_the_prescribed_error_dynamics():
    """A unit mass, x'' = u, required to follow sin t with e'' + 4 e' + 4 e = 0 written into
    b_r; from x(0) = 1, x'(0) = 1: e = x - sin t = (1 + 2t) e^(-2t)."""
    plant = ukdyn.from_callables(["x"], M=np.eye(1))

    def b_r(q, qd, t):
        e, e_dot = q[0] - math.sin(t), qd[0] - math.cos(t)
        return [-math.sin(t) - 4 * e_dot - 4 * e]

    ctrl = ukdyn.controller(plant, [ukdyn.constraint("track", lambda q, qd, t: [[1.0]], b_r)])
    assert ctrl.row_names == ["track"] and ctrl.law == "gauss" and ctrl.fully_actuated
    sol = ctrl.solver().compute([1.0], [1.0], 0.0)
    assert sol.ok and sol.met == [True]
    np.testing.assert_allclose(sol.Qc_control, [-4.0], rtol=0, atol=1e-14)  # -sin 0 - 0 - 4
    r = ukdyn.simulate(plant, [1.0], [1.0], controller=ctrl, t_end=3.0, rtol=1e-11, atol=1e-13)
    e = r.x - np.sin(r.t)
    np.testing.assert_allclose(e, (1 + 2 * r.t) * np.exp(-2 * r.t), rtol=0, atol=1e-8)
    assert "Qc_control.x" in r and r.control["not_met"] == 0


def test_control_solver_of_a_model_file_controller():
    m = ukdyn.load("control_duffing")
    p = m.parameters
    sol = m.controller.solver().compute([1.0], [0.0], 0.0)
    # e = 1, e' = -1 at t = 0: x'' = -sin 0 - 4(-1) - 4(1) = 0, so Qc = m*0 - Q
    Q = 1.0 - 1.0 + p["F"]
    np.testing.assert_allclose(sol.Qc_control, [-Q], rtol=0, atol=1e-13)
    assert sol.status == "ok" and sol.rank == 1
