# SPDX-License-Identifier: BSD-3-Clause
"""The run's columns for the plots (part of ukdyn/plotting.py, which re-exports what is public
here): reading trajectory.csv (:func:`read_csv`, thinned above :data:`MAX_ROWS` rows) and
summary.json (:func:`read_summary`), the metadata a figure needs (:func:`metadata`), and the
unit of each column (:func:`column_unit`; the rules are in plotting.py's text). Imports nothing
of ukdyn and no matplotlib: the command runs it as a script beside plotting.py."""

import csv
import json

import numpy as np

#: the work channels of the energy balance (io/trajectory_files.hpp), in CSV order, with labels
WORKS = (("work_nonideal", "work of the non-ideal forces"),
         ("work_ideal", "work of the ideal constraint forces"),
         ("work_drive", "work of the drives"),
         ("work_external", "work of the external forces"),
         ("work_control", "work of the control"),
         ("work_impact", "work of the impacts"))  # (only with unilateral contacts)

#: the control's scalar columns (control/control.hpp, control_csv_columns)
CONTROL_SCALARS = ("control_power", "control_effort", "control_work_abs", "control_work")

#: the most rows read from a CSV: a longer run is thinned to every k-th row and the last, so that
#: the plots' memory does not grow with the run
MAX_ROWS = 200000


class Table:
    """Columns by name: ``names`` in order, ``table[name]`` a float array, ``name in table``.

    Anything with ``names``, ``__getitem__`` and ``__contains__`` (a :class:`ukdyn.Result`)
    can stand in for it.
    """

    def __init__(self, names, columns):
        self.names = list(names)
        self._columns = {}
        for name, values in zip(self.names, columns):
            self._columns.setdefault(name, np.asarray(values, dtype=float))

    def __getitem__(self, name):
        return self._columns[name]

    def __contains__(self, name):
        return name in self._columns


