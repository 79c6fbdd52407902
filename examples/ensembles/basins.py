# SPDX-License-Identifier: BSD-3-Clause
"""Basins of attraction of a damped pendulum under a constant torque (docs/ensembles.md).

A grid sweep of driven_pendulum.yaml over the initial angle and rate: each sample ends either at
rest (omega -> 0, the angle asin(tau / (m g L))) or turning at about tau / (c L^2). The picture
(basins.png) colours each initial state by its rate of turn at t_end.

    PYTHONPATH=build/python /usr/bin/python3 examples/ensembles/basins.py [-n 41]
"""

import argparse
import math
import pathlib

import ukdyn

HERE = pathlib.Path(__file__).resolve().parent


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("-n", type=int, default=41, help="grid points per axis")
    ap.add_argument("-o", default=".", help="output directory")
    ap.add_argument("--workers", type=int, default=None)
    ap.add_argument("--scheduler", default=None,
                    help="a Dask scheduler's address (tcp://host:8786): run there")
    args = ap.parse_args()
    client = None
    if args.scheduler:
        from distributed import Client
        client = Client(args.scheduler)
    frame = ukdyn.sweep(HERE / "driven_pendulum.yaml",
                        grid={"omega0": f"-8:8:{args.n}", "theta0": f"{-math.pi}:{math.pi}:{args.n}"},
                        outputs=["omega"], workers=args.workers, client=client)
    running = frame["omega@end"].abs() > 0.5 * 5 / 0.5
    print(f"{len(frame)} samples ({int(frame['ok'].sum())} ok, statuses "
          f"{sorted(set(frame['status']))}): {int(running.sum())} end turning, "
          f"{int((~running).sum())} at rest; rates at the end: "
          f"{frame['omega@end'].min():.3f} … {frame['omega@end'].max():.3f} rad/s")
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    ds = ukdyn.to_dataset(frame)
    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    ds["omega@end"].plot(ax=ax, x="theta0", y="omega0", cmap="coolwarm",
                         cbar_kwargs={"label": "rate of turn at t = 15 s (rad/s)"})
    ax.set_title("damped pendulum, constant torque: at rest (pale) or turning (red)")
    fig.tight_layout()
    out = pathlib.Path(args.o) / "basins.png"
    fig.savefig(out, dpi=110)
    print(f"written {out}")


if __name__ == "__main__":
    main()
