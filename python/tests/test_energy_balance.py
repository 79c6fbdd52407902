# SPDX-License-Identifier: BSD-3-Clause
"""The energy balance in Python: the stats keys, the work columns, and the warning of a run whose
balance fails (docs/simulation.md, "Energy balance")."""

import math
import warnings

import numpy as np
import pytest

import ukdyn

WORKS = ["work_nonideal", "work_ideal", "work_drive", "work_external", "work_control"]


def test_stats_and_columns_of_a_rheonomic_constraint():
    # the bead on the rotating wire: the wire's work is the bead's gain of kinetic energy
    r = ukdyn.load("bead_on_rotating_wire").simulate()
    assert r.ok and r.status == "ok"
    assert 0.0 <= r.stats["energy_balance"] < 1e-8
    assert r.stats["energy_exchanged"] == pytest.approx(r.energy[-1] - r.energy[0], rel=1e-8)
    i = r.names.index("work_nonideal")
    assert r.names[i:i + 6] == WORKS + ["energy_balance_residual"]
    # T = ½ m (r'² + Ω² r²), r = r0 cosh t + rd0 sinh t (m = Ω = r0 = 1, rd0 = 0.5)
    t = r.t
    rr, rd = np.cosh(t) + 0.5 * np.sinh(t), np.sinh(t) + 0.5 * np.cosh(t)
    T = 0.5 * (rd ** 2 + rr ** 2)
    np.testing.assert_allclose(r.work_ideal, T - T[0], rtol=0, atol=1e-8)
    np.testing.assert_allclose(r.energy_balance_residual, 0.0, rtol=0, atol=1e-8)
    for name in ("work_nonideal", "work_drive", "work_external", "work_control"):
        np.testing.assert_array_equal(r[name], 0.0)


def damped(with_power):
    k, c = 4.0, 0.3
    return ukdyn.from_callables(
        ["x"], M=np.eye(1), Q=lambda q, qd, t: [-k * q[0] - c * qd[0]],
        V=lambda q, t: 0.5 * k * q[0] ** 2,
        P=(lambda q, qd, t: -c * qd[0] ** 2) if with_power else None)


def test_a_run_whose_balance_fails_warns_and_is_not_ok():
    # the damper's power undeclared: energy leaves that no work accounts for
    with pytest.warns(ukdyn.EnergyBalanceWarning, match="energy balance"):
        r = ukdyn.simulate(damped(False), [1.0], [0.0], t_end=3)
    assert r.status == "energy_balance" and not r.ok
    assert r.stats["energy_balance"] > 0.1
    assert r.t[-1] == pytest.approx(3.0)  # complete
    # declared, it balances; a tolerance can be set per run
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        ok = ukdyn.simulate(damped(True), [1.0], [0.0], t_end=3)
        assert ok.ok and ok.stats["energy_balance"] < 1e-8
        assert ok.work_external[-1] < -1.0
        loose = ukdyn.simulate(damped(False), [1.0], [0.0], t_end=3, energy_balance_tolerance=10.0)
        assert loose.ok
    with warnings.catch_warnings():
        warnings.simplefilter("error", ukdyn.EnergyBalanceWarning)
        with pytest.raises(ukdyn.EnergyBalanceWarning):
            ukdyn.simulate(damped(False), [1.0], [0.0], t_end=3)
    assert not math.isnan(ok.stats["energy_exchanged"])
