# SPDX-License-Identifier: BSD-3-Clause
"""Linear models of constrained systems: :meth:`Model.linearize` and :meth:`Model.equilibrium`.

The reduction to minimal coordinates of the constraint manifold, the choice of independent
coordinates and the error estimates are explained in docs/linearize.md.
"""

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
              equilibrium: bool = False, unknowns: Sequence[str] = (),
              project: bool = False) -> LinearModel:
    """The linear model of ``model`` about (q, q_dot, t) (default: its initial state), in
    minimal coordinates of the constraint manifold.

    ``inputs``: coordinate names (a generalized force along each) or parameter names;
    ``outputs``: coordinate names or ``NAME_dot``; ``independent`` (and
    ``independent_velocities``): the independent coordinates by name (default: chosen by a
    column-pivoted QR, the best conditioned). With ``equilibrium=True`` an equilibrium or steady
    motion is first found from the state (``unknowns`` as in :meth:`Model.equilibrium`).
    ``project=True`` first moves the state onto the constraints (least M-weighted correction).
    Raises ValueError on misuse, off the constraint manifold, or at a singular configuration;
    :class:`SolveError` when the dynamics cannot be evaluated near the point.
    """
    d = _ukdyn._linearize(model, q, q_dot, t, _names(inputs), _names(outputs),
                          _names(independent), _names(independent_velocities), bool(equilibrium),
                          _names(unknowns), bool(project))
    return LinearModel(**d)


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
