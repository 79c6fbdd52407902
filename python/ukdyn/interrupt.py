# SPDX-License-Identifier: BSD-3-Clause
"""Ctrl-C during a simulation (docs/python.md, "Interrupts").

A run holds no GIL and runs no Python (model files), so Python's own SIGINT handling would only
act when the run had ended. For the duration of a run, :func:`guard` replaces Python's default
SIGINT handler by one that only records the signal; the run asks every 20 ms (with the GIL, after
running Python's signal handlers) whether it came, stops at its next step when it did, and
returns what it computed; the guard then raises :class:`ukdyn.Interrupted` — a
``KeyboardInterrupt`` — with that partial :class:`ukdyn.Result` as ``.result`` (``.partial``).
A second Ctrl-C during the same run raises ``KeyboardInterrupt`` at once, as usual.

Only the main thread receives signals in Python: a run in another thread is not interrupted (the
main thread gets the ``KeyboardInterrupt``). A SIGINT handler of the user's own is left in place
and runs during the run; an exception it raises stops the run the same way and is raised again
with ``.partial`` set to the partial result when it allows attributes.
"""

from __future__ import annotations

import signal
import threading
from typing import Any, Optional

from .errors import Interrupted

__all__ = ["guard"]


class guard:
    """``with guard() as g: ... _run(..., stop=g.stop) ...; g.raise_if_interrupted(result, exc)``."""

    def __init__(self) -> None:
        self.signalled = False
        self._previous: Any = None
        self._installed = False

    def _handler(self, signum: int, frame: Any) -> None:
        if self.signalled:
            raise KeyboardInterrupt
        self.signalled = True

    def stop(self) -> bool:
        """Called by the run (with the GIL) every 20 ms: True once SIGINT arrived."""
        return self.signalled

    def __enter__(self) -> "guard":
        if (threading.current_thread() is threading.main_thread()
                and signal.getsignal(signal.SIGINT) is signal.default_int_handler):
            self._previous = signal.signal(signal.SIGINT, self._handler)
            self._installed = True
        return self

    def __exit__(self, *exc: Any) -> None:
        if self._installed:
            signal.signal(signal.SIGINT, self._previous)
            self._installed = False

    def raise_if_interrupted(self, result: Any, exception: Optional[BaseException]) -> None:
        """After the run: raises :class:`Interrupted` with ``result`` when SIGINT arrived during
        it, or the exception a user's signal handler raised (with ``.partial`` = result)."""
        if exception is not None:
            if isinstance(exception, KeyboardInterrupt) and not isinstance(exception, Interrupted):
                raise Interrupted(_message(result), result) from exception
            try:
                exception.partial = result  # type: ignore[attr-defined]
            except AttributeError:
                pass
            raise exception
        if self.signalled:
            raise Interrupted(_message(result), result)


def _message(result: Any) -> str:
    if result.status == "interrupted":
        return result.message or "interrupted"
    return (f"interrupted after the run had ended (status '{result.status}'): the result is "
            f"complete")
