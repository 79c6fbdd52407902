# SPDX-License-Identifier: BSD-3-Clause
"""Measured data in models (docs/model-format.md, "Tables"): a model file whose table is a CSV
beside it, tables given from Python (NumPy arrays), the range error and the errors of bad data.
Every reference comes from a closed form."""

import math
import re

import numpy as np
import pytest

import ukdyn

# u'' + k/m u = -a_g(t) from rest, a relative displacement on a shaken base
OSCILLATOR = """
parameters: {m: 3, k: 3*(2*pi)^2}
coordinates: [u]
kinetic_energy: 0.5*m*u_dot^2
potential_energy: 0.5*k*u^2
forces: [-m*ground.acc(t)]
tables:
  ground: %s
simulate: {t_end: %s, rtol: 1e-11, atol: 1e-13}
output: {every: 0.05}
"""


def shaken(t, A, omega, Omega):
    """The closed form of u'' + omega^2 u = -A sin(Omega t), u(0) = u'(0) = 0."""
    return -A / (omega**2 - Omega**2) * (np.sin(Omega * t) - Omega / omega * np.sin(omega * t))


def test_a_model_file_reads_its_csv_table_and_follows_the_closed_form(tmp_path):
    t = np.round(np.arange(0, 501) * 0.01, 10)
    lines = ["time,acc"] + [f"{x!r},{1.5 * math.sin(2 * x)!r}" for x in t]
    (tmp_path / "ground.csv").write_text("\n".join(lines) + "\n")
    model = tmp_path / "shaken.yaml"
    model.write_text(OSCILLATOR % ("{file: ground.csv, x: time, interpolation: cubic}", 5))
    r = ukdyn.load(model).simulate()
    assert r.ok
    assert len(r.t) == 101
    exact = shaken(r.t, 1.5, 2 * math.pi, 2.0)
    assert np.max(np.abs(r.u - exact)) < 1e-8
    assert np.max(np.abs(exact)) > 0.03


def test_a_table_given_from_numpy_replaces_the_files_data():
    # the file declares the table with data of its own; the NumPy arrays replace them
    t = np.linspace(0.0, 5.0, 501)
    text = OSCILLATOR % ("{x: t, interpolation: cubic, data: {t: [0, 1, 2, 5], acc: [0, 0, 0, 0]}}", 5)
    m = ukdyn.parse(text, tables={"ground": {"t": t, "acc": 1.5 * np.sin(2 * t)}})
    r = m.simulate()
    assert r.ok
    assert np.max(np.abs(r.u - shaken(r.t, 1.5, 2 * math.pi, 2.0))) < 1e-8
    # the file's own data: no excitation at all
    assert np.max(np.abs(ukdyn.parse(text).simulate().u)) == 0.0


def test_the_shaken_frame_example_with_a_record_of_ones_own():
    # a constant ground acceleration a = 2 on the example's frame, given from NumPy: the output
    # a_g is that record, and the floors' motion from rest is the linear system's closed form
    #   x' = A x + f,  x = (u, u'),  x(t) = A⁻¹ (e^{At} − I) f
    # (e^{At} from A's eigenvectors: its eigenvalues are distinct)
    t = np.linspace(0.0, 10.0, 11)
    m = ukdyn.load("shaken_frame", tables={"ground": {"t": t, "acc": np.full(11, 2.0)}})
    r = m.simulate(t_end=1.0)
    assert r.ok
    np.testing.assert_array_equal(r["a_g"], 2.0)
    mass, k, c, a = 2.0e4, 8.0e6, 4.0e4, 2.0
    K = np.array([[2 * k, -k], [-k, k]]) / mass
    C = np.array([[2 * c, -c], [-c, c]]) / mass
    A = np.block([[np.zeros((2, 2)), np.eye(2)], [-K, -C]])
    f = np.array([0.0, 0.0, -a, -a])
    w, V = np.linalg.eig(A)
    Vinv = np.linalg.inv(V)
    for i in (10, 25, 50):
        eAt = (V @ np.diag(np.exp(w * r.t[i])) @ Vinv).real
        x = np.linalg.solve(A, (eAt - np.eye(4)) @ f)
        np.testing.assert_allclose([r.u1[i], r.u2[i], r.u1_dot[i], r.u2_dot[i]], x, rtol=0,
                                   atol=1e-7 * np.max(np.abs(x)))


def test_outside_the_range_the_run_stops_naming_the_column_value_and_range():
    t = np.linspace(0.0, 1.0, 11)
    text = OSCILLATOR % ("{x: t}", 2)
    m = ukdyn.parse(text, tables={"ground": {"t": t, "acc": np.sin(t)}})
    with pytest.raises(ukdyn.SolveError) as failed:
        m.simulate()
    r = failed.value.result
    assert not r.ok
    assert re.match(r"table column 'ground\.acc' \(from the table given\) evaluated at 1\.\d+, "
                    r"outside its rows' range \[0, 1\]", r.message), r.message
    # the samples computed before are kept: every 0.05 s up to the table's end
    assert r.t[20] == 1.0 and r.t[-1] <= 1.05


def test_bad_tables_are_clear_errors():
    text = OSCILLATOR % ("{x: t}", 1)
    with pytest.raises(ukdyn.ModelError, match="the table 'groun' given is not declared"):
        ukdyn.parse(text, tables={"groun": {"t": [0, 1], "acc": [0, 1]}})
    with pytest.raises(ukdyn.ModelError, match="row 2: the abscissa 't' is not strictly"):
        ukdyn.parse(text, tables={"ground": {"t": [1, 0], "acc": [0, 1]}})
    with pytest.raises(ValueError, match=r"column ground\.acc must be one-dimensional"):
        ukdyn.parse(text, tables={"ground": {"t": [0, 1], "acc": [[0, 1]]}})
    with pytest.raises(TypeError, match="tables must be a dict"):
        ukdyn.parse(text, tables=[1, 2])
    with pytest.raises(ukdyn.ModelError, match="table 'ground' has no data"):
        ukdyn.parse(text)
