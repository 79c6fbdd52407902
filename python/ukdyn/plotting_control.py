# SPDX-License-Identifier: BSD-3-Clause
"""The control figure of a controlled run (``control``; part of ukdyn/plotting.py, which calls it
and lends it its style helpers as `kit`, so that this file imports nothing of ukdyn: the command
runs both as scripts from one directory). Its columns: ``error.<row>`` (and ``error_bound.<row>``
under a robust law), ``Qc_control.<coordinate>``, ``control_power``, ``control_work``,
``control_work_abs`` and ``control_effort`` (control/control.hpp, control_csv_columns)."""

import numpy as np


def control_figure(table, meta, kit):
    """The control: tracking error per requirement row (with the robust bound), desired against
    actual for the rows whose desired value the run has (an output expression
    ``desired_<row>``, which the model reader derives from a holonomic requirement written as
    actual − desired(t), or ``actual_<row>``, the row's ``.`` written ``_``: actual = desired +
    error), the control force per coordinate (one panel per unit), the power, the
    work (∫P dt, ∫|P| dt) and the effort ∫Qcᵀ Qc dt, each on its own axis. None for a run
    without control. `meta`: plotting.metadata's dict; `kit`: the plotting module."""
    if "control_power" not in table:
        return None
    coords = meta["coordinates"]
    rows = [h[len("error."):] for h in table.names if h.startswith("error.")]
    desired = [(r, d) for r, d in ((r, _desired(table, r)) for r in rows) if d is not None]
    actuated = [c for c in coords
                if "Qc_control." + c in table and kit._nonzero(table["Qc_control." + c])]
    force_groups = kit._groups(meta, actuated,
                               lambda c: kit.force_unit(kit.coordinate_unit(meta, c), meta))
    panels = (1 if rows else 0) + (1 if desired else 0) + len(force_groups) + 3
    height = 2.2 * kit.current_style()["row_height"] / 2.6
    fig, axes = kit._figure("control", meta, panels, height=height)
    t = table["t"]
    k = 0
    if rows:
        ax = axes[k]
        k += 1
        for i, r in enumerate(rows):
            style = kit.line_style(i)
            ax.plot(t, table["error." + r], label=r, **style)
            if "error_bound." + r in table:
                bound = table["error_bound." + r]
                ax.plot(t, bound, ":", color=style["color"], lw=0.8,
                        label="±bound " + r if i == 0 else "_")
                ax.plot(t, -bound, ":", color=style["color"], lw=0.8, label="_")
        ax.set_ylabel("tracking error")
    if desired:
        ax = axes[k]
        k += 1
        for i, (r, d) in enumerate(desired):
            colour = kit.line_style(i)["color"]
            ax.plot(t, d + table["error." + r], "-", color=colour, label=r + " actual")
            ax.plot(t, d, "--", color=colour, label=r + " desired")
        ax.set_ylabel("requirement\n(desired, actual)")
    for unit, members in force_groups:
        ax = axes[k]
        k += 1
        for i, c in enumerate(members):
            ax.plot(t, table["Qc_control." + c], label=c, **kit.line_style(i))
        ax.set_ylabel(kit._label("control force", unit))
    axes[k].plot(t, table["control_power"], color="k", label="P = Qcᵀ q̇")
    axes[k].set_ylabel(kit._label("power", kit._data.system_unit(meta, "power")))
    axes[k + 1].plot(t, table["control_work"], label="∫ P dt", **kit.line_style(0))
    axes[k + 1].plot(t, table["control_work_abs"], label="∫ |P| dt", **kit.line_style(1))
    axes[k + 1].set_ylabel(kit._label("work", kit._data.system_unit(meta, "energy")))
    fu = kit._common(kit.force_unit(kit.coordinate_unit(meta, c), meta) for c in actuated)
    axes[k + 2].plot(t, table["control_effort"], color="k", label="∫ Qcᵀ Qc dt")
    # (the effort's unit: the force's squared times the time's; (g·mm/ms²)²·ms in g, mm, ms)
    time = kit._data.system_unit(meta, "time")
    effort = {"N": "N²·s", "N·m": "N²·m²·s"}.get(fu) if time == "s" else None
    effort = effort or ("(%s)²·%s" % (fu, time) if fu else "")
    axes[k + 2].set_ylabel(kit._label("effort", effort))
    kit._finish(axes, meta)
    return fig


def _desired(table, row):
    """The desired value of requirement row `row` (its error φ written as actual − desired):
    the column ``desired.<row>``, or the output expression ``desired_<row>`` (``.`` written
    ``_``), or actual − error from an output expression ``actual_<row>``; None when the run has
    none of them."""
    spelled = row.replace(".", "_")
    for name in ("desired." + row, "desired_" + spelled):
        if name in table:
            return np.asarray(table[name], dtype=float)
    if "actual_" + spelled in table:
        return np.asarray(table["actual_" + spelled], dtype=float) - table["error." + row]
    return None
