# SPDX-License-Identifier: BSD-3-Clause
"""Singular (positive semi-definite) mass matrices from Python (issue #13, item 3; C++:
tests/dynamics/test_singular_mass.cpp). A pendulum in the redundant coordinates (x, y, theta) with
T = m (x'^2 + y'^2) / 2, i.e. M = diag(m, m, 0): theta has no inertia and follows from the
constraints x = L sin(theta), y = -L cos(theta) alone. Released at rest from theta0 it obeys
theta'' = -w^2 sin(theta), w^2 = m g L / (m L^2 + J) with J = 0, whose exact solution is

    sin(theta/2) = k sn(K(k) - w t, k),   k = sin(theta0/2),   period 4 K(k) / w.

The same pendulum with an inertia J > 0 on theta (a flywheel driven by the rod; a regular M)
checks the reference and the model file today; the J = 0 cases need the singular-mass support.
Every reference number comes from analysis, not from ukdyn."""

import math
import pathlib

import numpy as np
import pytest

import ukdyn

DATA = pathlib.Path(__file__).resolve().parents[2] / "tests" / "data"
M_, L_, G_, THETA0 = 1.3, 0.9, 9.81, 2.5


def jacobi_sn_cn_dn(u, k):
    """sn, cn, dn(u, k) (modulus k) for an array u: SciPy when present, else mpmath."""
    u = np.asarray(u, dtype=float)
    try:
        from scipy.special import ellipj
        sn, cn, dn, _ = ellipj(u, k * k)
        return sn, cn, dn
    except ImportError:
        import mpmath
        f = np.vectorize(lambda x, kind: float(mpmath.ellipfun(kind, x, m=k * k)))
        return f(u, "sn"), f(u, "cn"), f(u, "dn")


def complete_K(k):
    """K(k) by the arithmetic-geometric mean: pi / (2 agm(1, sqrt(1 - k^2)))."""
    a, b = 1.0, math.sqrt(1.0 - k * k)
    for _ in range(40):
        a, b = (a + b) / 2, math.sqrt(a * b)
    return math.pi / (2 * a)


class Elliptic:
    """theta(t), theta'(t) and the period of the pendulum released at rest from theta0."""

    def __init__(self, J=0.0, m=M_, L=L_, g=G_, theta0=THETA0):
        self.k = math.sin(theta0 / 2)
        self.K = complete_K(self.k)
        self.w = math.sqrt(m * g * L / (m * L * L + J))
        self.theta0 = theta0

    @property
    def period(self):
        return 4 * self.K / self.w

    def theta(self, t):
        sn, _, _ = jacobi_sn_cn_dn(self.K - self.w * np.asarray(t), self.k)
        return 2 * np.arcsin(self.k * sn)

    def theta_dot(self, t):
        # d/dt sin(theta/2) = cos(theta/2) theta'/2 = -k w cn dn, cos(theta/2) = sqrt(1 - k^2 sn^2)
        sn, cn, dn = jacobi_sn_cn_dn(self.K - self.w * np.asarray(t), self.k)
        return -2 * self.k * self.w * cn * dn / np.sqrt(1 - (self.k * sn) ** 2)


def test_the_reference_is_the_elliptic_solution():
    ref = Elliptic()
    # the example pendulum's period (L = 1, theta0 = pi/2): 2.367841947576 s
    assert Elliptic(m=1, L=1, theta0=math.pi / 2).period == pytest.approx(2.367841947576,
                                                                         abs=1e-11)
    assert ref.period == pytest.approx(3.126795873776, abs=1e-11)
    t = np.linspace(0, 2 * ref.period, 301)
    assert ref.theta(0.0) == pytest.approx(THETA0, abs=1e-14)
    # energy: theta'^2 = 2 w^2 (cos theta - cos theta0); turning points at the half periods
    np.testing.assert_allclose(ref.theta_dot(t) ** 2,
                               2 * ref.w**2 * (np.cos(ref.theta(t)) - math.cos(THETA0)),
                               rtol=0, atol=1e-11)
    np.testing.assert_allclose(ref.theta([ref.period / 2, ref.period]), [-THETA0, THETA0],
                               rtol=0, atol=1e-12)
    # theta'' = -w^2 sin(theta) by central differences
    h = 1e-4
    dd = (ref.theta(t + h) - 2 * ref.theta(t) + ref.theta(t - h)) / h**2
    np.testing.assert_allclose(dd, -ref.w**2 * np.sin(ref.theta(t)), rtol=0, atol=1e-5)


def pendulum(J=0.0):
    """The (x, y, theta) pendulum from callables, M = diag(m, m, J)."""
    def A(q, qd, t):
        return np.array([[1.0, 0.0, -L_ * math.cos(q[2])], [0.0, 1.0, -L_ * math.sin(q[2])]])

    def b(q, qd, t):
        return [-L_ * math.sin(q[2]) * qd[2] ** 2, L_ * math.cos(q[2]) * qd[2] ** 2]

    return ukdyn.from_callables(["x", "y", "theta"], M=np.diag([M_, M_, J]),
                                Q=lambda q, qd, t: [0.0, -M_ * G_, 0.0],
                                V=lambda q, t: M_ * G_ * q[1],
                                constraints=[ukdyn.constraint("rod", A, b, rows=2)])


def state(theta, theta_dot):
    s, c = math.sin(theta), math.cos(theta)
    return (np.array([L_ * s, -L_ * c, theta]),
            np.array([L_ * c * theta_dot, L_ * s * theta_dot, theta_dot]))


