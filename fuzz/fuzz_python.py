#!/usr/bin/python3
# SPDX-License-Identifier: BSD-3-Clause
"""Fuzzes the Python module's entry points with hypothesis.

usage: fuzz/fuzz_python.py [SECONDS]      (default 60; scripts/fuzz.sh runs it with the module of
                                          build/python on the path)

Each entry point gets arguments built from its own vocabulary and from hostile values (NaN, inf,
huge and tiny numbers, None, strings, nested lists, arrays of the wrong shape or dtype, mutated
model text, callables that return the wrong thing or raise):

* ``ukdyn.parse`` (mutated example models), ``ukdyn.load`` (examples, files, overrides);
* ``Model.simulate`` with every setting, ``Model.solve`` / ``Solver.solve`` / ``Solver.evaluate``
  / ``Model.check``, ``ControlSolver.compute`` of the control examples;
* ``ukdyn.from_callables`` and ``ukdyn.simulate`` of the system it builds;
* ``Result`` lookups and ``to_dataframe``.

The promise it checks (docs/python.md, "Errors"; docs/reliability.md): every call returns or
raises one of the documented exceptions (ModelError with a position for model text, SolveError,
ValueError, TypeError, the exception a user callable raised) with a message that names the
problem — never another exception type, an empty message, an escaped C++ type (``bad_alloc``,
``Unable to cast``), a crash or a hang (the interpreter is killed by scripts/fuzz.sh's timeout);
and what it returns is not silently wrong: a simulation that returns reached its end time with
one row per sample in every column and distinct column names, a solve that says ok has finite
accelerations, a solve that failed leaves no stale numbers behind.
"""

from __future__ import annotations

import math
import os
import random
import sys
import threading
import time
import warnings
from pathlib import Path
from typing import Any, Callable

import numpy as np
from hypothesis import HealthCheck, Phase, given, seed, settings
from hypothesis import strategies as st

import ukdyn

ROOT = Path(__file__).resolve().parent.parent
KEEP_GOING = os.environ.get("FUZZ_KEEP_GOING") == "1"  # collect every finding (development)
# FUZZ_SEED=N: batch k draws from seed N + k, so a run replays the same inputs in the same order
# (CI: it fails for a change, not for the luck of the draw); unset: fresh inputs every run
SEED = int(os.environ["FUZZ_SEED"]) if os.environ.get("FUZZ_SEED") else None
UNCLEAR = ("bad_alloc", "Unable to cast", "std::", "basic_string", "vector::")


class Finding(Exception):
    """A broken promise."""


class UserError(Exception):
    """Raised by the fuzzer's own callables: must come back unchanged."""


EXAMPLES = ukdyn.examples()
FAST = [e for e in EXAMPLES if not e.startswith("control_triple")]
CONTROL = [e for e in EXAMPLES if e.startswith("control_")]
TEXTS = {e: ukdyn.example_text(e) for e in EXAMPLES}
TOKENS = ["x", "y", "theta", "x_dot", "t", "sin(", "cos(", "sqrt(", ")", "(", "^", "/", "*",
          "-", "+", "1e308", "nan", "inf", "0", "-1", "{", "}", "[", "]", ":", ",", "&a", "*a",
          "!!str", "---", "\t", "\n", "  ", "'", '"', "#", "|", ">", "~", "null", "é", "\x00",
          "holonomic:", "nonholonomic:", "coordinates:", "kinetic_energy:", "mass_matrix:",
          "parameters:", "initial:", "simulate:", "friction:", "bodies:", "joints:"]


def floats() -> st.SearchStrategy[float]:
    return st.one_of(st.sampled_from([math.nan, math.inf, -math.inf, 0.0, -0.0, 1e300, -1e300,
                                      1e-300, 5e-324, 1.0, -1.0]),
                     st.floats(allow_nan=True, allow_infinity=True),
                     st.floats(min_value=-10, max_value=10))


def hostile() -> st.SearchStrategy[Any]:
    """Anything a user might pass where a number, a vector or a name is expected."""
    return st.one_of(floats(), st.none(), st.text(max_size=6), st.booleans(),
                     st.integers(min_value=-2**70, max_value=2**70),
                     st.lists(floats(), max_size=5), st.lists(st.text(max_size=3), max_size=3),
                     st.just([[1.0, 2.0], [3.0]]), st.just(np.zeros((2, 2))),
                     st.just(np.array(["a", "b"])), st.just(np.array([1 + 2j, 3j])),
                     st.just({"a": 1}))


