# SPDX-License-Identifier: BSD-3-Clause
"""The joint reactions figure of a multibody run (``joint_reactions``; part of ukdyn/plotting.py,
which calls it and lends it its style helpers as `kit`, so that this file imports nothing of
ukdyn either: the command runs both as scripts from one directory).

The data are the run's own columns (docs/model-format.md, "Initial state, outputs, reports";
``mb::report_csv_columns`` computes them, the viewer draws the same ones), never physics redone
here:

* ``reaction.<j>.fx, fy (, fz)`` and ``.tz`` (``.tx, ty, tz`` spatial): the ideal reaction of
  joint j on its child, world frame, reduced to the joint point (N, N·m);
* ``reaction.<j>.friction_fx …``: the joint friction's (non-ideal) part, when it has friction;
* ``reaction.<j>.torque``: a gear's multiplier, the torque along its first joint's angle;
* ``drive.<j>``: a driven joint's effort (a torque for a revolute joint, N·m; a force for a
  prismatic one, N).

Up to :data:`MAX_JOINT_ROWS` joints: a row per joint, its force components on the left and its
torque components on the right, ideal solid and non-ideal dashed in the same colour. More
joints: one row of magnitudes |f| and |τ|, one line per joint (and a row of the friction's
magnitudes). Drive efforts get a row of their own, across both columns.
"""

import numpy as np

#: a torque no larger than this fraction of the largest force's size (N, times 1 m) is taken as
#: zero, the roundoff of a joint that transmits none (a planar revolute joint's tz): not drawn
ZERO_TORQUE = 1e-9

#: the most joints drawn a row each (components); more are drawn as magnitudes, a line each (a
#: panel costs about 30 ms to lay out and draw: a slider-crank's four joints in a row each made
#: its joint_reactions figure the slowest of its plots)
MAX_JOINT_ROWS = 3

_FORCES = ("fx", "fy", "fz")
_TORQUES = ("tx", "ty", "tz")


def joints(table):
    """The joints of a multibody run, in column order: [(name, columns)] where columns maps
    ``fx`` … ``tz``, ``friction_fx`` … ``friction_tz``, ``torque`` (a gear) and ``drive`` to
    the column names the run has."""
    out = {}
    for h in table.names:
        if h.startswith("reaction."):
            joint, _, part = h[len("reaction."):].rpartition(".")
            known = _FORCES + _TORQUES + ("torque",)
            if joint and (part in known or part.replace("friction_", "", 1) in known):
                out.setdefault(joint, {})[part] = h
    for h in table.names:
        if h.startswith("drive.") and h[len("drive."):] in out:
            out[h[len("drive."):]]["drive"] = h
        elif h.startswith("drive."):  # a driven joint whose reaction is all drive
            out.setdefault(h[len("drive."):], {})["drive"] = h
    return list(out.items())


def _parts(columns, names):
    """(ideal, friction) column pairs of the components `names` the joint has."""
    return [(c, columns[c], columns.get("friction_" + c)) for c in names if c in columns]


def _draw_components(kit, ax, table, joint, parts):
    t = table["t"]
    for i, (c, ideal, friction) in enumerate(parts):
        colour = kit.line_style(i)["color"]
        ax.plot(t, table[ideal], color=colour, label=c, gid=ideal)
        if friction is not None and np.any(np.nan_to_num(table[friction])):
            ax.plot(t, table[friction], "--", color=colour, label="friction " + c, gid=friction)


def _largest(table, cols):
    return max([float(np.nanmax(np.abs(table[c]), initial=0.0)) for c in cols], default=0.0)


def _torques(columns):
    return [h for k, h in columns.items() if k in _TORQUES or k == "torque"
            or k.replace("friction_", "", 1) in _TORQUES]


def _magnitude(table, cols):
    return np.sqrt(sum(np.asarray(table[c], dtype=float) ** 2 for c in cols))


def _legend(ax):
    """A legend inside the panel (two columns of panels leave no room beside them)."""
    if ax.get_legend_handles_labels()[0]:
        ax.legend(loc="best", fontsize="small", ncol=2, frameon=False, handlelength=1.5,
                  borderaxespad=0.2, columnspacing=0.8)


