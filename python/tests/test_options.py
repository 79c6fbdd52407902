# SPDX-License-Identifier: BSD-3-Clause
"""The options table (include/ukdyn/simulation/options.hpp) in Python: the keyword settings that simulate()
takes, Model.options and simulation_options() are exactly the table's names, each value
round-trips, an out-of-range value raises ValueError naming the option, and the docstring of
Model.simulate lists every option."""

import math

import pytest

import ukdyn

TABLE = ukdyn.options()
NAMES = [o["name"] for o in TABLE]

OSCILLATOR = """
coordinates: [x]
kinetic_energy: 0.5*x_dot^2
potential_energy: 0.5*x^2
initial: {q: {x: 1}}
"""


def example(option):
    """The table's example as the Python value of the option's type."""
    text = option["example"]
    kind = option["type"]
    if kind == "number":
        return float(text)
    if kind == "integer":
        return int(text)
    if kind == "bool":
        return text == "true"
    if kind == "numbers":
        return [float(x) for x in text.split(",")]
    return text


def bad(option):
    """A value of the option's type outside its range (the C++ test derives the same)."""
    kind = option["type"]
    if kind == "bool":
        return None  # every bool is in range: the type error is tested elsewhere
    if kind == "choice":
        return "nonsense"
    if kind == "numbers":
        return [math.nan]
    if kind == "integer":
        return -1 if option["name"] == "sparse_threshold" else 0
    return math.nan


def test_the_table_is_what_every_python_surface_takes():
    assert len(NAMES) == len(set(NAMES)) >= 28
    # Model.options and simulation_options() give exactly the table's names
    assert list(ukdyn.simulation_options().keys()) == NAMES
    assert list(ukdyn.parse(OSCILLATOR).options.keys()) == NAMES
    # and their defaults
    defaults = ukdyn.simulation_options()
    for o in TABLE:
        assert defaults[o["name"]] == o["default"], o["name"]
    # the older spelling is an alias
    assert "projection_iterations" in TABLE[NAMES.index("projection_max_iterations")]["aliases"]


@pytest.mark.parametrize("option", TABLE, ids=NAMES)
def test_every_option_round_trips_and_simulate_accepts_it(option):
    name, value = option["name"], example(option)
    assert value != option["default"]
    assert ukdyn.simulation_options(**{name: value})[name] == value
    # aliases set the same option
    for alias in option["aliases"]:
        assert ukdyn.simulation_options(**{alias: value})[name] == value
    # Model.simulate takes it (a short run of a constrained model: algorithm='textbook' on a
    # model without constraints crashes, on main too, a bug outside the options table)
    settings = {"t_end": 1.0, name: value}
    r = ukdyn.load("pendulum").simulate(check=False, **settings)
    assert r.stats["status"] in ("ok", "energy_balance")


@pytest.mark.parametrize("option", [o for o in TABLE if bad(o) is not None],
                         ids=[o["name"] for o in TABLE if bad(o) is not None])
def test_out_of_range_raises_naming_the_option(option):
    named = option["name"] if option["type"] != "choice" else option["name"].split("_")[0]
    if option["range"] != "a list of numbers":  # (output_at: checked against the run's times)
        with pytest.raises(ValueError, match=named) as e:
            ukdyn.simulation_options(**{option["name"]: bad(option)})
        assert "simulation_options: " in str(e.value)
    with pytest.raises(ValueError, match=named):
        ukdyn.parse(OSCILLATOR).simulate(**{option["name"]: bad(option)})


def test_range_errors_read_as_in_cpp():
    with pytest.raises(ValueError) as e:
        ukdyn.simulation_options(rtol=-1.0)
    assert str(e.value) == ("simulation_options: rtol must be a finite number > 0, got -1 "
                            "(the default is 1e-09)")
    with pytest.raises(ValueError, match=r"unknown setting 'rtoll' \(known: t_start, t_end, "):
        ukdyn.simulation_options(rtoll=1.0)


def test_solver_settings_are_the_tables_solver_options():
    solver_names = [o["name"] for o in TABLE if o["solver"]]
    assert solver_names == ["engine", "algorithm", "sparse_threshold", "rank_threshold",
                            "sparse_rank_threshold", "consistency_tolerance",
                            "symmetry_tolerance", "compute_residuals"]
    m = ukdyn.parse(OSCILLATOR)
    with pytest.raises(ValueError) as e:
        m.system.solver(rtol=1e-6)
    assert "known: " + ", ".join(solver_names) in str(e.value)
    with pytest.raises(ValueError, match="rank_threshold must be a finite number in"):
        m.system.solver(rank_threshold=2.0)


def test_the_docstring_lists_every_option():
    doc = ukdyn.Model.simulate.__doc__
    for name in NAMES:
        assert f"``{name}``" in doc, name
