#!/usr/bin/python3
# SPDX-License-Identifier: BSD-3-Clause
"""The time `ukdyn run` spends on its plots, per example (docs/simulation.md "Plots"; a
benchmark, not a test).

usage: /usr/bin/python3 bench/bench_plotting.py [--ukdyn build/app/ukdyn] [--repeat 3]
                                                [--script python/ukdyn/plotting.py
                                                 [--baseline OLD/plotting.py]]
                                                [--baseline-python OLD_PYTHON] [NAME ...]

For each built-in example (or those NAMEd): `ukdyn run --example NAME` with and without its
plots (--no-plots), `--repeat` times each, alternating; the plots' time is the difference of the
wall times. With --script, the plot script itself is timed instead (python3 SCRIPT CSV DIR png on
the run's directory: the same work without the simulation, for comparing two versions of the
script; with --baseline, a second script is timed the same way, alternating with the first, so
that both see the same load; with --baseline-python, the command is timed a second time the same
way with UKDYN_PYTHON=OLD_PYTHON, a wrapper that runs an older plot script). Prints a Markdown
table for bench/RESULTS.md: the minimum and the
median wall time over the repeats (on a loaded machine the minimum is the better estimate of
the work; the median says what a user sees), the median CPU time (user + system, every process
of the plots: the work, which another program's load changes little), the number of figures,
and the worst example.
"""
import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")


def cpu():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def wall(args, cpu_times=None, env=None):
    start, used = time.perf_counter(), cpu()
    done = subprocess.run(args, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                          env=env)
    elapsed = time.perf_counter() - start
    if cpu_times is not None:
        cpu_times.append(cpu() - used)
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
    parser.add_argument("--baseline", help="with --script: time this one too, alternately")
    parser.add_argument("--baseline-python",
                        help="without --script: time the command with UKDYN_PYTHON set to this "
                             "too, alternately")
    parser.add_argument("names", nargs="*")
    args = parser.parse_args()
    names = args.names or examples(args.ukdyn)
    python = os.environ.get("UKDYN_PYTHON") or "/usr/bin/python3"
    scripts = [args.script] + ([args.baseline] if args.baseline and args.script else [])
    envs = [None] * len(scripts)
    if args.baseline_python and not args.script:
        scripts.append(None)
        envs.append(dict(os.environ, UKDYN_PYTHON=args.baseline_python))
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for name in names:
            out = os.path.join(tmp, name)
            run = [args.ukdyn, "run", "--example", name, "-o", out]
            times = [([], []) for _ in scripts]
            for _ in range(args.repeat):
                for script, env, (walls, cpus) in zip(scripts, envs, times):
                    if script:
                        wall(run + ["--no-plots"])
                        csv = os.path.join(out, "trajectory.csv")
                        walls.append(wall([python, script, csv, out, "png"], cpus))
                    else:
                        bare_cpu = []
                        bare = wall(run + ["--no-plots"], bare_cpu)
                        walls.append(wall(run, cpus, env) - bare)
                        cpus[-1] -= bare_cpu[0]
            figures = len([f for f in os.listdir(out) if f.endswith(".png")])
            row = [name, figures]
            for walls, cpus in times:
                row += [min(walls), statistics.median(walls), statistics.median(cpus)]
            rows.append(row)
            print(" ".join(str(round(v, 2)) if isinstance(v, float) else str(v) for v in row),
                  file=sys.stderr)
    labels = ["", " (baseline)"][:len(scripts)]
    print("| example | figures | " + " | ".join(
        "wall: min%s | median | CPU: median" % b for b in labels) + " |")
    print("|---|---|" + "---|---|---|" * len(labels))
    for row in rows:
        print("| %s | %d | " % tuple(row[:2]) + " | ".join("%.2f s" % v for v in row[2:]) + " |")
    for k, label in enumerate(labels):
        i = 2 + 3 * k
        worst = max(rows, key=lambda r: r[i + 1])
        print("\n%s: worst median %s, %.2f s; worst minimum %.2f s; mean of the medians %.2f s; "
              "worst CPU %.2f s" % (label.strip(" ()") or "this", worst[0], worst[i + 1],
                                    max(r[i] for r in rows),
                                    statistics.mean(r[i + 1] for r in rows),
                                    max(r[i + 2] for r in rows)))

if __name__ == "__main__":
    main()
