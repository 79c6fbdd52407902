#!/usr/bin/python3
# SPDX-License-Identifier: BSD-3-Clause
"""The plots of a ukdyn run: the one plotting implementation of the ``ukdyn`` command and of
the Python module.

The command embeds this file and runs it as a script on the run's directory::

    plotting.py [--wait] TRAJECTORY.csv OUTPUT_DIR [FORMATS [STYLE]]

(``FORMATS``: ``png``, ``pdf``, ``svg`` or a comma-separated list of them; ``png`` by default;
``STYLE``: ``screen``, the default, or ``paper`` — see :data:`STYLES`).
It reads ``summary.json`` beside the CSV for the model's name and the coordinates' units, and
writes, for each format, ``coordinates``, ``constraint_forces`` and ``violation`` (only when the
model has constraints), ``energy``, and when the run has them ``contacts`` (unilateral contacts:
normal forces and gaps, impacts marked), ``control``, ``bodies`` and ``joint_reactions``
(multibody models) and ``outputs`` (the model's output expressions). Each file is written under
a temporary name and renamed when complete. Exit codes: 0 written, 2 bad arguments, 3 no
matplotlib.

The parts, which the command writes beside this script: plotting_data.py reads the run's
columns and knows their units, plotting_files.py writes the files, plotting_control.py and
plotting_reactions.py draw the control and joint reactions figures; this file draws the others
and re-exports what is public in the parts.

The Python module uses the same functions through :class:`ukdyn.Result` (``Result.figures()``,
``Result.save_plots()``, ``Result.plot_*``). Everything works from column names and a small
metadata dict (:func:`metadata`), so that a CSV with its summary and a Result give the same
figures:

* ``model``: the model's name (in every title);
* ``coordinates``: the coordinate names, in order;
* ``contact_events``: the run's contact events (summary.json's list: ``t``, ``contact``,
  ``kind``, …), whose impacts the contacts figure marks;
* ``units``: coordinate name → its unit (``m``, ``rad``, ``1`` for a quaternion component, or
  what the model file's ``units:`` declares; ``""`` or absent: not known, and then no unit is
  drawn, never a guessed one); output expressions may have theirs too; ``t`` the time's;
* ``unit_system``: the model's units (summary.json's ``unit_system``: ``length``, ``mass``,
  ``time``, ``velocity``, ``force``, ``energy``, ``power``); SI when absent.

Units of derived quantities, per the model's time unit ``T`` (``s`` in SI units): velocities
``u/T``, accelerations ``u/T²``; generalized forces: the force (``N`` in SI units) for a
coordinate in the model's length unit, the torque (``N·m``) for one in ``rad`` (or a quaternion
component, whose conjugate force is an energy), none otherwise; energies and works the energy's
(``J``); power the power's (``W``). N, J and W only in SI units: in g, mm and ms an energy is
``g·mm²/ms²``.
Multipliers, constraint violations and tracking errors carry no unit (it depends on how the
constraint is written); output expressions have the one ``units:`` gives them, if any.

Needs only NumPy and matplotlib (no import of the rest of ukdyn), so that the command can run it
with /usr/bin/python3.
"""

from __future__ import annotations

import os
import sys

try:
    import numpy as np
except ImportError:
    if __name__ != "__main__":
        raise
    # run as the command's script by a python without NumPy (which matplotlib needs too): the
    # command's one-line "no matplotlib" warning (exit 3, as below), not a traceback
    sys.stderr.write("plotting.py: NumPy is not installed\n")
    sys.exit(3)


def _module(name):
    """The part `name` of the plots (plotting_data, plotting_files, plotting_control,
    plotting_reactions): ukdyn's, or when this file runs as the command's script, the copy
    beside it (whatever sys.path says). Those that need figures or styles take this module as
    their `kit`, so that none imports another."""
    if __package__:
        import importlib
        return importlib.import_module("%s.%s" % (__package__, name))
    module = sys.modules.get(name)
    if module is None:
        import importlib.util
        path = os.path.join(os.path.dirname(os.path.abspath(__file__)), name + ".py")
        spec = importlib.util.spec_from_file_location(name, path)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        sys.modules[name] = module
    return module


# the run's columns and their units (plotting_data.py) and the files (plotting_files.py)
_data = _module("plotting_data")
_files = _module("plotting_files")
WORKS, CONTROL_SCALARS, MAX_ROWS = _data.WORKS, _data.CONTROL_SCALARS, _data.MAX_ROWS
Table, read_csv, read_summary, metadata = _data.Table, _data.read_csv, _data.read_summary, \
    _data.metadata
