# SPDX-License-Identifier: BSD-3-Clause
"""Ensembles: parameter sweeps and Monte Carlo studies of a model file (docs/ensembles.md).

:func:`sweep` runs many samples of one model — the points of a grid, random draws (uniform,
normal, log-uniform; plain or Latin hypercube, from a seed), or both — on every core of this
machine (C++ threads, ``ukdyn::run_ensemble``) or, given a ``dask.distributed.Client``, on the
Dask cluster's workers, which read the model again from its text. Either way each sample is
computed by the same code from the same inputs, so the results are the same bit for bit. The
result is one ``pandas.DataFrame``, one row per sample; :func:`to_dataset` turns a grid sweep into
an ``xarray.Dataset`` with one dimension per axis.
"""

from __future__ import annotations

import math
import os
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from . import _ukdyn
from . import interrupt as _interrupt
from .errors import Interrupted

__all__ = ["sweep", "to_dataset"]

GridSpec = Mapping[str, Union[str, Sequence[float]]]
RandomSpec = Mapping[str, Union[str, Tuple[str, float, float]]]


def _model_source(model: Any, overrides: Mapping[str, float]) -> Tuple[str, str]:
    """(text, file) of the model: a path, an example's name, YAML text, or a ukdyn.Model read from
    a file or an example (without overrides: those go to ``set=``)."""
    from . import Model, example_text, examples, parse

    if isinstance(model, Model):
        if os.path.isfile(model.file):
            with open(model.file, encoding="utf-8") as f:
                text = f.read()
        elif (model.file.startswith("examples/models/") and model.file.endswith(".yaml")
              and model.file[len("examples/models/"):-len(".yaml")] in examples()):
            text = example_text(model.file[len("examples/models/"):-len(".yaml")])
        else:
            raise ValueError(
                f"sweep: the model '{model.name}' was not read from a file or an example "
                f"(file '{model.file}'), so its text cannot be sent to the samples: give its "
                "path, its example name or its YAML text")
        again = parse(text, model.file, **dict(overrides))
        if again.parameters != model.parameters:
            differ = sorted(k for k in model.parameters
                            if again.parameters.get(k) != model.parameters[k])
            raise ValueError(
                f"sweep: the model was loaded with parameter overrides ({', '.join(differ)}); "
                "give the path and the overrides as set={...}")
        return text, model.file
    source = os.fspath(model)
    if "\n" in source:
        return source, "<string>"
    if os.path.exists(source) or source.endswith((".yaml", ".yml")) or os.sep in source:
        with open(source, encoding="utf-8") as f:
            return f.read(), source
    return example_text(source), f"examples/models/{source}.yaml"


def _grid_axes(grid: Optional[GridSpec]) -> List[Tuple[str, List[float]]]:
    axes = []
    for name, spec in (grid or {}).items():
        if isinstance(spec, str):
            axis_name, values = _ukdyn._parse_grid(f"{name}={spec}")
            axes.append((axis_name, list(values)))
        else:
            values = [float(v) for v in np.asarray(spec, dtype=float).ravel()]
            axes.append((str(name), values))
    return axes


def _random_variables(random: Optional[RandomSpec]) -> List[Tuple[str, str, float, float]]:
    out = []
    for name, spec in (random or {}).items():
        if isinstance(spec, str):
            out.append(tuple(_ukdyn._parse_random(f"{name}~{spec}")))
        else:
            try:
                law, a, b = spec
            except (TypeError, ValueError):
                raise ValueError(
                    f"sweep: random['{name}'] = {spec!r}: give a law and its two numbers, "
                    f"('uniform', A, B), ('normal', MEAN, SD) or ('loguniform', A, B), or the "
                    f"same as a text: 'uniform(A,B)'") from None
            out.append((str(name), str(law), float(a), float(b)))
    return out


