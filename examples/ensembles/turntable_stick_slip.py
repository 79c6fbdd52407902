# SPDX-License-Identifier: BSD-3-Clause
"""The stick-slip boundary of a block on a turntable over (mu, Omega) (docs/ensembles.md).

A grid sweep of turntable_stick_slip.yaml: the block sticks when r0 Omega^2 <= mu g and slides
outwards otherwise. Each sample's radius at t = 2 s tells which; the script compares the
classification with the closed-form boundary Omega = sqrt(mu g / r0), prints the disagreements
(samples within a grid step of the boundary may fall either way only through the event
tolerance) and draws the map with the boundary over it (turntable_stick_slip.png).

    PYTHONPATH=build/python /usr/bin/python3 examples/ensembles/turntable_stick_slip.py [-n 21]
"""

import argparse
import math
import pathlib

import numpy as np

import ukdyn

HERE = pathlib.Path(__file__).resolve().parent


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("-n", type=int, default=21, help="grid points per axis")
    ap.add_argument("-o", default=".", help="output directory")
    ap.add_argument("--workers", type=int, default=None)
    args = ap.parse_args()
    g, r0 = 9.81, 0.2
    frame = ukdyn.sweep(HERE / "turntable_stick_slip.yaml",
                        grid={"mu": f"0.1:0.6:{args.n}", "Omega": f"1:8:{args.n}"},
                        outputs=["radius"], workers=args.workers)
    slid = frame["radius@end"] > r0 * (1 + 1e-6)
    theory = frame["Omega"] ** 2 * r0 > frame["mu"] * g
    wrong = frame[slid != theory]
    print(f"{len(frame)} samples ({int(frame['ok'].sum())} ok): {int(slid.sum())} slide, "
          f"{len(wrong)} disagree with Omega = sqrt(mu g / r0)")
    for _, row in wrong.iterrows():
        print(f"  mu = {row['mu']:.3f}, Omega = {row['Omega']:.3f}: r0 Omega^2 / (mu g) = "
              f"{row['Omega'] ** 2 * r0 / (row['mu'] * g):.6f}, radius {row['radius@end']:.6f}")
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    ds = ukdyn.to_dataset(frame)
    fig, ax = plt.subplots(figsize=(6, 4.5))
    (ds["radius@end"] / r0).plot(ax=ax, x="mu", y="Omega", cmap="viridis",
                                 cbar_kwargs={"label": "radius at t = 2 s / r0"})
    mu = np.linspace(0.1, 0.6, 200)
    ax.plot(mu, np.sqrt(mu * g / r0), "w--", label=r"$\Omega = \sqrt{\mu g / r_0}$")
    ax.legend(loc="lower right")
    ax.set_title("block on a turntable: sticks below, slides above")
    fig.tight_layout()
    out = pathlib.Path(args.o) / "turntable_stick_slip.png"
    fig.savefig(out, dpi=110)
    print(f"written {out}")


if __name__ == "__main__":
    main()
