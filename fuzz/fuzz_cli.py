#!/usr/bin/python3
# SPDX-License-Identifier: BSD-3-Clause
"""Fuzzes the `ukdyn` command line: argument parsing and everything it leads to.

usage: fuzz/fuzz_cli.py UKDYN [SECONDS]      (default 60; scripts/fuzz.sh runs it)

Hypothesis builds argument lists from the command line's own vocabulary (subcommands, options,
the built-in examples, the example model files, a few hostile paths) mixed with arbitrary text,
numbers at their limits (NaN, inf, 1e300, 1e-300, negative zero), unicode and empty strings, and
runs the real program on each in a fresh output directory. The promise it checks (README.md,
`ukdyn --help`, docs/reliability.md):

* the program ends by itself (no hang: at most FUZZ_TIMEOUT seconds, default 60) and is never
  killed by a signal;
* its exit code is a documented one (0-6), and a non-zero code comes with a message on stderr
  that is not an escaped C++ exception (`terminate called`, `std::bad_alloc`, `what():`);
* a run that exits 0 or 5 wrote trajectory.csv and summary.json, which agree (one row per
  sample, the last row at t_reached), and reached its end time; a run that failed (1) after it
  started still wrote both, with a status that is not ok (nothing silent, nothing lost).

Runs are kept short: the generated end times are either at most 0.5 s or values that must be
refused before any work (NaN, inf, 1e300, 1e-300, 0, negative), so the time budget buys many
inputs. The first finding is printed with its arguments and the script exits 1.
"""

from __future__ import annotations

import csv
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from hypothesis import HealthCheck, Phase, given, seed, settings
from hypothesis import strategies as st

def text(**kw: int) -> st.SearchStrategy[str]:
    """Arbitrary text, without NUL and lone surrogates (a command line cannot hold them)."""
    return st.text(alphabet=st.characters(blacklist_categories=("Cs",),
                                          blacklist_characters="\x00"), **kw)


ROOT = Path(__file__).resolve().parent.parent
TIMEOUT = float(os.environ.get("FUZZ_TIMEOUT", "60"))
KEEP_GOING = os.environ.get("FUZZ_KEEP_GOING") == "1"  # collect every finding (development)
# FUZZ_SEED=N: batch k draws from seed N + k, so a run replays the same inputs in the same order
# (CI: it fails for a change, not for the luck of the draw); unset: fresh inputs every run
SEED = int(os.environ["FUZZ_SEED"]) if os.environ.get("FUZZ_SEED") else None
EXIT_CODES = {0, 1, 2, 3, 4, 5, 6}
ESCAPED = ("terminate called", "std::bad_alloc", "what():", "Segmentation", "AddressSanitizer",
           "runtime error:")


class Finding(Exception):
    """A broken promise: the arguments and what went wrong."""


def examples(ukdyn: str) -> list[str]:
    out = subprocess.run([ukdyn, "examples"], capture_output=True, text=True, check=True)
    return [line.split()[0] for line in out.stdout.splitlines() if line.strip()]


def numbers() -> st.SearchStrategy[str]:
    """Numbers as the command line sees them: text, at their limits."""
    special = st.sampled_from(["nan", "inf", "-inf", "1e300", "-1e300", "1e-300", "0", "-0",
                               "-1", "1e400", "0x10", "1e", "", " 1", "1,5", "2*3", "NaN"])
    small = st.floats(min_value=1e-4, max_value=0.5).map(repr)
    anything = st.floats(allow_nan=True, allow_infinity=True).map(repr)
    return st.one_of(special, small, anything, text(max_size=8))


def t_ends() -> st.SearchStrategy[str]:
    """End times that keep a run short, or that must be refused before any work."""
    short = st.floats(min_value=1e-3, max_value=0.5).map(repr)
    refused = st.sampled_from(["nan", "inf", "-inf", "1e300", "1e-300", "0", "-1", "abc", "",
                               "1e400", "5e-324"])
    return st.one_of(short, short, refused)


def steps() -> st.SearchStrategy[str]:
    """Steps that keep a fixed-step run below a few 10^5 steps, or that must be refused."""
    fine = st.floats(min_value=1e-5, max_value=1.0).map(repr)
    refused = st.sampled_from(["0", "-1e-3", "nan", "inf", "1e-300", "1e-20", "1e-9", "x"])
    return st.one_of(fine, refused)


