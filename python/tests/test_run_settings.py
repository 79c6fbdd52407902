# SPDX-License-Identifier: BSD-3-Clause
"""Run settings in Python (issue #14, items 4 and 5): settings a run cannot use raise ValueError
naming them; max_steps from a model file; the energy drift of a block at rest; adaptive steps
that leave the model's domain are retried smaller (docs/simulation.md, "Settings")."""

import math

import numpy as np
import pytest

import ukdyn

OSCILLATOR = """
coordinates: [x]
kinetic_energy: 0.5*x_dot^2
potential_energy: 0.5*x^2
initial: {q: {x: 1}}
"""


@pytest.fixture(scope="module")
def oscillator():
    return ukdyn.parse(OSCILLATOR)


@pytest.mark.parametrize("t_end", [math.inf, math.nan, 1e-300])
def test_unusable_end_times_raise_naming_t_end(oscillator, t_end):
    # inf and 1e-300 returned 0 samples with status ok
    with pytest.raises(ValueError, match=r"t_end"):
        oscillator.simulate(t_end=t_end)


def test_end_below_the_resolution_says_the_rule(oscillator):
    with pytest.raises(ValueError, match=r"by more than 1e-12 max\(1, \|t_start\|, \|t_end\|\)"):
        oscillator.simulate(t_end=1e-300)


@pytest.mark.parametrize("integrator", ["rk4", "rk5"])
def test_fixed_steps_below_resolution_or_above_max_steps_raise(oscillator, integrator):
    # step 1e-300 failed with an unrelated projection error; 1e-8 ran 10^8 steps
    with pytest.raises(ValueError, match=r"step \(1e-300\) of .* below the resolution of t"):
        oscillator.simulate(integrator=integrator, step=1e-300)
    with pytest.raises(ValueError, match=r"takes 1e\+08 steps .* max_steps = 10000000"):
        oscillator.simulate(integrator=integrator, step=1e-8)
    with pytest.raises(ValueError, match=r"max_steps= in Python"):
        oscillator.simulate(integrator=integrator, step=1e-3, max_steps=999)
    r = oscillator.simulate(integrator=integrator, step=1e-3, max_steps=1000)
    assert r.ok and r.stats["steps"] == 1000
    assert r.x[-1] == pytest.approx(math.cos(1.0), abs=1e-10)


@pytest.mark.parametrize("at", [[100.0], [math.nan], [0.5, -1.0]])
def test_output_times_outside_the_run_or_nan_raise(oscillator, at):
    # ignored silently before, while the model file refused them
    with pytest.raises(ValueError, match=r"output_at time .* is outside the run \[0, 1\]"):
        oscillator.simulate(output_at=at)


@pytest.mark.parametrize("name", ["baumgarte_alpha", "baumgarte_beta", "rtol", "step",
                                  "initial_tolerance", "projection_tolerance", "output_every"])
def test_nan_settings_raise_naming_them(oscillator, name):
    with pytest.raises(ValueError, match=name):
        oscillator.simulate(**{name: math.nan})


def test_rtol_below_roundoff_is_raised_with_a_note(oscillator):
    r = oscillator.simulate(rtol=1e-30, atol=1e-30, t_end=0.5)
    assert r.ok
    assert any("rtol = 1e-30 is below the roundoff of double: the run uses rtol = 2.22e-14" in n
               for n in r.stats["notes"])
    assert r.x[-1] == pytest.approx(math.cos(0.5), abs=1e-12)


def test_max_steps_from_a_model_file_holds_for_dopri5_and_rk4():
    m = ukdyn.parse(OSCILLATOR + "simulate: {t_end: 100, max_steps: 25}\n")
    assert m.options["max_steps"] == 25
    r = m.simulate(check=False)
    assert not r.ok
    assert r.stats["steps"] == 25
    assert "raise it: simulate: max_steps in a model file" in r.stats["message"]
    # the limit is no collapse (u19 01): the mean step is said, not "the step size collapsed"
    assert "a mean step of " in r.stats["message"]
    assert "collapsed" not in r.stats["message"]
    with pytest.raises(ukdyn.ModelError) as e:
        ukdyn.parse(OSCILLATOR + "simulate: {t_end: 1, integrator: rk4, step: 1e-3, "
                                 "max_steps: 999}\n")
    assert (e.value.line, e.value.column) == (6, 45)
    assert "more than max_steps = 999" in e.value.message


