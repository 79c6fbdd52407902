# SPDX-License-Identifier: BSD-3-Clause
"""Ensembles on threads and on Dask (issue #17, bench/RESULTS.md): samples per second of
ukdyn.sweep for a short run (the pendulum, 1 s) and a long one (the double four-bar, 10 s) on 1 and
2 threads and on a LocalCluster of 1 and 2 worker processes; Dask's overhead per task; and the
chunk size from which that overhead is under 5 % of the work.

Run with the built module on the path: PYTHONPATH=build/python /usr/bin/python3
bench/bench_sweep_dask.py [--quick]. Each figure is the best of `repeat` runs (wall time), with
the CPU time of this process (threads) beside it; on a shared machine, the best of several is the
one least disturbed by the others.
"""

import argparse
import os
import resource
import time

import ukdyn

CASES = {
    # name: (model, t_end, grid, samples)
    "pendulum 1 s": ("pendulum", 1.0, "L", 64),
    "double four-bar 10 s": ("double_four_bar", 10.0, "v0", 8),
}


def cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def best(f, repeat):
    times = []
    for _ in range(repeat):
        w0, c0 = time.perf_counter(), cpu()
        f()
        times.append((time.perf_counter() - w0, cpu() - c0))
    return min(times)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    repeat = 1 if args.quick else args.repeat
    from distributed import Client, LocalCluster

    print(f"cores: {os.cpu_count()}, load average: {os.getloadavg()}")
    for label, (model, t_end, name, n) in CASES.items():
        grid = {name: [1.0 + 0.01 * i for i in range(n)]}
        kw = dict(grid=grid, t_end=t_end)
        for threads in (1, 2):
            wall, c = best(lambda: ukdyn.sweep(model, workers=threads, **kw), repeat)
            print(f"{label}: {threads} thread(s): {n / wall:.1f} samples/s "
                  f"(wall {wall:.3f} s, CPU {c:.3f} s)")
        for workers in (1, 2):
            with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                              dashboard_address=None, silence_logs=50) as cluster, \
                    Client(cluster) as client:
                ukdyn.sweep(model, client=client, chunk_size=n, grid={name: [1.0]},
                            t_end=t_end)  # warm the workers (import ukdyn)
                chunk = max(1, n // (2 * workers))
                wall, _ = best(lambda: ukdyn.sweep(model, client=client, chunk_size=chunk, **kw),
                               repeat)
                print(f"{label}: Dask {workers} worker(s), chunks of {chunk}: "
                      f"{n / wall:.1f} samples/s (wall {wall:.3f} s)")

    # the overhead per task: one worker, the pendulum with t_end tiny (a run of ~0 work), chunks
    # of one sample, against the same samples in this process on one thread
    model, name, n = "pendulum", "L", 64
    tiny = dict(grid={name: [1.0 + 0.01 * i for i in range(n)]}, t_end=1e-3)
    local, _ = best(lambda: ukdyn.sweep(model, workers=1, **tiny), repeat)
    one = dict(grid={name: [1.0 + 0.01 * i for i in range(n)]}, t_end=1.0)
    per_sample, _ = best(lambda: ukdyn.sweep(model, workers=1, **one), repeat)
    per_sample /= n
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=None,
                      silence_logs=50) as cluster, Client(cluster) as client:
        ukdyn.sweep(model, client=client, chunk_size=n, **tiny)
        dask1, _ = best(lambda: ukdyn.sweep(model, client=client, chunk_size=1, **tiny), repeat)
        overhead = (dask1 - local) / n
        print(f"Dask overhead per task (1 worker, chunks of 1 near-empty sample): "
              f"{overhead * 1e3:.2f} ms; a pendulum 1 s sample takes {per_sample * 1e3:.2f} ms")
        print(f"chunk size for overhead < 5 % (pendulum 1 s): "
              f"{overhead / (0.05 * per_sample):.1f} samples")
        for chunk in (1, 4, 16, 64):
            wall, _ = best(lambda: ukdyn.sweep(model, client=client, chunk_size=chunk, **one),
                           repeat)
            print(f"  pendulum 1 s, 1 worker, chunks of {chunk}: overhead "
                  f"{100 * (wall / (per_sample * n) - 1):+.1f} % against one thread in-process")


if __name__ == "__main__":
    main()