def vectors(n: int) -> st.SearchStrategy[Any]:
    """Mostly the right size, sometimes not; mostly finite."""
    right = st.lists(st.floats(min_value=-3, max_value=3), min_size=n, max_size=n)
    odd = st.lists(floats(), min_size=n, max_size=n)
    return st.one_of(right, right, right, odd, hostile())


def states(n: int) -> st.SearchStrategy[Any]:
    """Initial states of a simulation: as vectors(), but finite entries at most 1e3 in size.

    Not drawn, and recorded in docs/reliability.md ("Open"): states far outside a model's own
    scale make runs crawl rather than fail — the slave gyroscope of control_gyroscopes started
    at -6.7e5 rad crosses a pole of its force every 2 pi, and a run of 1 ms takes minutes of
    shrinking steps towards max_steps; an oscillator started at 1e16 m (energies 1e33 J) has its
    work channels' error control reject steps down to 1e-11 s."""
    bounded = st.one_of(st.floats(min_value=-1e3, max_value=1e3),
                        st.sampled_from([math.nan, math.inf, -math.inf, 0.0, -0.0, 1e-300]))
    right = st.lists(st.floats(min_value=-3, max_value=3), min_size=n, max_size=n)
    odd = st.lists(bounded, min_size=n, max_size=n)
    other = st.one_of(st.none(), st.text(max_size=6), st.lists(bounded, max_size=5),
                      st.just([[1.0, 2.0], [3.0]]), st.just(np.array(["a", "b"])),
                      st.just(np.array([1 + 2j, 3j])), st.just({"a": 1}))
    return st.one_of(right, right, right, odd, other)


def expect_clear(e: BaseException, where: str) -> None:
    """The exception is one of the documented ones, with a message that names the problem."""
    if isinstance(e, UserError):
        return
    if not isinstance(e, (ukdyn.ModelError, ukdyn.SolveError, ValueError, TypeError)):
        raise Finding(f"{where}: undocumented {type(e).__name__}: {e}") from e
    text = str(e)
    if not text.strip():
        raise Finding(f"{where}: {type(e).__name__} with an empty message") from e
    for marker in UNCLEAR:
        if marker in text:
            raise Finding(f"{where}: {type(e).__name__} '{marker}' in: {text[:300]}") from e


CALL_TIMEOUT = float(os.environ.get("FUZZ_TIMEOUT", "60"))


def _hang(where: str) -> None:
    print(f"fuzz_python: FINDING: no answer within {CALL_TIMEOUT:g} s (hang): {where[:1500]}",
          file=sys.stderr, flush=True)
    os._exit(1)


def call(where: str, fn: Callable[[], Any]) -> Any:
    watchdog = threading.Timer(CALL_TIMEOUT, _hang, args=(where,))
    watchdog.daemon = True
    watchdog.start()
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ukdyn.EnergyBalanceWarning)
            # a complex number cast to a real one silently is garbage: make it an exception
            warnings.simplefilter("error", np.ComplexWarning)
            return fn()
    except Finding:
        raise
    except Exception as e:  # noqa: BLE001 -- judged by expect_clear
        expect_clear(e, where)
        return None
    finally:
        watchdog.cancel()


def call_raw(where: str, fn: Callable[[], Any]) -> Any:
    """fn() under the watchdog, its exceptions unjudged."""
    watchdog = threading.Timer(CALL_TIMEOUT, _hang, args=(where,))
    watchdog.daemon = True
    watchdog.start()
    try:
        return fn()
    finally:
        watchdog.cancel()