def joint_reactions_figure(table, meta, kit):
    """The joint reactions of a multibody run (see the module's text); None for a run without
    joints. `meta`: plotting.metadata's dict; `kit`: the plotting module (its line styles, the
    current style's sizes, the titles)."""
    found = joints(table)
    if not found:
        return None
    drives = [(j, c["drive"]) for j, c in found if "drive" in c]
    reacting = [(j, c) for j, c in found if set(c) - {"drive"}]
    few = len(reacting) <= MAX_JOINT_ROWS
    friction = any(k.startswith("friction_") for _, c in reacting for k in c)
    rows = (len(reacting) if few else (2 if friction else 1) if reacting else 0) + bool(drives)
    # torques at roundoff (every joint a planar revolute one): one column, of the forces
    forces = [h for _, c in reacting for k, h in c.items()
              if k != "drive" and h not in _torques(c)]
    floor = ZERO_TORQUE * max(1.0, _largest(table, forces))
    torqued = {j for j, c in reacting if _largest(table, _torques(c)) > floor}
    width = 2 if torqued else 1
    style = kit.current_style()
    plt = kit._plt()
    fig = plt.figure(figsize=(style["width"], style["row_height"] * rows + 0.3),
                     layout=kit._layout(), dpi=kit.DPI)
    grid = fig.add_gridspec(rows, width)
    first = None

    def panel(row, column, span=False):
        nonlocal first
        ax = fig.add_subplot(grid[row, :] if span else grid[row, min(column, width - 1)],
                             sharex=first)
        first = first or ax
        ax.grid(True, alpha=0.3)
        return ax

    # the model's units (N and N·m in SI units)
    force = kit._data.system_unit(meta, "force")
    torque = kit._data.torque_unit(meta)
    row = 0
    if few:
        for j, columns in reacting:
            left = panel(row, 0)
            _draw_components(kit, left, table, j, _parts(columns, _FORCES))
            left.set_ylabel("%s: force [%s]" % (j, force))
            if torqued:
                right = panel(row, 1)
                right.set_ylabel("%s: torque [%s]" % (j, torque))
                if j not in torqued:
                    right.text(0.5, 0.5, "no torque (at roundoff)", transform=right.transAxes,
                               ha="center", va="center", color="0.35")
                else:
                    _draw_components(kit, right, table, j, _parts(columns, _TORQUES))
                if j in torqued and "torque" in columns:  # a gear: its multiplier, a torque
                    right.plot(table["t"], table[columns["torque"]], color="k",
                               label="gear torque", gid=columns["torque"])
            row += 1
    elif reacting:
        for part, name in (("", "reaction"), ("friction_", "friction")):
            if part and not friction:
                continue
            left = panel(row, 0)
            right = panel(row, 1) if torqued else None
            for i, (j, columns) in enumerate(reacting):
                fs = [columns[part + c] for c in _FORCES if part + c in columns]
                ts = [columns[part + c] for c in _TORQUES if part + c in columns]
                if not part and "torque" in columns:
                    ts = [columns["torque"]]
                style_i = kit.line_style(i)
                if fs:
                    left.plot(table["t"], _magnitude(table, fs), label=j,
                              gid="|reaction.%s.%sf|" % (j, part), **style_i)
                if ts and right is not None:
                    right.plot(table["t"], _magnitude(table, ts), label=j,
                               gid="|reaction.%s.%st|" % (j, part), **style_i)
            left.set_ylabel("|%s force| [%s]" % (name, force))
            if right is not None:
                right.set_ylabel("|%s torque| [%s]" % (name, torque))
            row += 1
    if drives:
        ax = panel(row, 0, span=True)
        for i, (j, h) in enumerate(drives):
            ax.plot(table["t"], table[h], label=j, gid=h, **kit.line_style(i))
        ax.set_ylabel("drive effort\n[%s; %s prismatic]" % (torque, force))
    for ax in fig.axes:
        _legend(ax)
    for ax in fig.axes[-width if not drives else -1:]:
        ax.set_xlabel(kit._time_label(meta))
    for ax in fig.axes:
        if not ax.get_xlabel():
            ax.tick_params(labelbottom=False)
    title = "joint reactions on the child (world frame, at the joint)"
    if reacting and not torqued:
        title += "; no torque (at roundoff)"
    fig.suptitle(kit._title(title, meta))
    kit.untitled(fig.axes)
    kit.few_ticks(fig.axes)
    return fig