def _whole_number(name: str, value: Any, minimum: int) -> int:
    """`value` as an int >= minimum (an int, or a float that is whole), else ValueError naming
    the argument: 2.5 is refused, not truncated, and -1 named, not a pybind11 TypeError."""
    whole: Optional[int] = None
    if not isinstance(value, bool):
        if isinstance(value, float):
            whole = int(value) if math.isfinite(value) and value.is_integer() else None
        else:
            try:
                whole = int(value.__index__())
            except (AttributeError, TypeError):
                whole = None
    if whole is None or whole < minimum or whole >= 2 ** 64:
        raise ValueError(f"sweep: {name}={value!r}: must be a whole number >= {minimum}")
    return whole


def _frame(parts: List[dict], offsets: List[int]):
    """One DataFrame from the tables of the chunks (each chunk's `sample` column made global)."""
    import pandas as pd

    names = parts[0]["names"]
    columns: Dict[str, Any] = {}
    for k, name in enumerate(names):
        values = [p["columns"][k] for p in parts]
        if name == "sample":
            values = [v + off for v, off in zip(values, offsets)]
        columns[name] = np.concatenate(values)
    columns["status"] = [s for p in parts for s in p["status"]]
    columns["message"] = [m for p in parts for m in p["message"]]
    frame = pd.DataFrame(columns)
    frame["sample"] = frame["sample"].astype(np.int64)
    for name in ("status_code", "ok", "steps", "rejected_steps", "evaluations",
                 "control_evaluations", "control_not_met"):
        frame[name] = frame[name].astype(np.int64)
    frame["ok"] = frame["ok"].astype(bool)
    return frame.set_index("sample", drop=False)


# the units of the summary figures that have one (the others are counts, flags or ratios, or in
# the constraints' own units): the model's time and energy (summary.json's unit_system keys)
FIGURE_UNITS = {"t_reached": "time", "energy_exchanged": "energy"}


def _column_units(frame: Any, text: str, file: str, overrides: dict) -> Dict[str, str]:
    """Each column's unit, for the known ones (``frame.attrs["units"]``): a swept coordinate's
    (``units:`` of the file, m/rad for bodies; ``_dot`` per s) and a recorded value's
    (``x@5``: x's, by the rules of ``Result.column_units``), ``t_start``/``t_end`` in the
    model's time unit, and the figures' (FIGURE_UNITS). Parameters have none (a model file gives
    them no units)."""
    from . import parse
    from .plotting_data import column_unit, system_unit

    model = parse(text, file, **overrides)
    meta = {"units": model.units, "unit_system": model.unit_system}
    swept = list(frame.attrs["grid"]) + list(frame.attrs["random"])
    units = {}
    for name in frame.columns:
        if name in swept:
            unit = (system_unit(meta, "time") if name in ("t_start", "t_end")
                    else column_unit(meta, name))
        elif "@" in name:
            unit = column_unit(meta, name.split("@", 1)[0])
        else:
            unit = system_unit(meta, FIGURE_UNITS[name]) if name in FIGURE_UNITS else ""
        if unit:
            units[name] = unit
    return units


def _run_chunk(text: str, file: str, overrides: dict, settings: dict, names: List[str],
               rows: np.ndarray, at: List[float], outputs: List[str], keep: bool) -> dict:
    """One Dask task: the samples `rows` in this worker's process, on one thread."""
    from ukdyn import _ukdyn as core

    out = core._run_ensemble(text, file, overrides, settings, names, rows, at, outputs, keep, 1,
                             None)
    out.pop("exception", None)
    return out


