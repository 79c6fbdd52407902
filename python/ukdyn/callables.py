# SPDX-License-Identifier: BSD-3-Clause
"""Systems from plain Python callables: the slow, flexible path (docs/python.md).

M, Q, V, each constraint's A and b, and the non-ideal work vector C are Python functions that
the C++ solver calls at every evaluation (with the GIL held). Each call costs microseconds of
Python, so a simulation is tens to hundreds of times slower than the same model written as a
model file or with SymPy (:func:`ukdyn.from_sympy`), whose expressions run in C++. Use this path
for what the expression language cannot say (table look-ups, external codes), or for checking.

Constraints are given in acceleration form A(q, q', t) q'' = b(q, q', t) (the library's
``acceleration_constraint``); they carry no position-level function, so drift control cannot
project onto them: integrate with tight tolerances, or write the constraint as a model file /
SymPy expression to get projection.
"""

from __future__ import annotations

import inspect
import math
import warnings
from typing import Any, Callable, NamedTuple, Optional, Sequence, Tuple, Union

import numpy as np

from . import _ukdyn
from . import interrupt as _interrupt
from .errors import EnergyBalanceWarning, SolveError
from .results import Result

__all__ = ["constraint", "nonideal", "viscous", "coulomb", "from_callables", "controller",
           "simulate"]


class ConstraintSpec(NamedTuple):
    """An acceleration-form constraint made by :func:`constraint`."""
    name: str
    rows: int
    A: Callable[..., Any]
    b: Callable[..., Any]
    begin: float
    end: float

    def _tuple(self) -> Tuple[Any, ...]:
        return (self.name, self.rows, self.A, self.b, self.begin, self.end)


class NonIdealSpec(NamedTuple):
    """A non-ideal force made by :func:`nonideal`, :func:`viscous` or :func:`coulomb`."""
    spec: Tuple[Any, ...]


def constraint(name: str, A: Callable[..., Any], b: Callable[..., Any], rows: int = 1,
               active: Optional[Tuple[float, float]] = None) -> ConstraintSpec:
    """A constraint A(q, q', t) q'' = b(q, q', t) given by two callables.

    Args:
        name: unique within the system.
        A: ``A(q, q_dot, t)`` → rows × n array (a 1-D array of n numbers when rows == 1).
        b: ``b(q, q_dot, t)`` → rows numbers.
        rows: the number of scalar equations.
        active: ``(t0, t1)``: the constraint acts on that interval only.

    For a holonomic constraint phi(q, t) = 0 differentiate twice: A = ∂phi/∂q,
    b = −(d/dt(A) q' + ...) — or let SymPy do it with :func:`ukdyn.from_sympy`.
    """
    if not callable(A) or not callable(b):
        raise ValueError(f"constraint '{name}': A and b must be callables A(q, q_dot, t), "
                         "b(q, q_dot, t)")
    begin, end = (-math.inf, math.inf) if active is None else (float(active[0]), float(active[1]))
    return ConstraintSpec(str(name), int(rows), A, b, begin, end)


def _adapt(fn: Callable[..., Any], most: int) -> Callable[..., Any]:
    """fn called with the first k of `most` arguments, k the number it accepts."""
    try:
        params = inspect.signature(fn).parameters.values()
    except (TypeError, ValueError):
        return fn
    if any(p.kind == p.VAR_POSITIONAL for p in params):
        return fn
    k = sum(1 for p in params if p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD))
    if k >= most:
        return fn
    return lambda *args: fn(*args[:k])


def nonideal(name: str, C: Callable[..., Any]) -> NonIdealSpec:
    """A non-ideal force given by ``C(q, q_dot, t[, Qc_ideal[, lambda_]])`` → n numbers.

    C may read the ideal constraint force Qc_ideal (n) and the multipliers lambda_ (m) of the
    current evaluation (friction whose magnitude follows a reaction); declare only the
    arguments you need. Its part along the constraints is replaced by the ideal force (eq. 12).
    """
    if not callable(C):
        raise ValueError(f"non-ideal force '{name}': C must be a callable")
    return NonIdealSpec(("C", str(name), _adapt(C, 5)))


