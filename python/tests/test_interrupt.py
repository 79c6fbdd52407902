# SPDX-License-Identifier: BSD-3-Clause
"""Ctrl-C during a run (issue #14, item 1; docs/python.md, "Interrupts"): a Python process running
simulate() receives SIGINT; the run stops within a fraction of a second and raises
ukdyn.Interrupted, a KeyboardInterrupt, whose .partial (.result) holds the samples computed up
to there — each as the uninterrupted run has it, the last at stats["t_reached"]. And
Result.to_csv writes whole files or none."""

import json
import pathlib
import subprocess
import sys

import numpy as np
import pytest

import ukdyn
from conftest import interrupt_python

LONG_MODEL = pathlib.Path(__file__).resolve().parents[2] / "tests" / "data" / "interrupt_pendulum.yaml"

# The child: runs a long simulation, reports when it starts, and what it caught, as JSON. The
# partial result is compared there with an uninterrupted run to its t_reached.
CHILD = r"""
import json, math, signal, sys, time
import numpy as np
import ukdyn

mode, model_path = sys.argv[1], sys.argv[2]
if mode == "model":
    model = ukdyn.load(model_path)
    run = lambda **kw: model.simulate(**kw)
    coordinates = ["x", "y"]
elif mode == "callables":
    G = 9.81
    system = ukdyn.from_callables(
        ["x", "y"], M=np.eye(2), Q=lambda q, qd, t: [0.0, -G], V=lambda q, t: G * q[1],
        constraints=[ukdyn.constraint("rod", lambda q, qd, t: [q], lambda q, qd, t: [-(qd @ qd)])])
    settings = dict(t_end=1e6, output_every=0.5, rtol=1e-10, atol=1e-12)
    run = lambda **kw: ukdyn.simulate(system, [1.0, 0.0], [0.0, 0.0], **{**settings, **kw})
    coordinates = ["x", "y"]
elif mode == "handler":
    # a SIGINT handler of the user's own, which raises its own exception
    class Stop(Exception):
        pass
    def handler(signum, frame):
        raise Stop("the user's handler")
    signal.signal(signal.SIGINT, handler)
    model = ukdyn.load(model_path)
    run = lambda **kw: model.simulate(**kw)
    coordinates = ["x", "y"]

print("started", flush=True)
report = {}
try:
    run()
    report["finished"] = True
except BaseException as e:
    report["caught_at"] = time.monotonic()
    report["type"] = type(e).__name__
    report["is_keyboard_interrupt"] = isinstance(e, KeyboardInterrupt)
    report["is_interrupted"] = isinstance(e, ukdyn.Interrupted)
    report["message"] = str(e)
    r = getattr(e, "partial", None)
    report["has_partial"] = r is not None
    if r is not None:
        t = np.asarray(r.t)
        report["same_object"] = getattr(e, "result", r) is r
        report["status"] = r.status
        report["samples"] = len(r)
        report["t_reached"] = r.stats["t_reached"]
        report["t_last"] = float(t[-1])
        report["increasing"] = bool(np.all(np.diff(t) > 0))
        # the same run to t_reached, uninterrupted (the SIGINT handler is Python's again)
        signal.signal(signal.SIGINT, signal.default_int_handler)
        full = run(t_end=r.stats["t_reached"])
        report["full_status"] = full.status
        report["full_samples"] = len(full)
        report["max_time_difference"] = float(np.max(np.abs(t - np.asarray(full.t))))
        report["max_state_difference"] = max(
            float(np.max(np.abs(np.asarray(r[c]) - np.asarray(full[c]))))
            for c in coordinates + [c + "_dot" for c in coordinates])
        report["max_rod_error"] = float(np.max(np.abs(np.hypot(r["x"], r["y"]) - 1.0)))
print(json.dumps(report), flush=True)
"""


def run_child(mode: str, delay: float = 0.7) -> dict:
    returncode, out, err, sent = interrupt_python(["-c", CHILD, mode, str(LONG_MODEL)], delay)
    assert returncode == 0, err
    report = json.loads(out.strip().splitlines()[-1])
    report["latency"] = report.get("caught_at", float("inf")) - sent
    return report


@pytest.mark.parametrize("mode", ["model", "callables"])
def test_ctrl_c_during_simulate_raises_keyboard_interrupt_with_the_partial_result(mode):
    r = run_child(mode)
    assert not r.get("finished"), "the run was not interrupted"
    assert r["type"] == "Interrupted"
    assert r["is_keyboard_interrupt"] and r["is_interrupted"]
    assert r["message"].startswith("interrupted at t = "), r["message"]
    # within a fraction of a second (20 ms checks plus a step; generous for a loaded machine)
    print(f"{mode}: KeyboardInterrupt {r['latency'] * 1e3:.1f} ms after SIGINT")
    assert 0.0 < r["latency"] < 2.0
    # the partial result: interrupted, times increasing, the last at t_reached
    assert r["has_partial"] and r["same_object"]
    assert r["status"] == "interrupted"
    assert r["samples"] >= 2  # the initial state and the state at t_reached, at least (loaded machine)
    assert r["increasing"]
    assert r["t_last"] == pytest.approx(r["t_reached"], rel=1e-15, abs=0.0)
    assert 0.5 < r["t_reached"] < 5e4
    # every sample is the uninterrupted run's
    assert r["full_status"] == "ok"
    assert r["full_samples"] == r["samples"]
    assert r["max_time_difference"] == pytest.approx(0.0, abs=1e-12)
    assert r["max_state_difference"] == pytest.approx(0.0, abs=1e-7)
    assert r["max_rod_error"] == pytest.approx(0.0, abs=1e-6)


