# SPDX-License-Identifier: BSD-3-Clause
"""Scale-invariant numerics from Python (issue #29 item 2): the reproducer solve_overflow_rank0.py
of ../shared/reproducers/2026-11-28 as a test. A state where A Aᵀ over- or underflows keeps its
constraint (rank 1, the closed-form q''), and a row that is itself not finite is reported as
non-finite input naming A, never a dropped constraint with status 'ok'."""

import math

import numpy as np
import pytest

import ukdyn

G = 9.81

# the rod written without the example's 1/(2 L): its gradient (2x, 2y) overflows at x = 1e308
RAW_ROD = """
coordinates: [x, y]
kinetic_energy: 0.5*(x_dot^2 + y_dot^2)
potential_energy: 9.81*y
constraints:
  - {name: rod, holonomic: x^2 + y^2 - 1}
initial: {q: {x: 1}}
"""


@pytest.mark.parametrize("c", [1.0, 1e150, 1e154, 1e200, 1e-150, 1e-200])
@pytest.mark.parametrize("source", ["example", "raw"])
def test_a_state_of_any_size_keeps_the_rod(source, c):
    # at q = (c, c), q' = 0 the rod asks x'' + y'' = 0: q'' = (g/2, -g/2) whatever c
    model = ukdyn.load("pendulum") if source == "example" else ukdyn.parse(RAW_ROD)
    sol = model.solver().solve([c, c], [0.0, 0.0], 0.0, check=False)
    assert sol.status == "ok" and sol.rank == 1
    np.testing.assert_allclose(sol.qdd, [G / 2, -G / 2], rtol=0, atol=1e-12)
    # ‖A q'' − b‖ is roundoff relative to ‖A‖ ‖q''‖ (it was inf with the row dropped)
    norm_a = math.sqrt(2.0) * c * (1.0 if source == "example" else 2.0)
    assert math.isfinite(sol.residuals["constraint"])
    assert sol.residuals["constraint"] <= 1e-14 * norm_a * G


def test_at_1e308_the_example_keeps_its_row_and_the_raw_rod_is_reported():
    # the example's rod (x^2 + y^2 - L^2)/(2 L) has the finite row (x, y)/L = (1e308, 0): x'' = 0,
    # the answer (0, -g) with rank 1 (the constraint acts; nothing is dropped)
    sol = ukdyn.load("pendulum").solver().solve([1e308, 0.0], [0.0, 0.0], 0.0, check=False)
    assert sol.status == "ok" and sol.rank == 1
    np.testing.assert_allclose(sol.A, [[1e308, 0.0]], rtol=1e-15, atol=0)
    np.testing.assert_allclose(sol.qdd, [0.0, -G], rtol=0, atol=1e-12)
    # the raw rod's row (2x, 2y) = (inf, 0) is not finite: reported, never ok (the C++ twin is
    # RowEquilibration.HugeStatesKeepTheConstraint)
    solver = ukdyn.parse(RAW_ROD).solver()
    sol = solver.solve([1e308, 0.0], [0.0, 0.0], 0.0, check=False)
    assert sol.status.startswith("non-finite input") and not sol.ok
    assert "A" in sol.message and "rod" in sol.message
    with pytest.raises(ukdyn.SolveError, match="rod"):
        solver.solve([1e308, 0.0], [0.0, 0.0], 0.0)
