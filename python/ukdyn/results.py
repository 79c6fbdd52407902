# SPDX-License-Identifier: BSD-3-Clause
"""Simulation results: the columns of ``trajectory.csv`` as NumPy arrays, a pandas view, plots.

A :class:`Result` holds exactly the columns that ``ukdyn run`` writes to ``trajectory.csv``, by the
same names and in the same order (io/trajectory_files.hpp lists them): ``t``; each coordinate ``x``; ``x_dot``;
``x_ddot``; ``Qc_ideal.x``; ``Qc_nonideal.x``; ``lambda.<constraint>``; ``violation.<constraint>``;
``violation_velocity.<constraint>``; ``kinetic_energy``, ``potential_energy``, ``energy``;
the energy balance: ``work_nonideal``, ``work_ideal``, ``work_drive``, ``work_external``,
``work_control``, ``energy_balance_residual``; then the control's columns (``error.<row>``, ``Qc_control.<coord>``, ...), the
bodies' poses of multibody models, and the model's output expressions.
"""

from __future__ import annotations

import json
import math
import os
import warnings
from typing import Any, Dict, Iterator, List, Optional, Sequence

import numpy as np

__all__ = ["Result"]


class Result:
    """The samples of a simulation, column by column.

    ``result["x"]`` is the column ``x`` (a 1-D float64 NumPy array with one value per sample, the
    array the C++ run filled: no copy was made); ``result.t`` the sample times;
    ``result.names`` the column names in CSV order; ``result.to_dataframe()`` a pandas
    DataFrame; ``result.plot()`` and its siblings draw with matplotlib, ``result.figures()`` and
    ``result.save_plots(dir)`` give the figures of ``ukdyn run`` (ukdyn/plotting.py). Columns whose names are
    Python identifiers are also attributes (``result.theta``).

    Attributes:
        names: the column names, in the order of ``trajectory.csv``.
        coordinates: the coordinate names.
        stats: the run's statistics (steps, rejected_steps, evaluations, least_squares,
            projections, events (stick/slip), switch_events (sign changes of non-smooth
            functions),
            stiff_switches, stiff_switch_time, stiff_steps,
            wall_time, max_position_violation, max_velocity_violation, energy_balance (the
            balance residual relative to the energy exchanged), energy_exchanged,
            energy_drift, t_reached, status, message; simulation/simulate.hpp, RunStatistics). The status
            is ``"energy_balance"`` when the run ended but its balance failed.
        control: the controller's statistics for a controlled run (evaluations, not_met,
            max_residual, first_not_met, not_met_message, max_kappa), else None.
        units: each coordinate's (and output expression's) unit by name (``Model.units``: the
            file's ``units:``, m, rad or 1 for a body's coordinates; "" when not known), for
            the plots' labels.
        model_name: the model's name (the plots' titles), or "".
        unit_system: the model's units (``Model.unit_system``: length, mass, time and the
            labels of velocity, force, energy, power; SI when None), which every derived label
            follows (``t`` in the time's, energies in the energy's: J only in SI units).
    """

    def __init__(self, names: Sequence[str], columns: Sequence[np.ndarray],
                 stats: Dict[str, Any], control: Optional[Dict[str, Any]],
                 coordinates: Sequence[str], units: Optional[Dict[str, str]] = None,
                 model_name: str = "", unit_system: Optional[Dict[str, str]] = None) -> None:
        self.names: List[str] = list(names)
        self._columns: List[np.ndarray] = list(columns)
        self._index: Dict[str, int] = {}
        for k, name in enumerate(self.names):
            self._index.setdefault(name, k)  # a duplicate name (an output expression): the first
        self.stats: Dict[str, Any] = dict(stats)
        self.control: Optional[Dict[str, Any]] = control
        self.coordinates: List[str] = list(coordinates)
        given = {str(k): str(v or "") for k, v in dict(units or {}).items()}
        self.units: Dict[str, str] = {c: given.get(c, "") for c in self.coordinates}
        self.units.update((k, v) for k, v in given.items() if k not in self.units)
        self.model_name: str = str(model_name or "")
        from .plotting_data import SI_UNITS
        self.unit_system: Dict[str, str] = dict(SI_UNITS)
        self.unit_system.update((str(k), str(v)) for k, v in dict(unit_system or {}).items())
        self._alias: Dict[str, int] = self._spellings()
        #: the scene the browser viewer draws (Model.simulate sets it; None otherwise)
        self.scene: Optional[Dict[str, Any]] = None
        # the run's summary.json text (summary_json, as `ukdyn run` writes it: options,
        # provenance, final_state ...), set by the simulate functions; to_hdf5 writes it
        self._summary: Optional[str] = None

    def _spellings(self) -> Dict[str, int]:
        """The other spelling of the columns of a body's coordinates: ``crank_x``, ``crank_x_dot``,
        ``Qc_ideal.crank_x`` … for ``crank.x``, ``crank.x_dot``, ``Qc_ideal.crank.x`` (model-file
        expressions write ``crank_x``; docs/multibody.md). Never shadows a real column."""
        other = {c: c.replace(".", "_") for c in self.coordinates if "." in c}
        alias: Dict[str, int] = {}
        if not other:
            return alias
        for name, k in self._index.items():
            spelled = None
            # <c>, <c>_dot, <c>_ddot, …
            for c in (name, name.rsplit("_", 1)[0]):
                if c in other:
                    spelled = other[c] + name[len(c):]
                    break
            # <prefix>.<c>: Qc_ideal.crank.x, Qc_control.crank.x, …
            if spelled is None:
                start = name.find(".")
                while start >= 0 and spelled is None:
                    rest = name[start + 1:]
                    if rest in other:
                        spelled = name[:start + 1] + other[rest]
                    start = name.find(".", start + 1)
            if spelled is not None and spelled not in self._index:
                alias.setdefault(spelled, k)
        return alias

    def _find(self, name: str) -> Optional[int]:
        k = self._index.get(name)
        return k if k is not None else self.__dict__.get("_alias", {}).get(name)

    # --- columns -----------------------------------------------------------------------------
    def __getitem__(self, name: str) -> np.ndarray:
        """The column called ``name`` (a body's coordinate in either spelling, ``crank.x`` or
        ``crank_x``). Raises KeyError naming the close matches."""
        k = self._find(name) if isinstance(name, str) else None
        if k is not None:
            return self._columns[k]
        import difflib
        close = difflib.get_close_matches(str(name), self.names, n=3)
        hint = f" (did you mean {', '.join(repr(c) for c in close)}?)" if close else ""
        raise KeyError(f"no column '{name}'{hint}")

    def __getattr__(self, name: str) -> np.ndarray:
        if name.startswith("_"):
            raise AttributeError(name)
        k = self._find(name) if "_index" in self.__dict__ else None
        if k is not None:
            return self._columns[k]
        raise AttributeError(f"'Result' object has no attribute or column '{name}'")

    def __contains__(self, name: object) -> bool:
        return isinstance(name, str) and self._find(name) is not None

    def __iter__(self) -> Iterator[str]:
        return iter(self.names)

    def __len__(self) -> int:
        """The number of samples N."""
        return len(self._columns[0]) if self._columns else 0

    def __repr__(self) -> str:
        return (f"<ukdyn.Result {len(self)} samples, {len(self.names)} columns, "
                f"t = {self.t[0] if len(self) else math.nan:g} … "
                f"{self.t[-1] if len(self) else math.nan:g}, status '{self.status}'>")

    def columns(self) -> Dict[str, np.ndarray]:
        """Every column by name (a new dict of the same arrays; first of duplicate names)."""
        return {name: self._columns[k] for name, k in self._index.items()}

    def group(self, prefix: str) -> Dict[str, np.ndarray]:
        """The columns whose names start with ``prefix + "."``, keyed by the rest of the name:
        ``result.group("lambda")`` → ``{"rod": array}``."""
        p = prefix + "."
        return {n[len(p):]: self._columns[k] for n, k in self._index.items() if n.startswith(p)}

    @property
    def t(self) -> np.ndarray:
        """The sample times (N)."""
        return self["t"]

    @property
    def q(self) -> np.ndarray:
        """The coordinates as an N × n array (a new array, coordinates in order)."""
        return np.column_stack([self[c] for c in self.coordinates])

    @property
    def q_dot(self) -> np.ndarray:
        """The velocities as an N × n array (a new array)."""
        return np.column_stack([self[c + "_dot"] for c in self.coordinates])

    @property
    def q_ddot(self) -> np.ndarray:
        """The accelerations as an N × n array (a new array)."""
        return np.column_stack([self[c + "_ddot"] for c in self.coordinates])

    # --- status ------------------------------------------------------------------------------
    @property
    def status(self) -> str:
        """The run's status: ``"ok"`` or why it stopped early (core/status.hpp)."""
        return str(self.stats.get("status", "ok"))

    @property
    def ok(self) -> bool:
        """True when the run reached its end time."""
        return self.status == "ok"

    @property
    def message(self) -> str:
        """What failed, where and when ("" when ok)."""
        return str(self.stats.get("message", ""))

    # --- units -------------------------------------------------------------------------------
    def column_units(self) -> Dict[str, str]:
        """Each column's unit by name, "" when not known, in the model's units
        (:attr:`unit_system`; here in SI): ``t`` in s; a coordinate's from :attr:`units`, its
        ``_dot`` and ``_ddot`` per s and s²; ``Qc_ideal.<c>`` (and the non-ideal, control and
        robust forces) N for a coordinate in m, N·m for one in rad or 1; energies and works J,
        ``control_power`` W; the output expressions' from ``units:`` (the rules of the plots'
        labels, ukdyn/plotting.py ``column_unit``)."""
        from .plotting import column_unit
        meta = {"units": self.units, "unit_system": self.unit_system}
        return {name: column_unit(meta, name) for name in self._index}

    # --- pandas and files ---------------------------------------------------------------------
    def to_dataframe(self, index: Optional[str] = None) -> "Any":
        """A pandas DataFrame of every column (CSV order; duplicate names keep their first
        column). ``index="t"`` makes the time the index. ``frame.attrs`` carries the units
        (``attrs["units"]``: :meth:`column_units`, the known ones), the model's name
        (``attrs["model"]``) and the run's status (``attrs["status"]``). Needs pandas
        (python3-pandas)."""
        import pandas as pd
        frame = pd.DataFrame(self.columns(), copy=False)
        frame = frame.set_index(index) if index else frame
        frame.attrs.update(self._attributes())
        return frame

    def _attributes(self) -> Dict[str, Any]:
        """What a DataFrame's or a Dataset's attrs say of the run."""
        return {"units": {k: v for k, v in self.column_units().items() if v},
                "model": self.model_name, "status": self.status}

    def to_xarray(self) -> "Any":
        """An ``xarray.Dataset`` over the dimension ``t``: every other column a variable whose
        ``attrs["units"]`` is its unit (:meth:`column_units`; absent when not known), ``t``'s
        ``attrs["units"]`` "s"; the Dataset's attrs name the model and the status. Needs xarray
        (python3-xarray)."""
        import xarray as xr
        units = self.column_units()
        t = xr.Variable("t", self.t, attrs={"units": self.unit_system["time"]})
        variables = {name: xr.Variable("t", self._columns[k],
                                       attrs={"units": units[name]} if units[name] else {})
                     for name, k in self._index.items() if name != "t"}
        return xr.Dataset(variables, coords={"t": t},
                          attrs={"model": self.model_name, "status": self.status})

    def _repr_html_(self) -> str:
        """A summary for Jupyter: the model, the status (and message), the samples and the time
        span, the steps and the largest violations, and a table of the coordinates with their
        units and first and last values. Names are HTML-escaped."""
        import html
        e = html.escape
        n = len(self)
        t0, t1 = (float(self.t[0]), float(self.t[-1])) if n else (math.nan, math.nan)
        status = e(self.status) + (": " + e(self.message) if self.message else "")
        time = e(self.unit_system["time"])
        rows = [("model", e(self.model_name) or "&mdash;"), ("status", status),
                ("samples", "%d, t = %.6g &hellip; %.6g %s" % (n, t0, t1, time))]
        if "steps" in self.stats:
            rows.append(("steps", "%s (%s rejected)" % (self.stats.get("steps"),
                                                       self.stats.get("rejected_steps", 0))))
        for key, what in (("max_position_violation", "max violation (position)"),
                          ("max_velocity_violation", "max violation (velocity)"),
                          ("energy_balance", "energy balance (relative)")):
            if isinstance(self.stats.get(key), (int, float)):
                rows.append((what, "%.3g" % self.stats[key]))
        head = "".join("<tr><th style=\"text-align:left\">%s</th><td style=\"text-align:left\">"
                       "%s</td></tr>" % row for row in rows)
        units = self.column_units()
        body = "".join(
            "<tr><td>%s</td><td>%s</td><td>%.6g</td><td>%.6g</td></tr>"
            % (e(c), e(units.get(c, "")), self[c][0] if n else math.nan,
               self[c][-1] if n else math.nan)
            for c in self.coordinates if c in self)
        return ("<div class=\"ukdyn-result\"><table>%s</table><table><thead><tr><th>coordinate"
                "</th><th>unit</th><th>first</th><th>last</th></tr></thead><tbody>%s</tbody>"
                "</table><p>%d columns: result.names; result.to_dataframe(), "
                "result.to_xarray()</p></div>" % (head, body, len(self.names)))

    @property
    def df(self) -> "Any":
        """``to_dataframe()``."""
        return self.to_dataframe()

    def to_csv(self, path: str) -> None:
        """Writes the columns as ``ukdyn run`` writes ``trajectory.csv``: the header, then one
        row per sample, numbers in the shortest form that reads back bit for bit. Like the C++
        writers, whole or not at all: a hidden temporary beside ``path``, renamed over it when
        complete (a path that exists and is not a regular file, like /dev/stdout, is written in
        place)."""
        def fmt(x: float) -> str:
            if math.isnan(x):
                return "nan"
            if math.isinf(x):
                return "inf" if x > 0 else "-inf"
            r = repr(float(x))
            return r[:-2] if r.endswith(".0") else r

        def write(f: Any) -> None:
            f.write(",".join(self.names) + "\n")
            for i in range(len(self)):
                f.write(",".join(fmt(c[i]) for c in self._columns) + "\n")

        target = os.path.realpath(os.fspath(path))
        if os.path.exists(target) and not os.path.isfile(target):
            with open(target, "w", encoding="utf-8") as f:
                write(f)
            return
        directory, name = os.path.split(target)
        temporary = os.path.join(directory, f".{name}.tmp-{os.getpid()}-{id(self)}")
        try:
            with open(temporary, "x", encoding="utf-8") as f:
                write(f)
            os.replace(temporary, target)
        finally:
            if os.path.exists(temporary):
                os.remove(temporary)

    def to_hdf5(self, path: str) -> None:
        """Writes the columns to HDF5 as ``ukdyn run --format hdf5`` writes ``trajectory.h5``:
        one 1-D float64 dataset per column, named as in the CSV (a ``/`` written ``|``, a name
        met twice suffixed ``#2``), the names in order as the root attribute ``columns``, and the
        run's summary — the same summary.json text the command writes (the C++ summary_json:
        statistics, ``options``, ``provenance`` with the parameters and which were overridden,
        the model file and its SHA-256 when the model was loaded from a file or an example,
        ``final_state``, ``control`` for a controlled run, units) — as the JSON attribute
        ``summary`` and one attribute per number or string. Whole or not at all, like
        ``to_csv``. Read it back with :func:`ukdyn.read_hdf5`; ``ukdyn run --from-summary
        FILE.h5`` makes the run again (a model loaded from a file or an example)."""
        from . import _ukdyn, __version__

        def plain(v: Any) -> Any:
            if isinstance(v, float) and not math.isfinite(v):
                return None  # JSON has no NaN or infinity
            if isinstance(v, dict):
                return {k: plain(x) for k, x in v.items()}
            if isinstance(v, (list, tuple)):
                return [plain(x) for x in v]
            return v

        if self._summary:
            summary = json.loads(self._summary)
        else:  # (a Result made by hand)
            summary = dict(plain(self.stats))
            if self.control is not None:
                summary["control"] = plain(self.control)
            summary["provenance"] = {"ukdyn_version": __version__, "model_name": self.model_name}
        summary.setdefault("provenance", {"ukdyn_version": __version__,
                                          "model_name": self.model_name})
        summary["provenance"]["written_by"] = "Result.to_hdf5"
        summary.setdefault("units", dict(self.units))
        summary.setdefault("unit_system", dict(self.unit_system))
        _ukdyn._write_table_hdf5(os.fspath(path), self.names,
                                 [np.asarray(c, dtype=np.float64) for c in self._columns],
                                 json.dumps(summary, indent=2))

    # --- the browser viewer (docs/viewer.md) --------------------------------------------------
    def animation_html(self, fps: float = 30.0) -> str:
        """The viewer page of this run (the ``animation.html`` of ``ukdyn run --viewer``): one
        self-contained HTML file with three.js and the samples decimated to ``fps`` frames per
        simulated second. Raises ValueError when there is nothing to draw (a run not made by
        Model.simulate, or a model in coordinates without a ``visual:`` section or a control
        whose requirements' errors it could chart)."""
        return self._page(fps, "Result.animation_html")

    def _page(self, fps: float, who: str) -> str:
        # the page; `who` names the method the user called in a refusal
        from . import viewer
        scene = self.scene
        if scene is None or not any(scene.get(k) for k in ("bodies", "points", "frames",
                                                            "contacts", "robot",
                                                            "controlled")):
            raise ValueError(
                who + ": nothing to draw: the model has no bodies and no visual: section "
                "(add visual: {points: {...}, links: [...]}, or from_sympy(..., visual=...); "
                "docs/viewer.md)"
                if scene is not None else
                who + ": this result has no scene (only Model.simulate() records one)")
        # a visual point that is not finite (NaN, ±inf) is hidden while so: say where it starts
        first = {}
        for c in viewer._point_columns(scene):
            if c in self.names:
                column = self._columns[self.names.index(c)]
                k = next((k for k, v in enumerate(column) if not math.isfinite(v)), None)
                if k is not None:
                    first[c] = float(self.t[k])
        for line in viewer.nonfinite_warnings(scene, first):
            warnings.warn(line[len("warning: "):], RuntimeWarning, stacklevel=3)
        return viewer.build_page(scene, self.names, self._columns, fps=fps,
                                 contact_events=self.contact_events,
                                 unit_system=self.unit_system)

    def save_animation(self, path: "str | os.PathLike[str]", fps: float = 30.0) -> None:
        """Writes the viewer page (:meth:`animation_html`) to ``path``; it opens from disk."""
        from . import viewer
        viewer.write_page(os.fspath(path), self._page(fps, "Result.save_animation"))

    def show(self, height: int = 480, fps: float = 30.0) -> Any:
        """The viewer, inline in a Jupyter notebook (an IPython HTML object holding the page in
        an iframe ``height`` pixels tall); outside IPython the same object's ``.data`` is the
        HTML text."""
        import html
        srcdoc = html.escape(self._page(fps, "Result.show"), quote=True)
        # (the iframe inside a div: IPython's HTML warns "Consider using IPython.display.IFrame
        # instead" for text that starts with <iframe and ends with </iframe>, a red box in a
        # notebook; IFrame cannot hold the page itself, it loads a URL)
        frame = ('<div class="ukdyn-viewer"><iframe srcdoc="%s" '
                 'style="width:100%%;height:%dpx;border:1px solid #ccc" '
                 'sandbox="allow-scripts"></iframe></div>' % (srcdoc, int(height)))
        try:
            from IPython.display import HTML
        except ImportError:  # pragma: no cover - IPython comes with Jupyter
            class HTML:  # type: ignore[no-redef]
                def __init__(self, data: str) -> None:
                    self.data = data
        return HTML(frame)

    # --- plots -------------------------------------------------------------------------------
    # --- plots (ukdyn/plotting.py, the plots of `ukdyn run` too) ------------------------------
    @property
    def contact_events(self) -> List[Dict[str, Any]]:
        """The impacts, releases and rests of the run's unilateral contacts and the sticks and
        slips of its Coulomb friction (docs/contact.md, "In a run"), in time order, as
        summary.json's ``contact_events`` lists them: dicts with ``t``, ``contact`` (the
        constraint's name: a stick's or slip's is the constraint that gives its N), ``kind``
        (``impact``, ``release``, ``rest``, ``stick``, ``slip``), ``speed_before``,
        ``speed_after`` (g' of the contact; |v_rel| for a stick or slip), ``impulse``,
        ``energy_change``; a release also ``force_before`` (the multiplier it carried just
        before), a stick or slip ``friction`` (its name), ``holding_force`` and
        ``friction_limit`` (mu_s N) of a slip at the limit (None when not known, as summary.json's
        null); empty without contacts and friction."""
        # the constraints in order: one violation.<name> column each
        constraints = [h[len("violation."):] for h in self.names if h.startswith("violation.")]
        out = []
        for e in self.stats.get("contact_events") or []:
            event = dict(e)
            k = event.pop("constraint", None)
            event = {"t": event.pop("t", None),
                     "contact": constraints[k] if isinstance(k, int) and 0 <= k < len(
                         constraints) else None, **event}
            # (NaN of the C++ event: None, as summary.json's null and read_hdf5 have it)
            for key in ("force_before", "holding_force", "friction_limit"):
                if isinstance(event.get(key), float) and event[key] != event[key]:
                    event[key] = None
            out.append(event)
        return out

    @property
    def plot_metadata(self) -> Dict[str, Any]:
        """What the plots know about the run besides its columns: the model's name, the
        coordinates and their units, the contact events (ukdyn/plotting.py, ``metadata``)."""
        return {"model": self.model_name, "coordinates": list(self.coordinates),
                "units": dict(self.units), "unit_system": dict(self.unit_system),
                "contact_events": self.contact_events}

    def figures(self, style: str = "screen") -> Dict[str, Any]:
        """Every figure ``ukdyn run`` draws for this run, as matplotlib Figures by file stem:
        ``coordinates``, ``constraint_forces``, ``violation``, ``energy``, ``control``,
        ``bodies``, ``outputs`` — those that apply (a figure without data is left out).
        Panels are grouped by unit, titles name the model (ukdyn/plotting.py). ``style``:
        ``"screen"`` or ``"paper"`` (a single journal column: 3.5 in wide, 8 pt text; as
        ``ukdyn run --plot-style paper``)."""
        from . import plotting
        return plotting.figures(self, self.plot_metadata, style)

    def save_plots(self, directory: str, formats: Any = None, style: str = "screen") -> List[str]:
        """Writes :meth:`figures` into ``directory`` as ``ukdyn run`` does: STEM.FORMAT for each
        of ``formats`` (``"png"``, ``"pdf"``, ``"svg"``, a list or ``"png,pdf"``; by default
        ``png``, or ``pdf`` for the ``paper`` style), each file whole or not at all;
        ``directory`` is created if missing (as by ``ukdyn run -o``). Returns the paths written.
        Raises ValueError naming the formats or styles for an unknown one."""
        from . import plotting
        formats = plotting.parse_formats(formats or ("pdf" if style == "paper" else "png"))
        plotting.style(style)  # checks the name before any file is written
        directory = os.fspath(directory)
        os.makedirs(directory, exist_ok=True)
        return plotting.write_figures(self, self.plot_metadata, directory, formats,
                                      style_name=style)

    def plot(self, *columns: str, ax: Any = None, x: str = "t", **kwargs: Any) -> Any:
        """Plots columns against time (or against column ``x``) with matplotlib; without
        columns, the coordinates. The y label names the unit when the columns share one.
        Returns the Axes. Extra keyword arguments go to ``ax.plot``."""
        from . import plotting
        if ax is None:
            _, ax = plotting._plt().subplots(layout="constrained")
        names = list(columns) or self.coordinates
        return plotting.draw_columns(ax, self, self.plot_metadata, names, x=x, **kwargs)

    def plot_forces(self, ax: Any = None) -> Any:
        """The ideal and non-ideal constraint forces per coordinate on one Axes
        (``Qc_ideal.*`` solid, ``Qc_nonideal.*`` dashed when not zero), with units.
        Returns the Axes. ``figures()["constraint_forces"]`` has one panel per unit."""
        from . import plotting
        if ax is None:
            _, ax = plotting._plt().subplots(layout="constrained")
        return plotting.draw_forces(ax, self, self.plot_metadata)

    def plot_violation(self, ax: Any = None) -> Any:
        """The running maximum of each constraint's violation ``violation.*`` on a log scale
        (while it is exactly zero it is not drawn). Returns the Axes."""
        from . import plotting
        if ax is None:
            _, ax = plotting._plt().subplots(layout="constrained")
        return plotting.draw_violation(ax, self, self.plot_metadata)

    def plot_energy(self, ax: Any = None) -> Any:
        """The energy balance: E(t) − E(0), each work channel that is not zero (non-ideal,
        ideal, drive, external, control) and the residual E(t) − E(0) − Σ W, which stays at the
        integration error when the balance holds. Returns the Axes."""
        from . import plotting
        if ax is None:
            _, ax = plotting._plt().subplots(layout="constrained")
        return plotting.draw_energy(ax, self, self.plot_metadata)

    def plot_all(self) -> Any:
        """Coordinates, constraint forces, violation and energy in a 2 × 2 figure titled with
        the model's name. Returns the Figure."""
        from . import plotting
        fig, axes = plotting._plt().subplots(2, 2, figsize=(13, 7), layout="constrained")
        self.plot(ax=axes[0, 0])
        self.plot_forces(ax=axes[0, 1])
        self.plot_violation(ax=axes[1, 0])
        self.plot_energy(ax=axes[1, 1])
        if self.model_name:
            fig.suptitle(self.model_name)
        return fig
