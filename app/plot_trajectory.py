#!/usr/bin/python3
"""Plots of a ukdyn trajectory.csv (embedded in the ukdyn binary, which runs it).

usage: plot_trajectory.py TRAJECTORY.csv OUTPUT_DIR

Writes coordinates.png, constraint_forces.png (ideal and non-ideal parts), violation.png,
energy.png (the energy balance: E(t) - E(0) with each work channel, and the residual), and when the run
has them: control.png (tracking error per requirement with the robust bound, control force per
coordinate, control power and cumulative effort), bodies.png (the paths of the bodies' centres
of mass, multibody models) and outputs.png (the model's output expressions). Each file is written
under a temporary name and renamed when complete. Exits 3 when matplotlib is missing.
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

# the work channels of the energy balance (io/trajectory_files.hpp), in CSV order
WORKS = ("work_nonideal", "work_ideal", "work_drive", "work_external", "work_control")


# the most rows a plot reads: a longer run (ukdyn run streams any number of rows to the CSV) is
# thinned to every k-th row and the last, so that the plots' memory does not grow with the run
MAX_ROWS = 200000


def read(path):
    """The columns of the CSV by name (in order) as lists of floats (at most about MAX_ROWS rows:
    every k-th one and the last)."""
    with open(path, newline="") as f:
        total = sum(1 for _ in f) - 1
    stride = max(1, -(-total // MAX_ROWS))
    with open(path, newline="") as f:
        rows = csv.reader(f)
        header = next(rows)
        data = [[] for _ in header]
        for i, row in enumerate(rows):
            if i % stride and i != total - 1:
                continue
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
    save(fig, path)


def save(fig, path):
    """Writes the figure whole or not at all: a hidden temporary beside path, then renamed."""
    directory, name = os.path.split(path)
    temporary = os.path.join(directory, ".%s.tmp-%d" % (name, os.getpid()))
    try:
        fig.savefig(temporary, dpi=110, format="png")
        os.replace(temporary, path)
    finally:
        plt.close(fig)
        if os.path.exists(temporary):
            os.remove(temporary)


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

    # the energy balance: E(t) - E(0) and each work channel, then the residual
    # E(t) - E(0) - (sum of the works), which the run's certificate bounds
    controlled = "control_work" in col
    fig, axes = figure("energy balance: " + name, rows=2)
    E0 = col["energy"][0]
    axes[0].plot(t, [e - E0 for e in col["energy"]], color="k", lw=1.6, label="E(t) - E(0)")
    # the channels that carry more than the drift (1e-9 of the energy exchanged)
    scale = max([abs(e - E0) for e in col["energy"]] + [abs(v) for h in WORKS for v in col[h]])
    for h in WORKS:
        if any(abs(v) > 1e-9 * scale for v in col[h]):
            axes[0].plot(t, col[h], label=h.replace("_", " "))
    axes[0].set_ylabel("J")
    axes[1].plot(t, col["energy_balance_residual"], color="k",
                 label="E(t) - E(0) - sum of the works")
    axes[1].set_ylabel("balance residual [J]")
    finish(fig, axes, os.path.join(out, "energy.png"))

    # the control: tracking errors (with the robust bound), forces, power and effort
    if controlled:
        fig, axes = figure("control: " + name, rows=3)
        for h in header:
            if h.startswith("error."):
                line = axes[0].plot(t, col[h], label=h[len("error."):])[0]
                bound = "error_bound." + h[len("error."):]
                if bound in col:
                    axes[0].plot(t, col[bound], "--", color=line.get_color(), lw=0.8)
                    axes[0].plot(t, [-b for b in col[bound]], "--", color=line.get_color(), lw=0.8)
        axes[0].set_ylabel("tracking error")
        for c in coords:
            axes[1].plot(t, col["Qc_control." + c], label=c)
        axes[1].set_ylabel("control force Qc")
        axes[2].plot(t, col["control_power"], label="power")
        axes[2].plot(t, col["control_effort"], label="effort: integral of Qc^T Qc")
        axes[2].plot(t, col["control_work_abs"], label="integral of |power|")
        axes[2].set_ylabel("power, effort")
        finish(fig, axes, os.path.join(out, "control.png"))

    # the bodies of a multibody model: paths of their centres of mass in the x-y plane
    bodies = [h[: -len(".qw")] for h in header if h.endswith(".qw")]
    if bodies:
        fig, ax = plt.subplots(figsize=(6.5, 6.5))
        fig.suptitle("bodies (centre of mass paths, x-y): " + name)
        for b in bodies:
            line = ax.plot(col[b + ".x"], col[b + ".y"], label=b, lw=0.9)[0]
            ax.plot(col[b + ".x"][0], col[b + ".y"][0], "o", color=line.get_color())
        ax.set_aspect("equal", "datalim")
        ax.grid(True, alpha=0.3)
        ax.legend(loc="best", fontsize="small")
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
        fig.tight_layout()
        save(fig, os.path.join(out, "bodies.png"))

    # the model's output expressions (named by identifiers: no '.', not a control column)
    control_scalars = {"control_power", "control_effort", "control_work_abs", "control_work"}
    extra = [h for h in header[header.index("energy_balance_residual") + 1:]
             if "." not in h and h not in control_scalars]
    if extra:
        fig, axes = figure("output expressions: " + name)
        for h in extra:
            axes[0].plot(t, col[h], label=h)
        finish(fig, axes, os.path.join(out, "outputs.png"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
