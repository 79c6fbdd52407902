# SPDX-License-Identifier: BSD-3-Clause
"""The exceptions of ukdyn (docs/python.md, "Errors").

The C++ library's errors arrive in Python as:

* :class:`ModelError` for a bad model file (the C++ ``ukdyn::ModelError``): ``str(err)`` is the
  C++ ``what()``, ``FILE:LINE:COLUMN: error: MESSAGE (hint: HINT)``, and the parts are
  attributes; :class:`ContactStartError`, a ModelError and a ValueError, for a model whose
  contacts cannot be solved at its start (Painlevé's paradox), located at their entries;
* :class:`SolveError` for an evaluation or a run that failed numerically (the C++
  ``ukdyn::SolveError``, or a run whose status is not ``ok``);
* :class:`ValueError` for misuse (the C++ ``std::invalid_argument``: wrong sizes, unknown
  settings, an inconsistent initial state, an unknown example);
* :class:`RuntimeError` for anything else the C++ code throws;
* :class:`EnergyBalanceWarning` (a warning, not an exception) for a run that reached its end but
  whose energy balance residual exceeds its tolerance (status ``"energy_balance"``);
* :class:`Interrupted`, a ``KeyboardInterrupt``, for Ctrl-C during a simulation: the run stops
  at its next step and ``.result`` (``.partial``) holds what it computed.

An exception raised inside a Python callable of a system (``ukdyn.from_callables``) is raised
again, unchanged, by the call that evaluated it.
"""

from __future__ import annotations

from typing import Any, Optional

__all__ = ["ContactStartError", "EnergyBalanceWarning", "InconsistentInitialState", "Interrupted",
           "ModelError", "SolveError"]


class ModelError(RuntimeError):
    """An error in a model file, with where it is and how to fix it.

    ``str(err)`` is exactly the C++ ``what()``: ``FILE:LINE:COLUMN: error: MESSAGE (hint: HINT)``
    (without ``:LINE:COLUMN`` when the error has no position, e.g. an override of a parameter
    the model does not declare).

    Attributes:
        file: the file (or the name given to :func:`ukdyn.parse`, ``"<sympy>"`` for SymPy models).
        line: 1-based line, 0 when the error has no position.
        column: 1-based column, 0 when the error has no position.
        message: what is wrong.
        hint: how to fix it ("" when there is no hint).
    """

    def __init__(self, what: str, file: str = "", line: int = 0, column: int = 0,
                 message: str = "", hint: str = "") -> None:
        super().__init__(what)
        self.file = file
        self.line = line
        self.column = column
        self.message = message or what
        self.hint = hint


class ContactStartError(ModelError, ValueError):
    """A model's run that cannot start because its contacts at the initial state cannot be
    solved: Painlevé's paradox (a sliding Coulomb contact past its critical mu), or an LCP of the
    contacts with no solution (docs/contact.md, "Painlevé").

    A :class:`ModelError` located as ``ukdyn run`` prints it — at the Coulomb friction's entry
    on the contact (where mu is given), else the contact's own — and a ``ValueError`` (the run's
    misuse, as a run of a system of callables raises it, unlocated).
    """


class SolveError(RuntimeError):
    """An evaluation or a simulation that failed numerically.

    ``str(err)`` is the C++ ``describe_status()`` text (what failed, where and when) or, for a
    run, the run's message.

    Attributes:
        status: the short status name (``"inconsistent constraints"``, ...; core/status.hpp).
        result: for a failed simulation, the :class:`ukdyn.Result` with the samples computed
            before the failure; None otherwise.
    """

    def __init__(self, what: str, status: str = "", result: Optional[Any] = None) -> None:
        super().__init__(what)
        self.status = status
        self.result = result


class InconsistentInitialState(ValueError):
    """The initial state does not satisfy the constraints (the C++
    ``ukdyn::InconsistentInitialState``; a ``ValueError`` like every misuse).

    Attributes:
        cause: ``"not_projected"`` (``project_initial=True`` may help), ``"contradictory"``
            (constraints no state satisfies together: no projection helps) or
            ``"projection_failed"`` (projection found no consistent state nearby) or
            ``"penetrated"`` (the C++ ``Cause::kPenetrated``: a contact's gap is < 0 at the
            start; projection does not act on a unilateral gap, so ``project_initial=True``
            cannot help: move the initial state).
    """

    def __init__(self, what: str, cause: str = "") -> None:
        super().__init__(what)
        self.cause = cause


class EnergyBalanceWarning(UserWarning):
    """A run reached its end, but its energy balance failed: E(t) − E(0) differs from the sum
    of the works by more than ``energy_balance_tolerance`` of the energy exchanged
    (``Result.stats["energy_balance"]``; docs/simulation.md, "Energy balance"). The result is
    complete; its status is ``"energy_balance"`` and ``Result.ok`` is False."""


class Interrupted(KeyboardInterrupt):
    """Ctrl-C (SIGINT) during :meth:`ukdyn.Model.simulate` or :func:`ukdyn.simulate`: the run
    stopped at its next step (within about 20 ms plus one step) and kept what it computed.

    ``except KeyboardInterrupt`` catches it. ``str(err)`` says where the run stopped.

    Attributes:
        result: the :class:`ukdyn.Result` with the samples computed before the interrupt — each
            as an uninterrupted run has it, the last one at ``result.stats["t_reached"]``;
            status ``"interrupted"`` (``"ok"`` if the signal came after the run had ended).
        partial: the same object.
    """

    def __init__(self, what: str, result: Optional[Any] = None) -> None:
        super().__init__(what)
        self.result = result

    @property
    def partial(self) -> Optional[Any]:
        """The partial result (``result``)."""
        return self.result
