# SPDX-License-Identifier: BSD-3-Clause
"""ukdyn: the Udwadia–Kalaba equations of motion of constrained mechanical systems, in Python.

The C++ library (README.md) behind a thin module (docs/python.md):

* :func:`load` a model file or a built-in example, with parameter overrides
  (``ukdyn.load("pendulum", L=2.0)``); :func:`parse` YAML text; :func:`from_sympy` a model from
  SymPy expressions (translated to the model-file language: exact derivatives, evaluation in
  C++); :func:`from_callables` a system from Python functions (slow, flexible);
* :meth:`Model.simulate` / :func:`simulate` → :class:`Result` (the columns of trajectory.csv as
  NumPy arrays, a pandas DataFrame, plots), bit-identical to ``ukdyn run``;
* :meth:`Model.solver` / :meth:`System.solver` → :class:`Solver`, one evaluation at a time
  (``solve(q, q_dot, t)`` → q'', forces, multipliers, rank, residuals);
* :attr:`Model.controller` / :func:`controller` → :class:`Controller`, exact tracking control,
  ``controller.solver().compute(q, q_dot, t)``;
* :func:`sweep` → a ``pandas.DataFrame`` of many runs (grids, Monte Carlo) on every core or on a
  Dask cluster (docs/ensembles.md).

Errors: :class:`ModelError`, :class:`SolveError`, :class:`InconsistentInitialState` (a
ValueError), :class:`ContactStartError` (a ModelError and a ValueError), ValueError, RuntimeError (:mod:`ukdyn.errors`);
Ctrl-C during a run raises :class:`Interrupted` (a KeyboardInterrupt) with the partial result.
"""

from __future__ import annotations

import json as _json
import os as _os
from typing import Any, Optional

from . import _ukdyn
from . import linear as _linear
from .linear import LinearModel
from . import interrupt as _interrupt
from ._ukdyn import (ControlSolution, ControlSolver, Controller, Model, Solution, Solver,
                     System, example_text, examples)
from .callables import (coulomb, constraint, controller, from_callables, nonideal, simulate,
                        viscous)
from .ensemble import sweep, to_dataset
from .errors import (ContactStartError, EnergyBalanceWarning, InconsistentInitialState,
                     Interrupted, ModelError, SolveError)
from .results import Result
from .symbolic import from_sympy, sympy_to_yaml, velocities

__version__ = "0.1.0"


def read_hdf5(path: str) -> "tuple[Result, dict]":
    """Reads a ``trajectory.h5`` (``ukdyn run --format hdf5``, :meth:`Result.to_hdf5`): its
    columns as a :class:`Result` and its summary (``summary.json``'s content) as a dict."""
    names, columns, summary_text = _ukdyn._read_table_hdf5(_os.fspath(path))
    summary = _json.loads(summary_text) if summary_text else {}
    coordinates = [n for n in names if n + "_dot" in names and n + "_ddot" in names]
    stats = {k: v for k, v in summary.items() if not isinstance(v, (dict, list))}
    # the lists a live run's statistics hold too (Result.contact_events reads them)
    for key in ("contact_events", "notes"):
        if isinstance(summary.get(key), list):
            stats[key] = summary[key]
    units = summary.get("units") if isinstance(summary.get("units"), dict) else None
    name = (summary.get("provenance") or {}).get("model_name") or ""
    system = summary.get("unit_system") if isinstance(summary.get("unit_system"), dict) else None
    return Result(names, columns, stats, summary.get("control"), coordinates, units,
                  name, system), summary


__all__ = [
    "ContactStartError", "ControlSolution", "ControlSolver", "Controller", "EnergyBalanceWarning",
    "InconsistentInitialState", "Interrupted", "LinearModel",
    "Model", "ModelError", "Result",
    "Solution", "SolveError", "Solver", "System", "constraint", "controller", "coulomb",
    "example_text", "examples", "from_callables", "from_sympy", "load", "nonideal", "options",
    "parse", "read_hdf5", "simulate", "simulation_options", "sweep", "sympy_to_yaml", "to_dataset",
    "velocities", "viscous",
]


def _overrides(who: str, overrides: dict) -> dict:
    out = {}
    for name, value in overrides.items():
        try:
            out[str(name)] = float(value)
        except (TypeError, ValueError):
            raise ValueError(f"{who}: the override {name}={value!r} is not a number") from None
    return out


