# SPDX-License-Identifier: BSD-3-Clause
"""What a run says about itself, from Python and the command alike (a new user's findings,
session 16, /work/u19/repro): the robust bound left (04), a violation that cannot be measured
(07), requirements that cannot be met (02), Result.to_hdf5's summary (09), and small items (06)."""

import json
import math
import pathlib
import subprocess
import warnings

import numpy as np
import pytest

import ukdyn

def caught(fn):
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        value = fn()
    return value, [w for w in seen if issubclass(w.category, UserWarning)]


# --- 04: the robust bound ------------------------------------------------------------------------

def test_robust_error_outside_its_bound_warns_in_python_and_the_command(cli, out_dir):
    # the plant's mass 0.4, the controller believing 1.2 within 20 %: outside the model
    model = ukdyn.load("control_uncertain_duffing", m=0.4)
    result, seen = caught(model.simulate)
    e, bound = np.abs(result["error.track"]), result["error_bound.track"]
    outside = e > 1.001 * bound
    first = float(result.t[np.argmax(outside)])
    assert outside.any()
    assert result.control["bound_exceeded_at"] == pytest.approx(first, abs=1e-12)
    assert result.control["bound_worst_ratio"] == pytest.approx(float(np.max(e / bound)), rel=1e-9)
    assert 17.0 < result.control["bound_worst_ratio"] < 18.2  # (the reproducer's 17.6)
    assert any("left its guaranteed bound" in n for n in result.stats["notes"])
    texts = [str(w.message) for w in seen]
    assert any(t.startswith("the error left its guaranteed bound at t = 4.6") for t in texts), texts
    # the command: the same line on stderr, in summary.json the time and the ratio
    proc = subprocess.run([cli, "run", "--example", "control_uncertain_duffing", "--set", "m=0.4",
                           "-o", str(out_dir), "--no-plots", "--no-viewer"],
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert "warning: the error left its guaranteed bound at t = 4.6" in proc.stderr
    control = json.loads((out_dir / "summary.json").read_text())["control"]
    assert control["bound_exceeded_at"] == pytest.approx(first, abs=1e-12)
    assert control["bound_worst_row"] == "track"
    # inside the model (m = 1): silent
    result, seen = caught(ukdyn.load("control_uncertain_duffing").simulate)
    assert math.isnan(result.control["bound_exceeded_at"]) and not seen
    assert 0.0 < float(np.max(np.abs(result["error.track"]) / result["error_bound.track"])) < 1.0


# --- 07: a violation that cannot be measured -----------------------------------------------------

def test_callables_acceleration_form_violation_is_nan_with_a_note():
    s = ukdyn.from_callables(
        ["x", "y"], M=np.eye(2), Q=lambda q, qd, t: np.array([0.0, -9.81]),
        V=lambda q, t: 9.81 * q[1],
        constraints=[ukdyn.constraint("rod", lambda q, qd, t: np.array([[q[0], q[1]]]),
                                      lambda q, qd, t: np.array([-(qd @ qd)]))])
    r = ukdyn.simulate(s, [1.0, 0.0], [0.0, 0.0], t_end=20, rtol=1e-6, atol=1e-8)
    true = np.abs(r["x"] ** 2 + r["y"] ** 2 - 1) / 2
    assert 1e-9 < true[-1] < 0.1  # it drifts: 0 would be wrong
    assert np.all(np.isnan(r["violation.rod"]))
    assert math.isnan(r.stats["max_position_violation"])
    assert math.isnan(r.stats["max_velocity_violation"])
    assert any("'rod' given in acceleration form only" in n for n in r.stats["notes"])


# --- 02: requirements that cannot be met ---------------------------------------------------------

def test_check_and_simulate_report_contradicting_requirements(cli, testdata_dir):
    path = testdata_dir / "requirements_contradicting.yaml"
    proc = subprocess.run([cli, "check", str(path)], capture_output=True, text=True)
    assert proc.returncode == 4, proc.stdout + proc.stderr
    assert "'r1' and 'r2' contradict each other" in proc.stdout
    # Python's check, and its run: a UserWarning, as the command's run warns
    model = ukdyn.load(str(path))
    assert not model.check()["ok"]
    result, seen = caught(model.simulate)
    texts = [str(w.message) for w in seen]
    assert any(t.startswith("the control could not meet every requirement in") for t in texts)
    # (least squares: e1'' + 4 e1' + 4 e1 = 4 from rest: e1(1) = 1 − 3 e^{−2})
    assert result["error.r1"][-1] == pytest.approx(1 - 3 * math.exp(-2), abs=1e-6)


def test_a_requirement_fixed_by_a_constraint_names_the_constraint(cli, testdata_dir):
    path = testdata_dir / "requirement_on_constraint.yaml"
    proc = subprocess.run([cli, "check", str(path)], capture_output=True, text=True)
    assert proc.returncode == 4
    assert "the physical constraint 'c' fixes" in proc.stdout
    result, seen = caught(ukdyn.load(str(path)).simulate)
    assert any("the physical constraint 'c' fixes" in str(w.message) for w in seen)
    assert "the physical constraint 'c' fixes" in result.control["not_met_message"]


# --- 09: Result.to_hdf5 writes the command's summary ---------------------------------------------

def test_to_hdf5_writes_the_commands_summary_and_runs_again(cli, out_dir):
    result = ukdyn.load("pendulum", L=0.5).simulate(t_end=0.3, rtol=1e-10)
    result.to_hdf5(out_dir / "py.h5")
    _, meta = ukdyn.read_hdf5(out_dir / "py.h5")
    proc = subprocess.run([cli, "run", "--example", "pendulum", "--set", "L=0.5", "--t-end", "0.3",
                           "--rtol", "1e-10", "--format", "hdf5", "-o", str(out_dir / "cli"),
                           "--no-plots", "--no-viewer"], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    _, cli_meta = ukdyn.read_hdf5(out_dir / "cli" / "trajectory.h5")
    assert sorted(set(cli_meta) - set(meta)) == []
    for key in ("options", "final_state", "units", "unit_system"):
        assert meta[key] == cli_meta[key], key
    made, cli_made = meta["provenance"], cli_meta["provenance"]
    for key in ("example", "model_sha256", "parameters", "overridden", "model_name"):
        assert made[key] == cli_made[key], key
    assert made["overridden"] == ["L"] and made["written_by"] == "Result.to_hdf5"
    assert meta["options"]["rtol"] == 1e-10 and meta["options"]["t_end"] == 0.3
    # the command makes the Python run again from the file, in its format
    again = subprocess.run([cli, "run", "--from-summary", str(out_dir / "py.h5"), "-o",
                            str(out_dir / "again"), "--no-plots", "--no-viewer"],
                           capture_output=True, text=True)
    assert again.returncode == 0, again.stderr
    # (a Python run records no --format: the command writes its default, CSV)
    lines = (out_dir / "again" / "trajectory.csv").read_text().splitlines()
    names, last = lines[0].split(","), [float(v) for v in lines[-1].split(",")]
    for c in result.coordinates:
        assert last[names.index(c)] == pytest.approx(result[c][-1], abs=1e-12), c


def test_from_summary_of_an_hdf5_run_writes_hdf5(cli, out_dir):
    first = subprocess.run([cli, "run", "--example", "pendulum", "--t-end", "0.2", "--format",
                            "hdf5", "-o", str(out_dir / "a"), "--no-plots", "--no-viewer"],
                           capture_output=True, text=True)
    assert first.returncode == 0, first.stderr
    again = subprocess.run([cli, "run", "--from-summary", str(out_dir / "a" / "summary.json"),
                            "-o", str(out_dir / "b"), "--no-plots", "--no-viewer"],
                           capture_output=True, text=True)
    assert again.returncode == 0, again.stderr
    assert (out_dir / "b" / "trajectory.h5").exists()
    assert not (out_dir / "b" / "trajectory.csv").exists()
    a, _ = ukdyn.read_hdf5(out_dir / "a" / "trajectory.h5")
    b, _ = ukdyn.read_hdf5(out_dir / "b" / "trajectory.h5")
    assert np.array_equal(a["x"], b["x"]) and np.array_equal(a["y"], b["y"])


# --- 06: small items -----------------------------------------------------------------------------

def test_from_sympy_takes_units_and_visual():
    sp = pytest.importorskip("sympy")
    x = sp.Symbol("x")
    xd, = ukdyn.velocities(x)
    model = ukdyn.from_sympy([x], T=xd ** 2 / 2, units={"length": "mm", "time": "ms"},
                             visual={"points": {"p": [x, 0]}}, initial={"q_dot": {x: 1}})
    assert model.unit_system["length"] == "mm" and model.unit_system["time"] == "ms"
    r = model.simulate(t_end=2)
    assert r["x"][-1] == pytest.approx(2.0, abs=1e-9)  # x = t, in the model's units
    assert "<html" in r.animation_html().lower()


def test_save_animation_names_itself_and_simulate_drops_the_cpp_prefix(out_dir):
    sp = pytest.importorskip("sympy")
    x = sp.Symbol("x")
    xd, = ukdyn.velocities(x)
    model = ukdyn.from_sympy([x], T=xd ** 2 / 2, initial={"q_dot": {x: 1}})
    r = model.simulate(t_end=0.1)
    with pytest.raises(ValueError, match=r"^Result\.save_animation: nothing to draw"):
        r.save_animation(out_dir / "a.html")
    with pytest.raises(ValueError) as err:
        model.simulate(q0=[float("nan")])
    assert str(err.value).startswith("q0 is not finite at coordinate 'x'"), str(err.value)
