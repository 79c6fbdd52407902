# SPDX-License-Identifier: BSD-3-Clause
"""The robust Duffing controller over 1,000 plants of its uncertainty set (docs/ensembles.md).

control_uncertain_duffing (examples/models) tracks x = sin(t) with a controller that believes the
mass is 1.2 and declares a gain uncertainty of 0.2: a requested acceleration v becomes (1.2 / m) v
on the plant, so every plant mass m in [1, 1.5] is inside the set the robust term is designed for.
The script draws 1,000 plant masses (Latin hypercube, seed 1), records the tracking error
error.track and the robust law's computed bound error_bound.track at 40 times, and compares: the
largest |error| of every plant with the bound at the same time (the guarantee: never above it),
and the spread of the tracking error over the plants once the transient has passed (t >= 5 s).
Writes uncertain_duffing.png (the largest error per plant against its mass, with the bound).

    PYTHONPATH=build/python /usr/bin/python3 examples/ensembles/uncertain_duffing.py [-n 1000]
"""

import argparse
import pathlib

import numpy as np

import ukdyn


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("-n", type=int, default=1000, help="plants")
    ap.add_argument("-o", default=".", help="output directory")
    ap.add_argument("--workers", type=int, default=None)
    args = ap.parse_args()
    times = [0.25 * k for k in range(1, 41)]  # 0.25 … 10 s
    frame = ukdyn.sweep("control_uncertain_duffing", random={"m": "uniform(1,1.5)"}, n=args.n,
                        seed=1, lhs=True, at=times, outputs=["error.track", "error_bound.track"],
                        workers=args.workers)
    err = np.abs(np.stack([frame[f"error.track@{t:g}"] for t in times], axis=1))
    bound = np.stack([frame[f"error_bound.track@{t:g}"] for t in times], axis=1)
    late = np.array(times) >= 5
    worst = err[:, late].max(axis=1)
    print(f"{len(frame)} plants, m in [{frame['m'].min():.4f}, {frame['m'].max():.4f}]: "
          f"{int(frame['ok'].sum())} ok ({sorted(set(frame['status']))})")
    print(f"largest |error| over t >= 5 s: {worst.max():.3e} (median {np.median(worst):.3e}); "
          f"computed bound at those times: {bound[:, late].min():.3e} … {bound[:, late].max():.3e}")
    above = int((err > bound).sum())
    print(f"samples with |error| above the bound at the same time: {above} of {err.size}")
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6.5, 4))
    order = np.argsort(frame["m"].to_numpy())
    m = frame["m"].to_numpy()[order]
    ax.semilogy(m, worst[order], ".", ms=3, label="largest |error|, t ≥ 5 s")
    ax.semilogy(m, bound[:, late].max(axis=1)[order], "-", lw=0.8, color="C3",
                label="robust law's bound")
    ax.set_xlabel("plant mass m (the controller assumes 1.2)")
    ax.set_ylabel("tracking error")
    ax.legend()
    ax.set_title(f"robust tracking over {len(frame)} plants")
    fig.tight_layout()
    out = pathlib.Path(args.o) / "uncertain_duffing.png"
    fig.savefig(out, dpi=110)
    print(f"written {out}")


if __name__ == "__main__":
    main()