def viscous(c: float, coordinates: Sequence[str] = ()) -> NonIdealSpec:
    """Viscous friction C_i = −c q'_i on ``coordinates`` (all when empty), in C++."""
    return NonIdealSpec(("viscous", float(c), list(coordinates)))


def coulomb(constraint: str, mu: float, coordinates: Sequence[str] = (),
            regularization_velocity: Optional[float] = None, mu_static: Optional[float] = None,
            surface_velocity: Optional[Callable[..., Any]] = None) -> NonIdealSpec:
    """Coulomb friction on the surface of ``constraint`` (core/nonideal.hpp, CoulombFriction), in C++:
    magnitude mu |N|, N that constraint's share of the ideal force, opposite to the sliding
    velocity of ``coordinates`` (all when empty) relative to the constraint; stick and slip are
    events in simulate() (docs/friction.md).

    Args:
        mu_static: the static coefficient (>= mu) of sticking and release; default mu.
        surface_velocity: ``f(q, q_dot, t) -> (u, u_dot)``, the surface's velocity along itself
            under the contact on ``coordinates`` (a belt, a turntable) and its rate
            u' = (du/dq) q' + du/dt; u may depend on q and t only. Default: none.
    """
    return NonIdealSpec(("coulomb", str(constraint), float(mu), list(coordinates),
                         regularization_velocity,
                         None if mu_static is None else float(mu_static), surface_velocity))


def from_callables(coordinates: Union[int, Sequence[str]], M: Any, Q: Optional[Callable[..., Any]] = None,
                   V: Optional[Callable[..., Any]] = None,
                   constraints: Sequence[ConstraintSpec] = (),
                   nonideal: Sequence[NonIdealSpec] = (),
                   P: Optional[Callable[..., Any]] = None) -> "_ukdyn.System":
    """A System whose M, Q, V, constraints and C are Python callables (the slow path).

    Args:
        coordinates: the coordinate names, or their number n (names q0, q1, ...).
        M: ``M(q, t)`` → n × n array, or a constant n × n array (factorized once).
        Q: ``Q(q, q_dot, t)`` → n numbers, the impressed force (default: zero).
        V: ``V(q, t)`` → a number, the potential energy of the forces in Q that derive from one
            (for the energy columns only; Q must contain −∂V/∂q itself).
        constraints: :func:`constraint` specs.
        nonideal: :func:`nonideal`, :func:`viscous`, :func:`coulomb` specs.
        P: ``P(q, q_dot, t)`` → a number, the external power: the rate at which the forces in
            Q that V does not account for do work (dampers, applied loads; core/system.hpp,
            PowerFn), integrated into the ``work_external`` column. Without it Q is taken to be
            −∂V/∂q plus forces that do no work, and a Q that does work otherwise makes the run's
            energy balance fail (status ``"energy_balance"``).

    Returns a :class:`ukdyn.System`; run it with :func:`simulate` or ``system.solver()``.
    Raises ValueError for a bad size or name (the C++ ``SystemBuilder::build`` message). An
    exception raised by a callable is raised again by the call that evaluated it.
    """
    names = [f"q{i}" for i in range(coordinates)] if isinstance(coordinates, int) else \
        [str(c) for c in coordinates]
    specs = []
    for c in constraints:
        if not isinstance(c, ConstraintSpec):
            raise ValueError("from_callables: constraints must be made by ukdyn.constraint()")
        specs.append(c._tuple())
    forces = []
    for f in nonideal:
        if not isinstance(f, NonIdealSpec):
            raise ValueError("from_callables: non-ideal forces must be made by ukdyn.nonideal(), "
                             "ukdyn.viscous() or ukdyn.coulomb()")
        forces.append(f.spec)
    return _ukdyn._from_callables(names, M, Q, V, specs, forces, P)


