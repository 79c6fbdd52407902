#!/usr/bin/python3
"""Plots of a ukdyn trajectory.csv (embedded in the ukdyn binary, which runs it).

usage: plot_trajectory.py TRAJECTORY.csv OUTPUT_DIR

Writes coordinates.png, constraint_forces.png (ideal and non-ideal parts), violation.png,
energy.png (energy and the work of the non-ideal forces) and, when the model has output
expressions (the columns after work_nonideal), outputs.png. Exits 3 when matplotlib is missing.
"""
import csv
import os
import sys

try:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError:
    sys.stderr.write("plot_trajectory.py: matplotlib is not installed\n")
    sys.exit(3)


def read(path):
    """The columns of the CSV by name (in order) as lists of floats."""
    with open(path, newline="") as f:
        rows = csv.reader(f)
        header = next(rows)
        data = [[] for _ in header]
        for row in rows:
            for j, value in enumerate(row):
                data[j].append(float(value))
    return header, data


def figure(title, rows=1):
    fig, axes = plt.subplots(rows, 1, figsize=(8, 3.2 * rows + 0.6), sharex=True, squeeze=False)
    fig.suptitle(title)
    return fig, [a[0] for a in axes]


def finish(fig, axes, path):
    axes[-1].set_xlabel("t [s]")
    for ax in axes:
        ax.grid(True, alpha=0.3)
        if ax.get_legend_handles_labels()[0]:
            ax.legend(loc="best", fontsize="small")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main():
    if len(sys.argv) != 3:
        sys.stderr.write(__doc__)
        return 2
    header, data = read(sys.argv[1])
    out = sys.argv[2]
    col = {name: data[j] for j, name in enumerate(header)}
    t = col["t"]
    # the coordinates are the columns between t and the first velocity column
    coords = []
    for name in header[1:]:
        if name.endswith("_dot") and name[: -len("_dot")] in coords:
            break
        coords.append(name)
    name = os.path.basename(os.path.dirname(os.path.abspath(sys.argv[1])))

    # coordinates
    fig, axes = figure("coordinates: " + name)
    for c in coords:
        axes[0].plot(t, col[c], label=c)
    axes[0].set_ylabel("q")
    finish(fig, axes, os.path.join(out, "coordinates.png"))

    # constraint forces: ideal and non-ideal parts
    fig, axes = figure("constraint forces: " + name, rows=2)
    for c in coords:
        axes[0].plot(t, col["Qc_ideal." + c], label=c)
        axes[1].plot(t, col["Qc_nonideal." + c], label=c)
    axes[0].set_ylabel("ideal Qc")
    axes[1].set_ylabel("non-ideal Qc")
    finish(fig, axes, os.path.join(out, "constraint_forces.png"))

    # constraint violation, on a log scale (zeros drawn at the floor)
    floor = 1e-18
    fig, axes = figure("constraint violation: " + name)
    for h in header:
        if h.startswith("violation.") or h.startswith("violation_velocity."):
            label = h.replace("violation_velocity.", "velocity: ").replace("violation.", "")
            axes[0].semilogy(t, [max(abs(v), floor) for v in col[h]], label=label)
    axes[0].set_ylabel("|violation|")
    finish(fig, axes, os.path.join(out, "violation.png"))

    # energy and the work of the non-ideal forces: E - W stays constant
    fig, axes = figure("energy: " + name, rows=2)
    for h in ("kinetic_energy", "potential_energy", "energy", "work_nonideal"):
        axes[0].plot(t, col[h], label=h.replace("_", " "))
    balance = [e - w - (col["energy"][0] - col["work_nonideal"][0])
               for e, w in zip(col["energy"], col["work_nonideal"])]
    axes[0].set_ylabel("J")
    axes[1].plot(t, balance, color="k", label="E(t) - E(0) - W(t)")
    axes[1].set_ylabel("energy balance [J]")
    finish(fig, axes, os.path.join(out, "energy.png"))

    # the model's output expressions
    extra = header[header.index("work_nonideal") + 1:]
    if extra:
        fig, axes = figure("output expressions: " + name)
        for h in extra:
            axes[0].plot(t, col[h], label=h)
        finish(fig, axes, os.path.join(out, "outputs.png"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