def sweep(model: Any, *, grid: Optional[GridSpec] = None, random: Optional[RandomSpec] = None,
          n: Optional[int] = None, seed: int = 0, lhs: bool = False,
          at: Optional[Sequence[float]] = None, outputs: Optional[Sequence[str]] = None,
          trajectories: bool = False, workers: Optional[int] = None, client: Any = None,
          chunk_size: Optional[int] = None, set: Optional[Mapping[str, float]] = None,
          dataset: bool = False, **settings: Any):
    """Runs a sweep or a Monte Carlo study of ``model`` → ``pandas.DataFrame``, one row per sample.

    ``model``: a model file's path, a built-in example's name, YAML text (a string with a line
    break), or a :class:`ukdyn.Model` read from a file or an example. ``set={...}`` overrides
    parameters for every sample; keyword ``settings`` (the options table: ``t_end``, ``rtol``,
    …) replace the file's ``simulate:`` settings for every sample.

    The samples: the Cartesian product of ``grid`` (``{"mu": "0:0.5:11", "omega": [1, 2, 4]}``;
    the first axis varies slowest), each point combined with the same ``n`` random draws of
    ``random`` (``{"theta0": "uniform(0,1)", "k": ("normal", 1.0, 0.1)}``; laws uniform(a,b),
    normal(mean,sd), loguniform(a,b)) from ``seed``; ``lhs=True`` draws a Latin hypercube. A name
    is a parameter of the model, else a coordinate (its initial value) or ``<coordinate>_dot``,
    else a numeric option (``t_end``, ``rtol``). The same seed gives the same samples here, on
    the command line (``ukdyn sweep``) and on every platform.

    Each row: the sample's values, ``status`` (``"ok"``, a failure's name, ``"refused"`` when
    the sample could not start, ``"not run"``), ``ok``, ``message``, the run's figures (steps,
    evaluations, t_reached, largest violations, energy balance, control statistics; for a model
    with unilateral contacts or Coulomb friction the counts ``impacts``, ``releases``,
    ``sticks``, ``slips`` of its contact events and ``rest_time``, NaN when none) and each
    coordinate, velocity and output (``outputs``; default the model's output expressions) at
    each time of ``at`` (columns ``x@5``; without ``at``, at the run's end: ``x@end``). A sample
    that fails is recorded and does not stop the others. ``trajectories=True`` also keeps every
    sample's whole trajectory, as ``frame.attrs["trajectories"]`` (a list of dicts column →
    array).

    Where: ``workers`` threads of this process (default: every core); or, with ``client`` a
    ``dask.distributed.Client``, chunks of ``chunk_size`` samples (default: about four chunks per
    worker) sent to the cluster's workers, which need ukdyn installed and read the model again
    from its text. The results are the same bit for bit either way.

    Ctrl-C stops the sweep (the runs under way at their next step) and raises
    :class:`ukdyn.Interrupted` whose ``.result`` is the DataFrame of the finished samples (the
    others with status ``"interrupted"`` or ``"not run"``).

    ``dataset=True`` returns :func:`to_dataset` of the frame (grids only).

    Raises :class:`ukdyn.ModelError` when the model cannot be read, ValueError for a name that
    is none of the above, a bad law or grid, or a bad setting.
    """
    overrides = {str(k): float(v) for k, v in (set or {}).items()}
    text, file = _model_source(model, overrides)
    axes = _grid_axes(grid)
    variables = _random_variables(random)
    draws = _whole_number("n", n, 1) if n is not None else 0
    if variables and draws == 0:
        raise ValueError("sweep: random variables need n, the number of draws (n=1000)")
    names, rows = _ukdyn._design(axes, variables, draws, _whole_number("seed", seed, 0),
                                 bool(lhs))
    at_list = [float(t) for t in (at if at is not None else [])]
    outputs_list = [str(o) for o in (outputs or [])]
    settings = {k: v for k, v in settings.items()}

    if client is None:
        # (0 or None: every core; as `ukdyn sweep --jobs`, at most 1024 threads)
        threads = _whole_number("workers", workers, 0) if workers is not None else 0
        if threads > 1024:
            raise ValueError("sweep: workers=%d: at most 1024 threads (0 or None: one per core, "
                             "%d here)" % (threads, os.cpu_count() or 1))
        threads = threads or (os.cpu_count() or 1)
        with _interrupt.guard() as guard:
            out = _ukdyn._run_ensemble(text, file, overrides, settings, names, rows, at_list,
                                       outputs_list, bool(trajectories), threads, guard.stop)
        parts, offsets = [out], [0]
        interrupted = out["interrupted"] and (guard.signalled or out["exception"] is not None)
    else:
        parts, offsets, interrupted = _run_on_dask(client, chunk_size, text, file, overrides,
                                                   settings, names, rows, at_list, outputs_list,
                                                   bool(trajectories))
    frame = _frame(parts, offsets)
    frame.attrs["grid"] = [a[0] for a in axes]
    frame.attrs["random"] = [v[0] for v in variables]
    frame.attrs["model"] = file
    frame.attrs["units"] = _column_units(frame, text, file, overrides)
    if trajectories:
        frame.attrs["trajectories"] = [t for p in parts for t in p["trajectories"]]
    if interrupted:
        raise Interrupted(f"sweep interrupted: {int((frame['status'] != 'not run').sum())} of "
                          f"{len(frame)} samples ran", frame)
    return to_dataset(frame) if dataset else frame