def read_csv(path):
    """Reads a trajectory.csv into a :class:`Table` (at most about MAX_ROWS rows: every k-th one
    and the last), with NumPy's C parser (numpy.loadtxt): a tenth of the time of Python's csv
    module on a wide multibody CSV."""
    with open(path, newline="") as f:
        total = max(0, sum(1 for _ in f) - 1)
    stride = max(1, -(-total // MAX_ROWS))
    with open(path, newline="") as f:
        header = next(csv.reader([f.readline()]))
        if total == 0:
            return Table(header, [[] for _ in header])
        rows = (line for i, line in enumerate(f) if not i % stride or i == total - 1)
        data = np.loadtxt(rows, delimiter=",", dtype=float, ndmin=2)
    return Table(header, data.T)


def _coordinates_of(names):
    """The coordinates of a CSV header: the columns between t and the first velocity column."""
    coords = []
    for name in names[1:]:
        if name.endswith("_dot") and name[: -len("_dot")] in coords:
            break
        coords.append(name)
    return coords


def read_summary(path):
    """The metadata (:func:`metadata`) that a run's summary.json gives: the model's name and
    the coordinates' units. A missing or unreadable file gives an empty dict."""
    try:
        with open(path, encoding="utf-8") as f:
            summary = json.load(f)
    except (OSError, ValueError):
        return {}
    meta = {}
    name = (summary.get("provenance") or {}).get("model_name")
    if name:
        meta["model"] = name
    if isinstance(summary.get("units"), dict):
        meta["units"] = dict(summary["units"])
    if isinstance(summary.get("unit_system"), dict):
        meta["unit_system"] = {str(k): str(v) for k, v in summary["unit_system"].items()}
    if isinstance(summary.get("contact_events"), list):
        meta["contact_events"] = [e for e in summary["contact_events"] if isinstance(e, dict)]
    return meta


def metadata(table, meta=None):
    """The metadata of a run completed from its columns: ``model`` (""), ``coordinates`` (from
    the columns when not given), ``units`` (each coordinate's, "" when not known)."""
    meta = dict(meta or {})
    meta.setdefault("model", "")
    if not meta.get("coordinates"):
        meta["coordinates"] = _coordinates_of(table.names)
    units = {str(k): str(v or "") for k, v in dict(meta.get("units") or {}).items()}
    meta["units"] = {c: units.get(c, "") for c in meta["coordinates"]}
    meta["units"].update((k, v) for k, v in units.items() if k not in meta["units"])
    return meta


# --- units -----------------------------------------------------------------------------------
# the SI labels, which a model's declared units replace (summary.json's unit_system, written
# from ukdyn::UnitSystem: N, J, W only when length, mass and time are m, kg and s)
SI_UNITS = {"length": "m", "mass": "kg", "time": "s", "velocity": "m/s", "force": "N",
            "energy": "J", "power": "W"}


def system_unit(meta, quantity):
    """The label of `quantity` (length, mass, time, velocity, force, energy, power) in the
    model's unit system (meta["unit_system"], from summary.json), SI when not given."""
    return ((meta or {}).get("unit_system") or {}).get(quantity) or SI_UNITS[quantity]


def torque_unit(meta):
    """N·m in SI units, else the energy's label (mass·length²/time²)."""
    energy = system_unit(meta, "energy")
    return "N·m" if energy == "J" else energy


def coordinate_unit(meta, c):
    """The unit of coordinate c ("" when not known)."""
    return (meta.get("units") or {}).get(c, "") or ""


def force_unit(unit, meta=None):
    """The unit of the generalized force conjugate to a coordinate in `unit`: the force (N in SI
    units) for the model's length unit, the torque (N·m) for rad and for a dimensionless
    coordinate (a quaternion component); "" otherwise."""
    if unit and unit == system_unit(meta, "length"):
        return system_unit(meta, "force")
    return torque_unit(meta) if unit in ("rad", "1") else ""


def _rate(unit, order, meta=None):
    """The unit of the order-th time derivative of a quantity in `unit` (per the model's time
    unit)."""
    if not unit:
        return ""
    per = system_unit(meta, "time") + ("" if order == 1 else "²")
    return "1/" + per if unit == "1" else unit + "/" + per


def _label(text, unit):
    """An axis label with its unit in brackets (none when unknown)."""
    return "%s [%s]" % (text, unit) if unit else text


def _kind(unit, quaternion, meta=None):
    if quaternion:
        return "quaternion components"
    if unit and unit == system_unit(meta, "length"):
        return "position"
    return "angle" if unit == "rad" else "coordinate"


def _is_quaternion(table, meta, c):
    """A rigid body's rotation coordinate <b>.u0 … <b>.u3."""
    body, _, last = c.rpartition(".")
    return bool(body) and last in ("u0", "u1", "u2", "u3") and (body + ".qw") in table


def _groups(meta, coords, unit_of):
    """The names grouped by unit_of(name), in the order of first appearance: [(unit, names)]."""
    groups = {}
    for c in coords:
        groups.setdefault(unit_of(c), []).append(c)
    return list(groups.items())


def column_unit(meta, name):
    """The unit of a column of trajectory.csv ("" when not known)."""
    units = meta.get("units") or {}
    if name == "t":
        return system_unit(meta, "time")
    if name in units:
        return units[name] or ""
    for suffix, order in (("_ddot", 2), ("_dot", 1)):
        if name.endswith(suffix) and name[: -len(suffix)] in units:
            return _rate(units[name[: -len(suffix)]], order, meta)
    prefix, _, rest = name.partition(".")
    if prefix in ("Qc_ideal", "Qc_nonideal", "Qc_control", "Qc_robust") and rest in units:
        return force_unit(units[rest], meta)
    if name in ("kinetic_energy", "potential_energy", "energy", "energy_balance_residual",
                "control_work", "control_work_abs") or name.startswith("work_"):
        return system_unit(meta, "energy")
    if name == "control_power":
        return system_unit(meta, "power")
    return ""