coordinate_unit, force_unit, column_unit = _data.coordinate_unit, _data.force_unit, \
    _data.column_unit
_label, _kind, _is_quaternion, _groups = _data._label, _data._kind, _data._is_quaternion, \
    _data._groups
FORMATS, PNG_COMPRESS_LEVEL = _files.FORMATS, _files.PNG_COMPRESS_LEVEL
parse_formats, write_replacing = _files.parse_formats, _files.write_replacing

__all__ = [
    "FORMATS", "Table", "metadata", "read_csv", "read_summary", "coordinate_unit",
    "column_unit", "force_unit",
    "line_style", "coordinates_figure", "forces_figure", "violation_figure", "energy_figure",
    "control_figure", "bodies_figure", "joint_reactions_figure", "outputs_figure",
    "contacts_figure", "figures", "save",
    "write_figures",
    "parse_formats", "draw_columns", "draw_forces", "draw_violation", "draw_energy", "main",
    "STYLES", "style", "current_style", "power_label", "DPI",
]

#: the figure styles (``--plot-style``, ``style=``): ``screen`` (9 in wide, matplotlib's fonts,
#: legends beside the panels) and ``paper``, a journal's single column: 3.5 in wide, 8 pt text,
#: thin lines, legends inside the panels; pick a vector format with it (``pdf``, ``svg``: the
#: command writes PDF for ``paper`` unless ``--plot-format`` says otherwise)
STYLES = {
    "screen": {"width": 9.0, "row_height": 2.6, "legend_outside": True, "rc": {}},
    "paper": {"width": 3.5, "row_height": 1.55, "legend_outside": False,
              "rc": {"font.size": 8, "axes.titlesize": 8, "axes.labelsize": 8,
                     "xtick.labelsize": 7, "ytick.labelsize": 7, "legend.fontsize": 6,
                     "figure.titlesize": 8, "lines.linewidth": 0.8, "lines.markersize": 2.5,
                     "axes.linewidth": 0.5, "grid.linewidth": 0.4, "pdf.fonttype": 42,
                     "svg.fonttype": "none"}},
}
_style = STYLES["screen"]


class style:
    """``with style("paper"): ...`` draws the figures made inside in that style (:data:`STYLES`);
    raises ValueError naming the styles for an unknown one."""

    def __init__(self, name):
        if name not in STYLES:
            raise ValueError("unknown plot style '%s': the styles are %s"
                             % (name, ", ".join(STYLES)))
        self.name = name

    def __enter__(self):
        global _style
        import matplotlib
        self._saved = _style
        self._rc = matplotlib.rc_context(STYLES[self.name]["rc"])
        self._rc.__enter__()
        _style = STYLES[self.name]
        return self

    def __exit__(self, *exc):
        global _style
        _style = self._saved
        return self._rc.__exit__(*exc)


#: violations below this are not drawn on the log axis (exact zeros, and the roundoff floor
#: under it, would fill the axis with a comb)
VIOLATION_FLOOR = 1e-300

#: the figures' resolution (dots per inch), given when they are made and when they are saved: text
#: is laid out once for both (matplotlib caches the text metrics per dpi), not again at savefig
DPI = 110

_COLOURS = ("#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2",
            "#7f7f7f", "#bcbd22", "#17becf")
_DASHES = ("-", "--", ":", "-.")
_MARKERS = (None, "o", "s", "^", "v", "D", "x", "+")