def tolerances() -> st.SearchStrategy[str]:
    fine = st.floats(min_value=1e-12, max_value=1e-2).map(repr)
    odd = st.sampled_from(["0", "-1e-6", "nan", "inf", "1e-30", "1", "10", "tol"])
    return st.one_of(fine, odd)


@st.composite
def command_lines(draw: st.DrawFn, names: list[str], models: list[str], out: str) -> list[str]:
    """One argument list: mostly well-formed pieces in any order, some noise."""
    sub = draw(st.sampled_from(["run", "run", "run", "check", "check", "examples", "",
                                "frob", "--help", "--version", "-h"]))
    args: list[str] = [sub] if sub else []
    source = draw(st.sampled_from(["example", "example", "file", "file", "bad", "none", "both"]))
    name = draw(st.one_of(st.sampled_from(names), text(max_size=12)))
    model = draw(st.sampled_from(models))
    if source in ("example", "both"):
        args += ["--example", name]
    if source in ("file", "both"):
        args.append(model)
    if source == "bad":
        args.append(draw(st.sampled_from(
            ["/dev/null", "/dev/zero", "/", str(ROOT / "examples"), "/nonexistent.yaml",
             str(ROOT / "README.md"), str(ROOT / "CMakeLists.txt"), "-", ""])))
    if sub == "run":
        args += ["--t-end", draw(t_ends())]
    options = st.one_of(
        st.tuples(st.just("--set"), st.one_of(
            st.builds(lambda n, v: f"{n}={v}",
                      st.sampled_from(["m", "L", "g", "k", "mu", "c", "zz", "", "L=2"]),
                      numbers()),
            text(max_size=10))),
        st.tuples(st.just("--integrator"), st.one_of(
            st.sampled_from(["rk4", "rk5", "dopri5", "rkf78", "bdf", "euler", "", "RK4"]),
            text(max_size=6))),
        st.tuples(st.just("--rtol"), tolerances()),
        st.tuples(st.just("--atol"), tolerances()),
        st.tuples(st.just("--step"), steps()),
        st.tuples(st.just("--no-plots")),
        st.tuples(st.just("--no-stiff-switch")),
        st.tuples(st.just("-o"), st.sampled_from([out, out + "/sub/dir", "/dev/null/x",
                                                   "/proc/ukdyn-fuzz", ""])),
        st.tuples(text(min_size=1, max_size=12)),
        st.tuples(st.sampled_from(["--", "-", "--t-end", "--set", "-o", "--example",
                                   "--output=" + out, "--t-end=0.1"])),
    )
    for extra in draw(st.lists(options, max_size=5)):
        args += list(extra)
    if sub == "run" and "--no-plots" not in args and draw(st.integers(0, 9)) > 0:
        args.append("--no-plots")  # plots cost a Python start-up each: mostly leave them out
    if sub == "run" and not any(a in ("-o", "--output") or a.startswith("--output=")
                                for a in args):
        args += ["-o", out]
    return args


def rows(path: Path) -> list[list[str]]:
    with open(path, newline="") as f:
        return list(csv.reader(f))


def check_outputs(args: list[str], code: int, out: Path) -> None:
    """A run that started wrote a CSV and a summary that agree."""
    summary_path, csv_path = out / "summary.json", out / "trajectory.csv"
    if code in (0, 5) or (code == 1 and summary_path.exists()):
        if not summary_path.exists() or not csv_path.exists():
            raise Finding(f"exit {code} but no summary.json/trajectory.csv in {out}")
        summary = json.loads(summary_path.read_text())
        table = rows(csv_path)
        samples = len(table) - 1
        if samples != summary["samples"]:
            raise Finding(f"CSV has {samples} rows, summary says {summary['samples']}")
        width = len(table[0])
        if any(len(r) != width for r in table):
            raise Finding("CSV rows of unequal width")
        if len(set(table[0])) != width:
            twice = sorted({c for c in table[0] if table[0].count(c) > 1})
            raise Finding(f"CSV header has duplicate columns: {twice[:8]}")
        status = summary["status"]
        if code == 0 and status != "ok":
            raise Finding(f"exit 0 with status {status}")
        if code == 1 and status == "ok":
            raise Finding("exit 1 with status ok")
        if code in (0, 5):
            t_end = summary["options"].get("t_end", summary.get("t_end"))
            if samples < 2:
                raise Finding(f"status {status} with {samples} samples")
            last = float(table[-1][0])
            reached = summary["t_reached"]
            if reached is None or not math.isclose(last, reached, rel_tol=1e-12, abs_tol=1e-12):
                raise Finding(f"last CSV row at t = {last}, t_reached = {reached}")
            if t_end is not None and not math.isclose(reached, t_end, rel_tol=1e-9,
                                                      abs_tol=1e-12):
                raise Finding(f"status {status} but t_reached {reached} != t_end {t_end}")