def expect_closed_form_solution(system, J):
    ref = Elliptic(J)
    for theta, theta_dot in [(2.5, 0.0), (0.9, -1.7), (-0.3, 4.2)]:
        q, qd = state(theta, theta_dot)
        sol = system.solver().solve(q, qd, 0.0)
        s, c = math.sin(theta), math.cos(theta)
        tdd = -ref.w**2 * s
        expected = [L_ * (c * tdd - s * theta_dot**2), L_ * (s * tdd + c * theta_dot**2), tdd]
        np.testing.assert_allclose(sol.qdd, expected, rtol=0, atol=1e-12)
        # Qc = M q'' - Q: the rod pulls the particle towards the pivot with
        # T = m g cos(theta) + m L theta'^2, across it with m sin(theta) (g - L w^2)
        Qc = np.asarray(sol.Qc)
        tension = M_ * G_ * c + M_ * L_ * theta_dot**2
        assert Qc[:2] @ [-s, c] == pytest.approx(tension, abs=1e-11)
        assert Qc[:2] @ [c, s] == pytest.approx(M_ * s * (G_ - L_ * ref.w**2), abs=1e-11)
        assert Qc[2] == pytest.approx(J * tdd, abs=1e-11)


def expect_follows_elliptic(result, J):
    ref = Elliptic(J)
    np.testing.assert_allclose(result.theta, ref.theta(result.t), rtol=0, atol=1e-7)
    np.testing.assert_allclose(result.theta_dot, ref.theta_dot(result.t), rtol=0, atol=1e-6)
    np.testing.assert_allclose(result.x, L_ * np.sin(result.theta), rtol=0, atol=1e-9)
    np.testing.assert_allclose(result.y, -L_ * np.cos(result.theta), rtol=0, atol=1e-9)
    # back at theta0 after each period, at -theta0 after each half
    for i in range(1, int(round(2 * result.t[-1] / ref.period)) + 1):
        at = int(np.argmin(np.abs(result.t - i * ref.period / 2)))
        assert result.t[at] == pytest.approx(i * ref.period / 2, abs=1e-12)
        assert result.theta[at] == pytest.approx((-1) ** i * THETA0, abs=1e-7)


def run(system, J, periods=3):
    T = Elliptic(J).period
    q0, qd0 = state(THETA0, 0.0)
    return ukdyn.simulate(system, q0, qd0, t_end=periods * T, rtol=1e-10, atol=1e-12,
                          output_every=0.01, output_at=[i * T / 2 for i in range(1, 2 * periods)])


def test_reference_compound_pendulum_with_inertia_on_theta():
    """Regular M = diag(m, m, 0.4): solvable without the singular-mass support."""
    system = pendulum(J=0.4)
    expect_closed_form_solution(system, 0.4)
    expect_follows_elliptic(run(system, 0.4), 0.4)


def test_pendulum_without_inertia_on_theta_is_the_elliptic_pendulum():
    system = pendulum(J=0.0)
    expect_closed_form_solution(system, 0.0)
    r = run(system, 0.0)
    assert r.ok
    expect_follows_elliptic(r, 0.0)
    # the massless coordinate takes no constraint force
    np.testing.assert_allclose(r["Qc_ideal.theta"], 0.0, rtol=0, atol=1e-9)


def test_reference_model_file_with_inertia_on_theta():
    r = ukdyn.load(DATA / "singular_pendulum_mass_matrix.yaml", J=0.4).simulate(
        t_end=3 * Elliptic(0.4).period, output_at=[i * Elliptic(0.4).period / 2 for i in range(1, 6)])
    expect_follows_elliptic(r, 0.4)


@pytest.mark.parametrize("name", ["singular_pendulum_lagrangian", "singular_pendulum_mass_matrix"])
def test_model_files_with_a_massless_theta_run(name):
    model = ukdyn.load(DATA / f"{name}.yaml")
    T = Elliptic().period
    r = model.simulate(output_at=[i * T / 2 for i in range(1, 6)])
    assert r.t[-1] == pytest.approx(3 * T, abs=1e-12)
    expect_follows_elliptic(r, 0.0)


def test_a_coordinate_that_nothing_determines_is_named():
    system = ukdyn.from_callables(["anchor", "slack"], M=np.diag([1.0, 0.0]),
                                  Q=lambda q, qd, t: [0.0, -1.0],
                                  constraints=[ukdyn.constraint(
                                      "pin", lambda q, qd, t: [1.0, 0.0], lambda q, qd, t: [0.0])])
    solver = system.solver()
    with pytest.raises(ukdyn.SolveError) as err:
        solver.solve([0.0, 0.0], [0.0, 0.0], 0.75)
    assert err.value.status == "motion not determined"
    assert "slack" in str(err.value) and "t = 0.75" in str(err.value)
    sol = solver.solve([0.0, 0.0], [0.0, 0.0], 0.75, check=False)
    assert not sol.ok and sol.status == "motion not determined"
    assert "slack" in sol.message and "anchor" not in sol.message


def test_an_indefinite_mass_matrix_is_still_refused():
    system = ukdyn.from_callables(["x", "y"], M=np.diag([1.0, -1.0]),
                                  constraints=[ukdyn.constraint(
                                      "pin", lambda q, qd, t: [0.0, 1.0], lambda q, qd, t: [0.0])])
    sol = system.solver().solve([0.0, 0.0], [0.0, 0.0], 0.0, check=False)
    assert sol.status == "mass matrix not positive definite"