# --- style -----------------------------------------------------------------------------------
def line_style(i):
    """The style of the i-th line of a panel: 10 colours × 4 dash patterns × 8 marker choices
    (none, then seven shapes), so that the first 320 lines of a panel all differ."""
    style = {"color": _COLOURS[i % len(_COLOURS)],
             "linestyle": _DASHES[(i // len(_COLOURS)) % len(_DASHES)]}
    marker = _MARKERS[(i // (len(_COLOURS) * len(_DASHES))) % len(_MARKERS)]
    if marker:
        style.update(marker=marker, markevery=0.1, markersize=4)
    return style


def _plt():
    import matplotlib.pyplot as plt
    return plt


def _layout():
    """The layout engine of a figure of the plots: plotting_layout.py's FixedLayout (one
    measurement of the labels, not matplotlib's constrained layout)."""
    return _module("plotting_layout").FixedLayout()


def _figure(title, meta, rows, height=None, width=None):
    """A figure of `rows` panels over a shared time axis, titled with the model's name, in the
    current style's size unless `height` (per panel) and `width` are given."""
    plt = _plt()
    width = width or _style["width"]
    height = height or _style["row_height"]
    fig, axes = plt.subplots(rows, 1, figsize=(width, height * rows + 0.8 * height / 2.6),
                             sharex=True, squeeze=False, layout=_layout(), dpi=DPI)
    fig.suptitle(_title(title, meta))
    axes = [a[0] for a in axes]
    untitled(axes)
    few_ticks(axes)
    return fig, axes


#: the most intervals between the major ticks of a linear axis (matplotlib's default, "auto",
#: fits as many as the axis has room for: eight or nine on a panel's y axis). Each tick is five
#: objects made, laid out and drawn: with five, the figures take about 7 % fewer instructions,
#: and need one layout round, not two (bench/RESULTS.md, "Plotting time ..., fourth step")
TICK_BINS = 5


def few_ticks(axes):
    """Gives each linear axis of `axes` matplotlib's own tick choice (AutoLocator: steps of 1, 2,
    2.5 and 5 times a power of ten) with at most :data:`TICK_BINS` intervals; a log axis, or one
    with a locator of its own, keeps it."""
    from matplotlib.ticker import AutoLocator, MaxNLocator
    for ax in axes:
        for axis in (ax.xaxis, ax.yaxis):
            if type(axis.get_major_locator()) is AutoLocator:
                axis.set_major_locator(MaxNLocator(TICK_BINS, steps=[1, 2, 2.5, 5, 10]))


def untitled(axes):
    """Marks panels that have no title of their own as such: matplotlib then no longer looks for
    a place for their (empty) titles, which it did three times in every layout and every draw,
    each time laying out the panel's x axis anew when its tick labels are hidden (an upper panel
    over a shared time axis): a third of the CPU of a multi-panel figure. The picture is the
    same: an empty title stays where it is, at the panel's top."""
    for ax in axes:
        ax.set_title("", y=1.0)  # (an explicit y: no automatic title position)


def _title(title, meta):
    return "%s: %s" % (meta["model"], title) if meta.get("model") else title


#: the gap between a panel and its legend beside it (points; about 1 % of a screen panel's width)
LEGEND_GAP = 5.0


def _legend(ax, title=None):
    """A legend beside the panel (outside the data), in columns when it is long."""
    handles, labels = ax.get_legend_handles_labels()
    if handles and not _style["legend_outside"]:
        ax.legend(handles, labels, loc="best", ncol=1 + len(handles) // 6, title=title,
                  frameon=False, handlelength=1.5, borderaxespad=0.2, columnspacing=0.8)
    elif handles:
        # LEGEND_GAP points right of the panel (not a fraction of its width, which would move the
        # legend when the layout resizes the panel, after it was measured)
        from matplotlib.transforms import offset_copy
        beside = offset_copy(ax.transAxes, fig=ax.figure, x=LEGEND_GAP, y=0.0, units="points")
        ax.legend(handles, labels, loc="upper left", bbox_to_anchor=(1.0, 1.0),
                  bbox_transform=beside, fontsize="small", ncol=1 + len(handles) // 16,
                  title=title, title_fontsize="small", borderaxespad=0.0)


def _time_label(meta):
    """The time axis' label, in the model's time unit ("t [s]" in SI units)."""
    return _label("t", _data.system_unit(meta, "time"))


def _finish(axes, meta=None):
    axes[-1].set_xlabel(_time_label(meta))
    for ax in axes:
        ax.grid(True, alpha=0.3)
        _legend(ax)


# --- panels (also Result.plot_* on one Axes) ---------------------------------------------------
def draw_columns(ax, table, meta, columns, x="t", **kwargs):
    """Draws `columns` against column `x` on `ax`, one style per line; the y label names the
    unit when every column has the same known one (coordinates, their velocities and
    accelerations, generalized forces). Extra keyword arguments go to ``ax.plot``."""
    meta = metadata(table, meta)
    units = set()
    for i, name in enumerate(columns):
        style = {} if ("color" in kwargs or "c" in kwargs) else line_style(i)
        style.update(kwargs)
        ax.plot(table[x], table[name], label=name, **style)
        units.add(column_unit(meta, name))
    unit = units.pop() if len(units) == 1 else ""
    ax.set_xlabel(_label(x, column_unit(meta, x)))
    if unit:
        ax.set_ylabel("[%s]" % unit)
    ax.grid(True, alpha=0.3)
    _legend(ax)
    return ax


def draw_forces(ax, table, meta):
    """The ideal and non-ideal constraint forces per coordinate on one Axes (ideal solid,
    non-ideal dashed in the same colour, only when not zero); the y label names the unit when
    all coordinates have the same force unit, the line labels otherwise."""
    meta = metadata(table, meta)
    coords = meta["coordinates"]
    units = {force_unit(coordinate_unit(meta, c), meta) for c in coords}
    common = units.pop() if len(units) == 1 else None
    for i, c in enumerate(coords):
        unit = force_unit(coordinate_unit(meta, c), meta)
        suffix = "" if common is not None or not unit else " [%s]" % unit
        colour = line_style(i)["color"]
        ax.plot(table["t"], table["Qc_ideal." + c], color=colour,
                linestyle=_DASHES[(i // len(_COLOURS)) % 2 * 2], label="Qc_ideal." + c + suffix)
        if np.any(table["Qc_nonideal." + c]):
            ax.plot(table["t"], table["Qc_nonideal." + c], "--", color=colour,
                    label="Qc_nonideal." + c + suffix)
    ax.set_xlabel(_time_label(meta))
    ax.set_ylabel(_label("generalized constraint force", common or ""))
    ax.grid(True, alpha=0.3)
    _legend(ax)
    return ax


def _positive(values):
    """|values| with those below VIOLATION_FLOOR (exact zeros) masked out (NaN: not drawn)."""
    a = np.abs(np.asarray(values, dtype=float))
    return np.where(a > VIOLATION_FLOOR, a, np.nan)


def _violation_columns(table, prefix):
    return [(h[len(prefix):], h) for h in table.names if h.startswith(prefix)]


def running_max(values):
    """max(|v₀|, …, |v_k|) at each sample k (NaN samples skipped): the largest violation so far,
    a staircase that only rises, where the samples themselves jump over decades at each step."""
    a = np.abs(np.asarray(values, dtype=float))
    return np.fmax.accumulate(np.where(np.isnan(a), -np.inf, a)) if a.size else a


_SUPERSCRIPTS = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")


def power_label(value, pos=None):
    """A tick label of a log axis in plain text, ``10⁻⁶`` or ``2×10⁻⁶`` (Unicode superscripts:
    the look of matplotlib's default labels without its mathtext parser, which took a third of
    the time of the violation figure)."""
    if not value > 0 or not np.isfinite(value):
        return ""
    exponent = int(np.floor(np.log10(value) + 1e-9))
    mantissa = value / 10.0 ** exponent
    power = "10" + str(exponent).translate(_SUPERSCRIPTS)
    if abs(mantissa - round(mantissa)) > 1e-6 * mantissa:
        return "%.3g×%s" % (mantissa, power)
    return power if round(mantissa) == 1 else "%d×%s" % (round(mantissa), power)


def _log_ticks(axis, low, high):
    """Major ticks of a log axis at the decades (and at 2 and 5 times them when the data span
    less than two decades, so that a narrow axis has labels), labelled by power_label; no minor
    ticks (each of the dozens a log axis makes is an object laid out and drawn, for no label)."""
    from matplotlib.ticker import FuncFormatter, LogLocator, NullLocator
    narrow = np.isfinite(low) and high > 0 and high < 100.0 * low
    axis.set_major_locator(LogLocator(10.0, subs=(1.0, 2.0, 5.0) if narrow else (1.0,)))
    axis.set_major_formatter(FuncFormatter(power_label))
    axis.set_minor_locator(NullLocator())


def draw_violation(ax, table, meta, prefix="violation."):
    """The running maximum of |violation| per constraint (:func:`running_max`) on a log scale,
    one line each; while it is exactly zero it is not drawn (a short note on the panel says so)
    rather than put at an arbitrary floor. `prefix` ``violation_velocity.`` draws the
    velocity-level violations."""
    drawn = 0
    zeros = False
    low, high = np.inf, 0.0
    for i, (label, h) in enumerate(_violation_columns(table, prefix)):
        values = running_max(table[h])
        values = np.where(values > VIOLATION_FLOOR, values, np.nan)
        zeros = zeros or bool(np.any(np.isnan(values)))
        if np.all(np.isnan(values)):
            continue
        style = line_style(drawn)
        style.update(drawstyle="steps-post", markevery=0.1 if style.get("marker") else None)
        ax.plot(table["t"], values, label=label, **style)
        drawn += 1
        finite = values[np.isfinite(values)]
        low, high = min(low, float(finite.min())), max(high, float(finite.max()))
    ax.set_yscale("log")
    _log_ticks(ax.yaxis, low, high)
    what = "position" if prefix == "violation." else "velocity"
    ax.set_ylabel("max |%s violation|" % what)  # so far: the title says running maximum
    ax.set_xlabel(_time_label(meta))
    if zeros:
        ax.text(0.01, 0.02, "exactly zero where not drawn", transform=ax.transAxes,
                fontsize="x-small", color="0.35")
    ax.grid(True, alpha=0.3)
    _legend(ax)
    return ax


def draw_energy(ax, table, meta, residual=True):
    """E(t) − E(0) and each work channel that carries more than 1e-9 of the energy exchanged
    (J); with `residual`, the balance residual E(t) − E(0) − ΣW too (dashed)."""
    t = table["t"]
    E = table["energy"]
    dE = E - E[0] if len(E) else E
    ax.plot(t, dE, color="k", lw=1.6, label="E(t) − E(0)")
    works = [(h, label) for h, label in WORKS if h in table]
    scale = max([float(np.max(np.abs(dE), initial=0.0))] +
                [float(np.max(np.abs(table[h]), initial=0.0)) for h, _ in works])
    i = 0
    for h, label in works:
        if np.max(np.abs(table[h]), initial=0.0) > 1e-9 * scale:
            ax.plot(t, table[h], label=label, **line_style(i))
            i += 1
    if residual and "energy_balance_residual" in table:
        ax.plot(t, table["energy_balance_residual"], "--", color="0.4",
                label="residual E(t) − E(0) − ΣW")
    ax.set_xlabel(_time_label(meta))
    ax.set_ylabel(_label("energy", _data.system_unit(meta, "energy")))
    ax.grid(True, alpha=0.3)
    _legend(ax)
    return ax


# --- figures ---------------------------------------------------------------------------------
def coordinates_figure(table, meta=None):
    """The coordinates, one panel per unit (metres, radians, quaternion components, each unit
    the model declares, and the coordinates of unknown unit)."""
    meta = metadata(table, meta)
    coords = meta["coordinates"]
    groups = _groups(meta, coords, lambda c: (coordinate_unit(meta, c),
                                                _is_quaternion(table, meta, c)))
    fig, axes = _figure("coordinates", meta, len(groups))
    for ax, ((unit, quaternion), members) in zip(axes, groups):
        for i, c in enumerate(members):
            ax.plot(table["t"], table[c], label=c, **line_style(i))
        ax.set_ylabel(_label(_kind(unit, quaternion, meta), unit))
    _finish(axes, meta)
    return fig


def _nonzero(values):
    return bool(np.any(np.asarray(values) != 0))


def forces_figure(table, meta=None):
    """The constraint forces: the ideal part, one panel per force unit, and the non-ideal part
    (friction) likewise when it is not zero. None when the model has no constraint force."""
    meta = metadata(table, meta)
    coords = meta["coordinates"]
    panels = []
    for part, name in (("Qc_ideal.", "ideal constraint force"),
                       ("Qc_nonideal.", "non-ideal constraint force")):
        present = [c for c in coords if part + c in table]
        if not any(_nonzero(table[part + c]) for c in present):
            continue
        for unit, members in _groups(meta, present,
                                     lambda c: force_unit(coordinate_unit(meta, c), meta)):
            if part == "Qc_nonideal.":
                members = [c for c in members if _nonzero(table[part + c])]
                if not members:
                    continue
            panels.append((part, name, unit, members))
    if not panels:
        return None
    fig, axes = _figure("constraint forces (generalized)", meta, len(panels))
    for ax, (part, name, unit, members) in zip(axes, panels):
        for i, c in enumerate(members):
            ax.plot(table["t"], table[part + c], label=c, **line_style(i))
        ax.set_ylabel(_label(name, unit))
    _finish(axes, meta)
    return fig


def violation_figure(table, meta=None):
    """The constraint violations on a log scale: position level, then velocity level, each
    panel only when some violation is not exactly zero. None when there is nothing to draw
    (no constraint, or every violation exactly zero)."""
    meta = metadata(table, meta)
    panels = [p for p in ("violation.", "violation_velocity.")
              if any(np.any(np.abs(table[h]) > VIOLATION_FLOOR)
                     for _, h in _violation_columns(table, p))]
    if not panels:
        return None
    fig, axes = _figure("constraint violation (running maximum)", meta, len(panels))
    for ax, prefix in zip(axes, panels):
        draw_violation(ax, table, meta, prefix)
        ax.set_xlabel("")
    _finish(axes, meta)
    return fig


def energy_figure(table, meta=None):
    """The energy balance: E(t) − E(0) with each work channel, then the residual
    E(t) − E(0) − ΣW (the integration error that the run's certificate bounds)."""
    meta = metadata(table, meta)
    fig, axes = _figure("energy balance", meta, 2)
    draw_energy(axes[0], table, meta, residual=False)
    axes[0].set_xlabel("")
    axes[1].plot(table["t"], table["energy_balance_residual"], color="k",
                 label="E(t) − E(0) − ΣW\n(ΣW: every work channel)")
    axes[1].set_ylabel(_label("balance residual", _data.system_unit(meta, "energy")))
    _finish(axes, meta)
    return fig


def _common(units):
    units = set(units)
    return units.pop() if len(units) == 1 else ""


def control_figure(table, meta=None):
    """The control: tracking error per requirement row (with the robust bound), desired against
    actual, the control force per coordinate (one panel per unit), the power, the work and the
    effort (ukdyn/plotting_control.py). None for a run without control."""
    if "control_power" not in table:
        return None
    return _module("plotting_control").control_figure(table, metadata(table, meta),
                                                      sys.modules[__name__])


def _bodies(table):
    """The bodies of a multibody run (those with pose columns <b>.qw), each with whether it is
    planar (a <b>.theta coordinate)."""
    return [(h[: -len(".qw")], (h[: -len(".qw")] + ".theta") in table)
            for h in table.names if h.endswith(".qw")]


def bodies_figure(table, meta=None):
    """The paths of the bodies' centres of mass: planar models in the x–y plane, spatial models
    in three orthogonal views (x–y from above, x–z and y–z from the side); equal axes, the start
    of each path marked. None for a model without bodies."""
    bodies = _bodies(table)
    if not bodies:
        return None
    meta = metadata(table, meta)
    planar = all(p for _, p in bodies)
    views = [("x", "y")] if planar else [("x", "y"), ("x", "z"), ("y", "z")]
    plt = _plt()
    k = _style["width"] / 9.0  # the screen sizes below, scaled to the style's width
    if planar:
        fig, axes = plt.subplots(1, 1, figsize=(7.5 * k, 6.0 * k), squeeze=False,
                                 layout=_layout(), dpi=DPI)
    elif k < 1:  # a column: the three views one above the other
        fig, axes = plt.subplots(3, 1, figsize=(_style["width"], 3 * _style["width"]),
                                 squeeze=False, layout=_layout(), dpi=DPI)
        axes = axes.T
    else:
        fig, axes = plt.subplots(1, 3, figsize=(14.0, 5.0), squeeze=False, layout=_layout(),
                                 dpi=DPI)
    axes = list(axes[0])
    few_ticks(axes)
    fig.suptitle(_title("paths of the centres of mass", meta))
    for ax, (a, b) in zip(axes, views):
        for i, (body, _) in enumerate(bodies):
            style = line_style(i)
            x, y = table[body + "." + a], table[body + "." + b]
            ax.plot(x, y, label=body, lw=1.0, **style)
            ax.plot(x[:1], y[:1], "o", color=style["color"], ms=5, label="_")
        ax.plot([], [], "o", color="0.3", ms=5, label="start")
        ax.set_aspect("equal", "datalim")
        ax.set_xlabel(_label(a, coordinate_unit(meta, bodies[0][0] + "." + a)
                                or _data.system_unit(meta, "length")))
        ax.set_ylabel(_label(b, coordinate_unit(meta, bodies[0][0] + "." + b)
                                or _data.system_unit(meta, "length")))
        # (an explicit y, as untitled's: no search for the title's place, which laid out the
        # panel's y axis in every layout round and draw; the ticks are below, the title at 1.0)
        ax.set_title("%s–%s view" % (a, b), fontsize="medium", y=1.0)
        ax.grid(True, alpha=0.3)
    _legend(axes[-1])
    return fig


def current_style():
    """The style the figures are being drawn in (:data:`STYLES`' entry; ``screen`` outside a
    :class:`style` block)."""
    return _style


def joint_reactions_figure(table, meta=None):
    """Each joint's reaction force and torque on its child, ideal and non-ideal (friction), and
    the drives' efforts, against time (ukdyn/plotting_reactions.py). None for a model without
    joints."""
    return _module("plotting_reactions").joint_reactions_figure(table, metadata(table, meta),
                                                                sys.modules[__name__])


#: the kinds of contact event marked as impacts (an impact that closed a contact at rest too)
IMPACT_KINDS = ("impact", "rest")


def _contacts(table):
    """The unilateral contacts of a run: those with a gap column ``gap.<name>`` (model files
    write one per unilateral constraint) and a multiplier ``lambda.<name>``, in column order."""
    return [h[len("gap."):] for h in table.names
            if h.startswith("gap.") and "lambda." + h[len("gap."):] in table]


def _contact_force(table, c):
    """Contact c's force: its whole multiplier ``lambda_total.<c>`` (lambda + lambda_nonideal,
    with its share of the non-ideal forces: joint friction, friction at other contacts), or
    ``lambda.<c>`` where a table has no such column (older runs)."""
    total = "lambda_total." + c
    return table[total] if total in table else table["lambda." + c]


def _contact_friction(table, c):
    """Contact c's friction force in the world, the columns ``visual.contact.<c>.fx``, ``.fy``
    (and ``.fz``) that a run writes for Coulomb friction at a contact point: [(axis, values)], empty
    when it has none."""
    return [(a, table["visual.contact.%s.f%s" % (c, a)]) for a in "xyz"
            if "visual.contact.%s.f%s" % (c, a) in table]


def contacts_figure(table, meta=None):
    """The unilateral contacts (docs/contact.md): each contact's normal force (its whole
    multiplier ``lambda_total.<name>``, which pushes when positive: the force itself when the gap
    is a distance) and its gap ``gap.<name>`` over time, the impacts marked (the ``contact_events``
    of summary.json or of Result.stats: a dotted line across both panels and a triangle on the
    gap's zero at each); below them, when the run has Coulomb friction at a contact point, each
    such contact's friction force in the world (``visual.contact.<name>.fx``, ``.fy``, ``.fz``).
    The gap of a contacts: entry is a distance, in the length unit (summary.json's ``units``
    give ``gap.<name>`` its unit), and its force then in the force unit; a generalized model's
    gap has the unit its coordinates share (those without one counting in the length unit), or
    the one ``units:`` gives it; a gap without a unit (coordinates of different units) is drawn
    without one. None for a run without contacts."""
    contacts = _contacts(table)
    if not contacts:
        return None
    meta = metadata(table, meta)
    t = table["t"]
    impacts = {c: [] for c in contacts}
    for e in meta.get("contact_events") or []:
        if e.get("kind") in IMPACT_KINDS and e.get("contact") in impacts and e.get("t") is not None:
            impacts[e["contact"]].append(float(e["t"]))
    friction = {c: _contact_friction(table, c) for c in contacts}
    rubbing = [c for c in contacts if friction[c]]
    fig, axes = _figure("contacts: normal forces and gaps" +
                        (" and friction" if rubbing else ""), meta, 3 if rubbing else 2)
    for i, c in enumerate(contacts):
        style = line_style(i)
        axes[0].plot(t, _contact_force(table, c), label=c, gid="force." + c, **style)
        axes[1].plot(t, table["gap." + c], label=c, gid="gap." + c, **style)
        times = impacts[c]
        if times:
            axes[1].plot(times, np.zeros(len(times)), "v", color=style["color"], ms=5,
                         label="impacts (%s): %d" % (c, len(times)), gid="impacts." + c)
            for ax in axes:
                ax.vlines(times, 0, 1, transform=ax.get_xaxis_transform(), colors=style["color"],
                          linestyles=":", lw=0.7, label="_")
    k = 0
    for c in rubbing:
        for a, values in friction[c]:
            axes[2].plot(t, values, label="%s f%s" % (c, a), gid="friction.%s.f%s" % (c, a),
                         **line_style(k))
            k += 1
    # units: the gaps' (one unit when all agree), the forces' from it (force_unit)
    gap_units = {column_unit(meta, "gap." + c) for c in contacts}
    gap_unit = gap_units.pop() if len(gap_units) == 1 else ""
    force = force_unit(gap_unit, meta) if gap_unit else ""
    axes[0].set_ylabel(_label("normal force λ", force))
    axes[1].set_ylabel(_label("gap g", gap_unit))
    if rubbing:
        # (the friction columns are forces in the world, whatever the gaps' units)
        axes[2].set_ylabel(_label("friction force", _data.system_unit(meta, "force")))
    _finish(axes, meta)
    return fig


def outputs_figure(table, meta=None):
    """The model's output expressions (the columns after the standard and control ones named by
    identifiers), one panel per unit (the model file's ``units:`` may give them). None when the
    model has none."""
    meta = metadata(table, meta)
    if "energy_balance_residual" not in table:
        return None
    names = table.names
    extra = [h for h in names[names.index("energy_balance_residual") + 1:]
             if "." not in h and h not in CONTROL_SCALARS]
    if not extra:
        return None
    groups = _groups(meta, extra, lambda h: column_unit(meta, h))
    fig, axes = _figure("output expressions", meta, len(groups))
    for ax, (unit, members) in zip(axes, groups):
        for i, h in enumerate(members):
            ax.plot(table["t"], table[h], label=h, **line_style(i))
        ax.set_ylabel("value [%s]" % unit if unit else "value (no unit given)")
    _finish(axes, meta)
    return fig


#: the figures by file stem, in the order they are written
FIGURES = (("coordinates", coordinates_figure), ("constraint_forces", forces_figure),
           ("violation", violation_figure), ("contacts", contacts_figure),
           ("energy", energy_figure),
           ("control", control_figure), ("bodies", bodies_figure),
           ("joint_reactions", joint_reactions_figure), ("outputs", outputs_figure))

#: the CPU time a figure typically takes to make, lay out and write as PNG (seconds, one
#: process on the 2-core machine of bench/RESULTS.md, "Plotting time ..., fourth step"): about
#: 0.1 s and 0.08 s a panel. The forked processes of write_figures take the figures dearest
#: first, so that the last one taken is a cheap one and the two finish together (in FIGURES'
#: order the control figure, six panels, came sixth of seven: one process drew it alone at the
#: end)
COST = {"control": 0.55, "bodies": 0.35, "constraint_forces": 0.3, "coordinates": 0.3,
        "violation": 0.27, "joint_reactions": 0.25, "energy": 0.24, "contacts": 0.21,
        "outputs": 0.15}


def figures(table, meta=None, style_name="screen"):
    """Every figure that applies to the run, by file stem (coordinates, constraint_forces,
    violation, energy, control, bodies, joint_reactions, outputs): a dict of matplotlib
    Figures; a figure without data is left out, never drawn empty. `style_name`: one of
    :data:`STYLES`."""
    meta = metadata(table, meta)
    out = {}
    with style(style_name):
        for stem, make in FIGURES:
            fig = make(table, meta)
            if fig is not None:
                out[stem] = fig
    return out


# --- files (plotting_files.py) ---------------------------------------------------------------
def save(fig, path, fmt=None):
    """Writes the figure to `path` whole or not at all (write_replacing) at :data:`DPI`. The
    format is `fmt`, or `path`'s extension."""
    _files.save(fig, path, fmt, DPI)


def write_figures(table, meta, directory, formats=("png",), close=True, style_name="screen",
                  processes=1):
    """Writes every figure of :func:`figures` into `directory` as STEM.FORMAT for each format
    (``png``, ``pdf``, ``svg``) in the style `style_name` (:data:`STYLES`); returns the paths
    written. With `close`, the figures are closed afterwards. With `processes` > 1 (the
    command, whose process has no threads: os.fork is safe there), forked copies of this
    process, made after the imports, draw figures too, each taking the next one from a shared
    queue; a copy that fails raises RuntimeError here (plotting_files.py)."""
    return _files.write_figures(sys.modules[__name__], table, meta, directory, formats, close,
                                style_name, processes)


def main(argv=None):
    """The command: plotting.py [--wait] TRAJECTORY.csv OUTPUT_DIR [FORMATS [STYLE]]. With
    ``--wait`` (the command, which starts the script before its simulation so that the imports
    overlap the run), the script imports what it needs, then reads a line from its standard
    input: ``go``, the files are written, draw them; end of input (the run failed), leave
    without drawing (exit 0)."""
    argv = sys.argv[1:] if argv is None else argv
    wait = bool(argv) and argv[0] == "--wait"
    argv = argv[1:] if wait else argv
    if len(argv) not in (2, 3, 4):
        sys.stderr.write("usage: plotting.py [--wait] TRAJECTORY.csv OUTPUT_DIR "
                         "[png,pdf,svg [screen|paper]]\n")
        return 2
    style_name = argv[3] if len(argv) == 4 else "screen"
    try:
        formats = parse_formats(argv[2] if len(argv) >= 3 else "png")
        if style_name not in STYLES:
            raise ValueError("unknown plot style '%s': the styles are %s"
                             % (style_name, ", ".join(STYLES)))
    except ValueError as e:
        sys.stderr.write("plotting.py: %s\n" % e)
        return 2
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot  # noqa: F401
    except ImportError:
        sys.stderr.write("plotting.py: matplotlib is not installed\n")
        return 3
    if wait:
        for part in ("plotting_layout", "plotting_control", "plotting_reactions"):
            _module(part)  # (imported now, while the run goes on)
        if sys.stdin.readline().strip() != "go":
            return 0  # the run wrote no files to draw
    table = read_csv(argv[0])
    if "t" not in table or len(table["t"]) == 0:
        return 0  # a run that recorded no sample: nothing to draw
    meta = read_summary(os.path.join(os.path.dirname(os.path.abspath(argv[0])), "summary.json"))
    write_figures(table, meta, argv[1], formats, style_name=style_name,
                  processes=min(2, os.cpu_count() or 1))
    return 0


if __name__ == "__main__":
    # out without the interpreter's teardown of matplotlib's objects, which took 0.2 s of the
    # pendulum's 1.1 s (every file is closed and renamed by now)
    code = main()
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)