def mutate(text: str, rnd: random.Random, edits: int) -> str:
    lines = text.split("\n")
    for _ in range(edits):
        i = rnd.randrange(len(lines))
        what = rnd.randrange(6)
        if what == 0 and len(lines) > 1:
            del lines[i]
        elif what == 1:
            lines.insert(i, lines[rnd.randrange(len(lines))])
        elif what == 2 and lines[i]:
            j = rnd.randrange(len(lines[i]))
            lines[i] = lines[i][:j] + rnd.choice(TOKENS) + lines[i][j + 1:]
        elif what == 3 and lines[i]:
            j = rnd.randrange(len(lines[i]))
            lines[i] = lines[i][:j] + lines[i][j + rnd.randrange(1, 4):]
        elif what == 4:
            lines[i] = lines[i] + rnd.choice(TOKENS)
        else:
            lines[i] = " " * rnd.randrange(4) + lines[i].lstrip()
    return "\n".join(lines)


def check_result(where: str, r: Any, t_end: float | None) -> None:
    if r is None:
        return
    names = list(r)
    if len(set(names)) != len(names):
        twice = sorted({n for n in names if names.count(n) > 1})
        raise Finding(f"{where}: duplicate result columns {twice[:6]}")
    t = r.t
    if len(t) < 2:
        raise Finding(f"{where}: returned a result with {len(t)} samples")
    for n in names:
        if len(r[n]) != len(t):
            raise Finding(f"{where}: column {n} has {len(r[n])} rows, t has {len(t)}")
    status = r.stats.get("status") if hasattr(r, "stats") else None
    if t_end is not None and status == "ok" and not math.isclose(t[-1], t_end, rel_tol=1e-9,
                                                                 abs_tol=1e-12):
        raise Finding(f"{where}: status ok but the last sample is at {t[-1]}, t_end {t_end}")
    r.to_dataframe()


# -- the entry points ----------------------------------------------------------------------------

def fuzz_parse(data: st.DataObject) -> None:
    name = data.draw(st.sampled_from(EXAMPLES))
    seed = data.draw(st.integers(0, 2**32 - 1))
    edits = data.draw(st.integers(1, 6))
    text = mutate(TEXTS[name], random.Random(seed), edits)
    try:
        model = call_raw("parse", lambda: ukdyn.parse(text, "<fuzz>"))
    except ukdyn.ModelError as e:
        if e.file != "<fuzz>" or e.line < 1 or e.column < 1 or not e.message:
            raise Finding(f"parse: ModelError without a position: {e}") from e
        return
    except Exception as e:  # noqa: BLE001
        raise Finding(f"parse: {type(e).__name__} instead of ModelError: {e}") from e
    call("check", model.check)
    n = len(model.coordinates)
    if n <= 200:
        r = call("simulate", lambda: model.simulate(t_end=model.options["t_start"] + 0.01,
                                                    integrator="rk4", step=1e-3))
        check_result("simulate(mutated model)", r, None)


def fuzz_load(data: st.DataObject) -> None:
    source = data.draw(st.one_of(st.sampled_from(EXAMPLES), st.text(max_size=10),
                                 st.sampled_from(["/", "/dev/null", str(ROOT / "README.md"),
                                                  str(ROOT / "examples"), "nope.yaml", ""])))
    overrides = data.draw(st.dictionaries(
        st.one_of(st.sampled_from(["m", "L", "g", "k", "mu", "c", "l", "r"]),
                  st.text(min_size=1, max_size=4)), hostile(), max_size=3))
    if any(not k.isidentifier() for k in overrides):
        overrides = {}
    call(f"load({source!r}, {overrides!r})", lambda: ukdyn.load(source, **overrides))


