# SPDX-License-Identifier: BSD-3-Clause
"""Linear models of constrained systems: :meth:`Model.linearize` and :meth:`Model.equilibrium`.

The reduction to minimal coordinates of the constraint manifold, the choice of independent
coordinates and the error estimates are explained in docs/linearize.md.
"""

import warnings
from dataclasses import dataclass
from typing import Any, Dict, List, Optional, Sequence, Tuple

import numpy as np

from . import _ukdyn


@dataclass(frozen=True)
class LinearModel:
    """x' = A x + B u, y = C x + D u about an operating point, in deviations from it.

    The state x is (independent positions, independent velocities), named by ``states`` (a
    velocity as ``NAME_dot``); ``inputs`` name the columns of B and D (a coordinate: a
    generalized force along it; a parameter), ``outputs`` the rows of C and D. ``A_error`` …
    ``D_error`` are Ridders' error estimates per entry (0 where exact). ``eigenvalues`` and
    ``eigenvectors`` (columns, rows named by ``states``) are those of A.
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    A_error: np.ndarray
    B_error: np.ndarray
    C_error: np.ndarray
    D_error: np.ndarray
    states: List[str]
    inputs: List[str]
    outputs: List[str]
    x0: np.ndarray
    f0: np.ndarray
    q: np.ndarray
    q_dot: np.ndarray
    t: float
    chart_condition: float
    #: the unilateral contacts open at the point, left out of the model (closed ones are held)
    open_contacts: List[str]
    eigenvalues: np.ndarray
    eigenvectors: np.ndarray

    def mode(self, k: int) -> Dict[str, complex]:
        """The mode of eigenvalue ``k`` as {state name: component}, largest magnitude first."""
        v = self.eigenvectors[:, k]
        order = np.argsort(-np.abs(v), kind="stable")
        return {self.states[i]: complex(v[i]) for i in order}


def _names(value: Any) -> List[str]:
    if value is None:
        return []
    if isinstance(value, str):
        return [value]
    return [str(v) for v in value]


def linearize(model: "_ukdyn.Model", q: Any = None, q_dot: Any = None, t: Optional[float] = None,
              *, inputs: Sequence[str] = (), outputs: Sequence[str] = (),
              independent: Sequence[str] = (), independent_velocities: Sequence[str] = (),
              states: Sequence[str] = (), equilibrium: bool = False,
              unknowns: Sequence[str] = (), project: bool = False,
              initial_step: float = 0.1) -> LinearModel:
    """The linear model of ``model`` about (q, q_dot, t) (default: its initial state), in
    minimal coordinates of the constraint manifold.

    ``inputs``: coordinate names (a generalized force along each) or parameter names;
    ``outputs``: coordinate names, ``NAME_dot`` or the model's output expressions
    (``output: expressions:``); ``independent`` (and ``independent_velocities``): the
    independent coordinates by name (default: chosen by a column-pivoted QR, the best
    conditioned); ``states``: keep only these states, a subsystem the others do not act on
    (e.g. a bicycle's ``["phi", "delta", "phi_dot", "delta_dot"]``; ValueError naming the
    dropped state that acts on a kept one otherwise). With ``equilibrium=True`` an equilibrium or steady
    motion is first found from the state (``unknowns`` as in :meth:`Model.equilibrium`).
    ``project=True`` first moves the state onto the constraints (least M-weighted correction).
    ``initial_step``: Ridders' first step relative to each variable's scale (docs/linearize.md,
    "Steps in the model's own scale").
    Raises ValueError on misuse, off the constraint manifold, or at a singular configuration;
    :class:`SolveError` when the dynamics cannot be evaluated near the point.
    """
    if getattr(model, "controller", None) is not None:
        # (the plant's open-loop model: said, as `ukdyn linearize` says it; u19 05)
        warnings.warn("the model's control: section is left out: this is the plant's open-loop "
                      "linear model, without the tracking control (docs/linearize.md, "
                      "\"Control\")", UserWarning, stacklevel=2)
    d = _ukdyn._linearize(model, q, q_dot, t, _names(inputs), _names(outputs),
                          _names(independent), _names(independent_velocities), _names(states),
                          bool(equilibrium), _names(unknowns), bool(project),
                          float(initial_step))
    return LinearModel(**d)


def linearize_along(model: "_ukdyn.Model", motion: Any = None, *, t: Any = None, q: Any = None,
                    q_dot: Any = None, inputs: Sequence[str] = (), outputs: Sequence[str] = (),
                    independent: Sequence[str] = (), independent_velocities: Sequence[str] = (),
                    states: Sequence[str] = (), initial_step: float = 0.1) -> List[LinearModel]:
    """The time-varying linearization along a motion: one :class:`LinearModel` per point, all in
    one chart (the independent coordinates named, or those chosen at the first point), so that
    dx' = A(t) dx + B(t) u is the variational equation of the motion (``f0`` is the motion's own
    x'). ``motion`` is a :class:`Result` of :meth:`Model.simulate` (its samples), or give the
    arrays ``t`` (N), ``q`` and ``q_dot`` (N × n). The other arguments are those of
    :meth:`Model.linearize`. Raises ValueError naming the point (index and t) where the chart
    becomes singular or a point is off the constraints.
    """
    if motion is not None:
        if t is not None or q is not None or q_dot is not None:
            raise ValueError("Model.linearize_along: give a motion or the arrays t, q, q_dot, "
                             "not both")
        t, q, q_dot = motion.t, motion.q, motion.q_dot
    if t is None or q is None or q_dot is None:
        raise ValueError("Model.linearize_along: give a motion (a Result) or the arrays t, q "
                         "and q_dot")
    t = np.asarray(t, dtype=float).reshape(-1)
    q = np.atleast_2d(np.asarray(q, dtype=float))
    q_dot = np.atleast_2d(np.asarray(q_dot, dtype=float))
    ds = _ukdyn._linearize_along(model, t.tolist(), q.tolist(), q_dot.tolist(), _names(inputs),
                                 _names(outputs), _names(independent),
                                 _names(independent_velocities), _names(states),
                                 float(initial_step))
    return [LinearModel(**d) for d in ds]


def equilibrium(model: "_ukdyn.Model", q: Any = None, q_dot: Any = None,
                t: Optional[float] = None, *, unknowns: Sequence[str] = (),
                tolerance: float = 1e-10,
                independent: Sequence[str] = ()) -> Tuple[np.ndarray, np.ndarray]:
    """An equilibrium or steady motion (q, q_dot) found from the guess (q, q_dot, t): Newton on
    the reduced accelerations for the ``unknowns`` (coordinate names, or ``NAME_dot`` for a
    steady rate; default every independent position), the rest of the state held. Raises
    RuntimeError naming the residual and the last iterate when none is found.
    """
    q_eq, qd_eq, _residual, _iterations = _ukdyn._equilibrium(
        model, q, q_dot, t, _names(unknowns), float(tolerance), _names(independent))
    return q_eq, qd_eq


# --- eigenvalues against a parameter, mode shapes -----------------------------------------------

@dataclass(frozen=True)
class EigenvalueSweep:
    """The eigenvalues of linear models along a parameter: ``eigenvalues[i, k]`` is eigenvalue
    k at ``values[i]``, the columns ordered so that each follows one branch (each eigenvalue
    matched to the nearest of the previous value's). ``label`` and ``unit`` name the
    parameter."""

    values: np.ndarray
    eigenvalues: np.ndarray
    label: str
    unit: str

    def crossings(self) -> List[float]:
        """The parameter values where the largest real part changes sign (linear
        interpolation between the grid points): the ends of the stable ranges."""
        s = self.eigenvalues.real.max(axis=1)
        out = []
        for i in range(len(s) - 1):
            if s[i] == 0 or s[i] * s[i + 1] < 0:
                w = s[i] / (s[i] - s[i + 1]) if s[i] != s[i + 1] else 0.0
                out.append(float(self.values[i] + w * (self.values[i + 1] - self.values[i])))
        return out


def _follow(previous: np.ndarray, current: np.ndarray) -> np.ndarray:
    # current reordered to follow previous: greedy nearest matching, closest pairs first
    n = len(current)
    dist = np.abs(previous[:, None] - current[None, :])
    order = np.full(n, -1)
    used = np.zeros(n, dtype=bool)
    for flat in np.argsort(dist, axis=None, kind="stable"):
        i, j = divmod(int(flat), n)
        if order[i] < 0 and not used[j]:
            order[i] = j
            used[j] = True
    return current[order]


def eigenvalue_sweep(model: "_ukdyn.Model", values: Sequence[float], at: Any, *,
                     label: str = "p", unit: str = "", **options: Any) -> EigenvalueSweep:
    """The eigenvalues of :meth:`Model.linearize` at each of ``values``: ``at(value)`` gives
    the operating point there as ``(q, q_dot)`` or ``(q, q_dot, t)`` (a speed, a spin rate …);
    ``options`` go to :meth:`Model.linearize` (``independent``, ``states`` …). Raises as
    :meth:`Model.linearize`, and ValueError when the number of states changes along the sweep.
    """
    values = np.asarray(values, dtype=float).reshape(-1)
    rows = []
    for value in values:
        point = tuple(at(float(value)))
        lm = linearize(model, *point, **options)
        ev = np.asarray(lm.eigenvalues, dtype=complex)
        if rows and len(ev) != len(rows[-1]):
            raise ValueError(f"eigenvalue_sweep: {len(ev)} states at {label} = {value}, "
                             f"{len(rows[-1])} before")
        rows.append(ev if not rows else _follow(rows[-1], ev))
    return EigenvalueSweep(values, np.array(rows), label, unit)


def plot_eigenvalues(sweep: EigenvalueSweep, path: Optional[str] = None, *,
                     title: str = "eigenvalues") -> Any:
    """The real parts (solid) and the positive imaginary parts (dashed) of the sweep's
    eigenvalues against the parameter, as in Meijaard et al. (2007, Fig. 3), with the stability
    boundaries (:meth:`EigenvalueSweep.crossings`) marked. Saved to ``path`` when given;
    returns the matplotlib Figure."""
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7.0, 4.5))
    x = sweep.values
    for k in range(sweep.eigenvalues.shape[1]):
        ev = sweep.eigenvalues[:, k]
        color = f"C{k}"
        ax.plot(x, ev.real, "-", color=color, label=f"Re λ{k + 1}")
        im = np.where(ev.imag > 0, ev.imag, np.nan)
        if np.any(np.isfinite(im)):
            ax.plot(x, im, "--", color=color, label=f"Im λ{k + 1}")
    ax.axhline(0.0, color="k", linewidth=0.6)
    for c in sweep.crossings():
        ax.axvline(c, color="0.5", linestyle=":", linewidth=1.0)
        ax.annotate(f"{c:.4g}", (c, 0), textcoords="offset points", xytext=(3, 4), fontsize=8)
    unit = f" [{sweep.unit}]" if sweep.unit else ""
    ax.set_xlabel(sweep.label + unit)
    ax.set_ylabel("eigenvalue [1/s]")
    ax.set_title(title)
    ax.legend(fontsize=7, ncol=2)
    fig.tight_layout()
    if path is not None:
        fig.savefig(path)
    return fig


def mode_shape(lm: LinearModel, k: int) -> Dict[str, complex]:
    """Mode ``k`` of ``lm`` scaled so that its largest component is 1 (real and positive):
    {state: component}, in the order of ``lm.states``. The magnitudes compare the states'
    participation, the phases their timing (a lag of the steer behind the lean …)."""
    if not 0 <= k < len(lm.eigenvalues):
        raise ValueError(f"mode_shape: no mode {k} (there are {len(lm.eigenvalues)})")
    v = np.asarray(lm.eigenvectors[:, k], dtype=complex)
    v = v / v[int(np.argmax(np.abs(v)))]
    return {s: complex(c) for s, c in zip(lm.states, v)}


def plot_mode(lm: LinearModel, k: int, path: Optional[str] = None, *,
              states: Optional[Sequence[str]] = None) -> Any:
    """The shape of mode ``k`` (:func:`mode_shape`): the magnitudes of its components as bars
    (left) and the components as phasors in the complex plane (right), for ``states`` (default
    all). Saved to ``path`` when given; returns the matplotlib Figure."""
    import matplotlib.pyplot as plt

    shape = mode_shape(lm, k)
    names = list(states) if states is not None else list(shape)
    for n in names:
        if n not in shape:
            raise ValueError(f"plot_mode: '{n}' is not a state; the states are {list(shape)}")
    comps = np.array([shape[n] for n in names])
    lam = complex(lm.eigenvalues[k])
    fig, (bars, phasors) = plt.subplots(1, 2, figsize=(9.0, 3.8))
    bars.bar(names, np.abs(comps), color=[f"C{i}" for i in range(len(names))])
    bars.set_ylabel("|component| (largest = 1)")
    bars.set_title(f"mode {k}: λ = {lam.real:.4g} {'+' if lam.imag >= 0 else '−'} "
                   f"{abs(lam.imag):.4g}i")
    for i, (n, c) in enumerate(zip(names, comps)):
        phasors.annotate("", xy=(c.real, c.imag), xytext=(0, 0),
                         arrowprops=dict(arrowstyle="->", color=f"C{i}"))
        phasors.plot([c.real], [c.imag], "o", color=f"C{i}", label=n)
    r = max(1.05, float(np.abs(comps).max()) * 1.05)
    phasors.set_xlim(-r, r)
    phasors.set_ylim(-r, r)
    phasors.set_aspect("equal")
    phasors.axhline(0, color="k", linewidth=0.5)
    phasors.axvline(0, color="k", linewidth=0.5)
    phasors.set_xlabel("Re")
    phasors.set_ylabel("Im")
    phasors.legend(fontsize=7)
    phasors.set_title("components (phasors)")
    fig.tight_layout()
    if path is not None:
        fig.savefig(path)
    return fig
