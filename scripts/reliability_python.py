#!/usr/bin/python3
# SPDX-License-Identifier: BSD-3-Clause
"""The Python cases of the bad-input report (D4, D5, D6, D13, D15), judged; run by
scripts/reliability_rerun.py with build/python on the path. Prints one line per case:
CASE<TAB>class<TAB>input<TAB>message (class C clear error, OK correct, U? not as promised)."""

from __future__ import annotations

import math
import signal
import subprocess
import sys
import time

import numpy as np

import ukdyn


def case(what: str, fn, expect, words: str = "") -> None:
    """expect: an exception class (a clear error whose message contains words) or a predicate
    of the returned value (correct)."""
    try:
        value = fn()
    except Exception as e:  # noqa: BLE001
        msg = f"{type(e).__name__}: {e}".replace("\n", " ")
        good = isinstance(expect, type) and isinstance(e, expect) and words in str(e) \
            and "Unable to cast" not in str(e)
        print(f"CASE\t{'C' if good else 'U?'}\t{what}\t{msg[:300]}", flush=True)
        return
    good = callable(expect) and not isinstance(expect, type) and expect(value)
    print(f"CASE\t{'OK' if good else 'U?'}\t{what}\treturned {value!r}"[:400].replace("\n", " "),
          flush=True)


m = ukdyn.load("pendulum")
case("simulate: t_end=inf", lambda: m.simulate(t_end=math.inf), ValueError, "t_end")
case("simulate: rk4 step=1e-300", lambda: m.simulate(integrator="rk4", step=1e-300), ValueError,
     "step")
case("simulate: output_at=[100] (outside)", lambda: m.simulate(output_at=[100.0]), ValueError,
     "output_at")
case("simulate: output_at=[nan]", lambda: m.simulate(output_at=[math.nan]), ValueError,
     "output_at")
case("simulate: baumgarte_alpha=nan",
     lambda: m.simulate(drift="baumgarte", baumgarte_alpha=math.nan), ValueError,
     "baumgarte_alpha")
s = m.solver()
s.solve([1.0, 0.0], [0.0, 0.0], 0.0)
case("solve: NaN q with check=False after a good solve",
     lambda: s.solve([math.nan, 0.0], [0.0, 0.0], 0.0, check=False),
     lambda r: r.status != "ok" and not np.any(np.isfinite(r.qdd)) and
     not np.any(np.isfinite(s.qdd)))
case("solve: q = None", lambda: s.solve(None, [0.0, 0.0], 0.0), ValueError, "None")
case("evaluate: wrong size", lambda: s.evaluate([1.0], [0.0], 0.0), ValueError, "evaluate")
case("from_callables: Q returns None",
     lambda: ukdyn.simulate(ukdyn.from_callables(["x", "y"], M=np.eye(2),
                                                 Q=lambda q, qd, t: None),
                            [1.0, 0.0], [0.0, 0.0], t_end=1.0), ValueError, "None")
case("from_callables: coulomb on unknown constraint",
     lambda: ukdyn.from_callables(["x", "y"], M=np.eye(2), constraints=[ukdyn.constraint(
         "rod", lambda q, qd, t: np.array([q[0], q[1]]), lambda q, qd, t: 0.0)],
         nonideal=[ukdyn.coulomb("nope", 0.3)]), ValueError, "nope")
case("load: a directory", lambda: ukdyn.load("/"), ukdyn.ModelError, "directory")
r = ukdyn.load("slider_crank").simulate(t_end=0.1)
case("slider_crank Result: distinct names", lambda: (len(r.names), len(set(r.names))),
     lambda v: v[0] == v[1])
case("slider_crank: crank.x and crank_x name one column",
     lambda: (r["crank.x"], r["crank_x"]), lambda v: v[0] is v[1] or np.array_equal(*v))

# D4: Ctrl-C during simulate: KeyboardInterrupt within a fraction of a second, partial result kept
CHILD = r'''
import time, ukdyn
t0 = time.time()
print("started", flush=True)
try:
    ukdyn.load("pendulum").simulate(t_end=30000)
    print("finished")
except KeyboardInterrupt as e:
    r = getattr(e, "partial", None)
    print("caught %.3f %s %d" % (time.time(), r.status if r is not None else None,
                                len(r) if r is not None else -1))
'''
p = subprocess.Popen([sys.executable, "-c", CHILD], stdout=subprocess.PIPE, text=True,
                     preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
p.stdout.readline()
time.sleep(2)
sent = time.time()
p.send_signal(signal.SIGINT)
out = p.communicate(timeout=120)[0].split()
latency = float(out[1]) - sent if out and out[0] == "caught" else math.inf
good = out[:1] == ["caught"] and latency < 1.0 and out[2] == "interrupted" and int(out[3]) > 10
print(f"CASE\t{'OK' if good else 'U?'}\tCtrl-C during Model.simulate\t"
      f"KeyboardInterrupt {latency * 1e3:.0f} ms after SIGINT, partial result {out[2:]}",
      flush=True)
