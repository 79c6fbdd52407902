#!/usr/bin/python3
# SPDX-License-Identifier: BSD-3-Clause
"""Re-runs every reproducer of the bad-input report and judges each outcome.

usage: scripts/reliability_rerun.py [REPORT_DIR]     (from the project root, after scripts/setup.sh)

REPORT_DIR is the defect report's folder of reproducers, outside the repository (default
../shared/reproducers/bad-input, beside the repository: its
models/ and scripts/). Each case runs the real program (build/app/ukdyn), the Python module
(build/python) or a small C++ program linked to build/libukdyn.a, and is judged against what
docs/reliability.md promises: the exit code, the words of the message (what and where), and for
runs the files on disk. Prints one line per case (category, input, outcome class, exit code, the
message's first line) and the table by category that docs/reliability.md records; exits 1 when a
case is a crash, a hang, silent garbage or lost data, or does not give the promised answer.

Outcome classes, as in the report: C clear error, OK correct, U unclear error, X crash, H hang,
G silent garbage, L data lost.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Callable, Optional

ROOT = Path(__file__).resolve().parent.parent
UKDYN = str(ROOT / "build" / "app" / "ukdyn")
PY = "/usr/bin/python3"
ENV = {**os.environ, "PYTHONPATH": str(ROOT / "build" / "python")}
W = Path(tempfile.mkdtemp(prefix="ukdyn-reliability."))
QUICK = os.environ.get("RELIABILITY_QUICK") == "1"  # skip the cases of minutes (development)


class Outcome:
    def __init__(self, code: Optional[int], out: str, seconds: float, hang: bool = False):
        self.code, self.out, self.seconds, self.hang = code, out, seconds, hang

    def first(self) -> str:
        for line in self.out.splitlines():
            if "error" in line or "warning" in line:
                return line.strip()[:200]
        lines = [l for l in self.out.splitlines() if l.strip()]
        return lines[-1].strip()[:200] if lines else ""


def sh(args: list[str], timeout: float = 120, env: Optional[dict] = None,
       cwd: Optional[Path] = None) -> Outcome:
    start = time.monotonic()
    try:
        p = subprocess.run(args, capture_output=True, timeout=timeout, env=env or ENV,
                           cwd=cwd or W, stdin=subprocess.DEVNULL)
    except subprocess.TimeoutExpired as e:
        return Outcome(None, (e.stdout or b"").decode(errors="replace") +
                       (e.stderr or b"").decode(errors="replace"), timeout, hang=True)
    return Outcome(p.returncode, p.stdout.decode(errors="replace") +
                   p.stderr.decode(errors="replace"), time.monotonic() - start)


def ukdyn(*args: str, timeout: float = 120) -> Outcome:
    return sh([UKDYN, *args], timeout=timeout)


def run_source(source: list[str], extra: tuple[str, ...], timeout: float) -> tuple[Outcome, Path]:
    out = W / ("o" + str(abs(hash((*source, *extra)))))
    shutil.rmtree(out, ignore_errors=True)
    return ukdyn("run", *source, "-o", str(out), "--no-plots", *extra, timeout=timeout), out


def run_model(model: str, *extra: str, timeout: float = 120) -> tuple[Outcome, Path]:
    return run_source([model], extra, timeout)


def run_example(name: str, *extra: str, timeout: float = 120) -> tuple[Outcome, Path]:
    return run_source(["--example", name], extra, timeout)


def summary(out: Path) -> dict:
    try:
        return json.loads((out / "summary.json").read_text())
    except (OSError, ValueError):
        return {}


RESULTS: list[tuple[str, str, str, str, str]] = []


def judge(cat: str, what: str, o: Outcome, code: Optional[set[int]] = None,
          words: str = "", ok: Optional[Callable[[], bool]] = None, cls: str = "C") -> None:
    """Records a case: the promised exit code(s), message regex and extra check give cls;
    a signal is X, a timeout H; anything else is U (to be read)."""
    if o.hang:
        got = "H"
    elif o.code is not None and o.code < 0 and not (o.code == -6 and "what():" in o.out and
                                                     "invalid_argument" in o.out):
        got = "X"  # killed by a signal (an uncaught std::invalid_argument's abort is the caller's)
    elif (code is None or o.code in code) and (not words or re.search(words, o.out, re.S)) \
            and (ok is None or ok()):
        got = cls
    else:
        got = "U?"
    RESULTS.append((cat, what, got, str(o.code), o.first()))
    print(f"{got:3} {cat:11} {what[:60]:60} exit {o.code}  {o.first()[:150]}", flush=True)
    if got == "U?":
        print("    ---- output ----\n    " + o.out[-1500:].replace("\n", "\n    "), flush=True)


def main() -> int:
    C = Path(sys.argv[1] if len(sys.argv) > 1 else ROOT.parent / "shared" / "reproducers" /
             "bad-input").resolve()
    M = C / "models"
    if not M.is_dir():
        print(f"no reproducers at {C} (give the report's bad-input folder)", file=sys.stderr)
        return 2

    # ---------------- command line ----------------
    judge("CLI", "a directory as the model", ukdyn("check", str(ROOT / "examples")), {3},
          r"is a directory")
    judge("CLI", "unknown subcommand 'frob'", ukdyn("frob"), {2}, r"frob")
    judge("CLI", "model /dev/zero", ukdyn("check", "/dev/zero", timeout=60), {3},
          r"/dev/zero.*(not a regular file|larger than|size)")
    o, out = run_example("pendulum", "--t-end", "inf")
    judge("CLI", "--t-end inf", o, {2, 3}, r"t.end.*(finite|inf)")
    o, out = run_example("pendulum", "--t-end", "1e-300")
    judge("CLI", "--t-end 1e-300", o, {2, 3}, r"t.end")
    o, out = run_example("pendulum", "--t-end", "1e300", timeout=60)
    judge("CLI", "--t-end 1e300 (refused at start)", o, {2, 3}, r"sample|t.end",
          ok=lambda: o.seconds < 10)
    o, out = run_example("pendulum", "--t-end", "1e9", timeout=60)
    judge("CLI", "--t-end 1e9 (10^11 samples, refused at start)", o, {2, 3},
          r"sample", ok=lambda: o.seconds < 10)

    # interrupts (D1, D2): the partial run is written, status interrupted
    for sig, code in (("SIGINT", 130), ("SIGTERM", 143)):
        out = W / ("sig" + sig)
        start = time.monotonic()
        p = subprocess.Popen([UKDYN, "run", "--example", "pendulum", "--t-end", "100000", "-o",
                              str(out), "--no-plots"], stdout=subprocess.PIPE,
                             stderr=subprocess.STDOUT, cwd=W,
                             preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
        time.sleep(3)
        p.send_signal(getattr(signal, sig))
        text = p.communicate(timeout=60)[0].decode(errors="replace")
        o = Outcome(p.returncode, text, time.monotonic() - start)
        s = summary(out)
        judge("CLI", f"{sig} 3 s into a long run", o, {code}, r"interrupted",
              ok=lambda: s.get("status") == "interrupted" and s.get("samples", 0) > 100 and
              csv_rows(out / "trajectory.csv") == s["samples"], cls="OK")
    # D2: interrupted while a previous complete run's files are there
    out = W / "wk"
    ukdyn("run", "--example", "four_bar_friction", "--t-end", "200", "-o", str(out), "--no-plots")
    p = subprocess.Popen([UKDYN, "run", "--example", "four_bar_friction", "--t-end", "2000", "-o",
                          str(out), "--no-plots"], stdout=subprocess.PIPE,
                         stderr=subprocess.STDOUT, cwd=W,
                         preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    time.sleep(0.8)
    p.send_signal(signal.SIGINT)
    text = p.communicate(timeout=120)[0].decode(errors="replace")
    s = summary(out)
    judge("CLI", "SIGINT while writing, over a previous complete run", Outcome(p.returncode, text, 0),
          {130}, ok=lambda: s.get("status") == "interrupted" and
          csv_rows(out / "trajectory.csv") == s.get("samples"), cls="OK")
    # D3: two runs into one directory
    out = W / "same"
    a = subprocess.Popen([UKDYN, "run", "--example", "pendulum", "--t-end", "2000", "--set", "L=1",
                          "-o", str(out), "--no-plots"], stdout=subprocess.PIPE,
                         stderr=subprocess.STDOUT)
    time.sleep(0.3)
    b = sh([UKDYN, "run", "--example", "pendulum", "--t-end", "2000", "--set", "L=2", "-o",
            str(out), "--no-plots"])
    a.communicate(timeout=300)
    s = summary(out)
    judge("CLI", "two runs (L=1, L=2) into one output dir at once", b, {6},
          r"in use|lock", ok=lambda: a.returncode == 0 and
          csv_rows(out / "trajectory.csv") == s.get("samples"))

    # ---------------- long runs ----------------
    if not QUICK:
        o, out = run_example("pendulum", "--t-end", "100000", timeout=600)
        s = summary(out)
        judge("long run", "pendulum 100000 s (step limit)", o, {0, 1},
              ok=lambda: (o.code == 0 and s.get("status") == "ok") or
              ("max_steps" in o.out and csv_rows(out / "trajectory.csv") == s.get("samples")),
              cls="OK" if o.code == 0 else "C")

    # ---------------- YAML ----------------
    for f, words in (("dup_keys_precedence.yaml", r"given twice"), ("dup_key.yaml", r"given twice"),
                     ("yaml_multi_doc.yaml", r"document"),
                     ("yaml_flow_comma.yaml", r"quot"),
                     ("deep_yaml.yaml", r"nest|deep")):
        judge("YAML", f, ukdyn("check", str(M / f)), {3}, re.escape(f) + r":\d+:\d+: error: [^\n]*" + words)
    alias = W / "self_alias.yaml"
    alias.write_text("coordinates: &c [*c]\nkinetic_energy: 0.5*x_dot^2\n")
    judge("YAML", "self-referencing alias", ukdyn("check", str(alias)), {3},
          r"self_alias\.yaml:\d+:\d+: error: [^\n]*(alias|anchor)")
    deep = W / "deep_brackets.yaml"
    deep.write_text("coordinates: [x]\nkinetic_energy: 0.5*x_dot^2\nparameters: " +
                    "[" * 100000 + "]" * 100000 + "\n")
    judge("YAML", "[[[...]]] 10^5 deep", ukdyn("check", str(deep)), {3},
          r"deep_brackets\.yaml:\d+:\d+: error: [^\n]*(nest|deep)")

    # ---------------- expressions ----------------
    for f in ("const_acos2.yaml", "const_exp1000.yaml", "const_10pow400.yaml",
              "const_cuberoot_neg.yaml", "const_sinh1e6.yaml", "tan_pole.yaml"):
        judge("expression", f, ukdyn("check", str(M / f)), {3},
              re.escape(f) + r":\d+:\d+: error: ")
    gen = W / "scaling"
    gen.mkdir(exist_ok=True)
    sh([PY, str(C / "scripts" / "gen_scaling.py"), "10000"], cwd=gen)
    if not QUICK:
        o = sh([UKDYN, "check", str(gen / "big_distinct_400000.yaml")], timeout=600)
        judge("expression", "8.3 MB expression, 400000 distinct terms (< 60 s)", o, {0, 4},
              ok=lambda: o.seconds < 60, cls="OK")

    # ---------------- numerics ----------------
    for f in ("mass_blowup.yaml", "mass_blowup_bdf.yaml", "mass_blowup_rk4.yaml"):
        o, out = run_model(str(M / f))
        s = summary(out)
        judge("numerics", f + " (valid to t = 1)", o, {1},
              r"no step beyond t = 0\.99999|(not positive definite|not determined) at t = 1 ",
              ok=lambda: (s.get("t_reached") or 0) > 0.99, cls="OK")
    for f in ("step_tiny.yaml", "step_1e-20.yaml"):
        o, out = run_model(str(M / f))
        judge("numerics", f, o, {2, 3}, r"step")
    o, out = run_model(str(M / "every_tiny.yaml"), timeout=60)
    judge("numerics", "output every 1e-9 on a 1 s run", o, {2, 3}, r"every|sample",
          ok=lambda: o.seconds < 10)
    # rk4 without error control steps across the pole: the samples every 0.01 it asks for are
    # refused (closer than the step); with samples every step the energy balance flags the jump
    o, out = run_model(str(M / "div0_runtime3.yaml"))
    judge("numerics", "force 1/x^2 crossed with rk4 h = 0.25", o, {3},
          r"output_every \(0\.01\) is below the step \(0\.25\)")
    cross = W / "div0_every_step.yaml"
    cross.write_text((M / "div0_runtime3.yaml").read_text() + "output: {every: 0.25}\n")
    o, out = run_model(str(cross))
    judge("numerics", "the same, samples every step", o, {5}, r"warning: energy balance")
    if not QUICK:
        o = sh([UKDYN, "check", str(gen / "coords_10000.yaml")], timeout=600)
        judge("numerics", "10^4 coordinates (decoupled oscillators) load (< 60 s)", o, {0, 4},
              ok=lambda: o.seconds < 60, cls="OK")

    # ---------------- constraints ----------------
    o, out = run_model(str(M / "inconsistent_noproj.yaml"))
    judge("constraints", "x = 0 and x = 1, run", o, {3},
          r"inconsistent", ok=lambda: "project: true" not in o.out)
    o = ukdyn("check", str(M / "inconsistent_noproj.yaml"))
    judge("constraints", "x = 0 and x = 1, check", o, {4}, r"contradict",
          ok=lambda: all(w == "none" for w in re.findall(r"redundant constraints\s+(\S+)", o.out)))
    o, out = run_model(str(M / "constraint_const.yaml"))
    judge("constraints", "1 + 0*x = 0", o, {3}, r"inconsistent|no state|cannot",
          ok=lambda: "project: true" not in o.out)
    o, out = run_model(str(M / "fourbar_lockup.yaml"))
    s = summary(out)
    judge("constraints", "four-bar driven into lock-up", o, {1}, r"locks? up",
          ok=lambda: abs((s.get("t_reached") or 0) - 0.7227) < 2e-3)

    # ---------------- multibody ----------------
    o = ukdyn("check", str(M / "mb_spring_zero_length.yaml"))
    judge("multibody", "spring-damper whose two points coincide", o, {0, 3, 4},
          r"mb_spring_zero_length\.yaml:\d+:\d+: (warning|error): [^\n]*(coincide|length|direction)")
    for ex in ("slider_crank", "double_four_bar_bodies", "heavy_top", "pendulum_loop",
               "rolling_disk_bodies", "double_four_bar_bodies_redundant", "bricard"):
        o, out = run_example(ex, "--t-end", "0.1")
        judge("multibody", f"built-in {ex}: distinct columns, no warning", o, {0},
              ok=lambda: "warning" not in o.out and distinct_header(out / "trajectory.csv"),
              cls="OK")

    # ---------------- D17 energy drift ----------------
    for f in ("stick_slip_chatter.yaml", "incline_tan_eq_mu.yaml"):
        o, out = run_model(str(M / f))
        s = summary(out)
        judge("friction", f + ": energy drift of a block at rest", o, {0},
              ok=lambda: abs(s.get("energy_drift", 1)) < 1e-6, cls="OK")

    # ---------------- Python ----------------
    o = sh([PY, str(ROOT / "scripts" / "reliability_python.py")], timeout=600)
    for line in o.out.splitlines():
        if line.startswith("CASE\t"):
            _, verdict, what, msg = line.split("\t", 3)
            RESULTS.append(("Python", what, verdict, "", msg[:200]))
            print(f"{verdict:3} {'Python':11} {what[:60]:60} {msg[:150]}", flush=True)
    if "CASE\t" not in o.out:
        judge("Python", "reliability_python.py", o, {0})

    # ---------------- C++ ----------------
    o = sh(["bash", str(C / "scripts" / "build_cpp.sh")], env={**ENV, "P": str(ROOT)})
    if o.code == 0:
        p = sh([str(W / "cpp_projection_nan_and_moved")])
        # the program does not catch: std::terminate prints the exception (SIGABRT is its own)
        judge("C++", "project_positions NaN / moved-from Workspace", p, None,
              r"converged 0 iterations 0 violation nan status 1.*invalid_argument.*the workspace "
              r"is empty \(moved from", ok=lambda: p.code in (0, -6))
        for case in ("foreign", "foreign_same_n", "size", "size0", "nan", "nant", "sim_size",
                     "sim_nan", "sim_inf"):
            p = sh([str(W / "cpp_misuse"), case])
            judge("C++", f"cpp_misuse {case}", p, {0},
                  r"invalid_argument|SolveError")
    else:
        judge("C++", "build_cpp.sh", o, {0})

    # ---------------- table ----------------
    print()
    cats: dict[str, dict[str, int]] = {}
    for cat, _, got, _, _ in RESULTS:
        d = cats.setdefault(cat, {})
        d[got] = d.get(got, 0) + 1
    cols = ["C", "OK", "U?", "X", "H", "G", "L"]
    print("| category | inputs | " + " | ".join(cols) + " |")
    for cat, d in cats.items():
        print(f"| {cat} | {sum(d.values())} | " + " | ".join(str(d.get(c, 0)) for c in cols) + " |")
    bad = [r for r in RESULTS if r[2] not in ("C", "OK")]
    shutil.rmtree(W, ignore_errors=True)
    print(f"\n{len(RESULTS)} cases, {len(bad)} not as promised")
    return 1 if bad else 0


def csv_rows(path: Path) -> int:
    try:
        with open(path, "rb") as f:
            return sum(1 for _ in f) - 1
    except OSError:
        return -1


def distinct_header(path: Path) -> bool:
    try:
        header = path.read_text().split("\n", 1)[0].split(",")
    except OSError:
        return False
    return len(set(header)) == len(header)


if __name__ == "__main__":
    sys.exit(main())