def _run_on_dask(client: Any, chunk_size: Optional[int], text: str, file: str, overrides: dict,
                 settings: dict, names: List[str], rows: np.ndarray, at: List[float],
                 outputs: List[str], keep: bool):
    """The samples in chunks on the Dask workers, in order; Ctrl-C cancels the chunks not done."""
    from distributed import as_completed

    total = rows.shape[0]
    if chunk_size is None:
        workers = max(1, len(client.scheduler_info().get("workers", {})))
        chunk_size = max(1, math.ceil(total / (4 * workers)))
    chunk_size = max(1, int(chunk_size))
    starts = list(range(0, total, chunk_size)) or [0]
    futures = [client.submit(_run_chunk, text, file, overrides, settings, names,
                             rows[s:s + chunk_size], at, outputs, keep, pure=False)
               for s in starts]
    index = {f.key: k for k, f in enumerate(futures)}
    parts: List[Optional[dict]] = [None] * len(futures)
    interrupted = False
    try:
        for future in as_completed(futures):
            parts[index[future.key]] = future.result()
    except KeyboardInterrupt:
        interrupted = True
        client.cancel([f for f in futures if not f.done()])
    # chunks not run: their rows as "not run", made by run_ensemble told to stop before any
    # sample (the same figures as the samples a sweep on threads did not run)
    if any(part is None for part in parts):
        stop_now = lambda: True  # noqa: E731
        for k, part in enumerate(parts):
            if part is None:
                parts[k] = _ukdyn._run_ensemble(text, file, overrides, settings, names,
                                                rows[starts[k]:starts[k] + chunk_size], at,
                                                outputs, keep, 1, stop_now)
                parts[k].pop("exception", None)
    return parts, starts, interrupted


def to_dataset(frame: Any):
    """A grid sweep's DataFrame as an ``xarray.Dataset``: one dimension per grid axis (in the
    grid's order), each other column a variable over them (``status`` and ``message`` too);
    each variable's and axis's ``attrs["units"]`` is the frame's (``frame.attrs["units"]``;
    absent when not known), the Dataset's ``attrs["model"]`` the model file.
    Raises ValueError for a frame with random draws (no grid structure to follow)."""
    import xarray as xr

    grid = frame.attrs.get("grid") or []
    if frame.attrs.get("random"):
        raise ValueError("to_dataset: the sweep has random draws; only a grid has dimensions "
                         "(use the DataFrame, or frame.to_xarray())")
    if not grid:
        raise ValueError("to_dataset: the sweep has no grid")
    indexed = frame.drop(columns=["sample"]).set_index(list(grid))
    ds = xr.Dataset.from_dataframe(indexed)
    for name, unit in (frame.attrs.get("units") or {}).items():
        if name in ds.variables:
            ds[name].attrs["units"] = unit
    if "model" in frame.attrs:
        ds.attrs["model"] = frame.attrs["model"]
    return ds