def run_one(ukdyn: str, args: list[str], out: Path) -> None:
    try:
        p = subprocess.run([ukdyn, *args], capture_output=True, timeout=TIMEOUT,
                           stdin=subprocess.DEVNULL, cwd=out.parent)
    except subprocess.TimeoutExpired:
        raise Finding(f"no answer within {TIMEOUT:g} s (hang)") from None
    err = p.stderr.decode(errors="replace")
    if p.returncode < 0:
        raise Finding(f"killed by signal {-p.returncode}: {err[-2000:]}")
    if p.returncode not in EXIT_CODES:
        raise Finding(f"undocumented exit code {p.returncode}: {err[-2000:]}")
    for marker in ESCAPED:
        if marker in err:
            raise Finding(f"exit {p.returncode} with '{marker}' on stderr: {err[-2000:]}")
    if p.returncode != 0 and not err.strip():
        raise Finding(f"exit {p.returncode} with nothing on stderr")
    target = output_dir(args)
    if args and args[0] == "run" and target is not None and target.is_dir():
        check_outputs(args, p.returncode, target)


def output_dir(args: list[str]) -> Path | None:
    """The directory a run writes to (the last -o/--output), None when not given."""
    found: str | None = None
    for i, a in enumerate(args):
        if a in ("-o", "--output") and i + 1 < len(args):
            found = args[i + 1]
        elif a.startswith("--output="):
            found = a[len("--output="):]
    return Path(found) if found else None


def main() -> int:
    if len(sys.argv) not in (2, 3):
        print(__doc__, file=sys.stderr)
        return 2
    ukdyn = os.path.abspath(sys.argv[1])
    seconds = float(sys.argv[2]) if len(sys.argv) == 3 else 60.0
    names = examples(ukdyn)
    models = sorted(str(p) for p in (ROOT / "examples" / "models").glob("*.yaml"))
    scratch = Path(tempfile.mkdtemp(prefix="ukdyn-fuzz-cli."))
    out = scratch / "out"
    count = 0
    finding: list[str] = []

    def batch(k: int) -> None:
        @settings(max_examples=25, deadline=None, database=None, derandomize=False,
                  phases=[Phase.generate], suppress_health_check=list(HealthCheck))
        @given(st.data())
        def run(data: st.DataObject) -> None:
            nonlocal count
            args = data.draw(command_lines(names, models, str(out)))
            shutil.rmtree(out, ignore_errors=True)
            count += 1
            try:
                run_one(ukdyn, args, out)
            except Finding as e:
                finding.append(f"{e}\n  arguments: {args!r}")
                if not KEEP_GOING:
                    raise

        (seed(SEED + k)(run) if SEED is not None else run)()

    start = time.monotonic()
    try:
        k = 0
        while time.monotonic() - start < seconds and (KEEP_GOING or not finding):
            try:
                batch(k)
            except Finding:
                break
            k += 1
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
    elapsed = time.monotonic() - start
    if finding:
        print(f"fuzz_cli: {len(finding)} FINDING(S) in {count} inputs ({elapsed:.0f} s, "
              f"seed {SEED}):",
              file=sys.stderr)
        for f in finding:
            print(f, file=sys.stderr)
        return 1
    print(f"fuzz_cli: {count} command lines in {elapsed:.0f} s (seed {SEED}): no crash, hang, undocumented "
          "exit code or inconsistent output")
    return 0


if __name__ == "__main__":
    sys.exit(main())