def fuzz_simulate(data: st.DataObject) -> None:
    name = data.draw(st.sampled_from(FAST))
    model = ukdyn.load(name)
    t0 = model.options["t_start"]
    t_end = data.draw(st.one_of(st.floats(min_value=1e-3, max_value=0.3).map(lambda d: t0 + d),
                                st.sampled_from([math.nan, math.inf, -math.inf, 1e300, t0,
                                                 t0 - 1, t0 + 1e-300])))
    keys = {
        "integrator": st.one_of(st.sampled_from(["rk4", "rk5", "dopri5", "rkf78", "bdf"]),
                                st.text(max_size=5), st.none(), st.integers()),
        "step": st.one_of(st.floats(min_value=1e-4, max_value=0.1), floats()),
        "rtol": st.one_of(st.floats(min_value=1e-12, max_value=1e-3), floats()),
        "atol": st.one_of(st.floats(min_value=1e-14, max_value=1e-3), floats()),
        "max_step": floats(), "max_steps": st.one_of(st.integers(-5, 10**6), hostile()),
        "stiff_switch": st.one_of(st.booleans(), hostile()),
        "output_every": st.one_of(st.floats(min_value=1e-3, max_value=0.1), floats()),
        "output_at": st.one_of(st.lists(st.floats(min_value=t0, max_value=t0 + 0.3),
                                        max_size=4), hostile()),
        "breakpoints": st.one_of(st.lists(st.floats(min_value=t0, max_value=t0 + 0.3),
                                          max_size=3), hostile()),
        "drift": st.one_of(st.sampled_from(["projection", "baumgarte", "none"]),
                           st.text(max_size=5)),
        "baumgarte_alpha": floats(), "baumgarte_beta": floats(),
        "project_initial": st.one_of(st.booleans(), hostile()),
        "energy_balance_tolerance": floats(), "nonsense": hostile(),
    }
    chosen = data.draw(st.lists(st.sampled_from(sorted(keys)), unique=True, max_size=4))
    kwargs = {k: data.draw(keys[k]) for k in chosen}
    if kwargs.get("integrator") in ("rk4", "rk5") or "step" in kwargs:
        step = kwargs.get("step", 1e-3)
        if isinstance(step, float) and math.isfinite(step) and 0 < step < 1e-4:
            kwargs["step"] = 1e-4  # keep fixed-step runs short; tiny steps have own cases
    # tolerances far below roundoff make an adaptive run crawl towards max_steps (minutes, a
    # documented open problem: docs/reliability.md, "Open"), not fail: keep accepted ones >= 1e-16
    for key in ("rtol", "atol"):
        tol = kwargs.get(key)
        if isinstance(tol, float) and 0 < tol < 1e-16:
            kwargs[key] = 1e-16
    max_step = kwargs.get("max_step")
    if (isinstance(max_step, float) and 0 < max_step < 1e-4 and isinstance(t_end, float)
            and math.isfinite(t_end) and (t_end - t0) / max_step <= 1e7):
        # keep adaptive runs short; a max_step too small for max_steps is refused (kept as drawn)
        kwargs["max_step"] = 1e-4
    n = len(model.coordinates)
    q0 = data.draw(st.one_of(st.none(), st.none(), states(n)))
    where = f"{name}.simulate(t_end={t_end!r}, q0={q0!r}, **{kwargs!r})"
    r = call(where, lambda: model.simulate(t_end=t_end, q0=q0, **kwargs))
    check_result(where, r, None if "output_at" in kwargs else t_end)


def fuzz_solve(data: st.DataObject) -> None:
    name = data.draw(st.sampled_from(FAST))
    model = ukdyn.load(name)
    n = len(model.coordinates)
    q = data.draw(st.one_of(st.just(list(model.q0)), vectors(n)))
    qd = data.draw(st.one_of(st.just(list(model.qd0)), vectors(n)))
    t = data.draw(st.one_of(st.floats(min_value=0, max_value=5), floats(), hostile()))
    check = data.draw(st.booleans())
    solver = model.solver()
    call("solve(good)", lambda: solver.solve(model.q0, model.qd0, 0.0))
    where = f"{name}: solve({q!r}, {qd!r}, {t!r}, check={check})"
    s = call(where, lambda: solver.solve(q, qd, t, check=check))
    if s is not None and s.ok and not np.all(np.isfinite(s.qdd)):
        raise Finding(f"{where}: status ok with non-finite qdd {s.qdd}")
    if s is not None and not s.ok and np.all(np.isfinite(solver.qdd)) and \
            np.array_equal(solver.qdd, model.solve(model.q0, model.qd0, 0.0).qdd):
        raise Finding(f"{where}: failed solve ({s.status}) left the last good qdd in place")
    call(f"{name}: evaluate", lambda: solver.evaluate(q, qd, t))
    settings_ = data.draw(st.dictionaries(
        st.sampled_from(["rank_threshold", "consistency_tolerance", "engine", "algorithm",
                         "sparse_threshold", "compute_residuals", "bogus"]), hostile(),
        max_size=2))
    call(f"{name}: solver(**{settings_!r})", lambda: model.solver(**settings_))


