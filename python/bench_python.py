#!/usr/bin/python3
# SPDX-License-Identifier: BSD-3-Clause
"""Benchmark of the Python module (issue #7, item 7; run by hand, numbers in docs/python.md):

(a) a SymPy-defined model against the same model file: the run time of simulate() for each
    (median of several runs) and their ratio (target: within 10 %);
(b) the per-call overhead of Solver.solve / Solver.evaluate from Python against the C++ cost of
    one evaluation (forward_dynamics in a C++ loop).

    PYTHONPATH=build/python /usr/bin/python3 python/bench_python.py
"""

import os
import statistics
import sys
import time

# this file sits next to the package's sources (python/ukdyn, without the compiled part): import
# the built package from PYTHONPATH instead
_here = os.path.dirname(os.path.abspath(__file__))
sys.path = [p for p in sys.path if os.path.abspath(p or ".") != _here]

import numpy as np
import sympy as sp

import ukdyn

REPEATS = 7


def median_time(fn, repeats=REPEATS):
    fn()  # warm-up
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def four_bar_sympy():
    """examples/models/four_bar_friction.yaml written with SymPy."""
    xB, yB, xC, yC = q = sp.symbols("xB yB xC yC")
    xBd, yBd, xCd, yCd = ukdyn.velocities(q)
    lc, lb, lr, d, rho, g, c, mu_pin, r_pin, eps = sp.symbols("lc lb lr d rho g c mu_pin r_pin eps")
    N_crank = sp.Symbol("N_crank")
    T = (rho * lc / 6 * (xBd**2 + yBd**2)
         + rho * lb / 6 * (xBd**2 + yBd**2 + xBd * xCd + yBd * yCd + xCd**2 + yCd**2)
         + rho * lr / 6 * (xCd**2 + yCd**2))
    V = rho * g * (lc * yB / 2 + lb * (yB + yC) / 2 + lr * yC / 2)
    w = (xB * yBd - yB * xBd) / lc**2
    torque = -(c * w + mu_pin * r_pin * N_crank * w / sp.sqrt(w**2 + eps**2))
    file = ukdyn.load("four_bar_friction")
    return ukdyn.from_sympy(
        q, T=T, V=V,
        constraints={"crank": (xB**2 + yB**2 - lc**2) / (2 * lc),
                     "coupler": ((xC - xB)**2 + (yC - yB)**2 - lb**2) / (2 * lb),
                     "rocker": ((xC - d)**2 + yC**2 - lr**2) / (2 * lr)},
        nonideal=[{"C": [torque * (-yB) / lc**2, torque * xB / lc**2, 0, 0]}],
        parameters={sp.Symbol(k): v for k, v in file.parameters.items()},
        initial={"q": dict(zip(q, file.q0.tolist())), "q_dot": dict(zip(q, file.qd0.tolist())),
                 "project": True},
        simulate={"t_end": 10, "integrator": "dopri5", "rtol": 1e-9, "atol": 1e-11,
                  "drift": "projection"},
        output={"every": 0.01, "expressions": {"crank_angle": sp.atan2(yB, xB),
                                               "crank_rate": w}},
        name="four-bar with pin friction")


def double_pendulum_sympy():
    """examples/models/double_pendulum.yaml written with SymPy."""
    x1, y1, x2, y2 = q = sp.symbols("x1 y1 x2 y2")
    x1d, y1d, x2d, y2d = ukdyn.velocities(q)
    m1, m2, L1, L2, g = sp.symbols("m1 m2 L1 L2 g")
    return ukdyn.from_sympy(
        q, T=m1 * (x1d**2 + y1d**2) / 2 + m2 * (x2d**2 + y2d**2) / 2, V=g * (m1 * y1 + m2 * y2),
        constraints={"rod1": (x1**2 + y1**2 - L1**2) / (2 * L1),
                     "rod2": ((x2 - x1)**2 + (y2 - y1)**2 - L2**2) / (2 * L2)},
        parameters={m1: 1, m2: 1, L1: 1, L2: 1, g: 9.81},
        initial={"q": {x1: L1, y1: 0, x2: L1 + L2, y2: 0}},
        simulate={"t_end": 10, "integrator": "dopri5", "rtol": 1e-10, "atol": 1e-12},
        output={"every": 0.01, "expressions": {"theta1": sp.atan2(x1, -y1),
                                               "theta2": sp.atan2(x2 - x1, -(y2 - y1))}},
        name="double pendulum")


def bench_sympy_vs_file():
    print("(a) SymPy-defined model vs the same model file: simulate(), median of", REPEATS)
    for name, make in [("double_pendulum", double_pendulum_sympy),
                       ("four_bar_friction", four_bar_sympy)]:
        file_model, sympy_model = ukdyn.load(name), make()
        a, b = file_model.simulate(), sympy_model.simulate()
        diff = max(float(np.max(np.abs(a[n] - b[n]))) for n in a.names)
        t_file = median_time(file_model.simulate)
        t_sympy = median_time(sympy_model.simulate)
        print(f"  {name:18s} file {t_file * 1e3:8.2f} ms   sympy {t_sympy * 1e3:8.2f} ms   "
              f"ratio {t_sympy / t_file:5.3f}   steps {a.stats['steps']} / {b.stats['steps']}   "
              f"max |difference| {diff:.1e}")


def bench_solve_overhead():
    print("(b) one evaluation: C++ loop vs Solver.evaluate / Solver.solve from Python")
    calls = 20000
    for name in ["pendulum", "four_bar_friction", "double_four_bar"]:
        model = ukdyn.load(name)
        solver = model.solver()
        q, qd = np.ascontiguousarray(model.q0), np.ascontiguousarray(model.qd0)
        if name == "pendulum":
            qd = np.array([0.0, -1.0])
        cpp = min(solver._time_cpp(q, qd, 0.0, calls) for _ in range(5))

        def loop(fn):
            start = time.perf_counter()
            for _ in range(calls):
                fn(q, qd, 0.0)
            return (time.perf_counter() - start) / calls

        ev = min(loop(solver.evaluate) for _ in range(5))
        so = min(loop(solver.solve) for _ in range(5))
        n, m = model.system.coordinate_count, model.system.constraint_rows
        print(f"  {name:18s} (n={n}, m={m})  C++ {cpp * 1e6:6.2f} µs   evaluate {ev * 1e6:6.2f} µs "
              f"(+{(ev - cpp) * 1e6:5.2f})   solve {so * 1e6:6.2f} µs (+{(so - cpp) * 1e6:5.2f})")


if __name__ == "__main__":
    bench_sympy_vs_file()
    bench_solve_overhead()