def test_energy_drift_of_a_block_at_rest():
    # E(0) = 0 and nothing moves: the drift was 7.1e15
    m = ukdyn.parse("""
parameters: {m: 1, g: 9.81, alpha: 0.5}
coordinates: [x, y]
kinetic_energy: 0.5*m*(x_dot^2 + y_dot^2)
potential_energy: m*g*y
constraints:
  - {name: plane, holonomic: x*sin(alpha) + y*cos(alpha)}
nonideal:
  - {friction: coulomb, constraint: plane, mu: tan(alpha)}
simulate: {t_end: 2}
""")
    r = m.simulate()
    assert r.ok
    assert 0.0 <= r.stats["energy_drift"] <= 1e-12
    assert r.stats["energy_drift"] == np.max(np.abs(r.energy_balance_residual))


@pytest.mark.parametrize("integrator", ["dopri5", "rkf78", "bdf"])
def test_steps_outside_the_domain_are_retried(integrator):
    # M = 1 − t: x'' = 0 until t = 1 (dopri5 stopped at 0.527, bdf at 0.381)
    m = ukdyn.parse(f"""
coordinates: [x]
mass_matrix: [[1 - t]]
forces: [0]
initial: {{q_dot: {{x: 1}}}}
simulate: {{t_end: 2, integrator: {integrator}}}
""")
    with pytest.raises(ukdyn.SolveError) as e:
        m.simulate()
    r = e.value.result
    assert 0.99 < r.stats["t_reached"] <= 1.0
    message = r.stats["message"]
    assert f"{integrator}: no step beyond t = " in message
    assert message.count("t = ") == 1
    np.testing.assert_allclose(r.x, r.t, rtol=0, atol=1e-9)
    assert r.t[-1] == pytest.approx(0.99, abs=1e-12)


def test_fixed_step_samples_closer_than_the_step_raise(oscillator):
    with pytest.raises(ValueError, match=r"output_every \(0\.001\) is below the step \(0\.01\) of rk4"):
        oscillator.simulate(integrator="rk4", step=0.01, output_every=0.001)


def test_settings_errors_do_not_name_the_cpp_function(oscillator):
    # a keyword's bad value: a ValueError naming the setting, not "ukdyn::simulate:"
    with pytest.raises(ValueError) as info:
        oscillator.simulate(t_end=1e300)
    assert str(info.value).startswith("the output grid (output_every = 0.01, t_start = 0, "
                                      "t_end = 1e+300) has 1e+302 samples")
    assert "ukdyn::" not in str(info.value)
    with pytest.raises(ValueError) as info:
        oscillator.simulate(t_end=1e-300)
    assert str(info.value).startswith("t_end (1e-300) must exceed t_start")


def test_a_grid_ukdyn_run_refuses_is_refused_when_the_model_is_read():
    # as `ukdyn run` and `ukdyn check` refuse it: at output: every's value
    with pytest.raises(ukdyn.ModelError) as info:
        ukdyn.parse(OSCILLATOR.lstrip("\n") + "output: {every: 1e-9}\n", "tiny.yaml")
    assert (info.value.line, info.value.column) == (5, 17)
    assert info.value.message.startswith("the output grid (output_every = 1e-09")


def test_inconsistent_initial_state_message_has_no_cpp_function_name():
    text = ("coordinates: [x, y]\nkinetic_energy: 0.5*(x_dot^2+y_dot^2)\nconstraints:\n"
            "  - {name: at0, holonomic: x}\n  - {name: at1, holonomic: x - 1}\n")
    with pytest.raises(ukdyn.InconsistentInitialState) as info:
        ukdyn.parse(text, "c.yaml").simulate()
    assert str(info.value).startswith("the constraints 'at0', 'at1' contradict each other")