def fuzz_control(data: st.DataObject) -> None:
    name = data.draw(st.sampled_from(CONTROL))
    model = ukdyn.load(name)
    n = len(model.coordinates)
    ctrl = model.controller
    q = data.draw(st.one_of(st.just(list(model.q0)), vectors(n)))
    qd = data.draw(st.one_of(st.just(list(model.qd0)), vectors(n)))
    t = data.draw(st.one_of(st.floats(min_value=0, max_value=5), floats()))
    s = call(f"{name}: compute", lambda: ctrl.solver().compute(q, qd, t,
                                                               check=data.draw(st.booleans())))
    if s is not None and s.ok and not np.all(np.isfinite(s.u)):
        raise Finding(f"{name}: compute ok with non-finite u {s.u}")


def fuzz_callables(data: st.DataObject) -> None:
    n = data.draw(st.integers(1, 3))
    shape = data.draw(st.sampled_from(["right", "right", "right", "none", "short", "nan",
                                       "raise", "string", "matrix"]))

    def out(v: np.ndarray) -> Any:
        return {"right": v, "none": None, "short": v[:-1], "nan": v * np.nan,
                "raise": (_ for _ in ()).throw(UserError("boom")) if shape == "raise" else v,
                "string": "v", "matrix": np.outer(v, v)}[shape]

    which = data.draw(st.sampled_from(["M", "Q", "A", "b"]))
    eye = np.eye(n)

    def M(q, t):  # noqa: N802 -- the equation's name
        return out(eye) if which == "M" else eye

    def Q(q, qd, t):  # noqa: N802
        return out(-q) if which == "Q" else -q

    def A(q, qd, t):  # noqa: N802
        return out(np.ones((1, n))) if which == "A" else np.ones((1, n))

    def b(q, qd, t):
        return out(np.zeros(1)) if which == "b" else np.zeros(1)

    coords = data.draw(st.one_of(st.just(n), st.just([f"q{i}" for i in range(n)]),
                                 st.lists(st.text(max_size=3), max_size=4)))
    system = call("from_callables", lambda: ukdyn.from_callables(
        coords, M, Q, constraints=[ukdyn.constraint("c", A, b)]))
    if system is None:
        return
    q0 = data.draw(states(n))
    qd0 = data.draw(st.one_of(st.just([0.0] * n), states(n)))
    where = f"simulate(from_callables, {which} -> {shape}, q0={q0!r})"
    r = call(where, lambda: ukdyn.simulate(system, q0, qd0, t_end=0.05, project_initial=True))
    check_result(where, r, 0.05)


ENTRY_POINTS = [fuzz_parse, fuzz_load, fuzz_simulate, fuzz_solve, fuzz_control, fuzz_callables]


def main() -> int:
    seconds = float(sys.argv[1]) if len(sys.argv) > 1 else 60.0
    findings: list[str] = []
    counts = {f.__name__: 0 for f in ENTRY_POINTS}
    start = time.monotonic()
    deadline = start + seconds

    def batch(fn: Callable[[st.DataObject], None], k: int) -> None:
        @settings(max_examples=20, deadline=None, database=None, derandomize=False,
                  phases=[Phase.generate], suppress_health_check=list(HealthCheck))
        @given(st.data())
        def run(data: st.DataObject) -> None:
            counts[fn.__name__] += 1
            try:
                fn(data)
            except Finding as e:
                findings.append(f"{fn.__name__}: {e}")
                if not KEEP_GOING:
                    raise
        (seed(SEED + k)(run) if SEED is not None else run)()

    k = 0
    while time.monotonic() < deadline and (KEEP_GOING or not findings):
        for fn in ENTRY_POINTS:
            if time.monotonic() >= deadline:
                break
            try:
                batch(fn, k)
            except Finding:
                break
            k += 1
    total = sum(counts.values())
    elapsed = time.monotonic() - start
    if findings:
        print(f"fuzz_python: {len(findings)} FINDING(S) in {total} calls ({elapsed:.0f} s, "
              f"seed {SEED}):",
              file=sys.stderr)
        for f in dict.fromkeys(findings):
            print(" ", f[:1500], file=sys.stderr)
        return 1
    print(f"fuzz_python: {total} calls in {elapsed:.0f} s, seed {SEED} ({counts}): every one "
          "returned or raised a documented, clear error")
    return 0


if __name__ == "__main__":
    sys.exit(main())