def test_a_users_sigint_handler_stops_the_run_with_its_own_exception():
    r = run_child("handler")
    assert r["type"] == "Stop" and r["message"] == "the user's handler"
    assert not r["is_keyboard_interrupt"]
    assert 0.0 < r["latency"] < 2.0
    assert r["has_partial"] and r["status"] == "interrupted"
    assert r["increasing"]
    assert r["t_last"] == pytest.approx(r["t_reached"], rel=1e-15, abs=0.0)
    assert r["max_state_difference"] == pytest.approx(0.0, abs=1e-7)


def test_interrupted_is_a_keyboard_interrupt_carrying_the_result():
    e = ukdyn.Interrupted("interrupted at t = 1", result="R")
    assert isinstance(e, KeyboardInterrupt) and not isinstance(e, Exception)
    assert e.result == "R" and e.partial == "R"
    assert str(e) == "interrupted at t = 1"


def test_to_csv_replaces_the_file_whole_and_leaves_no_temporary(tmp_path):
    result = ukdyn.load("pendulum").simulate(t_end=0.5)
    path = tmp_path / "run.csv"
    path.write_text("previous contents\n")
    result.to_csv(str(path))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.csv"]
    lines = path.read_text().splitlines()
    assert lines[0] == ",".join(result.names)
    assert len(lines) == len(result) + 1
    assert float(lines[-1].split(",")[0]) == pytest.approx(0.5, abs=1e-15)
    # an error (a missing directory) leaves nothing behind, and says which
    with pytest.raises(FileNotFoundError):
        result.to_csv(str(tmp_path / "missing" / "run.csv"))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.csv"]


# Programs that end while a run is under way on another thread (issue #29; reproducer
# py_thread_exit_abort.py). Each prints "main exits" and ends; the run's thread must not take
# the GIL once Python finalizes (CPython would end it with pthread_exit, which aborts a C++
# program: "terminate called without an active exception").
EXITING = {
    "simulate": """
m = ukdyn.load(LONG)
threading.Thread(target=lambda: m.simulate(), daemon=True).start()
""",
    "callables": """
system = ukdyn.from_callables(["x", "y"], M=np.eye(2), Q=lambda q, qd, t: [0.0, -9.81],
    constraints=[ukdyn.constraint("rod", lambda q, qd, t: [q], lambda q, qd, t: [-(qd @ qd)])])
threading.Thread(target=lambda: ukdyn.simulate(system, [1.0, 0.0], [0.0, 0.0], t_end=1e6,
                                                output_every=0.5),
                 daemon=True).start()
""",
    "sweep on two threads": """
threading.Thread(target=lambda: ukdyn.sweep(LONG, grid={"t_end": [5e4] * 4}, workers=2),
                 daemon=True).start()
""",
}


@pytest.mark.parametrize("mode", sorted(EXITING))
def test_a_program_that_exits_during_a_run_on_a_thread_ends_cleanly(mode):
    code = ("import threading, time\nimport numpy as np\nimport ukdyn\nLONG = %r\n" % str(LONG_MODEL)
            + EXITING[mode] + "time.sleep(1.0)\nprint('main exits', flush=True)\n")
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert (p.returncode, p.stdout, p.stderr) == (0, "main exits\n", "")


def test_ctrl_c_while_joining_a_sweeps_thread_then_exiting_ends_cleanly():
    """Ctrl-C while the main thread joins a thread running ukdyn.sweep; CPython 3.11 then returns
    at once from a second join (the thread is taken for finished), and the program ends while
    the sweep runs. (A Python whose second join waits sees the sweep end, about 20 s.)"""
    code = ("import threading, ukdyn\nres = {}\n"
            "th = threading.Thread(target=lambda: res.setdefault('df', ukdyn.sweep('pendulum', "
            "grid={'L': '1:2:6000'}, t_end=5.0, workers=1)))\n"
            "th.start()\nprint('started', flush=True)\n"
            "try:\n    th.join()\nexcept KeyboardInterrupt:\n    th.join()\n"
            "    print('second join returned', flush=True)\n")
    returncode, out, err, _ = interrupt_python(["-c", code], 1.0)
    assert (returncode, out, err) == (0, "second join returned\n", "")
