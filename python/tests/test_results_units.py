# SPDX-License-Identifier: BSD-3-Clause
"""A result's units reach pandas (DataFrame.attrs) and xarray (each variable's attrs), and a
result shows itself in Jupyter (_repr_html_), names escaped (issue #33 item 5)."""

import math

import numpy as np
import pytest

import ukdyn

from conftest import import_or_missing


@pytest.fixture(scope="module")
def pendulum():
    # pendulum.yaml: units {x: m, y: m, theta: rad, r: m}; the rod a constraint on x, y
    return ukdyn.load("pendulum").simulate(t_end=0.5)


def test_column_units_follow_the_coordinates(pendulum):
    units = pendulum.column_units()
    assert units["t"] == "s"
    assert units["x"] == "m" and units["x_dot"] == "m/s" and units["x_ddot"] == "m/s²"
    assert units["Qc_ideal.x"] == "N" and units["Qc_nonideal.y"] == "N"
    assert units["energy"] == "J" and units["work_ideal"] == "J"
    assert units["theta"] == "rad"  # an output expression, by the file's units:
    assert units["lambda.rod"] == ""  # not known: said as unknown, not guessed
    assert set(units) == set(pendulum.names)


def test_dataframe_attrs_carry_the_units(pendulum):
    import_or_missing("pandas", "pandas is not installed (python3-pandas)")
    frame = pendulum.to_dataframe(index="t")
    assert frame.attrs["units"]["x"] == "m"
    assert frame.attrs["units"]["Qc_ideal.y"] == "N"
    assert "lambda.rod" not in frame.attrs["units"]
    assert frame.attrs["model"] == pendulum.model_name != ""
    assert frame.attrs["status"] == "ok"
    np.testing.assert_array_equal(frame["x"].to_numpy(), pendulum.x)


def test_xarray_variables_carry_the_units(pendulum):
    import_or_missing("xarray", "xarray is not installed (python3-xarray)")
    ds = pendulum.to_xarray()
    assert ds["x"].dims == ("t",)
    assert ds["x"].attrs["units"] == "m"
    assert ds["x_dot"].attrs["units"] == "m/s"
    assert ds["t"].attrs["units"] == "s"
    assert "units" not in ds["lambda.rod"].attrs
    assert ds.attrs["model"] == pendulum.model_name
    np.testing.assert_array_equal(ds["y"].values, pendulum.y)
    assert ds.sizes["t"] == len(pendulum)


def test_repr_html_summarises_and_escapes():
    text = """
name: "<b>bold</b> & co"
coordinates: [x]
kinetic_energy: x_dot^2/2
potential_energy: x^2/2
units: {x: m}
initial: {q: {x: 1}}
"""
    r = ukdyn.parse(text).simulate(t_end=math.pi)
    page = r._repr_html_()
    assert "&lt;b&gt;bold&lt;/b&gt; &amp; co" in page and "<b>bold" not in page
    assert "<td>x</td><td>m</td><td>1</td>" in page
    # x(t) = cos t: at t = π, −1 to the run's tolerance
    last = float(page.split("<td>x</td><td>m</td><td>1</td><td>")[1].split("<")[0])
    assert last == pytest.approx(-1.0, abs=1e-6)
    assert "%d, t = 0 &hellip; 3.14159 s" % len(r) in page
    assert ">ok<" in page
