#!/usr/bin/python3
# SPDX-License-Identifier: BSD-3-Clause
"""The time `ukdyn run` spends on its plots, per example (docs/simulation.md "Plots"; a
benchmark, not a test).

usage: /usr/bin/python3 bench/bench_plotting.py [--ukdyn build/app/ukdyn] [--repeat 3]
                                                [--script python/ukdyn/plotting.py] [NAME ...]

For each built-in example (or those NAMEd): `ukdyn run --example NAME` with and without its
plots (--no-plots), `--repeat` times each, alternating; the plots' time is the difference of the
wall times. With --script, the plot script itself is timed instead (python3 SCRIPT CSV DIR png on
the run's directory: the same work without the simulation, for comparing two versions of the
script). Prints a Markdown table for bench/RESULTS.md: the minimum and the median over the
repeats (on a loaded machine the minimum is the better estimate of the work; the median says
what a user sees), the number of figures, and the worst example.
"""
import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")


def wall(args):
    start = time.perf_counter()
    done = subprocess.run(args, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    elapsed = time.perf_counter() - start
    if done.returncode not in (0, 5):  # 5: energy balance exceeded, the files are written
        sys.exit("%s failed (exit %d): %s" % (" ".join(args), done.returncode, done.stderr))
    return elapsed


def examples(ukdyn):
    out = subprocess.run([ukdyn, "examples"], capture_output=True, text=True, check=True).stdout
    return [line.split()[0] for line in out.splitlines()
            if line.strip() and not line.startswith("run one") and len(line.split()) > 1]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ukdyn", default=os.path.join(ROOT, "build", "app", "ukdyn"))
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--script", help="time this plot script on the run's files instead")
    parser.add_argument("names", nargs="*")
    args = parser.parse_args()
    names = args.names or examples(args.ukdyn)
    python = os.environ.get("UKDYN_PYTHON") or "/usr/bin/python3"
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for name in names:
            out = os.path.join(tmp, name)
            run = [args.ukdyn, "run", "--example", name, "-o", out]
            times = []
            for _ in range(args.repeat):
                if args.script:
                    wall(run + ["--no-plots"])
                    csv = os.path.join(out, "trajectory.csv")
                    times.append(wall([python, args.script, csv, out, "png"]))
                else:
                    bare = wall(run + ["--no-plots"])
                    times.append(wall(run) - bare)
            figures = len([f for f in os.listdir(out) if f.endswith(".png")])
            rows.append((name, figures, min(times), statistics.median(times)))
            print("%-34s %d figures  min %.2f s  median %.2f s" % rows[-1], file=sys.stderr)
    print("| example | figures | plots: min | median |")
    print("|---|---|---|---|")
    for name, figures, low, mid in rows:
        print("| %s | %d | %.2f s | %.2f s |" % (name, figures, low, mid))
    worst = max(rows, key=lambda r: r[3])
    print("\nworst median: %s, %.2f s; worst minimum: %.2f s; mean of the medians: %.2f s"
          % (worst[0], worst[3], max(r[2] for r in rows), statistics.mean(r[3] for r in rows)))


if __name__ == "__main__":
    main()