def controller(system: "_ukdyn.System", requirements: Sequence[ConstraintSpec],
               law: str = "gauss", N: Any = None, actuated: Optional[Sequence[str]] = None,
               S: Any = None, robust: Optional[dict] = None) -> "_ukdyn.Controller":
    """A tracking Controller (control/control.hpp, ControllerBuilder) for the nominal model ``system``.

    Args:
        system: the nominal model (its constraints are the plant's physical constraints).
        requirements: :func:`constraint` specs in acceleration form A_r q'' = b_r; b_r holds
            the error dynamics you want (e.g. for phi = x − sin t with e'' + 2ζω e' + ω² e = 0:
            A_r = [1, 0], b_r = −sin t − 2ζω (x' − cos t) − ω² (x − sin t)). Requirements
            written as expressions get their error dynamics from ukdyn:
            ``ukdyn.from_sympy(..., requirements=...)``.
        law: ``"gauss"`` (eq. 25) or ``"weighted"`` (needs N).
        N: the weight, a constant n × n array or ``N(q, q_dot, t)``.
        actuated: the actuated coordinates (default: all).
        S: a general actuation matrix (n × k).
        robust: ``{"bound", "relative_bound", "gain_uncertainty", "boundary_layer"}``.

    Raises ValueError with the C++ ``ControllerBuilder::build`` message.
    """
    specs = [c._tuple() for c in requirements]
    return _ukdyn._build_controller(system, specs, law, N, actuated, S, robust)


def simulate(system: Any, q0: Any = None, qd0: Any = None, *, controller: Any = None,
             check: bool = True, **settings: Any) -> Result:
    """Simulates a Model or a System and returns a :class:`ukdyn.Result`.

    For a Model this is ``model.simulate(q0=..., qd0=..., check=..., **settings)``. For a System
    (from :func:`from_callables` or ``model.system``) q0 and qd0 are required; ``controller``
    (a :class:`ukdyn.Controller`) runs it under control (simulate_controlled). The settings are
    those of :meth:`ukdyn.Model.simulate`. The GIL is released during the run (Python callables
    take it back when called).

    Raises ValueError (bad settings, an inconsistent initial state unless
    ``project_initial=True``), :class:`ukdyn.SolveError` (with ``.result``) when the run fails
    and ``check`` is True, or the exception of a callable; Ctrl-C raises
    :class:`ukdyn.Interrupted` (a KeyboardInterrupt) with the partial result as ``.result``.
    """
    if isinstance(system, _ukdyn.Model):
        if controller is not None:
            raise ValueError("simulate: a Model runs under its own controller (its control: "
                             "section); pass model.system to use another")
        return system.simulate(q0=q0, qd0=qd0, check=check, **settings)
    if not isinstance(system, _ukdyn.System):
        raise ValueError(f"simulate: expected a ukdyn.Model or ukdyn.System, got "
                         f"{type(system).__name__}")
    if q0 is None or qd0 is None:
        raise ValueError("simulate: a System needs q0 and qd0")
    with _interrupt.guard() as interrupt:
        names, columns, stats, control, raised, summary = _ukdyn._simulate_system(
            system, q0, qd0, settings, controller, interrupt.stop)
    result = Result(names, columns, stats, control, system.coordinates)
    result._summary = summary
    interrupt.raise_if_interrupted(result, raised)
    return _finish(result, check)


def _finish(result: Result, check: bool) -> Result:
    # the control's warnings, as `ukdyn run` prints them (requirements not met, the robust bound
    # left): UserWarning
    if result.control:
        for line in _ukdyn._control_warnings(result.control, result.unit_system["time"]):
            warnings.warn(line, UserWarning, stacklevel=3)
    if result.status == "energy_balance":
        # the run is complete: a warning, not an error (warnings.simplefilter("error") makes it one)
        warnings.warn(EnergyBalanceWarning(result.message), stacklevel=3)
        return result
    if check and not result.ok:
        raise SolveError(result.message or result.status, result.status, result)
    return result
