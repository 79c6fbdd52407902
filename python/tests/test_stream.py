# SPDX-License-Identifier: BSD-3-Clause
"""Sample grids above the documented bound (issue #14, item 3; docs/simulation.md, "Sample grid
and streaming"): refused with ValueError before the run, naming the options, the count and the
bound. Python's simulate() keeps its samples in memory (kMaxStoredValues = 2^28 values)."""

import numpy as np
import pytest

import ukdyn


def test_a_grid_whose_count_overflowed_is_refused_naming_it():
    m = ukdyn.load("pendulum")
    with pytest.raises(ValueError) as err:
        m.simulate(t_end=1e300)
    text = str(err.value)
    assert "the output grid (output_every = 0.01, t_start = 0, t_end = 1e+300) has 1e+302 samples" in text
    assert "more than the bound of 11671106 of a run kept in memory" in text  # 2^28 / 23


def test_a_grid_of_1e9_samples_is_refused_in_memory():
    m = ukdyn.load("pendulum")
    with pytest.raises(ValueError, match=r"output_every = 1e-09, t_start = 0, t_end = 1\) has "
                                         r"1000000002 samples, more than the bound of 11671106"):
        m.simulate(t_end=1.0, output_every=1e-9)


def test_a_grid_below_the_bound_runs_as_before():
    m = ukdyn.load("pendulum")
    r = m.simulate(t_end=1.0)
    t = np.asarray(r["t"])
    assert len(t) == 101
    np.testing.assert_allclose(np.diff(t), 0.01, rtol=0, atol=1e-12)
    assert t[-1] == 1.0