def _tables(who: str, tables: Any) -> dict:
    """`tables` ({table: {column: 1-D array-like}}) as the module's GivenTables."""
    if tables is None:
        return {}
    if not isinstance(tables, dict):
        raise TypeError(f"{who}: tables must be a dict {{table: {{column: values}}}}, "
                        f"got {type(tables).__name__}")
    import numpy as np
    out = {}
    for name, columns in tables.items():
        if not isinstance(columns, dict):
            raise TypeError(f"{who}: tables[{name!r}] must be a dict {{column: values}}, "
                            f"got {type(columns).__name__}")
        given = []
        for column, values in columns.items():
            try:
                a = np.asarray(values, dtype=float)
            except (TypeError, ValueError):
                raise ValueError(f"{who}: column {name}.{column} is not an array of numbers") \
                    from None
            if a.ndim != 1:
                raise ValueError(f"{who}: column {name}.{column} must be one-dimensional "
                                 f"(got shape {a.shape})")
            given.append((str(column), a.tolist()))
        out[str(name)] = given
    return out


def load(source: "str | os.PathLike[str]", /, *, tables: Optional[dict] = None,
         **overrides: float) -> Model:
    """Reads a model file, or a built-in example by name, with parameter overrides.

    ``ukdyn.load("model.yaml", m=2.0)`` is ``ukdyn run model.yaml --set m=2``;
    ``ukdyn.load("arm.urdf")`` reads a URDF as a robot (gravity, zero torques, neutral pose;
    docs/robots.md); ``ukdyn.load("pendulum")`` reads the built-in example (:func:`examples`
    lists them; they are compiled into the module). A path-like source, or a string that names
    an existing file, ends in .yaml/.yml/.urdf or contains a path separator, is read as a file.

    Raises :class:`ModelError` (file:line:column, message, hint) for a bad or unreadable model
    file and for an override of a parameter the model does not declare; ValueError for a name
    that is neither a file nor an example (the message suggests the nearest example, as the
    command does, and lists them) or an override that is not a number.

    ``tables`` gives measured data for the model's ``tables:`` ({table: {column: 1-D array}},
    the columns in order; docs/model-format.md, "Tables"): each table must be declared by the
    file, and the data given replace any it has there, as overrides replace parameters —
    ``ukdyn.load("shaken_frame", tables={"ground": {"t": t, "acc": record}})``. (So a
    parameter called ``tables`` cannot be overridden here: use ``--set`` or rename it.)
    """
    values = _overrides("load", overrides)
    given = _tables("load", tables)
    path = _os.fspath(source)
    with _as_keywords("load"):
        if (not isinstance(source, str) or _os.path.exists(path)
                or path.endswith((".yaml", ".yml", ".urdf"))
                or _os.sep in path):
            return _ukdyn._load_file(path, values, given)
        return _ukdyn._load_example(path, values, given)


class _as_keywords:
    """A ModelError that names an override as the command gives it (``--set mu=-1: …``) names
    it as the keyword argument of ``ukdyn.load`` or ``ukdyn.parse`` instead (``load(mu=-1):
    …``): the same error, file, line, column and hint."""

    def __init__(self, who: str) -> None:
        self.who = who

    def __enter__(self) -> None:
        return None

    def __exit__(self, kind: Any, err: Any, trace: Any) -> bool:
        if not isinstance(err, ModelError) or "--set " not in str(err):
            return False
        import re
        pattern = re.compile(r"--set ([^:]*)")

        def keywords(text: str) -> str:
            return pattern.sub(lambda m: f"{self.who}({m.group(1)})", text)
        raise type(err)(keywords(str(err)), err.file, err.line, err.column,
                        keywords(err.message), keywords(err.hint)) from None


def parse(text: str, file: str = "<string>", *, tables: Optional[dict] = None,
          **overrides: float) -> Model:
    """Reads a model from YAML text (docs/model-format.md); ``file`` names it in errors (and a
    table's relative ``file:`` is read from its directory); ``tables`` as :func:`load`'s.

    Raises :class:`ModelError` as :func:`load`.
    """
    values, given = _overrides("parse", overrides), _tables("parse", tables)
    with _as_keywords("parse"):
        return _ukdyn._parse(text, file, values, given)


def _model_simulate(self: Model, *, t_end: Optional[float] = None, q0: Any = None,
                    qd0: Any = None, check: bool = True, **settings: Any) -> Result:
    """Simulates the model exactly as ``ukdyn run`` does (run_model, modelfile/run.hpp) → :class:`Result`.

    Without arguments the model's own ``simulate:`` and ``output:`` settings apply; keyword
    settings replace them: every option of :func:`ukdyn.options` (the table of simulation/options.hpp,
    listed below; the same as the model file's ``simulate:`` keys and ``ukdyn run``'s flags).
    ``q0``/``qd0`` replace the initial state. A model with a ``control:`` section runs under its controller.
    The GIL is released during the run.

    Raises ValueError for a bad setting or an inconsistent initial state (unless
    ``project_initial=True`` or the model says ``project: true``), and
    :class:`ukdyn.SolveError` (``.result`` holds the samples up to the failure) when the run
    fails numerically and ``check`` is True; with ``check=False`` the failed run's Result is
    returned (see ``Result.ok``, ``Result.message``). Ctrl-C stops the run at its next step and
    raises :class:`ukdyn.Interrupted` (a KeyboardInterrupt) whose ``.result`` (``.partial``)
    holds the samples computed up to there (docs/python.md, "Interrupts").
    """
    if t_end is not None:
        settings["t_end"] = t_end
    from .callables import _finish
    with _interrupt.guard() as interrupt:
        names, columns, stats, control, raised, summary = self._run(
            settings, q0, qd0, interrupt.stop, getattr(self, "_source", None))
    result = Result(names, columns, stats, control, self.coordinates, self.units, self.name,
                    self.unit_system)
    result._summary = summary
    result.scene = _json.loads(self._scene_json)  # what Result.show() draws
    interrupt.raise_if_interrupted(result, raised)
    return _finish(result, check)


def _model_solve(self: Model, q: Any, q_dot: Any, t: float = 0.0, check: bool = True) -> Solution:
    """One evaluation of the model's fundamental equation at (q, q', t) → :class:`Solution`.

    A convenience that makes a new :class:`Solver` per call; in a loop, make one with
    :meth:`Model.solver` and call its ``solve``. Raises as :meth:`Solver.solve`.
    """
    return self.solver().solve(q, q_dot, t, check)


def options() -> list:
    """The simulation options table (include/ukdyn/simulation/options.hpp): one dict per option with its
    ``name``, ``type`` ('number', 'integer', 'bool', 'choice', 'numbers'), ``default``,
    ``range`` (in words), ``choices``, ``aliases`` (older spellings, also accepted), ``solver``
    (a solver setting, also taken by :meth:`System.solver`), ``flag`` (``ukdyn run``'s) and
    ``doc``. Every ``simulate`` takes exactly these names as keyword settings."""
    return _ukdyn._options()


def simulation_options(**settings: Any) -> dict:
    """The default simulation options with ``settings`` applied, as a dict by option name:
    each setting checked exactly as ``simulate`` checks it (ValueError naming the option)."""
    return _ukdyn._simulation_options(settings)


def _options_doc() -> str:
    lines = ["", "    Settings (the options table; defaults in brackets):", ""]
    for o in _ukdyn._options():
        alias = f" (also {', '.join(o['aliases'])})" if o["aliases"] else ""
        lines.append(f"    - ``{o['name']}``{alias} [{o['default']!r}]: {o['doc']}; "
                     f"{o['range']}")
    return "\n".join(lines) + "\n"


_model_simulate.__doc__ = (_model_simulate.__doc__ or "") + _options_doc()

Model.simulate = _model_simulate  # type: ignore[attr-defined]
Model.solve = _model_solve  # type: ignore[attr-defined]
Model.linearize = _linear.linearize  # type: ignore[attr-defined]
Model.linearize_along = _linear.linearize_along  # type: ignore[attr-defined]
Model.equilibrium = _linear.equilibrium  # type: ignore[attr-defined]

# `dir(ukdyn)` lists the API and the submodules, not the helpers this file uses: the annotations
# are strings (PEP 563), so the typing names are not needed once the functions are defined
del annotations, Any, Optional
